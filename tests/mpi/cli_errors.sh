#!/usr/bin/env bash
# `mpirun -np N talus run` with a bad scene: the error is printed once (by rank 0), every rank exits
# with the input error's code 2, and nothing is written. (ctest Mpi.BadSceneReportedOnce)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/bad.json" <<'JSON'
{ "name": "bad", "grid": { "origin": [0, 0, 0], "size": [0.2, 0.2, 0.2], "cell_size": 0.02 },
  "time": { "end": 0.1, "courant": 7.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e5, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "rubber", "box": { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } } ] }
JSON
"$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/bad.json" --out "$work/out" --quiet > "$work/log" 2>&1
rc=$?
lines=$(grep -c "^talus: error: time.courant" "$work/log")
cat "$work/log"
if [ "$rc" -ne 2 ]; then echo "FAIL: exit code $rc, expected 2"; exit 1; fi
if [ "$lines" -ne 1 ]; then echo "FAIL: the error was printed $lines times, expected once"; exit 1; fi
if [ -e "$work/out" ]; then echo "FAIL: the output folder was created"; exit 1; fi
echo "ok: one line, exit code 2, nothing written"
