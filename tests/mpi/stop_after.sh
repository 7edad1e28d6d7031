#!/usr/bin/env bash
# `mpirun -np N talus run --stop-after T`: every rank stops at the same step, writes the checkpoint
# and exits with 75; run.json says "interrupted"; the restart on N ranks finishes with the energy
# history and the frames of an uninterrupted N-rank run, byte for byte. (ctest Mpi.StopAfterResumesBitForBit)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/s.json" <<JSON
{ "name": "slide", "grid": { "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 },
  "time": { "end": 2.0, "courant": 0.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] },
                "particles_per_cell": 2, "velocity": [2.0, 0.0, -0.5] } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 }, "z+": "open" },
  "output": { "frame_interval": 0.1 } }
JSON
run() { "$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/s.json" --quiet --threads 1 "$@"; }
fail=0
start=$(date +%s.%N)
run --out "$work/whole" > "$work/whole.log" 2>&1 || { echo "FAIL: the uninterrupted run: $(tail -3 "$work/whole.log")"; exit 1; }
limit=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", (b - a) / 3 }')  # a third of the whole run
run --out "$work/part" --stop-after "${limit}s" > "$work/part.log" 2>&1
rc=$?
grep "^talus" "$work/part.log"
if [ "$rc" -eq 0 ]; then echo "skipped: the run finished within ${limit} s"; exit 0; fi
[ "$rc" -eq 75 ] || { echo "FAIL: exit code $rc, expected 75"; exit 1; }
grep -q '"status": "interrupted"' "$work/part/run.json" || { echo "FAIL: run.json does not say interrupted"; fail=1; }
grep -q 'resume with: mpirun -np .* --threads 1$' "$work/part.log" || { echo "FAIL: no resume line with --threads 1"; fail=1; }
run --restart "$work/part/checkpoint.h5" > "$work/resume.log" 2>&1 || { echo "FAIL: the restart: $(tail -3 "$work/resume.log")"; exit 1; }
cmp -s "$work/whole/energy.csv" "$work/part/energy.csv" || { echo "FAIL: energy.csv differs from the uninterrupted run's"; fail=1; }
diff -rq "$work/whole/frames" "$work/part/frames" > /dev/null || { echo "FAIL: the frames differ from the uninterrupted run's"; fail=1; }
[ "$fail" -eq 0 ] && echo "ok: stopped after ${limit} s with exit 75; the restart matches the uninterrupted run"
exit $fail
