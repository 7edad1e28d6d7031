#!/usr/bin/env bash
# Install what is missing, build and run the test suite (GoogleTest through ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh
ctest --test-dir build --output-on-failure -j 2
