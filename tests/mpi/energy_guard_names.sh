#!/usr/bin/env bash
# The energy guard under mpirun names the fastest particle over every rank: it named rank 0's own
# (a block at rest) when the fast body lay in rank 1's slab. (ctest Mpi.EnergyGuardNamesTheFastestOfAllRanks)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/s.json" <<JSON
{ "name": "two", "grid": { "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 },
  "time": { "end": 0.1, "courant": 0.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] } },
              { "name": "fast", "material": "rubber", "box": { "min": [0.8, 0.1, 0.0], "max": [1.0, 0.3, 0.2] },
                "velocity": [3.0, 0.0, 0.0] } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 } },
  "guards": { "energy_growth_factor": 1e-6 } }
JSON
"$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/s.json" --out "$work/run" --quiet --threads 1 \
  > "$work/run.log" 2>&1
rc=$?
grep "^talus" "$work/run.log"
[ "$rc" -eq 3 ] || { echo "FAIL: exit code $rc, expected 3"; exit 1; }
grep -q 'energy_growth_factor' "$work/run.log" || { echo "FAIL: not the energy guard"; exit 1; }
# (a breach of the global ledger: said as all ranks', not rank 0's, which holds the block at rest)
grep -q '^talus: error (energy guard, all ranks): ' "$work/run.log" || { echo "FAIL: not said as all ranks' error"; exit 1; }
grep -q 'on rank 0 of' "$work/run.log" && { echo "FAIL: blamed on rank 0"; exit 1; }
grep -q 'fastest: particle [0-9]* (body "fast")' "$work/run.log" || { echo "FAIL: the fastest particle is not the fast body's"; exit 1; }
echo "ok: the energy guard named the fast body on rank 1"
