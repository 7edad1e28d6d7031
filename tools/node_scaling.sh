#!/usr/bin/env bash
# Issue 19's measurements on a many-core node, in one sitting with a time budget (docs/performance.md,
# "Measured on a 16-core node"). Each phase is skipped when less of the budget is left than it needs,
# and the results are packed into OUT/results.tar.gz after every phase, so a run stopped from outside
# still returns what it finished.
#
#   TALUS=build/talus BUDGET=510 tools/node_scaling.sh OUT
#
# Phases, most needed first: the machine (lscpu, NUMA nodes, the OMP_* variables, BUDGET); STREAM at
# 1, 2, 4, 8 (those up to N) and N threads and mpm_limit at 1 and N, built with -march=native from
# shared/bench inside the checkout (the only copy that travels to a device machine), else ../shared/bench
# (MPM_LIMIT_SRC / STREAM_SRC point at other sources; a WARNING names a source missing or not built);
# the core-to-core time (tools/core_latency.cpp, measured with or without the references); determinism
# (the outputs of 1, 7 and N threads, same bits, three flumes); tools/scaling_runs.py
# (the default flume with both scatters to 0.1 s, the h = 0.005 m flume with both to 0.0025 s);
# tools/scaling.py (bench block, strong and weak); issue 18's 1-thread table (tools/bench_kernels.py);
# issue 18's MLS shares on the AVX2 and the automatic path, and the reused variant's; the shear bench (tools/scaling.py). Each model's c(T) is measured at every thread count. OMP_PROC_BIND=close, OMP_PLACES=cores; OMP_WAIT_POLICY is left unset
# (libgomp's own: spin, then sleep), as users run: the 2026-12-04 node ran under PASSIVE by mistake,
# which measured the waking of sleeping threads (about 100 us per region at 16 threads).
set -u
usage() { sed -n '2,/^[^#]/{/^#/s/^# \{0,1\}//p}' "$0"; }  # the header above
case "${1:-}" in
  -h|--help) usage; exit 0;;
  # an empty OUT or an option taken for one wrote log.txt and results.tar.gz into / (OUT=-h)
  ""|-*) echo "node_scaling.sh: OUT ${1:-(none)}: give the folder for log.txt and results.tar.gz (usage: tools/node_scaling.sh -h)" >&2; exit 2;;
esac
OUT=$1
# a BUDGET like 8m broke every phase's arithmetic; refused before any work
[[ "${BUDGET:-510}" =~ ^[0-9]+$ ]] || { echo "node_scaling.sh: BUDGET=$BUDGET: give whole seconds, 0 or more (e.g. BUDGET=510)" >&2; exit 2; }
# OUT and TALUS are read from the caller's folder, before the cd (a relative OUT lost its results:
# pack() runs tar inside the temporary folder)
OUT=$(realpath -m "$OUT")
[ -n "${TALUS:-}" ] && TALUS=$(realpath -m "$TALUS")
cd "$(dirname "$0")/.."
TALUS=${TALUS:-$PWD/build/talus}
[ -x "$TALUS" ] || { echo "node_scaling.sh: $TALUS is not an executable talus (build it: bash tools/build.sh, or set TALUS)" >&2; exit 2; }
BUDGET=${BUDGET:-510}
# only a shared/ inside the checkout travels to a device machine: ../shared/bench alone left the node
# without its references, silently
BENCH=../shared/bench
[ -d shared/bench ] && BENCH=shared/bench
MPM_LIMIT_SRC=${MPM_LIMIT_SRC:-$BENCH/mpm_limit.cpp}
STREAM_SRC=${STREAM_SRC:-$BENCH/stream.cpp}
T0=$(date +%s)
W=$(mktemp -d) && S=$(mktemp -d) || { echo "node_scaling.sh: mktemp -d failed (is ${TMPDIR:-/tmp} writable?)" >&2; exit 1; }
mkdir -p "$OUT" || { echo "node_scaling.sh: cannot create $OUT" >&2; exit 1; }  # W: results, S: scratch
trap 'rm -rf "$W" "$S"' EXIT
exec > >(tee -a "$OUT/log.txt") 2>&1
el() { echo $(( $(date +%s) - T0 )); }
pack() {
  # through a .part file: a kill during tar kept the results packed before
  if (cd "$W" && tar czf "$OUT/results.tar.gz.part" . && mv -f "$OUT/results.tar.gz.part" "$OUT/results.tar.gz"); then echo "[$(el) s] packed"; else echo "[$(el) s] packing into $OUT/results.tar.gz FAILED"; fi
}
phase() { # name, seconds it needs
  local left=$(( BUDGET - $(el) ))
  if [ $left -lt "$2" ]; then echo "[$(el) s] SKIP $1 (needs $2 s, $left left)"; return 1; fi
  echo "[$(el) s] PHASE $1"; return 0
}
# The drivers need numpy and matplotlib: the first python3 on PATH may lack them (a pyenv shim on the
# development VM failed every scaling phase); Debian's own has them once tools/setup.sh has run.
PY=python3
if ! "$PY" -c "import numpy, matplotlib" 2>/dev/null && /usr/bin/python3 -c "import numpy, matplotlib" 2>/dev/null; then
  PY=/usr/bin/python3
