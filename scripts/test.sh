#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (CTest). Tests use lavapipe (Mesa's CPU
# Vulkan driver); no GPU is needed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Real photographed skies (Debian blender-data, Poly Haven CC0; checksummed, cached in
# datasets/cache/) for the real-sky fit tests.
# A failed download (mirror or network) must not hide the other results: the real-sky
# tests then report SKIPPED, and this says why.
bash datasets/fetch_real_skies.sh --with-npm || echo "[test] WARNING: real skies not fetched; real_sky_test will skip" >&2
cd build
ctest --output-on-failure -j2 --timeout 900
