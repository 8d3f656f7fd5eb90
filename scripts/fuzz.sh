#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, clang, ASan + UBSan, into build-fuzz/) and runs
# each for SECONDS (default 20) on a scratch copy of its seed corpus (fuzz/corpus/<name>/),
# so the repository is never modified. Fails if any harness crashes, leaks, times out or
# exceeds its memory limit; the reproducer and the log are kept under the work directory.
#
#   bash scripts/fuzz.sh [SECONDS] [HARNESS...]     e.g. bash scripts/fuzz.sh 600 exr_frame
#   SKYCAL_FUZZ_WORK=DIR  keep corpora, logs and crash files in DIR (default: a fresh
#                         directory under /tmp, printed at the end)
#   SKYCAL_FUZZ_STRICT=1  also report non-skycal exceptions escaping a reader (fuzz_support.h)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(preset rig probe_samples json_file exr_frame command_line weather_map camera_image radiance_picture)

bash scripts/setup.sh --deps-only
# -gline-tables-only: crash stacks keep file and line at a fraction of -g's compile time.
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DSKYCAL_SANITIZE=address,undefined -DSKYCAL_BUILD_FUZZERS=ON \
  -DSKYCAL_BUILD_TESTS=OFF -DSKYCAL_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz -j2 --target skycal_fuzzers

# Per-harness limits. -max_len bounds the input; -rss_limit_mb (also the single-malloc
# limit) bounds memory, so a reader that allocates what a header claims is reported as a
# crash. The EXR readers refuse images beyond their documented size before allocating
# (core/exr_io.h; build-fuzz lowers that limit to 2048 x 1024 pixels, cmake/Sanitizers.cmake),
# so 2 GiB is room for any image they accept plus ASan's overhead. exr_frame's -timeout is
# 60 s: a loaded 2-core machine runs an accepted 2048 x 1024 image's sun detection and
# pixel classes under ASan for seconds.
options_for() {
  case "$1" in
    preset)        echo "-max_len=16384 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/json.dict" ;;
    rig)           echo "-max_len=8192 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/json.dict" ;;
    probe_samples) echo "-max_len=8192 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/json.dict" ;;
    json_file)     echo "-max_len=8192 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/json.dict" ;;
    exr_frame)     echo "-max_len=65536 -rss_limit_mb=2048 -timeout=60 -dict=fuzz/exr.dict" ;;
    command_line)  echo "-max_len=4096 -rss_limit_mb=2048 -timeout=20" ;;
    weather_map)   echo "-max_len=65536 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/exr.dict" ;;
    camera_image)  echo "-max_len=65536 -rss_limit_mb=2048 -timeout=20" ;;
    radiance_picture) echo "-max_len=65536 -rss_limit_mb=2048 -timeout=20 -dict=fuzz/radiance.dict" ;;
    *) echo "unknown harness '$1' (expected preset rig probe_samples json_file exr_frame command_line weather_map camera_image radiance_picture)" >&2; return 1 ;;
  esac
}

work=${SKYCAL_FUZZ_WORK:-$(mktemp -d /tmp/skycal-fuzz.XXXXXX)}
mkdir -p "$work"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
for h in "${harnesses[@]}"; do
  opts=$(options_for "$h")
  mkdir -p "$work/$h/corpus" "$work/$h/crashes"
  cp -n fuzz/corpus/"$h"/* "$work/$h/corpus/"
  echo "[fuzz] $h: ${seconds}s ($opts)" >&2
  # shellcheck disable=SC2086
  if ! build-fuzz/fuzz/${h}_fuzzer -max_total_time="$seconds" -print_final_stats=1 $opts \
       -artifact_prefix="$work/$h/crashes/" "$work/$h/corpus" >"$work/$h/log.txt" 2>&1; then
    failed+=("$h")
    tail -n 60 "$work/$h/log.txt" >&2
  fi
  # The last status line (cov/ft/corp) and the final stats, for bench/results/fuzz.md.
  { grep -E '^#[0-9]+' "$work/$h/log.txt" | tail -n 1
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$work/$h/log.txt"; } |
    sed "s/^/[fuzz] $h: /" >&2 || true
  echo "[fuzz] $h: corpus $(ls "$work/$h/corpus" | wc -l) files, $(du -sk "$work/$h/corpus" | cut -f1) KiB" >&2
done
echo "[fuzz] work directory (corpora, logs, crashes): $work" >&2
if [ ${#failed[@]} -gt 0 ]; then
  echo "[fuzz] FAILED: ${failed[*]}" >&2
  exit 1
fi
