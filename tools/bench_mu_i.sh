#!/bin/bash
# μ(I) against Drucker-Prager, back to back (docs/performance.md, "μ(I) against Drucker–Prager"):
# the constitutive update alone (3 pairs), then whole steps of the shear scene (2 pairs), 1 thread.
# Run it under the exclusive lock on a shared machine:
#   flock -x /work/quiet.lock tools/bench_mu_i.sh [build/talus]
set -e
talus=${1:-build/talus}
date -u; uptime
for rep in 1 2 3; do
  for m in dp mu_i; do
    OMP_WAIT_POLICY=PASSIVE "$talus" bench --scene update --material $m --particles 1000000 --threads 1 --steps 20 | grep -E "updates/s|plastic"
  done
done
for rep in 1 2; do
  for m in dp mu_i; do
    OMP_WAIT_POLICY=PASSIVE "$talus" bench --scene shear --material $m --particles 300000 --threads 1 --steps 10 | grep -E "M particle|stress|plastic"
  done
done
uptime; date -u
