#!/usr/bin/env bash
# Install what is missing, build (Release) and run the default scene: the Denlinger-style sand flume
# (docs/flume.md; about 3 minutes on 2 cores). Output lands in runs/denlinger_flume/; the run ends by
# printing the runout distance and where the ParaView series is.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
bash tools/build.sh
build/talus run inputs/denlinger_flume.json --out runs/denlinger_flume
