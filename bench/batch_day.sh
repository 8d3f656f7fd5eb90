#!/usr/bin/env bash
# The batch benchmark: a synthetic time-lapse day fitted by `skycal batch`.
#   bash bench/batch_day.sh [SKYCAL] [--frames N] [--size WxH] [--jobs N] [--frames-per-job N] [--out DIR]
# Defaults: build/skycal, 96 frames (every 15 min over 24 h), 128x64, --jobs 2, 8 frames per
# job, out/bench_batch. The day: the sun of 70 deg N at the June solstice (midnight sun:
# elevation 3.4 ... 43.4 deg, so every frame has a sun above the horizon), rendered (cpu)
# from a perturbed default preset (haziness g 0.6 instead of 0.8, 15% CIE overcast blended
# in) and fitted from the default preset. Runs, each into its own batch directory:
#   1. local engine, warm starts (each chunk's frames from the previous frame's fit);
#   2. local engine, --cold-start (every frame from the default preset);
#   3./4. the same two with --no-linear-start (the coarse-to-fine Ceres path, where the
#      starting point matters most);
#   5. the Slurm engine on a single-node cluster started here (root only; skipped otherwise),
#      same jobs: its wall time minus run 1's, per submitted job, is the Slurm overhead.
# Writes OUT/batch.md (the table) and OUT/runs.json; copy batch.md to bench/results/.
set -euo pipefail
cd "$(dirname "$0")/.."
SKYCAL=build/skycal
FRAMES=96 SIZE=128x64 JOBS=2 FPJ=8 OUT=out/bench_batch
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then SKYCAL=$1; shift; fi
while [ $# -gt 0 ]; do
  case $1 in
    --frames) FRAMES=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    --frames-per-job) FPJ=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "bench/batch_day.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
SKYCAL=$(readlink -f "$SKYCAL")
rm -rf "$OUT" && mkdir -p "$OUT/day" "$OUT/preset"
OUT=$(readlink -f "$OUT")

# The perturbed preset (its LUT EXRs beside it).
cp datasets/presets/default_clear.* "$OUT/preset/"
python3 - "$OUT/preset/default_clear.json" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
p["parameters"]["haziness_g"]["value"] = 0.6
p["parameters"]["overcast_weight"]["value"] = 0.15
json.dump(p, open(sys.argv[1], "w"), indent=1)
PY

echo "[bench-batch] rendering $FRAMES frames ($SIZE)" >&2
python3 - "$FRAMES" <<'PY' > "$OUT/sun_path.txt"
import math, sys
n = int(sys.argv[1]); lat = math.radians(70.0); dec = math.radians(23.44)
for i in range(n):
    h = 24.0 * i / n
    H = math.radians(15.0 * (h - 12.0))  # hour angle, solar time
    el = math.asin(math.sin(lat) * math.sin(dec) + math.cos(lat) * math.cos(dec) * math.cos(H))
    az = math.degrees(math.atan2(-math.sin(H) * math.cos(dec),
                                 math.cos(lat) * math.sin(dec) - math.sin(lat) * math.cos(dec) * math.cos(H)))
    print(f"{i:03d} {h:.4f} {math.degrees(el):.4f} {az:.4f}")
PY
while read -r i h el az; do
  "$SKYCAL" render --preset "$OUT/preset/default_clear.json" --backend cpu --size "$SIZE" \
    --sun-elevation "$el" --sun-azimuth "$az" --time-of-day "$h" --out "$OUT/day/frame$i.exr" >/dev/null 2>&1
done < "$OUT/sun_path.txt"

run() {  # NAME ENGINE EXTRA...
  local name=$1 engine=$2; shift 2
  echo "[bench-batch] run $name" >&2
  "$SKYCAL" batch --references "$OUT/day/*.exr" --out "$OUT/$name" --engine "$engine" --jobs "$JOBS" \
    --frames-per-job "$FPJ" --backend cpu --quiet --poll 0.2 "$@" > /dev/null 2> "$OUT/$name.log"
}
run warm local
run cold local --cold-start
run warm_ceres local --no-linear-start
run cold_ceres local --no-linear-start --cold-start
SLURM_NOTE=""
source tests/slurm_cluster.sh
if why=$(slurm_cluster_check); then
  T=$(mktemp -d /tmp/skycal-bench-slurm.XXXXXX)
  trap 'slurm_cluster_stop; rm -rf "$T"' EXIT
  slurm_cluster_start "$T"
  run slurm slurm
else
  SLURM_NOTE="Slurm run skipped: $why"
fi

