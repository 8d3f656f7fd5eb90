#!/usr/bin/env bash
# The hostile sweep: every verb run the way a careless or unlucky user would run it (bad
# paths, directories, FIFOs, symlink loops, truncated and garbage files, NaN / inf / zero /
# negative frames, cropped EXR windows, outputs over files of another kind, wrong
# extensions, hostile environment variables, bad option values, signals mid-run). Each case
# is scored on:
#   crash       a signal other than the one sent, an exit code other than 0/1 (or 128 + the
#               signal sent), or no answer within the time limit (a hang)
#   wrong exit  0 where a refusal (1) was expected, or 1 where success was expected
#   non-finite  an EXR written under the case's output directory holding a NaN or inf
#   lost        a fixture file (the inputs, the user's files) changed or removed
#   leftover    a temporary (.NAME.tmp-PID[-N], .NAME.old-PID) left anywhere in the tree
# and the table goes to bench/results/hostile_sweep.md (or --out FILE).
#
#   scripts/hostile_sweep.sh [--quick] [--build DIR | --skycal BIN --tool EXR_TOOL] [--out FILE]
#
# --quick runs one case in ten (about 60 cases, under a minute) for the test suite;
# exit status 1 when any case scored a defect.
set -u
BUILD=build
OUT=bench/results/hostile_sweep.md
QUICK=0
BIN_ARG=""
TOOL_ARG=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) QUICK=1 ;;
    --build) BUILD=$2; shift ;;
    --skycal) BIN_ARG=$2; shift ;;
    --tool) TOOL_ARG=$2; shift ;;
    --out) OUT=$2; shift ;;
    *) echo "usage: $0 [--quick] [--build DIR | --skycal BIN --tool EXR_TOOL] [--out FILE]" >&2; exit 2 ;;
  esac
  shift
done
BIN=$(realpath "${BIN_ARG:-$BUILD/skycal}")
TOOL=$(realpath "${TOOL_ARG:-$BUILD/tests/skycal_exr_tool}")
[ -x "$BIN" ] && [ -x "$TOOL" ] || { echo "need $BUILD/skycal and $BUILD/tests/skycal_exr_tool" >&2; exit 2; }
LIMIT=${SWEEP_CASE_TIMEOUT:-120}

W=$(mktemp -d "${TMPDIR:-/tmp}/skycal-sweep.XXXXXX")
trap 'rm -rf "$W"' EXIT
F=$W/fix   # fixtures: inputs and the user's files, never to change
O=$W/out   # each case's outputs, emptied between cases
mkdir -p "$F" "$O"

# --- fixtures -------------------------------------------------------------------------
"$BIN" render --sun-elevation 20 --sun-azimuth 30 --size 64x32 --backend cpu --out "$F/sky.exr" 2>/dev/null
"$BIN" render --sun-elevation 25 --sun-azimuth 35 --size 64x32 --backend cpu --out "$F/sky2.exr" 2>/dev/null
"$BIN" bake --out "$F/p.json" 2>/dev/null
"$BIN" weather --size 16 --out "$F/w.exr" 2>/dev/null
for v in nan inf -inf 0 -1; do "$TOOL" fill "$F/frame_$v.exr" 64 32 "$v"; done
"$TOOL" crop "$F/crop.exr"
head -c 2000 "$F/sky.exr" > "$F/trunc.exr"
head -c 4000 /dev/urandom > "$F/garbage.exr"
: > "$F/empty.exr"
printf 'a,b\n1,2\n' > "$F/notes.csv"
cp "$F/notes.csv" "$F/csv_named.exr"
cp "$F/notes.csv" "$F/csv_named.json"
cp "$F/notes.csv" "$F/csv_named.png"
printf '<html><body>mine</body></html>\n' > "$F/mine.html"
mkdir -p "$F/adir" "$F/userdir"
printf 'keep\n' > "$F/userdir/notes.txt"
mkfifo "$F/fifo.exr" "$F/fifo.json" "$F/fifo.html"
ln -s loop_b.exr "$F/loop_a.exr"; ln -s loop_a.exr "$F/loop_b.exr"
ln -s nowhere.exr "$F/dangling.exr"
ln -s sky.exr "$F/link_to_sky.exr"
mkdir -p "$F/empty_drivers"

