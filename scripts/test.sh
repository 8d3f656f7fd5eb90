#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (CTest). Tests use lavapipe (Mesa's CPU
# Vulkan driver); no GPU is needed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cd build
ctest --output-on-failure -j2 --timeout 900
