#!/usr/bin/env bash
# The Vulkan path on a real GPU in one call: fresh process vs warm, wall and device time.
#
#   scripts/gpu_device_bench.sh [--small] [OUTDIR]
#
# Fresh: `skycal render --json` in a new process, 3 runs per case (the first also pays the
# pipeline cache's first fill: it is reported apart): the process's wall time, the render's
# wall (time_ms.sky / time_ms.clouds) and its device time (time_ms.gpu). Warm: `skycal bench
# --suite gpu` (renderers and textures kept): wall and device medians per render. Cases:
# sky 2048x1024; clouds 512x256 and 2048x1024, the game's march and the naive one, each with
# the textures as sampled images (hardware filter) and as texel buffers
# (SKYCAL_VULKAN_TEXTURES).
# --small: 256x128 and 128x64 (a smoke test on lavapipe). SKYCAL: the binary (default
# build/skycal). Prints one table; everything lands in OUTDIR (default $OUT or a temp dir).
# Budget: about 4 minutes on an H200 (the 2048x1024 naive march is the longest case).
set -euo pipefail
SMALL=0
if [[ "${1:-}" == "--small" ]]; then SMALL=1; shift; fi
BIN=${SKYCAL:-build/skycal}
OUTDIR=${1:-${OUT:-$(mktemp -d)}}
mkdir -p "$OUTDIR"
if [[ ! -x "$BIN" ]]; then echo "gpu_device_bench: no skycal binary at $BIN (set SKYCAL)" >&2; exit 2; fi
if ldd "$BIN" 2>/dev/null | grep -q "not found"; then
  echo "gpu_device_bench: $BIN misses shared libraries:" >&2; ldd "$BIN" | grep "not found" >&2; exit 2
fi
# The pipeline cache of this run only: the first fresh run fills it, the next ones read it.
export SKYCAL_PIPELINE_CACHE_DIR="$OUTDIR/pipeline_cache"
rm -rf "$SKYCAL_PIPELINE_CACHE_DIR"
if [[ $SMALL == 1 ]]; then SKY=256x128; CL_SMALL=128x64; CL_BIG=256x128; QUICK=--quick
else SKY=2048x1024; CL_SMALL=512x256; CL_BIG=2048x1024; QUICK=""; fi

"$BIN" --version 2>/dev/null | head -1 || true
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv,noheader || true

fresh() {  # name, textures (images|buffers), then render flags
  local name=$1 textures=$2; shift 2
  for i in 1 2 3; do
    local t0 t1
    t0=$(date +%s%N)
    SKYCAL_VULKAN_TEXTURES=$textures "$BIN" render --sun-elevation 25 --sun-azimuth 40 --out "$OUTDIR/$name.exr" --json "$@" \
      > "$OUTDIR/fresh_${name}_$i.json" 2> "$OUTDIR/fresh_${name}_$i.log"
    t1=$(date +%s%N)
    echo "$(( (t1 - t0) / 1000 ))" > "$OUTDIR/fresh_${name}_$i.process_us"
  done
}
fresh sky buffers --size "$SKY"
for tex in images buffers; do
  fresh clouds_game_small_$tex $tex --size "$CL_SMALL" --clouds
  fresh clouds_naive_small_$tex $tex --size "$CL_SMALL" --clouds --cloud-naive
  fresh clouds_game_big_$tex $tex --size "$CL_BIG" --clouds
  fresh clouds_naive_big_$tex $tex --size "$CL_BIG" --clouds --cloud-naive
done

"$BIN" bench --suite gpu $QUICK --no-report --out "$OUTDIR/warm" > "$OUTDIR/warm.log" 2>&1 || {
  echo "gpu_device_bench: the warm bench failed (see $OUTDIR/warm.log)" >&2; tail -5 "$OUTDIR/warm.log" >&2; }

python3 - "$OUTDIR" "$SKY" "$CL_SMALL" "$CL_BIG" <<'PY'
import json, os, statistics, sys
out, sky, small, big = sys.argv[1:5]
def f(v): return "-" if v is None else f"{v:.2f}"
def fresh(name, pass_key):
    runs = []
    for i in (1, 2, 3):
        try:
            j = json.load(open(f"{out}/fresh_{name}_{i}.json"))
            us = int(open(f"{out}/fresh_{name}_{i}.process_us").read())
        except Exception as e:
            runs.append(None); continue
        t = j["time_ms"]
        runs.append((us / 1000.0, t[pass_key], (t.get("gpu") or {}).get(pass_key), t["init"]))
    return runs
warm = {}
try:
    for c in json.load(open(f"{out}/warm/results.json"))["cases"]:
        s = c["settings"]
        warm[(s["pass"], s["size"], s.get("march", "game"), s.get("textures", "buffers"))] = (
            c["time_ms"]["median_ms"], c["time_ms"].get("gpu_median_ms"), c.get("extra", {}).get("memory"))
except Exception as e:
    print("no warm results:", e)
device = "?"
rows = [("sky", sky, "game", "sky", "buffers")]
for tex in ("images", "buffers"):
    rows += [(f"clouds_game_small_{tex}", small, "game", "clouds", tex), (f"clouds_naive_small_{tex}", small, "naive", "clouds", tex),
             (f"clouds_game_big_{tex}", big, "game", "clouds", tex), (f"clouds_naive_big_{tex}", big, "naive", "clouds", tex)]
for name, *_ in rows:
    try: device = json.load(open(f"{out}/fresh_{name}_1.json"))["device"]; break
    except Exception: pass
print(f"\ndevice: {device}")
print("| case | size | march | textures | fresh process ms (1st / median 2-3) | fresh pass wall ms | fresh pass gpu ms | fresh init ms | warm wall ms | warm gpu ms | memory | fresh/warm (pass wall) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, size, march, pass_key, tex in rows:
    r = fresh(name, pass_key)
    ok = [x for x in r[1:] if x]
    first = r[0]
    med = lambda k: statistics.median(x[k] for x in ok) if ok else None
    w = warm.get((pass_key, size, march, tex), (None, None, None))
    ratio = (med(1) / w[0]) if (ok and w[0]) else None
    print(f"| {pass_key} | {size} | {march} | {tex if pass_key == 'clouds' else '-'} | {f(first[0] if first else None)} / {f(med(0))} | {f(med(1))} | "
          f"{f(med(2))} | {f(med(3))} | {f(w[0])} | {f(w[1])} | {w[2] or '-'} | {f(ratio)} |")
PY
echo "files: $OUTDIR"
