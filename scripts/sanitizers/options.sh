# Sanitizer run-time options for the build-asan test run (sourced by scripts/sanitize.sh;
# source it yourself to run one test binary from build-asan/ by hand).
#
# ASan: leaks on (LeakSanitizer at exit), stack-use-after-return and init-order checks on;
# every report ends the process with a non-zero status, so CTest marks the test failed.
# UBSan: no recovery (the build also has -fno-sanitize-recover=undefined), with a stack.
# LSan: the suppressions in lsan.supp, third-party code only (reasons in that file).
_skycal_san_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export ASAN_OPTIONS="detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:halt_on_error=1:symbolize=1${SKYCAL_EXTRA_ASAN_OPTIONS:+:$SKYCAL_EXTRA_ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:symbolize=1"
export LSAN_OPTIONS="suppressions=$_skycal_san_dir/lsan.supp:print_suppressions=1"
# keep_icd_loaded.so (built by scripts/sanitize.sh) keeps lavapipe mapped after the
# Vulkan loader unloads it, so leak stacks name libvulkan_lvp.so instead of "<unknown
# module>" (the reason is in keep_icd_loaded.c). libasan must come first in LD_PRELOAD.
_skycal_keep="$_skycal_san_dir/../../build-asan/keep_icd_loaded.so"
if [ -f "$_skycal_keep" ]; then
  export LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(cd "$(dirname "$_skycal_keep")" && pwd)/keep_icd_loaded.so"
fi
unset _skycal_san_dir _skycal_keep
