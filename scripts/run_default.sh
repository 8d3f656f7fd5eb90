#!/usr/bin/env bash
# The main job on the bundled data, end to end: install (scripts/setup.sh: apt only when a
# package is missing) and build, fetch the real skies (checksummed, datasets/fetch_real_skies.sh),
# calibrate them (fit, the game's image beside the photo, game tables, HTML report). Ends by
# printing where to look.
#
#   out/main_job/<frame>/     skycal calibrate per photo (photo, mask, preset, fit.json, render.exr,
#                             compare.png, report.html)
#   out/main_job/game/        the game tables: half-float LUTs, keyframes, SH-9, fog
#   out/main_job/report.html  the whole job on one page
#
# One `skycal calibrate` over every bundled frame, with no mask and no per-frame flag: the
# tool segments each sky, places its sun, decides the kind of sky and what to fit
# (docs/calibrate.md). It refuses forest (under a canopy) and night (a night sky) with the
# classifier's reason, and exits 1 for them; the others are calibrated, exported to
# out/main_job/game/ and reported.
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
rm -rf "$OUT" "$OUT.calibrate.json"  # the job's own output of an earlier run (perhaps an older skycal's)
mkdir -p "$(dirname "$OUT")"
SKYCAL=build/skycal
REAL=datasets/real

PHOTOS=()
for f in dawn sunrise city sky sunset forest night; do PHOTOS+=(--photo "$REAL/$f.exr"); done
set +e
"$SKYCAL" calibrate "${PHOTOS[@]}" --out "$OUT" --json >"$OUT.calibrate.json"
RC=$?
set -e
# Exit 1 means some frames were refused (listed above, with the reason); anything else, or no
# report, is a failure of the job.
if [ "$RC" -gt 1 ] || [ ! -f "$OUT/report.html" ]; then
  log "calibrate failed (exit $RC): see the messages above"
  exit 1
fi
T_FIT=$(now)

T_END=$(now)

cat >&2 <<DONE
[run_default] done in $(secs "$T0" "$T_END") s: install and build $(secs "$T0" "$T_SETUP") s, fetch $(secs "$T_SETUP" "$T_FETCH") s,
[run_default]   calibrate (fits, game images, export, report) $(secs "$T_FETCH" "$T_FIT") s
[run_default] where to look:
[run_default]   $OUT/report.html          the whole job on one page (open it in a browser; it embeds everything)
[run_default]   $OUT/game/                the game tables: manifest.json, keyframes.csv/.json, <preset>/*.exr
[run_default]   $OUT/<frame>/preset.json  each calibrated preset; fit.json beside it has the numbers,
[run_default]   $OUT/<frame>/compare.png  the photo beside the game's image of its preset
DONE