snapshot() { (cd "$F" && find . -type f -print0 | sort -z | xargs -0 sha256sum; find . -type l | sort) 2>/dev/null; }
BASE=$(snapshot)
cp -a "$F" "$W/pristine"  # restored after any case that changed a fixture (FIFOs and links kept)

N=0; CRASH=0; WRONG=0; NONFIN=0; LOST=0; LEFT=0
declare -A VERB_CASES
ROWS=""
FAILS=""

# run NAME EXPECT ENV VERB ARGS...   EXPECT: ok (exit 0), refuse (exit 1), any (0 or 1)
run() {
  local name=$1 expect=$2 envs=$3 verb=$4; shift 4
  N=$((N + 1))
  if [ "$QUICK" = 1 ] && [ $((N % 10)) -ne 1 ]; then return; fi
  VERB_CASES[$verb]=$(( ${VERB_CASES[$verb]:-0} + 1 ))
  local rc
  (cd "$W" && env $envs timeout -k 5 "$LIMIT" "$BIN" "$verb" "$@" >"$W/log" 2>&1 </dev/null)
  rc=$?
  score "$name" "$expect" "$rc" 0
}

# score NAME EXPECT RC SIGNAL_SENT
score() {
  local name=$1 expect=$2 rc=$3 sig=$4 defect=""
  if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then defect="hang"; CRASH=$((CRASH + 1))
  elif [ "$rc" != 0 ] && [ "$rc" != 1 ] && { [ "$sig" = 0 ] || [ "$rc" != $((128 + sig)) ]; }; then
    defect="crash (exit $rc)"; CRASH=$((CRASH + 1))
  elif { [ "$expect" = ok ] && [ "$rc" != 0 ]; } || { [ "$expect" = refuse ] && [ "$rc" = 0 ]; }; then
    defect="wrong exit $rc (expected $expect)"; WRONG=$((WRONG + 1))
  fi
  local exrs bad
  exrs=$(find "$O" -name '*.exr' -type f 2>/dev/null)
  if [ -n "$exrs" ]; then
    bad=$("$TOOL" count $exrs | awk '$2 > 0')
    if [ -n "$bad" ]; then defect="$defect non-finite: $bad"; NONFIN=$((NONFIN + 1)); fi
  fi
  if [ "$(snapshot)" != "$BASE" ]; then defect="$defect fixture changed"; LOST=$((LOST + 1)); fi
  if [ -n "$(find "$W" -name '.*.tmp-*' -o -name '.*.old-*' 2>/dev/null)" ]; then
    defect="$defect leftovers: $(find "$W" -name '.*.tmp-*' -o -name '.*.old-*' | head -3 | tr '\n' ' ')"
    LEFT=$((LEFT + 1))
  fi
  if [ -n "$defect" ]; then
    FAILS+="| $name | $defect | $(tail -c 300 "$W/log" | tr '\n|' '  ') |"$'\n'
  fi
  # Back to the fixtures as they were, whatever the case did.
  rm -rf "$O"; mkdir -p "$O"
  find "$W" \( -name '.*.tmp-*' -o -name '.*.old-*' \) -exec rm -rf {} + 2>/dev/null
  # A case that changed a fixture is counted once; the next case starts from the pristine set.
  if [ "$(snapshot)" != "$BASE" ]; then rm -rf "$F"; cp -a "$W/pristine" "$F"; fi
}

# signal NAME SIG DELAY_S VERB ARGS...: sends SIG after DELAY_S; exit 0 or 128 + SIG expected.
signal_case() {
  local name=$1 sig=$2 delay=$3 verb=$4; shift 4
  N=$((N + 1))
  if [ "$QUICK" = 1 ] && [ $((N % 10)) -ne 1 ]; then return; fi
  VERB_CASES[$verb]=$(( ${VERB_CASES[$verb]:-0} + 1 ))
  (cd "$W" && exec "$BIN" "$verb" "$@" >"$W/log" 2>&1 </dev/null) &
  local pid=$!
  sleep "$delay"
  kill -"$sig" "$pid" 2>/dev/null
  wait "$pid"
  local rc=$?
  score "$name" any "$rc" "$sig"
}

