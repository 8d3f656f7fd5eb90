#!/usr/bin/env bash
# Installs skycal's build dependencies (Debian 12, as root; apt only when something is
# missing, so re-running is fast), then configures and builds into build/ (Release).
# --deps-only: install, do not build (scripts/sanitize.sh and scripts/fuzz.sh build elsewhere).
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libceres-dev libeigen3-dev libopencv-dev libopenexr-dev libopencolorio-dev opencolorio-tools
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslc glslang-tools spirv-tools
  nlohmann-json3-dev libgtest-dev libcli11-dev nettle-dev
  libexiv2-dev
  # capture's lens profiles: lensfun and its lens database (capture/lens_profile.h).
  liblensfun-dev liblensfun-data-v1
  # capture's colour-chart correction: OpenCV contrib's mcc module (ColorChecker detection, ccm).
  libopencv-contrib-dev
  # capture's camera RAW brackets: LibRaw (libraw_r); libtiff writes the tests' DNGs.
  libraw-dev libtiff-dev
  # PNG in and out (core/png_io.h) and JPEG/TIFF brackets (capture/src/camera_image.cc):
  # the codecs themselves, not OpenCV's imgcodecs (it drags GDAL into every start-up).
  libpng-dev libjpeg-dev
  # skycal batch --engine slurm and its test (tests/batch_slurm_test.sh): a single-node Slurm
  # cluster and its authentication; python3 for its free ports and JSON checks.
  slurm-wlm munge python3
  # skycal bench's Pareto plots and skycal report's charts: PLplot and its cairo drivers
  # (pngcairo, svgcairo).
  libplplot-dev plplot-driver-cairo
  # The report's browser test (tests/report_browser_test.cc): headless Chromium.
  chromium
  # scripts/fuzz.sh: clang and its runtimes (libFuzzer, ASan, UBSan; not pulled in by
  # clang under --no-install-recommends).
  clang libclang-rt-14-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm fetches the second set of real skies (@pmndrs/assets); Debian's npm unless one exists.
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing: ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi

[ "${1:-}" = "--deps-only" ] && exit 0
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build
