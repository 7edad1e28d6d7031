#!/usr/bin/env bash
# The default flume (inputs/denlinger_flume.json, full 4 s) on 1, 2, 3 and 4 ranks, one thread each,
# then the comparison table of tools/compare_ranks.py (docs/performance.md "Distributed runs").
# Usage: [TALUS=build/talus] tools/mpi_flume_ranks.sh [OUT_DIR] [RANKS...]   (default: runs/flume_ranks, 1 2 3 4;
# OUT_DIR and TALUS relative to the caller's folder)
# About 6 minutes a run on a 2-core machine (more ranks than cores: --oversubscribe, slower).
set -euo pipefail
out=$(realpath -m "${1:-runs/flume_ranks}")
[ -n "${TALUS:-}" ] && TALUS=$(realpath -m "$TALUS")
shift || true
cd "$(dirname "$0")/.."
TALUS=${TALUS:-$PWD/build/talus}
[ -x "$TALUS" ] || { echo "mpi_flume_ranks.sh: $TALUS is not an executable talus (build it: bash tools/build.sh, or set TALUS)" >&2; exit 2; }
# a failed run names itself and shows the end of its log (it was silent, with the error only in the log)
failed() { echo "mpi_flume_ranks.sh: the run on $1 rank(s) failed; the end of $out/ranks$1.log:" >&2; tail -5 "$out/ranks$1.log" >&2; exit 1; }
ranks=("$@")
[ ${#ranks[@]} -eq 0 ] && ranks=(1 2 3 4)
mkdir -p "$out"
runs=()
for n in "${ranks[@]}"; do
  dir="$out/ranks$n"
  if [ "$n" = 1 ]; then
    "$TALUS" run inputs/denlinger_flume.json --out "$dir" --quiet --threads 1 > "$out/ranks$n.log" 2>&1 || failed "$n"
  else
    mpirun --oversubscribe -np "$n" "$TALUS" run inputs/denlinger_flume.json --out "$dir" --quiet --threads 1 \
      > "$out/ranks$n.log" 2>&1 || failed "$n"
  fi
  cp "$out/ranks$n.log" "$dir/talus.log"
  runs+=("$dir")
done
/usr/bin/python3 tools/compare_ranks.py "${runs[@]}" --markdown
