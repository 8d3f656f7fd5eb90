#!/usr/bin/env bash
# Does lane divergence cap HZD's cloud-march optimisations on lavapipe (docs/benchmarks.md)? Runs the
# `clouds-divergence` bench suite (naive, game, game without cheap light samples and with
# cheap light samples from opacity 0.6 at
# 512x256, each a median of REPEATS renders after a warm-up) in separate processes that
# alternate lavapipe's SIMD width, LP_NATIVE_VECTOR_WIDTH=256 (8 float lanes on AVX2, the
# default) and 128 (4 lanes), ROUNDS times (the order swapped every round), then writes a
# Markdown report: per width the medians over rounds of each march's wall and CPU time
# (ms) and of the per-process ratios naive / game, with the machine's load before and after.
# The work counts (iterations, texel loads, lockstep groups of 8 and 4 lanes) come from the
# float CPU twin and are the same in every process.
#
#   scripts/clouds_divergence.sh [ROUNDS=7] [REPEATS=5] [OUT=bench/results/clouds_divergence.md]
#
# Needs a built ./build/skycal and python3 (scripts/setup.sh installs it).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-7}
REPEATS=${2:-5}
OUT=${3:-bench/results/clouds_divergence.md}
BIN=${SKYCAL:-./build/skycal}  # SKYCAL: another binary (e.g. a copy, while the build changes)
[[ -x $BIN ]] || { echo "clouds_divergence.sh: $BIN not found (build first)" >&2; exit 1; }
[[ $ROUNDS =~ ^[1-9][0-9]*$ ]] || { echo "clouds_divergence.sh: ROUNDS = '$ROUNDS' (expected a positive integer)" >&2; exit 1; }
[[ $REPEATS =~ ^[1-9][0-9]*$ ]] || { echo "clouds_divergence.sh: REPEATS = '$REPEATS' (expected a positive integer)" >&2; exit 1; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
LOAD_BEFORE=$(uptime)
for ((r = 1; r <= ROUNDS; ++r)); do
  if ((r % 2)); then order="256 128"; else order="128 256"; fi
  for w in $order; do
    echo "[clouds_divergence] round $r/$ROUNDS, LP_NATIVE_VECTOR_WIDTH=$w" >&2
    LP_NATIVE_VECTOR_WIDTH=$w "$BIN" bench --suite clouds-divergence --repeat "$REPEATS" --no-report \
      --out "$WORK/w$w-r$r" >/dev/null 2>"$WORK/w$w-r$r.log"
  done
done
LOAD_AFTER=$(uptime)
python3 - "$WORK" "$ROUNDS" "$REPEATS" "$LOAD_BEFORE" "$LOAD_AFTER" >"$WORK/report.md" <<'EOF'
import json, statistics, sys
work, rounds, repeats, before, after = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
marches = ["naive", "game", "no-cheap-light", "cheap-light-0.6"]
rows, work_counts, device = {}, {}, {}
for w in ("256", "128"):
    for r in range(1, rounds + 1):
        d = json.load(open(f"{work}/w{w}-r{r}/results.json"))
        for c in d["cases"]:
            m = c["settings"]["march"]
            rows.setdefault((w, m), []).append((c["time_ms"]["median_ms"], c["extra"]["cpu_time_ms"]))
            work_counts[m] = c["extra"]
            device[w] = c["extra"]["device"]
med = statistics.median
print("# Clouds: does lane divergence cap the optimisations on lavapipe?\n")
print(f"`scripts/clouds_divergence.sh {rounds} {repeats}`: the `clouds-divergence` suite (default_cloudy, sun 25 deg, "
      f"512x256, Vulkan) in {2 * rounds} processes alternating LP_NATIVE_VECTOR_WIDTH=256 and 128 (order swapped "
      f"each round); each process: per march the median of {repeats} renders after a warm-up. Below: medians over "
      f"the {rounds} processes per width.\n")
print(f"Load before: `{before.strip()}`  \nLoad after: `{after.strip()}`\n")
for w in ("256", "128"):
    print(f"- LP_NATIVE_VECTOR_WIDTH={w}: device `{device[w]}`")
print("\n| width | march | wall ms | CPU ms | naive / march, wall | naive / march, CPU |")
print("|---|---|---|---|---|---|")
for w in ("256", "128"):
    for m in marches:
        t = rows[(w, m)]
        n = rows[(w, "naive")]
        rw = [a[0] / b[0] for a, b in zip(n, t)]
        rc = [a[1] / b[1] for a, b in zip(n, t)]
        print(f"| {w} | {m} | {med(x[0] for x in t):.1f} | {med(x[1] for x in t):.1f} | "
              f"{med(rw):.2f} (min {min(rw):.2f}, max {max(rw):.2f}) | {med(rc):.2f} (min {min(rc):.2f}, max {max(rc):.2f}) |")
print("\nRatio of the 128-bit to the 256-bit run's naive / game (per round, then the median):")
for k, name in ((0, "wall"), (1, "CPU")):
    q = [(a[k] / b[k]) / (c[k] / d[k]) for a, b, c, d in zip(rows[("128", "naive")], rows[("128", "game")],
                                                            rows[("256", "naive")], rows[("256", "game")])]
    print(f"- {name}: {med(q):.3f} (min {min(q):.3f}, max {max(q):.3f})")
print("\nWork per image from the float CPU twin (millions; the same in every process):\n")
print("| march | iterations | texel loads | lockstep 8 lanes | lockstep 4 lanes |")
print("|---|---|---|---|---|")
for m in marches:
    e = work_counts[m]
    print(f"| {m} | {e['iterations'] / 1e6:.3f} | {e['texel_loads'] / 1e6:.2f} | {e['lockstep8_iterations'] / 1e6:.3f} | "
          f"{e['lockstep4_iterations'] / 1e6:.3f} |")
n, g = work_counts["naive"], work_counts["game"]
print("\nnaive / game: iterations (an ideal branching machine, every density evaluation the same cost) "
      f"{n['iterations'] / g['iterations']:.2f}; texel loads (cheap base-only samples cost less) "
      f"{n['texel_loads'] / g['texel_loads']:.2f}; lockstep 8 lanes {n['lockstep8_iterations'] / g['lockstep8_iterations']:.2f}; "
      f"lockstep 4 lanes {n['lockstep4_iterations'] / g['lockstep4_iterations']:.2f}.")
EOF
mkdir -p "$(dirname "$OUT")"
mv "$WORK/report.md" "$OUT.tmp"
mv "$OUT.tmp" "$OUT"
echo "[clouds_divergence] wrote $OUT" >&2