python3 - "$OUT" "$FRAMES" "$SIZE" "$JOBS" "$FPJ" "$SLURM_NOTE" <<'PY'
import json, os, statistics as st, sys
out, frames, size, jobs, fpj, note = sys.argv[1:7]
runs = {}
for name in ["warm", "cold", "warm_ceres", "cold_ceres", "slurm"]:
    p = os.path.join(out, name, "batch.json")
    if not os.path.exists(p):
        continue
    b = json.load(open(p))
    fr = b["frames"]
    def stats(sel):
        sel = list(sel)
        return {"frames": len(sel),
                "fit_s_mean": st.mean(f["fit_time_s"] for f in sel) if sel else None,
                "iterations_mean": st.mean(f["iterations"] for f in sel) if sel else None,
                "rel_rmse_mean": st.mean(f["rel_rmse"] for f in sel) if sel else None,
                "rel_rmse_max": max(f["rel_rmse"] for f in sel) if sel else None}
    runs[name] = {"wall_s": b["run"]["wall_s"], "frames_per_s": b["run"]["frames_per_s"], "reduce_s": b["reduce_s"],
                  "chunks": b["counts"]["chunks"],
                  "all": stats(fr),
                  "warm_frames": stats(f for f in fr if f["warm_start_from"] is not None),
                  "first_of_chunk": stats(f for f in fr if f["warm_start_from"] is None),
                  "frame_wall_s_mean": st.mean(f["wall_s"] for f in fr)}
json.dump(runs, open(os.path.join(out, "runs.json"), "w"), indent=1)
L = [f"# skycal batch: a synthetic {frames}-frame day ({size}, 70 deg N June solstice sun, perturbed preset)", "",
     f"`bash bench/batch_day.sh --frames {frames} --size {size} --jobs {jobs} --frames-per-job {fpj}`; local engine "
     f"--jobs {jobs}; fit backend cpu. Times are wall-clock on a shared 2-core machine (noisy; compare within one run).", "",
     "| run | wall s | frames/s (incl. reduce) | reduce s | fit s/frame (mean) | iterations (mean) | rel RMSE mean | rel RMSE max |",
     "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
for name, r in runs.items():
    a = r["all"]
    L.append(f"| {name} | {r['wall_s']:.1f} | {r['frames_per_s']:.2f} | {r['reduce_s']:.1f} | {a['fit_s_mean']:.3f} | "
             f"{a['iterations_mean']:.1f} | {100*a['rel_rmse_mean']:.4f}% | {100*a['rel_rmse_max']:.4f}% |")
L += ["", "Warm-started frames only (the chunks' first frames start cold in every run):", "",
      "| run | frames | fit s/frame | iterations | rel RMSE mean |", "| --- | ---: | ---: | ---: | ---: |"]
for name, r in runs.items():
    w = r["warm_frames"]
    if w["frames"]:
        L.append(f"| {name} | {w['frames']} | {w['fit_s_mean']:.3f} | {w['iterations_mean']:.1f} | {100*w['rel_rmse_mean']:.4f}% |")
for a, b in [("warm", "cold"), ("warm_ceres", "cold_ceres")]:
    if a in runs and b in runs:
        L.append(f"\n{a} vs {b}: fit time per frame {runs[a]['all']['fit_s_mean']:.3f} s vs {runs[b]['all']['fit_s_mean']:.3f} s "
                 f"({abs(100*(1-runs[a]['all']['fit_s_mean']/runs[b]['all']['fit_s_mean'])):.0f}% {'less' if runs[a]['all']['fit_s_mean'] < runs[b]['all']['fit_s_mean'] else 'more'}), wall {runs[a]['wall_s']:.1f} s vs "
                 f"{runs[b]['wall_s']:.1f} s, rel RMSE mean {100*runs[a]['all']['rel_rmse_mean']:.4f}% vs {100*runs[b]['all']['rel_rmse_mean']:.4f}%.")
if "slurm" in runs and "warm" in runs:
    jobs_submitted = runs["slurm"]["chunks"] + 1
    over = (runs["slurm"]["wall_s"] - runs["warm"]["wall_s"]) / jobs_submitted
    L.append(f"\nSlurm (single node, {jobs} CPUs, same chunks): wall {runs['slurm']['wall_s']:.1f} s vs local {runs['warm']['wall_s']:.1f} s "
             f"over {jobs_submitted} jobs ({runs['slurm']['chunks']} array tasks + the reduce): overhead {over:.2f} s per job "
             "(submission, scheduling, squeue polling every 0.2 s, task start).")
if note:
    L.append("\n" + note)
open(os.path.join(out, "batch.md"), "w").write("\n".join(L) + "\n")
print("\n".join(L))
PY
