#!/usr/bin/env bash
# `mpirun -np N talus run` with no --threads: each rank takes the CPUs it may use shared among the
# ranks on its host that may use them (each took them all: 3 ranks x 2 threads on 2 CPUs, far
# slower than with --threads 1; docs/architecture.md), and a host whose ranks' threads exceed its logical CPUs is
# said once, by rank 0, in run and check. (ctest Mpi.DefaultThreadsShareTheHost)
set -uo pipefail
mpirun_cmd=$1; talus=$2; ranks=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
unset OMP_NUM_THREADS
cat > "$work/s.json" <<'JSON'
{ "name": "tiny", "grid": { "origin": [0, 0, 0], "size": [0.4, 0.2, 0.2], "cell_size": 0.04 },
  "time": { "end": 0.002 },
  "materials": { "rubber": { "model": "linear_elastic", "density": 1000, "young": 1e5, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "rubber", "box": { "min": [0.04, 0.04, 0.0], "max": [0.36, 0.16, 0.1] } } ] }
JSON
fail=0
# (--bind-to none: every rank may use every CPU of this process's, as on a node bound to sockets)
cpus=$(nproc)
logical=$(getconf _NPROCESSORS_ONLN)
expected=$(( cpus / ranks )); [ "$expected" -ge 1 ] || expected=1
"$mpirun_cmd" -np "$ranks" --oversubscribe --bind-to none "$talus" run "$work/s.json" --out "$work/a" --quiet \
  > "$work/a.log" 2>&1 || { echo "FAIL: the run: $(tail -3 "$work/a.log")"; exit 1; }
grep "^talus" "$work/a.log"
grep -q "^talus: .* particles, $ranks ranks x $expected thread" "$work/a.log" ||
  { echo "FAIL: expected $ranks ranks x $expected threads ($cpus CPUs shared by $ranks ranks)"; fail=1; }
if [ $(( ranks * expected )) -le "$logical" ] && grep -q "oversubscribed" "$work/a.log"; then
  echo "FAIL: the default threads were said to oversubscribe the host"; fail=1
fi
# --threads as many as the host's CPUs on each rank: more threads than CPUs, said once
for command in run check; do
  out=(); [ "$command" = run ] && out=(--out "$work/b" --quiet --threads "$logical")
  env=(); [ "$command" = check ] && env=(-x "OMP_NUM_THREADS=$logical")
  "$mpirun_cmd" -np "$ranks" --oversubscribe --bind-to none "${env[@]}" "$talus" $command "$work/s.json" "${out[@]}" \
    > "$work/$command.log" 2>&1 || { echo "FAIL: $command: $(tail -3 "$work/$command.log")"; fail=1; continue; }
  lines=$(grep -c "^talus: warning: $ranks ranks x $logical threads\? = $(( ranks * logical )) threads on host .*, which has $logical logical CPUs\?: oversubscribed" "$work/$command.log")
  grep "oversubscribed" "$work/$command.log"
  [ "$lines" -eq 1 ] || { echo "FAIL: $command: the oversubscription was said $lines times, expected once"; fail=1; }
done
[ "$fail" -eq 0 ] && echo "ok: $ranks ranks x $expected threads on $cpus CPUs; $ranks x $logical threads said once"
exit $fail
