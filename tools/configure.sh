#!/usr/bin/env bash
# Configure a build folder with Ninja: tools/configure.sh DIR LOG [CMake arguments...]
# Ninja (ninja-build, installed by tools/setup.sh) compiles a target's files as soon as the headers
# they need exist, while make waits until every library the target links is built: with the
# unity batches (CMakeLists.txt) make kept one of two cores idle for a third of the sanitizer
# build (docs/reliability.md "CI"). A folder configured earlier with another generator is
# configured afresh, since CMake cannot switch a folder's generator.
set -euo pipefail
dir="$1"; log="$2"; shift 2
if [ -f "$dir/CMakeCache.txt" ] && ! grep -qx 'CMAKE_GENERATOR:INTERNAL=Ninja' "$dir/CMakeCache.txt"; then
  rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles"
fi
cmake -G Ninja -S . -B "$dir" "$@" > "$log" 2>&1 || { cat "$log"; exit 1; }
