#!/usr/bin/env bash
# `cmake --install` to a temporary prefix, the prefix moved to another directory, and the
# moved copy run from outside the checkout: `skycal --data-dir` must name the moved prefix's
# share/skycal with origin "install" (an installed binary prefers it to the checkout it was
# built from, so nothing below can be read from the source tree), then a render (the bundled
# preset, a preview PNG through the bundled OCIO config), a fit of that render (the bundled
# preset as the start) and the HTML report of the fit.
# usage: install_test.sh CMAKE_COMMAND BUILD_DIR
# Every step says where it failed (the line, the command and its status) and nothing is sent
# to /dev/null: a failure in CI must explain itself from the test's own output.
set -euo pipefail
exec 2>&1
trap 'echo "FAIL: line $LINENO: \"$BASH_COMMAND\" exited $?"' ERR
CMAKE=$1
BUILD=$2
T=$(mktemp -d "${TMPDIR:-/tmp}/skycal-install-test.XXXXXX")
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
echo "install: $BUILD -> $T/staged"

"$CMAKE" --install "$BUILD" --prefix "$T/staged" >"$T/install.log" || { cat "$T/install.log"; fail "cmake --install"; }
mv "$T/staged" "$T/moved"
P=$(realpath "$T/moved")
DATA="$P/share/skycal"
for f in bin/skycal share/skycal/config/skycal.ocio share/skycal/datasets/presets/default_clear.json \
         share/skycal/datasets/presets/default_clear.rayleigh.exr share/skycal/datasets/presets/default_cloudy.json \
         share/skycal/datasets/tables/cie_general_sky.csv; do
  [ -f "$P/$f" ] || fail "$f not installed"
done
echo "installed: $(du -sk "$P" | cut -f1) KiB"

unset SKYCAL_DATA_DIR OCIO
mkdir "$T/work"
cd "$T/work"  # cwd outside the checkout
SKYCAL="$P/bin/skycal"
[ "$("$SKYCAL" --data-dir)" = "$DATA"$'\t'install ] || fail "--data-dir: '$("$SKYCAL" --data-dir)', expected '$DATA<TAB>install'"
# SKYCAL_DATA_DIR still wins over the install (a user's own data tree).
[ "$(SKYCAL_DATA_DIR=/elsewhere "$SKYCAL" --data-dir)" = $'/elsewhere\tSKYCAL_DATA_DIR' ] || fail "SKYCAL_DATA_DIR not honoured"

"$SKYCAL" render --sun-elevation 20 --sun-azimuth 30 --size 128x64 --backend cpu --out sky.exr --png sky.png --json >render.json
grep -q "\"preset\": *\"$DATA/datasets/presets/default_clear.json\"" render.json || fail "render used $(grep preset render.json)"
[ -s sky.exr ] && [ -s sky.png ] || fail "render wrote no EXR/PNG"

"$SKYCAL" fit --reference sky.exr --quiet --backend cpu --out fit >fit.log || { cat fit.log; fail "fit"; }
grep -q "\"path\": *\"$DATA/datasets/presets/default_clear.json\"" fit/preset.json || fail "fit started from elsewhere"
python3 - fit/fit.json <<'PY' || fail "fit.json"
import json, sys
j = json.load(open(sys.argv[1]))
rmse = j["references"][0]["rel_rmse"]
assert rmse < 0.01, f"rel_rmse {rmse} of a fit to the default preset's own render"
PY

"$SKYCAL" report fit --out report.html >report.log || { cat report.log; fail "report"; }
grep -q '<img' report.html || fail "report.html has no image"
echo "PASS"