SUN="--sun-elevation 20 --sun-azimuth 30"
BAD_INPUTS="missing.exr adir fifo.exr empty.exr garbage.exr trunc.exr loop_a.exr dangling.exr csv_named.exr crop.exr"
DEGENERATE="frame_nan.exr frame_inf.exr frame_-inf.exr frame_0.exr frame_-1.exr"

# --- 1. hostile inputs, every verb that reads an image --------------------------------
for in in $BAD_INPUTS; do
  run "fit --reference $in" refuse "" fit --quiet --backend cpu --reference "$F/$in" --out "$O/fit"
  run "ceiling --reference $in" refuse "" ceiling --reference "$F/$in"
  run "mask --reference $in" refuse "" mask --reference "$F/$in" --out "$O/m.exr"
  run "stars --reference $in" refuse "" stars --reference "$F/$in" --out "$O/s.exr"
  run "probe-extract --image $in" refuse "" probe-extract --image "$F/$in" --out "$O/s.json"
  run "import --in $in" refuse "" import --in "$F/$in" --out "$O/i.exr"
  run "resample --in $in" refuse "" resample --in "$F/$in" --out "$O/r.exr"
  run "flow A=$in" refuse "" flow "$F/$in" "$F/sky.exr" --out "$O/v.exr"
  run "flow B=$in" refuse "" flow "$F/sky.exr" "$F/$in" --out "$O/v.exr"
  run "capture --brackets $in" refuse "" capture --brackets "$F/$in" --lens latlong --out "$O/c.exr"
  run "chart --image $in" refuse "" chart --image "$F/$in" --out "$O/c.json"
  run "render --preset $in" refuse "" render $SUN --size 32x16 --backend cpu --preset "$F/$in" --out "$O/r.exr"
  run "export --preset $in" refuse "" export --preset "$F/$in" --out "$O/game"
  run "probe-predict --preset $in" refuse "" probe-predict $SUN --backend cpu --preset "$F/$in"
  run "render --weather-map $in" refuse "" render $SUN --size 32x16 --backend cpu --clouds --weather-map "$F/$in" --out "$O/r.exr"
  run "batch --references $in" refuse "" batch --references "$F/$in" --out "$O/batch"
  run "report $in" refuse "" report "$F/$in" --out "$O/r.html"
done

# --- 2. degenerate frames (finite output or a refusal; never NaN written) -------------
for in in $DEGENERATE; do
  run "fit --reference $in" any "" fit --quiet --backend cpu --reference "$F/$in" --out "$O/fit"
  run "ceiling --reference $in" any "" ceiling --reference "$F/$in"
  run "mask --reference $in" any "" mask --reference "$F/$in" --out "$O/m.exr"
  run "stars --reference $in" any "" stars --reference "$F/$in" --out "$O/s.exr" --mask-out "$O/sm.exr"
  run "probe-extract --image $in" any "" probe-extract --image "$F/$in" --out "$O/s.json"
  run "import --in $in" any "" import --in "$F/$in" --out "$O/i.exr"
  run "import --half --in $in" any "" import --half --in "$F/$in" --out "$O/i.exr"
  run "resample --in $in" any "" resample --in "$F/$in" --out "$O/r.exr"
  run "resample --half --in $in" any "" resample --half --in "$F/$in" --out "$O/r.exr"
  run "flow $in sky" any "" flow "$F/$in" "$F/sky.exr" --out "$O/v.exr"
  run "capture --brackets $in" any "" capture --brackets "$F/$in" --lens latlong --out "$O/c.exr"
  run "chart --image $in" any "" chart --image "$F/$in" --out "$O/c.json"
  run "render --weather-map $in" any "" render $SUN --size 32x16 --backend cpu --clouds --weather-map "$F/$in" --out "$O/r.exr"
done

