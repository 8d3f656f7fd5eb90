#!/usr/bin/env bash
# skycal batch --engine slurm against a real single-node Slurm cluster started here:
# munged (private key and socket), slurmctld and slurmd (SLURM_CONF -> a temp slurm.conf),
# all stopped by PID in a trap. Exit 77 (CTest: skipped) with the reason where it cannot run.
#
# 1. a 4-frame day (64x32, 2 chunks): every frame fitted by array tasks, the reduce job
#    writes batch.json;
# 2. a frame damaged after planning (same size and mtime, so the plan still matches): its
#    chunk fails, the reduce is cancelled (afterok + kill_invalid_depend: never left
#    pending), batch exits 1 naming the frame; the frame repaired, --resume resubmits only
#    that chunk and completes.
# usage: batch_slurm_test.sh SKYCAL_BINARY
set -euo pipefail
SKYCAL=$1
# Under scripts/sanitize.sh every process gets the sanitizer runtime by LD_PRELOAD: munged,
# the Slurm daemons and tools must run without it (their own leaks are not ours); skycal
# is instrumented itself and keeps ASAN_OPTIONS (sbatch passes the environment to the jobs).
unset LD_PRELOAD
source "$(dirname "$0")/slurm_cluster.sh"
why=$(slurm_cluster_check) || { echo "SKIP: $why"; exit 77; }
T=$(mktemp -d /tmp/skycal-slurm-test.XXXXXX)
cleanup() {
  local rc=$?
  slurm_cluster_stop
  if [ $rc -ne 0 ]; then
    echo "--- slurmctld.log"; tail -n 30 "$T/slurmctld.log" 2>/dev/null || true
    echo "--- slurmd.log"; tail -n 30 "$T/slurmd.log" 2>/dev/null || true
  fi
  [ -n "${SKYCAL_KEEP_SLURM_TEST:-}" ] || rm -rf "$T"
  exit $rc
}
trap cleanup EXIT INT TERM
t0=$(date +%s.%N)
slurm_cluster_start "$T" || { echo "FAIL: the cluster did not start"; exit 1; }
echo "cluster up in $(python3 -c "print(round($(date +%s.%N) - $t0, 2))") s: $(sinfo -h -o '%P %t %D')"

# A 4-frame day: sun along an arc, times out of file-name order.
mkdir -p "$T/day"
n=0
for spec in "8 30 -60" "10 50 -30" "12 60 0" "14 50 30"; do
  set -- $spec
  "$SKYCAL" render --sun-elevation "$2" --sun-azimuth "$3" --time-of-day "$1" --size 64x32 --backend cpu \
    --out "$T/day/frame$((3 - n)).exr" >/dev/null 2>&1
  n=$((n + 1))
done
BATCH=("$SKYCAL" batch --references "$T/day/*.exr" --engine slurm --frames-per-job 2 --backend cpu --quiet --poll 0.2)

# 1. The whole day.
"${BATCH[@]}" --out "$T/out1" 2> "$T/run1.log" || { cat "$T/run1.log"; echo "FAIL: slurm batch"; exit 1; }
python3 - "$T/out1" <<'PY'
import json, sys
b = json.load(open(sys.argv[1] + "/batch.json"))
assert b["ok"] and len(b["frames"]) == 4, b
assert [f["time_of_day_h"] for f in b["frames"]] == [8, 10, 12, 14]
assert all(f["status"] == "ok" and f["rel_rmse"] < 1e-3 for f in b["frames"]), b["frames"]
assert b["run"]["engine"] == "slurm" and b["run"]["reduce_state"] == "COMPLETED", b["run"]
assert len(b["run"]["tasks"]) == 2 and all(t["JobState"] == "COMPLETED" for t in b["run"]["tasks"]), b["run"]
print("slurm day: ok,", b["run"]["wall_s"], "s")
PY
grep -q "submitted the chunk array" "$T/run1.log"

# 2. A frame damaged after planning: same size and modification time.
cp -p "$T/day/frame1.exr" "$T/frame1.good"
size=$(stat -c %s "$T/day/frame1.exr")
dd if=/dev/zero of="$T/day/frame1.exr" bs=1 seek=$((size - 400)) count=390 conv=notrunc status=none
touch -r "$T/frame1.good" "$T/day/frame1.exr"
set +e
"${BATCH[@]}" --out "$T/out2" 2> "$T/run2.log"
rc=$?
set -e
[ $rc -eq 1 ] || { cat "$T/run2.log"; echo "FAIL: expected exit 1 with a damaged frame, got $rc"; exit 1; }
grep -q "1 of 4 frames are not fitted" "$T/run2.log" || { cat "$T/run2.log"; echo "FAIL: no count of unfitted frames"; exit 1; }
grep -q "frame1: .*frame1.exr" "$T/run2.log" || { cat "$T/run2.log"; echo "FAIL: the failed frame is not named with its message"; exit 1; }
grep -q "CANCELLED" "$T/run2.log" || { cat "$T/run2.log"; echo "FAIL: the reduce was not cancelled"; exit 1; }
[ ! -e "$T/out2/batch.json" ] || { echo "FAIL: batch.json written by a failed batch"; exit 1; }
[ -z "$(squeue -h)" ] || { squeue; echo "FAIL: jobs left in the queue"; exit 1; }
cp -p "$T/frame1.good" "$T/day/frame1.exr"
before=$(stat -c %Y "$T/out2/state/frame3.json")
"${BATCH[@]}" --out "$T/out2" --resume 2> "$T/run3.log" || { cat "$T/run3.log"; echo "FAIL: --resume"; exit 1; }
grep -q "3 done earlier, 1 chunks to run" "$T/run3.log" || { cat "$T/run3.log"; echo "FAIL: resume did not resubmit only the failed chunk"; exit 1; }
[ "$(stat -c %Y "$T/out2/state/frame3.json")" = "$before" ] || { echo "FAIL: a done frame was fitted again"; exit 1; }
python3 - "$T/out2" <<'PY'
import json, sys
b = json.load(open(sys.argv[1] + "/batch.json"))
assert b["ok"] and all(f["status"] == "ok" for f in b["frames"]), b
assert b["run"]["frames_fitted"] == 1 and b["run"]["chunks"] == 1, b["run"]
print("slurm resume: ok")
PY
echo "PASS"
