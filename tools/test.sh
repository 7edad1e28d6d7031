#!/usr/bin/env bash
# Install what is missing, build and run the test suite (GoogleTest through ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh
# Two test processes share two cores: idle OpenMP threads must sleep, not spin, or the
# barrier-heavy small scenes slow each other down several times.
OMP_WAIT_POLICY=PASSIVE ctest --test-dir build --output-on-failure -j 2