# --- 3. hostile outputs, every verb that writes ----------------------------------------
# out_cases VERB EXT READS_SKY FRESH ARGS-BEFORE-OUT: the output over a directory, a FIFO, a
# missing parent, a device, a file of another kind, the user's page, a preset's LUT, the
# verb's input and a link to it (READS_SKY=1: sky.exr is an input; else writing an EXR over
# an EXR skycal wrote is a plain re-run, not a case), then a fresh path (FRESH: the exit).
out_cases() {
  local verb=$1 ext=$2 reads_sky=$3 fresh=$4; shift 4
  run "$verb --out directory" refuse "" "$verb" "$@" --out "$F/adir"
  run "$verb --out fifo" refuse "" "$verb" "$@" --out "$F/fifo$ext"
  run "$verb --out missing parent" refuse "" "$verb" "$@" --out "$O/no/such/dir/x$ext"
  run "$verb --out empty" refuse "" "$verb" "$@" --out ""
  run "$verb --out csv" refuse "" "$verb" "$@" --out "$F/notes.csv"
  run "$verb --out user's html" refuse "" "$verb" "$@" --out "$F/mine.html"
  if [ "$reads_sky" = 1 ] || [ "$ext" != .exr ]; then
    run "$verb --out input" refuse "" "$verb" "$@" --out "$F/sky.exr"
    run "$verb --out link to input" refuse "" "$verb" "$@" --out "$F/link_to_sky.exr"
  fi
  run "$verb --out preset LUT" refuse "" "$verb" "$@" --out "$F/p.mie.exr"
  run "$verb --out /dev/null" refuse "" "$verb" "$@" --out /dev/null
  case "$ext" in
    .exr) run "$verb --out csv named .exr" refuse "" "$verb" "$@" --out "$F/csv_named.exr"
          run "$verb --out x.png" refuse "" "$verb" "$@" --out "$O/x.png"
          run "$verb --out x.json" refuse "" "$verb" "$@" --out "$O/x.json" ;;
    .json) run "$verb --out csv named .json" refuse "" "$verb" "$@" --out "$F/csv_named.json" ;;
  esac
  run "$verb --out fresh" "$fresh" "" "$verb" "$@" --out "$O/fresh$ext"
}
out_cases render .exr 0 ok $SUN --size 32x16 --backend cpu
out_cases import .exr 1 ok --in "$F/sky.exr"
out_cases resample .exr 1 ok --in "$F/sky.exr"
out_cases mask .exr 1 any --reference "$F/sky.exr"
out_cases stars .exr 1 ok --reference "$F/sky.exr"
out_cases weather .exr 0 ok --size 16
out_cases flow .exr 1 ok "$F/sky.exr" "$F/sky2.exr"
out_cases capture .exr 1 any --brackets "$F/sky.exr" --lens latlong
out_cases probe-extract .json 1 any --image "$F/sky.exr"
out_cases chart .json 1 any --image "$F/sky.exr"
out_cases bake .json 0 ok
out_cases report .html 0 refuse "$F"  # the fixtures hold no run: a fresh --out is refused too
# Directory outputs: a user's directory, a file, the inputs' directory, a FIFO.
for v in fit export batch bench; do
  case $v in
    fit) args=(--quiet --backend cpu --reference "$F/sky.exr") ;;
    export) args=(--preset "$F/p.json" --no-report) ;;
    batch) args=(--references "$F/sky.exr") ;;
    bench) args=(--suite no-such-suite --quick) ;;
  esac
  run "$v --out user's directory" refuse "" $v "${args[@]}" --out "$F/userdir"
  run "$v --out a file" refuse "" $v "${args[@]}" --out "$F/notes.csv"
  run "$v --out the inputs' directory" refuse "" $v "${args[@]}" --out "$F"
  run "$v --out fifo" refuse "" $v "${args[@]}" --out "$F/fifo.json"
  run "$v --out missing parent" refuse "" $v "${args[@]}" --out "$O/no/such/dir"
done
run "fit --out fresh" ok "" fit --quiet --backend cpu --reference "$F/sky.exr" --out "$O/fit"
run "export --out fresh" ok "" export --preset "$F/p.json" --out "$O/game"

# --- 4. bad option values, every verb --------------------------------------------------
for v in render bake ceiling capture chart export fit batch import flow resample mask stars probe-extract \
         probe-predict bench report sun weather; do
  run "$v --no-such-flag" refuse "" $v --no-such-flag
  run "$v (no arguments)" any "" $v
  run "$v --help" ok "" $v --help
