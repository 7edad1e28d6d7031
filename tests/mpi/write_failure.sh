#!/usr/bin/env bash
# `mpirun -np N talus run` whose frame piece or checkpoint cannot be written (a full disk, a quota;
# here a folder where the file goes): the error is said once, by rank 0, naming the rank that failed,
# every rank exits with the I/O error's code 2 without MPI_Abort, run.json says "failed" with the
# message, and the .pvd lists the frames written before. Before 2026-12-07 each rank that failed
# said it on its own line (once per rank on a full disk) and MPI_Abort ended the job.
# (ctest Mpi.WriteFailureReportedOnce)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/scene.json" <<'JSON'
{ "name": "write_failure", "grid": { "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 },
  "time": { "end": 0.1, "courant": 0.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.9, 0.3, 0.2] },
                "particles_per_cell": 2 } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 } },
  "output": { "frame_interval": 0.02, "checkpoint_interval": 0.05 } }
JSON
fail=0
# check NAME ERROR_START: runs the scene into $work/NAME (made ready by the caller), then checks the
# one line, the exit code, run.json and the series
check() {
  local name=$1 error=$2 failed_before=$fail
  fail=0
  "$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/scene.json" --out "$work/$name" --quiet \
    --threads 1 > "$work/$name.log" 2>&1
  local rc=$?
  grep "^talus" "$work/$name.log"
  local lines
  lines=$(grep -c "^talus: .*error" "$work/$name.log")
  if [ "$rc" -ne 2 ]; then echo "FAIL ($name): exit code $rc, expected 2"; fail=1; fi
  if [ "$lines" -ne 1 ]; then echo "FAIL ($name): $lines error lines, expected 1"; fail=1; fi
  grep -q "^talus: error: $error" "$work/$name.log" || { echo "FAIL ($name): no line 'talus: error: $error'"; fail=1; }
  if grep -q "MPI_ABORT" "$work/$name.log"; then echo "FAIL ($name): the job ended with MPI_Abort"; fail=1; fi
  grep -q '"status": "failed"' "$work/$name/run.json" || { echo "FAIL ($name): run.json does not say failed"; fail=1; }
  grep -q "\"message\": \"$error" "$work/$name/run.json" || { echo "FAIL ($name): run.json has not the message"; fail=1; }
  local listed
  listed=$(grep -o 'file="[^"]*"' "$work/$name/particles.pvd" | sed 's/file="//; s/"$//')
  for f in $listed; do
    [ -f "$work/$name/$f" ] || { echo "FAIL ($name): $f is listed but missing"; fail=1; }
  done
  [ "$fail" -eq 0 ] && echo "ok ($name): exit code $rc, one line, run.json says failed, $(echo "$listed" | grep -c pvtu) frames listed"
  fail=$((fail | failed_before))
}
# the third frame's pieces: every rank's cannot be written (one line, not one per rank)
for r in $(seq 0 $((ranks - 1))); do mkdir -p "$work/every_rank/frames/particles_000002_$(printf %04d "$r").vtu/x"; done
check every_rank "cannot write .*particles_000002_0000.vtu"
# only the last rank's: rank 0 says it, naming that rank
last=$(printf %04d $((ranks - 1)))
mkdir -p "$work/last_rank/frames/particles_000002_$last.vtu/x"
check last_rank "on rank $((ranks - 1)) of $ranks: cannot write .*particles_000002_$last.vtu"
# the checkpoint, which rank 0 writes while the others wait
mkdir -p "$work/checkpoint/checkpoint.h5.tmp/x"
check checkpoint "cannot write checkpoint .*checkpoint.h5"
exit $fail
