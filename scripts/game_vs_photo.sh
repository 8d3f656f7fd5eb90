#!/usr/bin/env bash
# What a user sees after calibrating on a bundled photo: the calibrated preset rendered as
# the game renders it (the sky model, plus its HZD clouds when the preset has a clouds
# section, at the photo's sun and size, times the fit's exposure) against the photo, in the
# two numbers of `skycal compare` (docs/fitting.md "Judging a calibration"), next to the
# fit's own log RMSE on the pixels it kept.
#
# Each frame is fitted the way the main job fits it (scripts/run_default.sh: hand masks for
# sunrise and sunset, --clouds stats for dawn, city and sky). The comparison's sky pixels:
# the hand mask where the frame has one, else `skycal mask` (the automatic segmentation).
#
#   scripts/game_vs_photo.sh [--build DIR] [--work DIR] [--results FILE]
#
# Needs datasets/real (datasets/fetch_real_skies.sh --with-npm). Writes the table to
# bench/results/game_vs_photo.md (or --results) and keeps every image under --work.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build
WORK=out/game_vs_photo
RESULTS=bench/results/game_vs_photo.md
while [ $# -gt 0 ]; do
  case "$1" in
    --build) BUILD=$2; shift ;;
    --work) WORK=$2; shift ;;
    --results) RESULTS=$2; shift ;;
    *) echo "usage: $0 [--build DIR] [--work DIR] [--results FILE]" >&2; exit 2 ;;
  esac
  shift
done
SKYCAL=$BUILD/skycal
REAL=datasets/real
[ -x "$SKYCAL" ] || { echo "no $SKYCAL: build first" >&2; exit 2; }
for f in sunrise sunset dawn city sky; do
  [ -f "$REAL/$f.exr" ] || { echo "no $REAL/$f.exr: run datasets/fetch_real_skies.sh --with-npm" >&2; exit 2; }
done
mkdir -p "$WORK"
log() { echo "[game_vs_photo] $*" >&2; }

# json FILE EXPR: a value from a JSON file (python3, as the other scripts).
json() { python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print(eval(sys.argv[2], {"j": j}))' "$1" "$2"; }

# one FRAME HOURS KIND: fit, render the game's image, compare; prints one table row.
one() {
  local f=$1 hours=$2 kind=$3 w="$WORK/$1" mask flags
  rm -rf "$w"; mkdir -p "$w"
  if [ -f "datasets/masks/${f}_mask.exr" ]; then
    mask="datasets/masks/${f}_mask.exr"; flags="--mask $mask"
  else
    "$SKYCAL" mask --reference "$REAL/$f.exr" --out "$w/mask.exr" >/dev/null
    mask="$w/mask.exr"; flags=""
  fi
  [ "$kind" = cloudy ] && flags="$flags --clouds stats"
  local t0=$SECONDS
  # shellcheck disable=SC2086
  "$SKYCAL" fit --quiet --reference "$REAL/$f.exr" $flags --time "$hours" --out "$w/fit" >/dev/null
  local fit_s=$((SECONDS - t0))
  local sun exposure fit_log size clouds=""
  sun=$(json "$w/fit/fit.json" '",".join(repr(v) for v in j["references"][0]["sun_direction"])')
  exposure=$(json "$w/fit/fit.json" 'j["references"][0]["exposure"]')
  fit_log=$(json "$w/fit/fit.json" 'round(j["references"][0]["log_rmse"], 3)')
  size=$(json "$REAL/.$f.import.json" '"x".join(str(v) for v in j["size"])')
  [ "$(json "$w/fit/preset.json" '"clouds" in j')" = True ] && clouds="--clouds"
  "$SKYCAL" render --preset "$w/fit/preset.json" --sun-dir "$sun" --size "$size" $clouds --out "$w/game.exr" \
    --png "$w/game.png" >/dev/null 2>&1
  "$SKYCAL" compare --photo "$REAL/$f.exr" --game "$w/game.exr" --mask "$mask" --exposure "$exposure" --json \
    >"$w/compare.json" 2>/dev/null
  local px ap
  px=$(json "$w/compare.json" 'round(j["per_pixel_log_rmse"], 3)')
  ap=$(json "$w/compare.json" 'round(j["appearance_error"], 3)')
  log "$f: game vs photo per-pixel log RMSE $px, appearance $ap (fit's own log RMSE $fit_log; fit ${fit_s} s)"
  echo "| $f | $kind${clouds:+, clouds rendered} | $(basename "$mask") | $px | $ap | $fit_log | $fit_s |"
}

{
  echo "# The game's image against the photo"
  echo
  echo "Written by \`scripts/game_vs_photo.sh\` ($(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(date -u +%Y-%m-%d))."
  echo "Each bundled photo fitted as the main job fits it; the calibrated preset rendered as the game"
  echo "renders it (clouds when the preset has them) at the photo's sun and size, times the fit's"
  echo "exposure; compared above the horizon on the sky pixels (hand mask, else \`skycal mask\`)."
  echo "Natural logarithms: 0.1 is about 10%. The fit's own log RMSE is on the pixels the fit kept."
  echo
  echo "| frame | fit | sky pixels | per-pixel log RMSE | appearance error | fit's own log RMSE | fit s |"
  echo "|---|---|---|---|---|---|---|"
  one sunrise 6.5 clear
  one sunset 19.5 clear
  one dawn 6 cloudy
  one city 11 cloudy
  one sky 13 cloudy
} >"$WORK/table.md"
mkdir -p "$(dirname "$RESULTS")"
cp "$WORK/table.md" "$RESULTS"
log "wrote $RESULTS"
