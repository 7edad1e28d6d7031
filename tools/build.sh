#!/usr/bin/env bash
# Configure (Ninja: tools/configure.sh) and build talus (Release) in ./build. Extra arguments go to
# CMake's configure step, e.g. tools/build.sh -DTALUS_NATIVE=ON
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/configure.sh build build.log -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j "$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
echo "build: ok (log in build.log)"
