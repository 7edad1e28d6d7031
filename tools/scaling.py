#!/usr/bin/env python3
"""Strong and weak scaling of talus: runs `talus bench` over thread counts, writes CSV and plots.

    tools/scaling.py [--talus build/talus] [--particles 1000000] [--steps 10] [--max-threads N]
                     [--out docs/performance]

Strong scaling: fixed particle count, threads 1..N (powers of two and N).
Weak scaling: particles proportional to the thread count.
Threads are pinned with OMP_PROC_BIND=close and OMP_PLACES=cores (set them yourself to override);
on a multi-socket node, compare with OMP_PROC_BIND=spread. Runs unchanged on 2 to 64+ cores.
Each bench also measures the STREAM triad at the same thread count (`talus bench --stream`), so the
CSV shows the MPM speed-up next to the memory-bandwidth speed-up of the same machine in the same run:
`speedup_vs_stream` = (MPM speed-up) / (STREAM speed-up), the issue's target being >= 0.9 at 2 threads.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile


def thread_counts(max_threads):
    counts, t = [], 1
    while t < max_threads:
        counts.append(t)
        t *= 2
    counts.append(max_threads)
    return counts


def bench(talus, particles, threads, steps, extra):
    with tempfile.NamedTemporaryFile(suffix=".json") as f:
        env = dict(os.environ)
        env.setdefault("OMP_PROC_BIND", "close")
        env.setdefault("OMP_PLACES", "cores")
        cmd = [talus, "bench", "--particles", str(particles), "--threads", str(threads), "--steps", str(steps),
               "--json", f.name, "--stream"] + extra
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
        return json.load(open(f.name))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default="build/talus")
    ap.add_argument("--particles", type=int, default=1000000)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--max-threads", type=int, default=os.cpu_count())
    ap.add_argument("--out", default="docs/performance")
    ap.add_argument("bench_args", nargs="*", help="extra arguments for talus bench (after --)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for kind in ("strong", "weak"):
        for t in thread_counts(a.max_threads):
            n = a.particles if kind == "strong" else a.particles * t
            r = bench(a.talus, n, t, a.steps, a.bench_args)
            rows.append({"kind": kind, "threads": t, "particles": r["particles"],
                         "updates_per_second": r["particle_updates_per_second"],
                         "stream_triad_gb_per_s": r["stream_triad_bytes_per_second"] / 1e9, "cpu": r["cpu"]})
            base = [x for x in rows if x["kind"] == kind][0]
            mpm_speedup = rows[-1]["updates_per_second"] / base["updates_per_second"]
            stream_speedup = rows[-1]["stream_triad_gb_per_s"] / base["stream_triad_gb_per_s"]
            rows[-1]["speedup"] = mpm_speedup
            rows[-1]["stream_speedup"] = stream_speedup
            rows[-1]["speedup_vs_stream"] = mpm_speedup / stream_speedup
            print(f"{kind:6} threads={t:3} particles={r['particles']:9} {r['particle_updates_per_second'] / 1e6:8.3f} M/s"
                  f"  speed-up {mpm_speedup:5.2f}  STREAM {rows[-1]['stream_triad_gb_per_s']:6.2f} GB/s"
                  f" (speed-up {stream_speedup:5.2f})  ratio {mpm_speedup / stream_speedup:5.2f}", flush=True)
    path = os.path.join(a.out, "scaling.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print("wrote", path)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for kind, marker in (("strong", "o"), ("weak", "s")):
        rs = [r for r in rows if r["kind"] == kind]
        base = rs[0]["updates_per_second"]
        threads = [r["threads"] for r in rs]
        speedup = [r["updates_per_second"] / base for r in rs]
        ax1.plot(threads, speedup, marker=marker, label=kind)
        ax2.plot(threads, [s / t for s, t in zip(speedup, threads)], marker=marker, label=kind)
    ax1.plot(threads, threads, "k--", lw=0.8, label="ideal")
    ax1.set(xlabel="threads", ylabel="speed-up (particle-updates/s)", title="talus scaling")
    ax2.set(xlabel="threads", ylabel="efficiency", ylim=(0, 1.1))
    for ax in (ax1, ax2):
        ax.legend()
        ax.grid(alpha=0.3)
    fig.suptitle(rows[0]["cpu"], fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "scaling.png"), dpi=120)
    print("wrote", os.path.join(a.out, "scaling.png"))


if __name__ == "__main__":
    main()
