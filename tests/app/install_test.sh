#!/usr/bin/env bash
# Install.ProgramRunsAnInstalledScene: `cmake --install BUILD --prefix P` puts talus in P/bin, the
# scenes in P/share/talus/inputs and the docs in P/share/doc/talus; the installed talus, run from
# another folder, checks and runs an installed scene (a few steps) and writes its series.
set -euo pipefail
build="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
talus="$work/prefix/bin/talus"
scenes="$work/prefix/share/talus/inputs"
for f in "$talus" "$scenes/denlinger_flume.json" "$scenes/benchmarks/dynamic_bar.json" \
         "$work/prefix/share/doc/talus/README.md" "$work/prefix/share/doc/talus/docs/scene-reference.md"; do
  [ -e "$f" ] || { echo "not installed: ${f#"$work/prefix/"}"; exit 1; }
done
cd "$work"
"$talus" check "$scenes/benchmarks/dynamic_bar.json" > check.txt
python3 - "$scenes/benchmarks/dynamic_bar.json" > short.json <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["time"]["end"] = s["time"]["end"] / 100
s.setdefault("output", {})["frame_interval"] = s["time"]["end"]
print(json.dumps(s))
PY
"$talus" run short.json --out run --threads 1 --quiet --foreground-frames
[ -s run/particles.pvd ] && [ -s run/energy.csv ] || { echo "the installed talus wrote no series"; exit 1; }
echo "installed talus ran $(grep -c '<DataSet' run/particles.pvd) frames of an installed scene"
