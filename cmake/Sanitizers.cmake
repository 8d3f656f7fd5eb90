# Sanitizer and libFuzzer instrumentation for skycal's own targets.
#
# Included from the top-level CMakeLists.txt before any add_subdirectory(), so the flags
# reach every target this project defines (libraries, cli, tests, fuzz harnesses) and
# nothing else: the system libraries (OpenEXR, Ceres, OpenCV, Mesa...) are prebuilt Debian
# packages and stay uninstrumented.
#
#   SKYCAL_SANITIZE=address,undefined   scripts/sanitize.sh (gcc, build-asan/)
#   SKYCAL_BUILD_FUZZERS=ON             scripts/fuzz.sh (clang, build-fuzz/); adds
#                                       -fsanitize=fuzzer-no-link here, and the harnesses
#                                       in fuzz/ link with -fsanitize=fuzzer.
set(SKYCAL_SANITIZE "" CACHE STRING
    "Comma-separated -fsanitize= list for skycal's own targets, e.g. address,undefined")
option(SKYCAL_BUILD_FUZZERS "Build the libFuzzer harnesses in fuzz/ (clang only)" OFF)

if(SKYCAL_SANITIZE)
  # No recovery from UBSan: a report must fail the test that triggered it, not scroll by.
  # Frame pointers keep ASan's fast unwinder's stacks complete at -O1 and above.
  set(_skycal_san_flags -fsanitize=${SKYCAL_SANITIZE} -fno-omit-frame-pointer)
  if(SKYCAL_SANITIZE MATCHES "undefined")
    list(APPEND _skycal_san_flags -fno-sanitize-recover=undefined)
  endif()
  add_compile_options(${_skycal_san_flags})
  add_link_options(${_skycal_san_flags})
  # Eigen (Memory.h) stops trusting glibc's 16-byte-aligned malloc when __SANITIZE_ADDRESS__
  # is defined and switches to its hand-made aligned allocation, which keeps the original
  # pointer just before each block. The prebuilt libceres (no ASan) allocates with plain
  # malloc, so a matrix it allocates and our instrumented code frees (e.g. the members of
  # ceres::GradientChecker::ProbeResults) was freed as if hand-made: ASan reported a
  # heap-buffer-overflow read 8 bytes before the block. Tell Eigen what is true on glibc
  # x86-64 (and of ASan's allocator): malloc is 16-byte aligned, as libceres assumes.
  if(SKYCAL_SANITIZE MATCHES "address")
    add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
  endif()
  message(STATUS "skycal: sanitizers ${SKYCAL_SANITIZE} on skycal's own targets")
endif()

if(SKYCAL_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "SKYCAL_BUILD_FUZZERS needs clang (libFuzzer): CC=clang CXX=clang++")
  endif()
  # Coverage instrumentation for the libraries; the libFuzzer runtime (and its main) only
  # in the harness executables (fuzz/CMakeLists.txt).
  add_compile_options(-fsanitize=fuzzer-no-link)
  # The EXR readers' pixel limit (core/exr_io.h), lowered to 2048 x 1024 in this build only:
  # the same check, but a mutated header just under the limit costs a 25 MB allocation
  # instead of 1.5 GiB, so the fuzzer keeps its pace (and its -rss_limit_mb stays small).
  add_compile_definitions(SKYCAL_EXR_MAX_PIXELS=2097152LL)
endif()
