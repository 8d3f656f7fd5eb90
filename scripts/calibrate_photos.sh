#!/usr/bin/env bash
# `skycal calibrate` as a user runs it, with no flag, on photographs: the bundled frames (the
# ones the method was developed on) and a held-out set nobody tuned anything on (the other
# Poly Haven HDRIs of npm @pmndrs/assets: parks, streets, bridges, interiors; and the three
# worlds of Debian's blender-data the bundled set does not use), reported apart.
# Per photo: what kind of sky it was called and why, where the sun came from, the game's
# image against the photo (per-pixel log RMSE and appearance error, `fit.json`'s
# `calibration`), and the seconds. For the two clear frames with hand masks, the game's image
# is also compared over the hand mask, beside the main job's hand-masked fit
# (bench/results/game_vs_photo.md), the 1.1x target; and each fit beside the model's ceiling.
#
#   scripts/calibrate_photos.sh [--build DIR] [--work DIR] [--results FILE] [--baseline DIR LABEL]
#
# --baseline: another build (e.g. the previous commit's, in a worktree) timed in the same
# fresh-process loop, interleaved, so that a change in speed is read as a ratio in one run
# (the machine's own speed drifts by a fifth from minute to minute here); LABEL names it.
#
# Needs datasets/real, the npm tarball and the blender-data package in datasets/cache
# (datasets/fetch_real_skies.sh --with-npm). Writes bench/results/calibrate.md (or --results); keeps every output in --work.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build
WORK=out/calibrate_photos
RESULTS=bench/results/calibrate.md
BASELINE=
BASELINE_LABEL=
while [ $# -gt 0 ]; do
  case "$1" in
    --build) BUILD=$2; shift ;;
    --work) WORK=$2; shift ;;
    --results) RESULTS=$2; shift ;;
    --baseline)
      [ $# -ge 3 ] || { echo "$0: --baseline needs a build directory and a label" >&2; exit 2; }
      BASELINE=$2; BASELINE_LABEL=$3; shift 2 ;;
    *) echo "usage: $0 [--build DIR] [--work DIR] [--results FILE] [--baseline DIR LABEL]" >&2; exit 2 ;;
  esac
  shift
done
SKYCAL=$BUILD/skycal
if [ -n "$BASELINE" ] && [ ! -x "$BASELINE/skycal" ]; then
  echo "$0: --baseline $BASELINE: no executable $BASELINE/skycal" >&2
  exit 2
fi
REAL=datasets/real
TGZ=datasets/cache/pmndrs-assets-1.7.0.tgz
DEB=datasets/cache/blender-data_3.4.1+dfsg-2_all.deb
DEB_WORLD_DIR=usr/share/blender/datafiles/studiolights/world
BUNDLED=(sunrise sunset dawn city sky forest night)
[ -x "$SKYCAL" ] || { echo "no $SKYCAL: build first" >&2; exit 2; }
for f in "${BUNDLED[@]}"; do
  [ -f "$REAL/$f.exr" ] || { echo "no $REAL/$f.exr: run datasets/fetch_real_skies.sh --with-npm" >&2; exit 2; }
done
for f in "$TGZ" "$DEB"; do
  [ -f "$f" ] || { echo "no $f: run datasets/fetch_real_skies.sh --with-npm" >&2; exit 2; }
done
log() { echo "[calibrate_photos] $*" >&2; }
rm -rf "$WORK"
mkdir -p "$WORK/heldout_photos"

# The held-out photos: every HDRI of the package but the two bundled ones (sky, dawn), as
# published (Blender's convention, no envmap attribute: calibrate converts them).
HELDOUT=()
for js in $(tar tzf "$TGZ" | grep -E '^package/hdri/[a-z]+\.exr\.js$'); do
  name=$(basename "$js" .exr.js)
  case "$name" in sky|dawn) continue ;; esac
  tar -xzOf "$TGZ" "$js" | sed -e "s/^export default '[^,]*,//" -e "s/'[;[:space:]]*\$//" | base64 -d \
    >"$WORK/heldout_photos/$name.exr"
  HELDOUT+=("$name")
done
# And the worlds of Blender's package that the bundled set does not use (1024x512, the same
# convention), named blender-* apart from the package's namesakes.
for name in courtyard interior studio; do
  dpkg-deb --fsys-tarfile "$DEB" | tar -xO "./$DEB_WORLD_DIR/$name.exr" >"$WORK/heldout_photos/blender-$name.exr"
  HELDOUT+=("blender-$name")
done

