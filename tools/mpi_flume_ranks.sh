#!/usr/bin/env bash
# The default flume (inputs/denlinger_flume.json, full 4 s) on 1, 2, 3 and 4 ranks, one thread each,
# then the comparison table of tools/compare_ranks.py (docs/performance.md "Distributed runs").
# Usage: tools/mpi_flume_ranks.sh [OUT_DIR] [RANKS...]   (default: runs/flume_ranks, 1 2 3 4)
# About 6 minutes a run on a 2-core machine (more ranks than cores: --oversubscribe, slower).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/flume_ranks}
shift || true
ranks=("$@")
[ ${#ranks[@]} -eq 0 ] && ranks=(1 2 3 4)
mkdir -p "$out"
runs=()
for n in "${ranks[@]}"; do
  dir="$out/ranks$n"
  if [ "$n" = 1 ]; then
    build/talus run inputs/denlinger_flume.json --out "$dir" --quiet --threads 1 > "$out/ranks$n.log" 2>&1
  else
    mpirun --oversubscribe -np "$n" build/talus run inputs/denlinger_flume.json --out "$dir" --quiet --threads 1 \
      > "$out/ranks$n.log" 2>&1
  fi
  cp "$out/ranks$n.log" "$dir/talus.log"
  runs+=("$dir")
done
/usr/bin/python3 tools/compare_ranks.py "${runs[@]}" --markdown
