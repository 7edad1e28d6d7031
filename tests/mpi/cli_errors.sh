#!/usr/bin/env bash
# `mpirun -np N talus run` with a bad scene: the error is printed once (by rank 0), every rank exits
# with the input error's code 2, and nothing is written; so for a scene that needs one rank, whose
# line names the scene key (ctest Mpi.BadSceneReportedOnce)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# expect_refused NAME ERROR_START: runs $work/NAME.json on the ranks and checks the one line, the
# exit code and that no output folder was made
expect_refused() {
  local name=$1 error=$2
  "$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" run "$work/$name.json" --out "$work/${name}_out" --quiet \
    > "$work/log" 2>&1
  local rc=$?
  local lines
  lines=$(grep -c "^talus: error: $error" "$work/log")
  cat "$work/log"
  if [ "$rc" -ne 2 ]; then echo "FAIL: $name: exit code $rc, expected 2"; exit 1; fi
  if [ "$lines" -ne 1 ]; then echo "FAIL: $name: the error was printed $lines times, expected once"; exit 1; fi
  if [ -e "$work/${name}_out" ]; then echo "FAIL: $name: the output folder was created"; exit 1; fi
}

cat > "$work/bad.json" <<'JSON'
{ "name": "bad", "grid": { "origin": [0, 0, 0], "size": [0.2, 0.2, 0.2], "cell_size": 0.02 },
  "time": { "end": 0.1, "courant": 7.3 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e5, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "rubber", "box": { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } } ] }
JSON
expect_refused bad "time.courant"

# MLS smoothing needs one rank: the line names the key that asks for it (it said smoothing.enabled)
cat > "$work/mls.json" <<'JSON'
{ "name": "mls", "grid": { "origin": [0, 0, 0], "size": [0.2, 0.2, 0.2], "cell_size": 0.02 },
  "time": { "end": 0.01 },
  "solver": { "shape": "bspline2", "smoothing": { "basis": "linear" } },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e5, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "rubber", "box": { "min": [0.04, 0.04, 0.04], "max": [0.1, 0.1, 0.1] } } ] }
JSON
expect_refused mls "solver.smoothing.enabled = true: MLS smoothing is not available in a distributed run"
# A machine (here the last rank, given less memory) that cannot hold its ranks' share: `run` and
# `check` both refuse on every rank, once, naming that rank (check said ok on rank 0's word alone)
cat > "$work/small.json" <<'JSON'
{ "name": "small", "grid": { "origin": [0, 0, 0], "size": [0.4, 0.2, 0.2], "cell_size": 0.02 },
  "time": { "end": 0.01 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e5, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "rubber", "box": { "min": [0.04, 0.04, 0.04], "max": [0.3, 0.1, 0.1] } } ] }
JSON
if [ "$ranks" -ge 2 ]; then
  for command in check run; do
    out=(); [ "$command" = run ] && out=(--out "$work/small_out" --quiet)
    "$mpirun_cmd" --oversubscribe -np $((ranks - 1)) -x TALUS_MEMORY_LIMIT=1G "$talus" $command "$work/small.json" \
      "${out[@]}" : -np 1 -x TALUS_MEMORY_LIMIT=10k "$talus" $command "$work/small.json" "${out[@]}" > "$work/log" 2>&1
    rc=$?
    cat "$work/log"
    lines=$(grep -c "^talus: error: on rank $((ranks - 1)) of $ranks: scene .* needs about .* on this machine" "$work/log")
    if [ "$rc" -ne 2 ] || [ "$lines" -ne 1 ] || grep -q "^ok" "$work/log" || [ -e "$work/small_out" ]; then
      echo "FAIL: $command with a small machine: exit code $rc, $lines refusals"; exit 1
    fi
  done
fi
# The commands that do not use the ranks run on rank 0 alone: their output came once per rank
# (`mpirun talus schema > s.json` interleaved the copies) and element-test wrote its CSV twice
versions=$("$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" --version | grep -c "^talus ")
[ "$versions" -eq 1 ] || { echo "FAIL: --version printed $versions times"; exit 1; }
"$mpirun_cmd" -np "$ranks" --oversubscribe "$talus" schema > "$work/schema.json" || { echo "FAIL: schema"; exit 1; }
"$talus" schema | cmp -s - "$work/schema.json" || { echo "FAIL: schema under mpirun differs from the serial one"; exit 1; }
echo "ok: one line, exit code 2, nothing written; --version and schema once"
