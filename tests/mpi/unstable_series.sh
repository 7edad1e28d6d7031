#!/usr/bin/env bash
# `mpirun -np N talus run` that one rank's instability ends (MPI_Abort): the job exits with the
# instability's code 3, and the ParaView series lists the frames written before it, each with its
# .pvtu, so that it opens. Two cases: a breach in the first step (the first frame is listed before the
# first step: before 2026-12-05 there was no .pvd at all) and one after six frames. Either way run.json
# says "unstable" with the error's message, and so does runout.json. (ctest Mpi.UnstableRunKeepsItsSeries)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene() {  # $1: the block's speed along x [m/s]; a pull of 200 m/s2 along x speeds it up until the guard trips
  cat <<JSON
{ "name": "unstable", "grid": { "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 },
  "gravity": [200.0, 0.0, -9.81], "time": { "end": 0.5, "courant": 0.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] },
                "particles_per_cell": 2, "velocity": [$1, 0.0, 0.0] } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 } },
  "guards": { "max_step_displacement": 0.08 }, "output": { "frame_interval": 0.01, "checkpoint_interval": 0.02 },
  "diagnostics": { "runout": {} } }
JSON
}
fail=0
check() {  # $1: case name, $2: speed, $3: the fewest frames the .pvd must list
  scene "$2" > "$work/$1.json"
  "$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/$1.json" --out "$work/$1" --quiet --threads 1 > "$work/$1.log" 2>&1
  local rc=$?
  grep "^talus" "$work/$1.log"
  if [ "$rc" -ne 3 ]; then echo "FAIL ($1): exit code $rc, expected 3"; fail=1; return; fi
  grep -q "CFL breach" "$work/$1.log" || { echo "FAIL ($1): no CFL breach reported"; fail=1; }
  if [ ! -f "$work/$1/particles.pvd" ]; then echo "FAIL ($1): no particles.pvd"; fail=1; return; fi
  local listed
  listed=$(grep -o 'file="[^"]*"' "$work/$1/particles.pvd" | sed 's/file="//; s/"$//')
  local count
  count=$(echo "$listed" | grep -c pvtu)
  if [ "$count" -lt "$3" ]; then echo "FAIL ($1): the .pvd lists $count frames, expected at least $3"; fail=1; fi
  for f in $listed; do
    [ -f "$work/$1/$f" ] || { echo "FAIL ($1): $f is listed but missing"; fail=1; }
  done
  # run.json: the rank that failed wrote how the run ended, whichever rank it was
  grep -q '"status": "unstable"' "$work/$1/run.json" || { echo "FAIL ($1): run.json does not say unstable"; cat "$work/$1/run.json"; fail=1; }
  grep -q '"message": ".*CFL breach' "$work/$1/run.json" || { echo "FAIL ($1): run.json has not the error's message"; fail=1; }
  # runout.json, from runout.csv's last row, marked unstable (a distributed run wrote none), and the
  # line says what checkpoint.h5 holds once a periodic one was written
  grep -q '"status": "unstable"' "$work/$1/runout.json" 2>/dev/null || { echo "FAIL ($1): no runout.json saying unstable"; fail=1; }
  if [ -f "$work/$1/checkpoint.h5" ]; then
    grep -q "checkpoint.h5 holds the last periodic checkpoint (.*): --restart resumes from it" "$work/$1.log" ||
      { echo "FAIL ($1): the error does not say what checkpoint.h5 holds"; fail=1; }
  fi
  echo "ok ($1): exit code 3, $count frames listed, each on disk, run.json says unstable (rank $(grep -o '"rank": [0-9]*' "$work/$1/run.json" | grep -o '[0-9]*$'))"
}
check first_step 30.0 1
check later 2.0 5
exit $fail
