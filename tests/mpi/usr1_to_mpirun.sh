#!/usr/bin/env bash
# SIGUSR1 to mpirun: Open MPI forwards it to every rank, and talus takes it as it takes SIGTERM to
# the ranks (a SIGTERM to mpirun kills them a second later, before a large checkpoint is written):
# every rank stops at the same step, the checkpoint is written, the exit code is 128 + 10 and
# run.json says "interrupted". (ctest Mpi.Usr1ToMpirunWritesACheckpoint)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/s.json" <<JSON
{ "name": "slide", "grid": { "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 },
  "time": { "end": 1000.0, "courant": 0.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] },
                "particles_per_cell": 2, "velocity": [0.5, 0.0, 0.0] } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 } },
  "output": { "frame_interval": 100.0 } }
JSON
"$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/s.json" --out "$work/run" --quiet --progress-every 0.2 --threads 1 \
  > "$work/run.log" 2>&1 &
pid=$!
# until the run has taken steps (its record says how far it got)
for _ in $(seq 1 600); do
  grep -q '"progress"' "$work/run/run.json" 2>/dev/null && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
sleep 0.5
kill -USR1 "$pid"
wait "$pid"
rc=$?
grep "^talus" "$work/run.log"
fail=0
[ "$rc" -eq 138 ] || { echo "FAIL: exit code $rc, expected 138 (128 + SIGUSR1)"; tail -5 "$work/run.log"; exit 1; }
grep -q '"status": "interrupted"' "$work/run/run.json" || { echo "FAIL: run.json does not say interrupted"; fail=1; }
grep -q 'stopped by signal 10' "$work/run.log" || { echo "FAIL: no 'stopped by signal 10' line"; fail=1; }
[ -s "$work/run/checkpoint.h5" ] || { echo "FAIL: no checkpoint"; fail=1; }
[ "$fail" -eq 0 ] && echo "ok: SIGUSR1 to mpirun stopped every rank with a checkpoint and exit 138"
exit $fail
