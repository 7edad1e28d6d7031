#!/usr/bin/env python3
"""The vector kernels against the plain C++ reference, back to back (docs/performance.md, "Vector kernels").

For each case of issue 18's table it runs `talus bench` on the reference path and on the vector
paths, alternating, ROUNDS times, and prints M particle-updates/s and the stress phase; beside them
the minimal MPM step of shared/bench or ../shared/bench (mpm_limit, USL, 2 colour) and the STREAM triad when their
binaries are given, in the same sitting. Results also go to a JSON file (--json), with what measured
them (`provenance`: the talus build and commit, native or portable, CPU, logical CPUs, date, this
command line) and the vector path each --paths value ran (`resolved_paths`: auto's is the best this
CPU has). The summary is the median of the rounds (with an even number of rounds, the mean of the
middle two).

Usage: /usr/bin/python3 tools/bench_kernels.py --talus build/talus [--paths reference,avx2,avx512]
       [--mpm-limit /tmp/mpm_limit] [--stream /tmp/stream] [--particles 1000000] [--rounds 2] [--json out.json]
(build the references with g++ -O3 -march=native -fopenmp ../shared/bench/mpm_limit.cpp -o /tmp/mpm_limit, and
stream.cpp likewise). On a shared machine run it under an exclusive lock and report `uptime`.
"""
import argparse
import os
import re
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import (choices_list, provenance, require_at_least, require_folders, require_talus,  # noqa: E402
                        run_or_stop, utc_now, write_json_atomically)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CASES = [  # name, talus bench arguments
    ("shear, B-spline, DP, MUSL", ["--scene", "shear", "--material", "dp", "--shape", "bspline2"]),
    ("shear, cpGIMP, DP, MUSL", ["--scene", "shear", "--material", "dp", "--shape", "cpgimp"]),
    ("shear, B-spline, DP, USL", ["--scene", "shear", "--material", "dp", "--shape", "bspline2", "--scheme", "usl"]),
    ("block, linear, elastic, MUSL", ["--scene", "block", "--material", "elastic", "--shape", "linear"]),
]


def run(cmd, env=None):
    return run_or_stop(cmd, os.path.basename(str(cmd[0])), env=env).stdout


def vector_paths(talus):
    """The --isa values this binary takes on this CPU: auto and the paths `talus --version` lists
    ("vector paths here: reference, scalar, avx2"); a wrong --paths failed mid-run, after other cases."""
    m = re.search(r"vector paths here: ([^;)]*)", run([talus, "--version"]))
    return ["auto"] + ([p.strip() for p in m.group(1).split(",")] if m else [])