fi
export PYTHONUNBUFFERED=1 OMP_PROC_BIND=close OMP_PLACES=cores
unset OMP_WAIT_POLICY
N=$(nproc)

phase machine 1
{ date -u; echo "BUDGET=$BUDGET s; $(env | grep '^OMP_' | sort | tr '\n' ' ')OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-unset}"
  uname -a; head -2 /etc/os-release; nproc; lscpu; free -g; ls /sys/devices/system/node/ | grep node; } > "$W/env.txt" 2>&1
grep -E "Model name|^CPU\(s\)|Thread|Socket|NUMA" "$W/env.txt"
"$TALUS" --version > "$W/talus_version.txt" 2>&1 || { cat "$W/talus_version.txt"; echo "talus does not start: $TALUS"; pack; exit 1; }
cat "$W/talus_version.txt"  # the commit, compiler and vector paths of the binary measured

# the references: a source missing or not built is named (g++'s errors were thrown away, and the
# kernels phase then ran without --mpm-limit/--stream unnoticed)
build_ref() { # source, binary
  if [ ! -f "$1" ]; then echo "WARNING: no $1: its reference is not measured"; return 1; fi
  g++ -O3 -march=native -fopenmp "$1" -o "$2" > "$2.log" 2>&1 && return 0
  echo "WARNING: g++ could not build $1: its reference is not measured"; head -5 "$2.log"; return 1
}
ML=""; ST=""
build_ref "$MPM_LIMIT_SRC" "$S/mpm_limit" && ML=$S/mpm_limit
build_ref "$STREAM_SRC" "$S/stream" && ST=$S/stream
phase references 30 && {
  # 1, 2, 4, 8 up to N, and N: at N = 2 the list ran 8 threads on 2 cores, and 2 twice
  [ -n "$ST" ] && for t in $(printf "%s\n" 1 2 4 8 | awk -v n="$N" '$1 < n'; echo "$N"); do
    echo "STREAM $t threads: $(OMP_NUM_THREADS=$t "$ST") GB/s"; done | tee "$W/stream.txt"
  [ -n "$ML" ] && for t in $(printf "%s\n" 1 "$N" | sort -un); do echo "mpm_limit 2 colour 20 50 10, $t threads: $(OMP_NUM_THREADS=$t "$ML" 2 colour 20 50 10 | grep -o 'particle-updates/s: [0-9.e+]*')"; done | tee "$W/mpm_limit.txt"
  # the time a cache line takes from CPU 0 to a neighbour, the middle and the last CPU: a small scene's
  # c(T) follows it (docs/performance.md, "2 threads when the host puts the vCPUs far apart"); it needs
  # no reference source, so it runs without them
  if g++ -O2 -pthread tools/core_latency.cpp -o "$S/core_latency" > "$S/core_latency.log" 2>&1; then
    timeout 20 "$S/core_latency" $(printf "%s\n" 1 $((N / 2)) $((N - 1)) | sort -un) > "$W/core_latency.txt" ||
      echo "WARNING: core_latency failed or ran past 20 s: its times are partial or missing"
    cat "$W/core_latency.txt"
  else echo "WARNING: g++ could not build tools/core_latency.cpp"; head -5 "$S/core_latency.log"; fi
  pack; }

