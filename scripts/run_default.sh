#!/usr/bin/env bash
# The main job on the bundled default data: installs, builds, and renders the bundled
# default preset (sun 35 deg up, azimuth 20 deg) to out/default_sky.exr + a PNG preview.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
build/skycal render --sun-elevation 35 --sun-azimuth 20 \
  --out out/default_sky.exr --png out/default_sky.png --json