done
for val in nan inf -1e30 1e400 abc ""; do
  run "render --size $val" refuse "" render $SUN --size "$val" --backend cpu --out "$O/r.exr"
  run "render --sun-elevation $val" refuse "" render --sun-elevation "$val" --sun-azimuth 0 --size 32x16 --backend cpu --out "$O/r.exr"
  run "bake --haziness $val" refuse "" bake --haziness "$val" --out "$O/p.json"
  run "weather --size $val" refuse "" weather --size "$val" --out "$O/w.exr"
  run "weather --mean-coverage $val" refuse "" weather --mean-coverage "$val" --out "$O/w.exr"
  run "sun --lat $val" refuse "" sun --time 2026-06-21T12:00:00Z --lat "$val" --lon 11
  run "resample --horizon-density $val" refuse "" resample --in "$F/sky.exr" --horizon-density "$val" --out "$O/r.exr"
  run "stars --star-sigma $val" refuse "" stars --reference "$F/sky.exr" --star-sigma "$val" --out "$O/s.exr"
  run "mask --horizon-deg $val" refuse "" mask --reference "$F/sky.exr" --horizon-deg "$val" --out "$O/m.exr"
  run "probe-predict --albedo $val" refuse "" probe-predict $SUN --backend cpu --albedo "$val"
  run "fit --clouds $val" refuse "" fit --quiet --backend cpu --reference "$F/sky.exr" --clouds "$val" --out "$O/fit"
done
run "bake --n-gamma 300" any "" bake --n-gamma 300 --out "$O/p.json"
run "bench --compare missing" refuse "" bench --compare "$F/missing.json" "$F/missing.json"
run "bench --compare csv" refuse "" bench --compare "$F/notes.csv" "$F/notes.csv"

# --- 5. environment ---------------------------------------------------------------------
for drv in "$F/empty_drivers" "$F/absent_drivers"; do
  run "fit, PLPLOT_DRV_DIR=${drv##*/}" ok "PLPLOT_DRV_DIR=$drv" fit --quiet --backend cpu --reference "$F/sky.exr" --out "$O/fit"
  run "export, PLPLOT_DRV_DIR=${drv##*/}" ok "PLPLOT_DRV_DIR=$drv" export --preset "$F/p.json" --out "$O/game"
  run "report, PLPLOT_DRV_DIR=${drv##*/}" any "PLPLOT_DRV_DIR=$drv" report "$F" --out "$O/r.html"
  run "batch, PLPLOT_DRV_DIR=${drv##*/}" any "PLPLOT_DRV_DIR=$drv" batch --references "$F/sky*.exr" --out "$O/batch"
done
for env in "OCIO=$F/missing.ocio" "OCIO=$F/notes.csv" "XDG_CACHE_HOME=relative/cache" "XDG_CACHE_HOME=" \
           "TMPDIR=$F/missing" "TMPDIR=$F/notes.csv" "HOME=$F/missing" "LC_ALL=de_DE.UTF-8" "PLPLOT_LIB=$F/missing"; do
  run "render --png, $env" any "$env" render $SUN --size 32x16 --backend cpu --out "$O/r.exr" --png "$O/r.png"
  run "fit, $env" ok "$env" fit --quiet --backend cpu --reference "$F/sky.exr" --out "$O/fit"
  run "render --clouds, $env" ok "$env" render $SUN --size 32x16 --backend cpu --clouds --out "$O/r.exr"
done
[ -d "$W/relative" ] && { echo "a relative XDG_CACHE_HOME made $W/relative" >&2; LEFT=$((LEFT + 1)); }

# --- 6. signals mid-run -------------------------------------------------------------------
for sig in INT TERM HUP; do
  num=$(kill -l "$sig")
  for d in 0.2 0.5 1.0; do
    signal_case "render 2048x1024, SIG$sig at ${d}s" "$num" "$d" render $SUN --size 2048x1024 --backend cpu --out "$O/big.exr"
    signal_case "fit, SIG$sig at ${d}s" "$num" "$d" fit --quiet --backend cpu --reference "$F/sky.exr" --out "$O/fit"
    signal_case "bake, SIG$sig at ${d}s" "$num" "$d" bake --n-gamma 256 --n-theta 256 --out "$O/p.json"
    signal_case "export, SIG$sig at ${d}s" "$num" "$d" export --preset "$F/p.json" --out "$O/game"
  done
