#!/usr/bin/env bash
# Does talus build with Debian 12's clang (14) and LLVM's OpenMP runtime, pass its tests, and give
# the same bits as the g++ build? Builds Release in build-clang (Ninja), runs the test suite there,
# then runs tools/compare_binaries.py between build/talus (g++, built first if missing) and
# build-clang/talus on every vector path this CPU has. About 10 minutes on 2 cores; not part of CI
# (which builds with g++ only), run it after changes that touch the C++ language level, OpenMP or
# the vector kernels. Exit status 1 when the build, a test or a comparison fails.
#   tools/check_clang.sh            # installs clang and libomp-dev when missing (tools/setup.sh --with-clang)
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh --with-clang
[ -x build/talus ] || bash tools/build.sh
CC=clang CXX=clang++ bash tools/configure.sh build-clang build-clang.log -DCMAKE_BUILD_TYPE=Release
cmake --build build-clang -j "$(nproc)" >> build-clang.log 2>&1 || { tail -50 build-clang.log; exit 1; }
echo "clang build: ok (log in build-clang.log)"
OMP_WAIT_POLICY=PASSIVE ctest --test-dir build-clang --output-on-failure -j "$(nproc)"
failed=0
for isa in reference scalar avx2 avx512; do
  if ! build/talus bench --isa "$isa" --particles 1000 --steps 1 > /dev/null 2>&1; then
    echo "--isa $isa: not on this CPU, skipped"
    continue
  fi
  echo "compare g++ and clang builds, --isa $isa:"
  TALUS_ISA="$isa" python3 tools/compare_binaries.py build/talus build-clang/talus --work "build-clang/compare_$isa" |
    tail -1 || failed=1
done
exit "$failed"
