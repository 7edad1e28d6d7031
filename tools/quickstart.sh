#!/usr/bin/env bash
# Install what is missing, build (Release) and run the default scene. Output lands in runs/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh
build/talus run inputs/elastic_block_slide.json --out runs/elastic_block_slide