def median(values):
    """The median: the middle value, or the mean of the middle two for an even count (it took
    sorted(v)[n // 2], the upper of two rounds)."""
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def talus_bench(talus, args, path, particles, threads, steps, cpu_time):
    """One bench; returns (M particle-updates/s, stress seconds, the vector path it ran: its first
    line's "..., avx512 kernels, ...", which for --isa auto is the path auto chose)."""
    clock = ["--cpu-time"] if cpu_time else []
    out = run([talus, "bench", *args, "--particles", str(particles), "--threads", str(threads), "--steps", str(steps),
               "--isa", path, *clock], env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    rate = float(re.search(r"([0-9.]+) M particle-updates/s", out).group(1))
    stress = float(re.search(r"stress\s+([0-9.]+) s", out).group(1))
    ran = re.search(r", (\w+) kernels,", out)
    return rate, stress, ran.group(1) if ran else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    # from the repository root, as scaling.py's (it was from the current folder)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--paths", default="reference,avx2,auto")
    ap.add_argument("--mpm-limit", help="binary of ../shared/bench/mpm_limit.cpp")
    ap.add_argument("--stream", help="binary of ../shared/bench/stream.cpp")
    ap.add_argument("--particles", type=int, default=1000000)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--cpu-time", action="store_true",
                    help="talus bench --cpu-time: phases on the process's CPU time (a shared machine, 1 thread)")
    ap.add_argument("--skip", default="",
                    help="case numbers to leave out, comma-separated, 1 = the first case of the table (the names hold commas)")
    ap.add_argument("--json")
    a = ap.parse_args()
    require_at_least(1, particles=a.particles, threads=a.threads, steps=a.steps, rounds=a.rounds)
    try:
        skipped = {int(n) for n in a.skip.split(",") if n.strip()}
    except ValueError:
        sys.exit(f"bench_kernels.py: --skip {a.skip}: give case numbers 1..{len(CASES)}, comma-separated")
    if not skipped <= set(range(1, len(CASES) + 1)):
        sys.exit(f"bench_kernels.py: --skip {a.skip}: the cases are 1..{len(CASES)}: " +
                 "; ".join(f"{i} {name}" for i, (name, _) in enumerate(CASES, start=1)))
    require_talus(a.talus)
    # before the runs, not after: a missing folder, or a folder named as the file (open() failed at the end)
    require_folders(json=a.json)
    paths = choices_list("--paths", a.paths, vector_paths(a.talus))
    for option, binary in (("--mpm-limit", a.mpm_limit), ("--stream", a.stream)):
        if binary:
            require_talus(binary, option)
    started = utc_now()
    print(time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
          "load average %.2f %.2f %.2f" % os.getloadavg(), flush=True)
    results = {"paths": paths, "resolved_paths": {}, "cpu_time": a.cpu_time, "threads": a.threads,
               "particles": a.particles, "steps": a.steps, "rounds": a.rounds, "cases": {}, "mpm_limit": [],
               "stream": []}
    env1 = dict(os.environ, OMP_NUM_THREADS=str(a.threads))
    for rnd in range(a.rounds):
        if a.mpm_limit:  # order 2 (B-spline), 8-colour scatter, 20 steps, 50^3 cells x 8 = 1 M particles, resort 10
            out = run([a.mpm_limit, "2", "colour", "20", "50", "10"], env=env1)
            rate = float(re.search(r"particle-updates/s: ([0-9.e+]+)", out).group(1)) / 1e6
            results["mpm_limit"].append(rate)
            print(f"mpm_limit 2 colour 20 50 10: {rate:.3f} M/s", flush=True)
        if a.stream:
            gbs = float(run([a.stream], env=env1).split()[-1])
            results["stream"].append(gbs)
            print(f"STREAM triad: {gbs:.2f} GB/s", flush=True)
        for number, (name, args) in enumerate(CASES, start=1):
            if number in skipped:
                continue
            row = results["cases"].setdefault(name, {p: [] for p in paths})
            for p in paths:
                rate, stress, ran = talus_bench(a.talus, args, p, a.particles, a.threads, a.steps, a.cpu_time)
                row[p].append({"rate": rate, "stress_seconds": stress, "isa": ran})
                results["resolved_paths"][p] = ran
                print(f"{name:32s} {p + (f' ({ran})' if ran and ran != p else ''):18s} {rate:7.3f} M/s  "
                      f"stress {stress:.3f} s", flush=True)
    print(f"summary (median of {a.rounds} round{'s' if a.rounds > 1 else ''}; ratio to the first path):")
    for name, row in results["cases"].items():
        med = {p: median(r["rate"] for r in row[p]) for p in paths}
        print(f"  {name:32s} " + "  ".join(f"{p} {med[p]:.3f} ({med[p] / med[paths[0]]:.2f}x)" for p in paths))
    usl = results["cases"].get("shear, B-spline, DP, USL")
    if results["mpm_limit"] and usl:
        lim = median(results["mpm_limit"])
        print(f"  mpm_limit median {lim:.3f} M/s; USL B-spline DP / mpm_limit: " +
              "  ".join(f"{p} {median(r['rate'] for r in usl[p]) / lim:.2f}" for p in paths))
    print("load average %.2f %.2f %.2f" % os.getloadavg())
    if a.json:
        # the build from talus --version (the benches print no build); `isa`: each --paths value and the
        # path it ran
        results["provenance"] = provenance(a.talus, {"isa": results["resolved_paths"]}, started)
        write_json_atomically(a.json, results)


if __name__ == "__main__":
    sys.exit(main())
