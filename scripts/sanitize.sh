#!/usr/bin/env bash
# The whole test suite (CTest, Vulkan through lavapipe included) under AddressSanitizer
# (with LeakSanitizer) and UndefinedBehaviorSanitizer: gcc, -O1 -g, skycal's own targets
# instrumented (cmake/Sanitizers.cmake), system libraries as packaged, into build-asan/.
# Any sanitizer report fails the test that triggered it. Suppressions: third-party code
# only, each justified, in scripts/sanitizers/ (docs/testing.md "Sanitizers").
#
#   bash scripts/sanitize.sh [CTEST ARGS...]     e.g. bash scripts/sanitize.sh -R Rig
#   bash scripts/sanitize.sh --ci                 the CI subset (below)
#
# --ci builds only the libraries below the CLI and the in-process tests of them, and runs
# their `fast` tests. The whole suite under the sanitizers is a second full build plus a
# 2-3x slower run of every test, more than CI's time allows on 2 cores; what CI leaves out
# here (the CLI, report, export and batch end to end, the slow tests) runs in the Release
# stage, and the parsers the CLI feeds (command line, JSON, EXR, presets, rigs) run under
# ASan + UBSan in the fuzz stage (scripts/fuzz.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
CI_SUBSET=0
if [ "${1:-}" = "--ci" ]; then
  CI_SUBSET=1
  shift
fi
# Library tests that run in-process (no skycal binary, no cli/report/export/batch library),
# chosen for what they reach per second under ASan: the parsers and writers (io, the Radiance
# picture reader), the fit's costs and solvers, the conventions, the Vulkan host code (compute
# pipeline, render parity).
# Left to the full run: the noise cache, the probe GradientChecker and the cloud statistics
# suites (each minutes under ASan on 2 cores).
CI_TARGETS=(conventions_test io_test linear_sky_test fit_cost_test fit_roundtrip_test
  fit_degenerate_test shape_noise_covariance_test weather_map_test cie_sky_test
  workgroup_order_test compute_pipeline_test cloud_mask_test response_recovery_test
  render_parity_test appearance_test radiance_io_test)
bash scripts/setup.sh --deps-only

# -O1: the usual sanitizer trade-off (readable stacks, tests ~2-3x a Release run); NDEBUG
# as in the Release build, so the code under test is the code that ships. -g1 (line tables
# only): the reports' stacks keep function, file and line, and each Ceres-heavy file
# compiles in ~0.6x the time of -g (sky_row_cost.cc: 14 s vs 22 s, measured in one run),
# which matters on CI's 2 cores where this build is the stage's larger half.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DSKYCAL_SANITIZE=address,undefined -DSKYCAL_BUILD_TESTS=ON -DSKYCAL_BUILD_BENCH=OFF >/dev/null
if [ "$CI_SUBSET" = 1 ]; then
  cmake --build build-asan -j2 --target "${CI_TARGETS[@]}"
  # Tests of executables not built here appear as <target>_NOT_BUILT (gtest discovery).
  set -- -L fast -E _NOT_BUILT "$@"
else
  cmake --build build-asan -j2
fi
gcc -shared -fPIC -O1 -o build-asan/keep_icd_loaded.so scripts/sanitizers/keep_icd_loaded.c -ldl

source scripts/sanitizers/options.sh

cd build-asan
ctest --output-on-failure -j2 --timeout 1800 "$@"