# run SET PHOTO...: one calibrate command over the photos; its JSON and wall time kept.
run() {
  local set=$1; shift
  local args=() t0
  for p in "$@"; do args+=(--photo "$p"); done
  t0=$(date +%s.%N)
  "$SKYCAL" calibrate "${args[@]}" --out "$WORK/$set" --json >"$WORK/$set.json" 2>"$WORK/$set.log" || true
  awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }' >"$WORK/$set.seconds"
  log "$set: $(cat "$WORK/$set.seconds") s for $# photos (log: $WORK/$set.log)"
}
bundled_paths=(); for f in "${BUNDLED[@]}"; do bundled_paths+=("$REAL/$f.exr"); done
heldout_paths=(); for f in "${HELDOUT[@]}"; do heldout_paths+=("$WORK/heldout_photos/$f.exr"); done
run bundled "${bundled_paths[@]}"
run heldout "${heldout_paths[@]}"

# The clear frames over their hand masks (the main job's pixels).
for f in sunrise sunset; do
  if [ -f "$WORK/bundled/$f/render.exr" ]; then
    "$SKYCAL" compare --photo "$WORK/bundled/$f/photo.exr" --game "$WORK/bundled/$f/render.exr" \
      --mask "datasets/masks/${f}_mask.exr" --json >"$WORK/$f.handmask.json" 2>/dev/null || true
  fi
done

# The model's own ceiling on the same sky pixels (skycal ceiling: the best any LUT reaches),
# beside the fit's rel RMSE, for every calibrated bundled photo.
for d in "$WORK"/bundled/*/; do
  [ -f "$d/fit.json" ] || continue
  init=()
  [ -f "$d/overcast_start.json" ] && init=(--init "$d/overcast_start.json")
  "$SKYCAL" ceiling --reference "$d/photo.exr" --mask "$d/mask.exr" "${init[@]}" --json \
    >"$WORK/$(basename "$d").ceiling.json" 2>/dev/null || true
done

# A fresh process per photo, as a user runs one (the slowest frame, partly cloudy `sky`):
# 5 runs each with and without the huge-page re-exec (core/huge_pages.h), interleaved so a
# drift of the machine's speed falls on both; wall seconds, one per line.
# With --baseline, that build's runs (huge pages on) between them.
for _ in 1 2 3 4 5; do
  for mode in 1 0 baseline; do
    [ "$mode" = baseline ] && [ -z "$BASELINE" ] && continue
    rm -rf "$WORK/fresh"
    exe=$SKYCAL huge=$mode
    [ "$mode" = baseline ] && exe=$BASELINE/skycal huge=1
    t0=$(date +%s.%N)
    SKYCAL_HUGE_PAGES=$huge "$exe" calibrate --photo "$REAL/sky.exr" --out "$WORK/fresh" >/dev/null 2>&1 || true
    awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f\n", b - a }' >>"$WORK/fresh_huge$mode.seconds"
  done
done
rm -rf "$WORK/fresh"
[ -n "$BASELINE" ] && printf '%s\n' "$BASELINE_LABEL" >"$WORK/fresh_hugebaseline.label"

# Larger photos, as users bring them (1K and 2K lat-longs): a partly cloudy sky the game's own
# march draws (a procedural weather map, sun 40 deg up) at four sizes (1000x500: no multiple of
# the working widths), one fresh calibrate each; wall seconds and the game's image against it.
"$SKYCAL" weather --seed 5 --size 256 --mean-coverage 0.25 --coverage-contrast 3 --coverage-cells 8 \
  --mean-precipitation 0 --out "$WORK/sizes_weather.exr" >/dev/null 2>&1
for size in 512x256 1000x500 1024x512 2048x1024; do
  "$SKYCAL" render --preset datasets/presets/default_cloudy.json --clouds --weather-map "$WORK/sizes_weather.exr" \
    --sun-elevation 40 --sun-azimuth 60 --size "$size" --out "$WORK/sizes_$size.exr" >/dev/null 2>&1
  t0=$(date +%s.%N)
  "$SKYCAL" calibrate --photo "$WORK/sizes_$size.exr" --out "$WORK/sizes_$size" --json >"$WORK/sizes_$size.json" 2>/dev/null || true
  awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f\n", b - a }' >"$WORK/sizes_$size.seconds"
  # Where the game's clouds sit against the truth's (both EXRs carry cloudTransmittance).
  "$SKYCAL" compare --photo "$WORK/sizes_$size.exr" --game "$WORK/sizes_$size/sizes_$size/render.exr" \
    --mask "$WORK/sizes_$size/sizes_$size/mask.exr" --json >"$WORK/sizes_$size.truth.json" 2>/dev/null || true
done

python3 scripts/calibrate_photos_table.py "$WORK" "$(git rev-parse --short HEAD 2>/dev/null || echo unknown)" >"$WORK/table.md"
mkdir -p "$(dirname "$RESULTS")"
cp "$WORK/table.md" "$RESULTS"
log "wrote $RESULTS"
