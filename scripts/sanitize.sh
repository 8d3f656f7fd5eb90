#!/usr/bin/env bash
# The whole test suite (CTest, Vulkan through lavapipe included) under AddressSanitizer
# (with LeakSanitizer) and UndefinedBehaviorSanitizer: gcc, -O1 -g, skycal's own targets
# instrumented (cmake/Sanitizers.cmake), system libraries as packaged, into build-asan/.
# Any sanitizer report fails the test that triggered it. Suppressions: third-party code
# only, each justified, in scripts/sanitizers/ (docs/testing.md "Sanitizers").
#
#   bash scripts/sanitize.sh [CTEST ARGS...]     e.g. bash scripts/sanitize.sh -R Rig
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --deps-only

# -O1: the usual sanitizer trade-off (readable stacks, tests ~2-3x a Release run); NDEBUG
# as in the Release build, so the code under test is the code that ships. -g1 (line tables
# only): the reports' stacks keep function, file and line, and each Ceres-heavy file
# compiles in ~0.6x the time of -g (sky_row_cost.cc: 14 s vs 22 s, measured in one run),
# which matters on CI's 2 cores where this build is the stage's larger half.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DSKYCAL_SANITIZE=address,undefined -DSKYCAL_BUILD_TESTS=ON -DSKYCAL_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j2
gcc -shared -fPIC -O1 -o build-asan/keep_icd_loaded.so scripts/sanitizers/keep_icd_loaded.c -ldl

source scripts/sanitizers/options.sh

cd build-asan
ctest --output-on-failure -j2 --timeout 1800 "$@"
