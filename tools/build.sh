#!/usr/bin/env bash
# Configure and build talus (Release) in ./build. Extra arguments go to CMake's configure step,
# e.g. tools/build.sh -DTALUS_NATIVE=ON
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j "$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
echo "build: ok (log in build.log)"
