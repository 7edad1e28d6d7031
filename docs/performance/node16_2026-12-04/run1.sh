#!/usr/bin/env bash
# One device session: issue 19's many-core measurements (tools/scaling.py, tools/scaling_runs.py) and
# issue 18's 1-thread table, with mpm_limit and STREAM in the same sitting. Each phase is skipped
# when too little of the budget is left; results are packed into $OUT after every phase.
set -u
T0=$(date +%s)
BUDGET=${BUDGET:-520}
W=/tmp/w; mkdir -p $W
D=$(pwd)/.device
LOG=$OUT/log.txt
exec > >(tee -a $LOG) 2>&1
el() { echo $(( $(date +%s) - T0 )); }
pack() { (cd $W && tar czf $OUT/results.tar.gz . 2>/dev/null); echo "[$(el) s] packed"; }
phase() { # name, seconds it needs
  local left=$(( BUDGET - $(el) ))
  if [ $left -lt $2 ]; then echo "[$(el) s] SKIP $1 (needs $2 s, $left left)"; return 1; fi
  echo "[$(el) s] PHASE $1"; return 0
}
export PYTHONUNBUFFERED=1 OMP_PROC_BIND=close OMP_PLACES=cores OMP_WAIT_POLICY=PASSIVE
# the talus binary and the Debian 12 libraries it links (not glibc's or libstdc++'s: the image's are newer)
chmod +x $D/talus.bin $D/*_v3
cat > $D/talus <<EOF
#!/bin/sh
LD_LIBRARY_PATH=$D/lib exec $D/talus.bin "\$@"
EOF
chmod +x $D/talus
TALUS=$D/talus

phase env 1
{ date -u; uname -a; cat /etc/os-release | head -2; nproc; lscpu; free -g; numactl -H 2>&1 | head -5;
  ls /sys/devices/system/node/ | grep node; g++ --version 2>&1 | head -1; python3 --version; } > $W/env.txt 2>&1
cat $W/env.txt | grep -E "Model name|^CPU\(s\)|Thread|Socket|NUMA|L3|Flags" | cut -c1-300
LD_LIBRARY_PATH=$D/lib ldd $D/talus.bin | grep "not found"
$TALUS --version || { echo "talus does not start"; pack; exit 1; }
N=$(nproc)
if g++ -O3 -march=native -fopenmp $D/mpm_limit.cpp -o $W/mpm_limit 2>/dev/null && g++ -O3 -march=native -fopenmp $D/stream.cpp -o $W/stream; then
  ML=$W/mpm_limit; ST=$W/stream; echo "references built here (-march=native)"
else ML=$D/mpm_limit_v3; ST=$D/stream_v3; echo "references: carried x86-64-v3 builds"; fi
cp $ML /tmp/ml; cp $ST /tmp/st; rm -f $W/mpm_limit $W/stream; ML=/tmp/ml; ST=/tmp/st

phase references 30 && {
  for t in 1 2 4 8 $N; do echo "STREAM $t threads: $(OMP_NUM_THREADS=$t $ST) GB/s"; done | tee $W/stream.txt
  for t in 1 $N; do echo "mpm_limit 2 colour 20 50 10, $t threads: $(OMP_NUM_THREADS=$t $ML 2 colour 20 50 10 | grep -o 'particle-updates/s: [0-9.e+]*')"; done | tee $W/mpm_limit.txt
  pack; }

phase determinism 45 && {
  # the outputs (frames, energy, runout, deposit) of 1, 7 and N threads must be the same bits
  for sc in inputs/denlinger_flume.json@0.03 inputs/denlinger_flume_block_buffers.json@0.03 $D/flume_h005_block_buffers.json@0.0015; do
    f=${sc%@*}; e=${sc#*@}; b=$(basename $f .json)
    python3 -c "import json,sys; s=json.load(open('$f')); s['time']['end']=$e; s['output']['frame_interval']=$e/3; json.dump(s,open('/tmp/det_$b.json','w'))"
    for t in 1 7 $N; do $TALUS run /tmp/det_$b.json --threads $t --quiet --out /tmp/det_${b}_$t > /dev/null || echo "run failed: $b $t"; done
    for t in 7 $N; do diff -rq /tmp/det_${b}_1 /tmp/det_${b}_$t > /dev/null && echo "determinism $b: 1 vs $t threads identical ($(find /tmp/det_${b}_1 -type f | wc -l) files)" || echo "determinism $b: 1 vs $t threads DIFFER"; done
  done | tee $W/determinism.txt
  pack; }

phase scaling_block 90 && {
  python3 tools/scaling.py --talus $TALUS --particles 1000000 --steps 10 --max-threads $N --out $W --name scaling_node_block
  pack; }

phase scaling_runs 170 && {
  python3 tools/scaling_runs.py inputs/denlinger_flume.json@0.1 inputs/denlinger_flume_block_buffers.json@0.1 \
    $D/flume_h005_block_buffers.json@0.004 $D/flume_h005.json@0.004 --talus $TALUS --max-threads $N --repeat 2 \
    --out $W --name scaling_runs_node
  pack; }

phase scaling_shear 90 && {
  python3 tools/scaling.py --talus $TALUS --particles 1000000 --steps 10 --max-threads $N --out $W \
    --name scaling_node_shear -- --scene shear --material dp
  pack; }

phase kernels_1thread 60 && {
  python3 tools/bench_kernels.py --talus $TALUS --paths reference,auto --rounds 1 --mpm-limit $ML --stream $ST \
    --json $W/kernels_node.json
  pack; }

phase block_buffers_bench 60 && {
  for t in 1 $N; do for s in colour_passes block_buffers; do
    $TALUS bench --particles 1000000 --steps 10 --threads $t --scatter $s --json $W/bench_${s}_$t.json | grep -E "particle-updates/s"
    echo "  ($s, $t threads)"; done; done
  pack; }

echo "[$(el) s] done"
pack
