#!/usr/bin/env bash
# Do the builds a user may choose instead of the default build, pass the tests and give the default
# build's bits? CI builds one configuration only (g++, portable, with MPI); this checks the others:
#   clang    Debian 12's clang (14) with LLVM's OpenMP runtime, in build-clang
#   native   -DTALUS_NATIVE=ON (-march=native: this CPU only) and -DTALUS_MPI=OFF, in build-native
# Each is built (Release, Ninja), its tests run, and tools/compare_binaries.py compares its talus
# with build/talus (built first if missing) on every vector path both binaries run here, and on
# the path each picks by itself (`auto`). About 6 minutes a variant on 2 cores. Run it after changes
# to the C++ language level, OpenMP, the vector kernels or CMakeLists.txt.
#   tools/check_builds.sh [clang] [native]     # no argument: both
# Installs clang and libomp-dev when missing (tools/setup.sh --with-clang). Exit status 1 when a
# build, a test or a comparison fails.
set -euo pipefail
cd "$(dirname "$0")/.."
variants=("$@")
[ ${#variants[@]} -gt 0 ] || variants=(clang native)
for v in "${variants[@]}"; do
  case "$v" in
    clang | native) ;;
    *) echo "check_builds: unknown variant '$v'; the variants are clang and native" >&2; exit 2 ;;
  esac
done
bash tools/setup.sh --with-clang
[ -x build/talus ] || bash tools/build.sh

runs_path() {  # does this talus run the vector path $2 on this CPU?
  "$1" bench --isa "$2" --particles 1000 --steps 1 > /dev/null 2>&1
}

failed=0
for v in "${variants[@]}"; do
  dir="build-$v"
  if [ "$v" = clang ]; then
    CC=clang CXX=clang++ bash tools/configure.sh "$dir" "$dir.log" -DCMAKE_BUILD_TYPE=Release
  else
    bash tools/configure.sh "$dir" "$dir.log" -DCMAKE_BUILD_TYPE=Release -DTALUS_NATIVE=ON -DTALUS_MPI=OFF
  fi
  if ! cmake --build "$dir" -j "$(nproc)" >> "$dir.log" 2>&1; then
    tail -50 "$dir.log"
    echo "check_builds: $v: the build failed (log in $dir.log)"
    failed=1
    continue
  fi
  echo "check_builds: $v: built (log in $dir.log)"
  OMP_WAIT_POLICY=PASSIVE ctest --test-dir "$dir" --output-on-failure -j "$(nproc)" || failed=1
  for isa in auto reference scalar avx2 avx512 avx512_dl; do
    if ! runs_path build/talus "$isa" || ! runs_path "$dir/talus" "$isa"; then continue; fi
    echo "check_builds: $v against build/talus, --isa $isa:"
    TALUS_ISA="$isa" python3 tools/compare_binaries.py build/talus "$dir/talus" --work "$dir/compare_$isa" |
      tail -1 || failed=1
  done
done
exit "$failed"