done

# --- 7. compare (the game's image against the photo): every hostile and degenerate input on
# either side, a mask of another size, bad option values (appended last, so that the cases
# above keep their numbers and --quick its selection) --------------------------------------
for in in $BAD_INPUTS $DEGENERATE; do
  run "compare --photo $in" refuse "" compare --photo "$F/$in" --game "$F/sky.exr"
done
for in in $BAD_INPUTS; do
  run "compare --game $in" refuse "" compare --photo "$F/sky.exr" --game "$F/$in"
done
for in in $DEGENERATE; do  # a game image of zeros or NaN is compared (floored), never a crash
  run "compare --game $in" any "" compare --photo "$F/sky.exr" --game "$F/$in"
done
run "compare --mask w.exr (another size)" refuse "" compare --photo "$F/sky.exr" --game "$F/sky2.exr" --mask "$F/w.exr"
run "compare ok" ok "" compare --photo "$F/sky.exr" --game "$F/sky2.exr" --json
for v in "--exposure 0" "--exposure nan" "--exposure -1" "--band 0" "--band 91" "--min-elevation 90" "--band x"; do
  # shellcheck disable=SC2086
  run "compare $v" refuse "" compare --photo "$F/sky.exr" --game "$F/sky2.exr" $v
done

# --- 8. calibrate (photos in, presets out): every hostile and degenerate photo refused by name,
# outputs over a file or a FIFO, bad option values, and one photo that calibrates (appended
# last, as compare's) ---------------------------------------------------------------------------
for in in $BAD_INPUTS $DEGENERATE; do
  run "calibrate --photo $in" refuse "" calibrate --photo "$F/$in" --out "$O/cal"
done
run "calibrate --out notes.csv (a file)" refuse "" calibrate --photo "$F/sky.exr" --out "$F/notes.csv"
run "calibrate --out fifo.json" refuse "" calibrate --photo "$F/sky.exr" --out "$F/fifo.json"
run "calibrate ok" ok "" calibrate --photo "$F/sky.exr" --out "$O/cal" --json
for v in "--lat 95 --lon 0 --time 2026-06-21T12:00Z" "--lat 45" "--sun-elevation 10" "--time noon --lat 1 --lon 1" \
         "--north 10" "--photo $F/sky.exr"; do
  # shellcheck disable=SC2086
  run "calibrate $v" refuse "" calibrate --photo "$F/sky.exr" --out "$O/cal" $v
done

# --- the table ------------------------------------------------------------------------------
RAN=0; for v in "${!VERB_CASES[@]}"; do RAN=$((RAN + VERB_CASES[$v])); done
{
  echo "# Hostile sweep"
  echo
  echo "scripts/hostile_sweep.sh$([ "$QUICK" = 1 ] && echo " --quick"), $(date -u +%Y-%m-%dT%H:%MZ), commit" \
       "$(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores."
  echo
  echo "| cases | crashes / hangs | wrong exits | non-finite outputs | files lost | leftovers |"
  echo "|---|---|---|---|---|---|"
  echo "| $RAN | $CRASH | $WRONG | $NONFIN | $LOST | $LEFT |"
  echo
  echo "Cases per verb:"
  echo
  echo "| verb | cases |"
  echo "|---|---|"
  for v in $(printf '%s\n' "${!VERB_CASES[@]}" | sort); do echo "| $v | ${VERB_CASES[$v]} |"; done
  if [ -n "$FAILS" ]; then
    echo
    echo "Defects:"
    echo
    echo "| case | defect | log tail |"
    echo "|---|---|---|"
    printf '%s' "$FAILS"
  fi
} > "$W/table.md"
mkdir -p "$(dirname "$OUT")"
cp "$W/table.md" "$OUT"
cat "$W/table.md"
[ $((CRASH + WRONG + NONFIN + LOST + LEFT)) = 0 ]