H005=$W/flume_h005.json; H005BB=$W/flume_h005_block_buffers.json
"$PY" tools/make_flume_scene.py --cell 0.005 --name flume_h005 > "$H005"
"$PY" tools/make_flume_scene.py --cell 0.005 --scatter block_buffers --name flume_h005_block_buffers > "$H005BB"

phase determinism 45 && {
  # the outputs (frames, energy, runout, deposit) of 1, 7 and N threads must be the same bits
  for sc in inputs/denlinger_flume.json@0.03 inputs/denlinger_flume_block_buffers.json@0.03 "$H005BB@0.0015"; do
    f=${sc%@*}; e=${sc#*@}; b=$(basename "$f" .json); d=$S/det_$b
    "$PY" -c "import json; s=json.load(open('$f')); s['time']['end']=$e; s['output']['frame_interval']=$e/3; json.dump(s,open('$d.json','w'))"
    for t in 1 7 "$N"; do "$TALUS" run "$d.json" --threads $t --quiet --out "${d}_$t" > /dev/null || echo "run failed: $b, $t threads"; done
    for t in 7 "$N"; do
      if diff -rq -x run.json "${d}_1" "${d}_$t" > /dev/null; then echo "determinism $b: 1 vs $t threads identical ($(find "${d}_1" -type f ! -name run.json | wc -l) files; run.json, the record, aside)"
      else echo "determinism $b: 1 vs $t threads DIFFER"; fi
    done
  done | tee "$W/determinism.txt"
  pack; }

# (on the 2026-12-04 node: about 290 s for these four scenes with 2 repeats and c(16) alone; the
# h = 0.005 m flumes dominate, hence 0.0025 s here, with c(T) at every count)
phase scaling_runs 240 && {
  "$PY" tools/scaling_runs.py inputs/denlinger_flume.json@0.1 inputs/denlinger_flume_block_buffers.json@0.1 \
    "$H005BB@0.0025" "$H005@0.0025" --talus "$TALUS" --max-threads "$N" --repeat 2 --out "$W" --name scaling_runs_node
  pack; }

phase scaling_block 100 && {
  "$PY" tools/scaling.py --talus "$TALUS" --particles 1000000 --steps 10 --repeat 2 --max-threads "$N" --out "$W" \
    --name scaling_node_block
  pack; }

phase kernels_1thread 80 && {
  # avx2 beside auto: on the 2026-12-04 node (AVX-512) the vector path gained 1.39x over the reference
  # on the block where the AVX-512 EPYC VM gained 1.94x; is AVX2 faster there?
  "$PY" tools/bench_kernels.py --talus "$TALUS" --paths reference,avx2,auto --rounds 1 ${ML:+--mpm-limit "$ML"} \
    ${ST:+--stream "$ST"} --json "$W/kernels_node.json"
  pack; }
phase mls_1thread 100 && {
  # issue 18's MLS shares (targets <= 35% at 1 cell, <= 50% at 2), never measured on Intel: the AVX-512
  # fit was only 1.2x faster than the AVX2 one on the Zen 4 VMs, which run a 512-bit operation as two halves.
  # Then the `reused` variant's reusing steps (reuse_strain 1: the bench's steps from rest never refit),
  # bound by memory traffic on those VMs (docs/performance.md, "The 2-cell reusing step").
  { for isa in avx2 auto; do for r in 1 2; do
    "$TALUS" bench --scene column --material dp --shape bspline2 --particles 1000000 --threads 1 --steps 2 \
      --mls linear --mls-radius $r --cpu-time --isa $isa --json "$W/mls_${isa}_r$r.json" | grep -E "talus bench|M particle|smooth"
  done; done
  for r in 1 2; do
    "$TALUS" bench --scene column --material dp --shape bspline2 --particles 1000000 --threads 1 --steps 4 \
      --mls linear --mls-radius $r --mls-variant reused --mls-reuse-strain 1 --cpu-time \
      --json "$W/mls_reused_r$r.json" | grep -E "talus bench|M particle|smooth|MLS:"
  done; } | tee "$W/mls_1thread.txt"
  pack; }
phase scaling_shear 60 && {
  "$PY" tools/scaling.py --talus "$TALUS" --particles 1000000 --steps 10 --repeat 1 --max-threads "$N" --out "$W" \
    --name scaling_node_shear -- --scene shear --material dp
  pack; }
echo "[$(el) s] done"
pack
