#!/usr/bin/env bash
# The main job on the bundled data, end to end: install (scripts/setup.sh: apt only when a
# package is missing) and build, fetch the real skies (checksummed, datasets/fetch_real_skies.sh),
# fit them, export the game tables and write the HTML report. Ends by printing where to look.
#
#   out/main_job/<frame>/     skycal fit outputs (preset, fit renders, fit.json, report.html)
#   out/main_job/game/        skycal export: half-float LUTs, keyframes, SH-9, fog (+ report.html)
#   out/main_job/report.html  the whole job on one page: every fit, the day's time-of-day plots,
#                             the game tables
#
# Which frame gets which fit (datasets/README.md describes the frames):
#   sunrise, sunset  clear: the atmosphere, with the hand-drawn masks of trees and buildings
#   sky, dawn, city  cloudy: fit --clouds stats — the atmosphere on the clear pixels, the cloud
#                    lighting from the statistics of the cloud pixels (sun detected for dawn,
#                    behind its ridge, and for city, through overcast)
#   forest, night    canopy / night sky: no sky model applies; not fitted
#   probe            no bundled frame shows a gray ball: no probe fit (docs/cli.md: "probe-extract")
# The sources record no time of day; nominal times (dawn 06:00, sunrise 06:30, city 11:00,
# sky 13:00, sunset 19:30)
# order the keyframes along the sun's course and are labelled nominal in the log.
set -euo pipefail
cd "$(dirname "$0")/.."

now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
log() { echo "[run_default] $*" >&2; }

T0=$(now)
bash scripts/setup.sh
T_SETUP=$(now)
log "install and build: $(secs "$T0" "$T_SETUP") s"

datasets/fetch_real_skies.sh --with-npm
T_FETCH=$(now)

OUT=out/main_job
mkdir -p "$OUT"
SKYCAL=build/skycal
REAL=datasets/real
MASKS=datasets/masks

fit_clear() {  # NAME HOURS: the atmosphere on a clear sky, buildings and trees masked
  log "fit $1 (clear; mask $MASKS/$1_mask.exr; nominal time $2 h)"
  "$SKYCAL" fit --quiet --reference "$REAL/$1.exr" --mask "$MASKS/$1_mask.exr" --time "$2" --out "$OUT/$1"
}
fit_cloudy() {  # NAME HOURS: a cloudy sky: the atmosphere on its clear pixels, the clouds' lighting by statistics
  log "fit $1 (cloudy: --clouds stats; nominal time $2 h)"
  "$SKYCAL" fit --quiet --reference "$REAL/$1.exr" --clouds stats --time "$2" --out "$OUT/$1"
}

fit_cloudy dawn 6
fit_clear sunrise 6.5
fit_cloudy city 11
fit_cloudy sky 13
fit_clear sunset 19.5
log "not fitted: forest (under a canopy), night (no sky model for a night sky)"
log "probe: no bundled frame shows a gray ball (see the README's probe-extract and fit --probe)"
T_FIT=$(now)

"$SKYCAL" export --preset "$OUT/dawn/preset.json" --preset "$OUT/sunrise/preset.json" --preset "$OUT/city/preset.json" \
  --preset "$OUT/sky/preset.json" --preset "$OUT/sunset/preset.json" --out "$OUT/game"
T_EXPORT=$(now)

"$SKYCAL" report "$OUT" --out "$OUT/report.html" --title "skycal: the bundled real skies, fitted and exported"
T_END=$(now)

cat >&2 <<DONE
[run_default] done in $(secs "$T0" "$T_END") s: install and build $(secs "$T0" "$T_SETUP") s, fetch $(secs "$T_SETUP" "$T_FETCH") s,
[run_default]   fits $(secs "$T_FETCH" "$T_FIT") s, export $(secs "$T_FIT" "$T_EXPORT") s, report $(secs "$T_EXPORT" "$T_END") s
[run_default] where to look:
[run_default]   $OUT/report.html          the whole job on one page (open it in a browser; it embeds everything)
[run_default]   $OUT/game/                the game tables: manifest.json, keyframes.csv/.json, <preset>/*.exr
[run_default]   $OUT/<frame>/preset.json  each calibrated preset; fit.json beside it has the numbers
DONE
