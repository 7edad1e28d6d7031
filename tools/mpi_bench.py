#!/usr/bin/env python3
"""2 ranks x 1 thread against 1 rank x 2 threads (issue 20's target), back to back on one machine.

Runs `talus bench` (default: the 1 M-particle block, linear, elastic, MUSL, 10 timed steps, as
docs/performance.md) in rounds, each round every layout once, the order rotated from round to
round so that no layout always goes first:
  1x2        1 rank,  2 threads  (no mpirun; OMP_PROC_BIND=close OMP_PLACES=cores)
  2x1-bound  2 ranks, 1 thread   (mpirun -np 2 --bind-to core)
  2x1-free   2 ranks, 1 thread   (mpirun -np 2 --bind-to none; no OpenMP binding either)
  1x1        1 rank,  1 thread   (no mpirun; OMP_PROC_BIND=close OMP_PLACES=cores)
  1x2+keep, 2x1-bound+keep: the same with glibc told to keep freed memory (GLIBC_TUNABLES, below)
In the same session: the STREAM triad and mpm_limit (../shared/bench) at 1 and 2 threads, and the
MPI message costs (tools/mpi_message_costs.cpp, built by hand), before and after the rounds.
The load average is recorded beside every run. Run it under `flock -x` on a shared machine:

  flock -x /work/quiet.lock /usr/bin/python3 tools/mpi_bench.py --talus build/talus --rounds 3 \
      --stream /tmp/stream --mpm-limit /tmp/mpm_limit --message-costs /tmp/mpi_message_costs \
      --json docs/performance/mpi_bench.json

Writes every bench's JSON, with what measured them (`provenance`: the talus build and commit, the
vector path, CPU, logical CPUs, date, this command line), and prints the medians, the ratio 2x1 / 1x2
and the per-phase largest and mean over the ranks (docs/performance.md, "Distributed runs (MPI)").
A reference not given (--stream, --mpm-limit) is printed as "not measured" and left out of the JSON.
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# from cli_checks, not talus_plot: talus_plot imports numpy, which this tool does not need
from cli_checks import (choices_list, cpu_model, provenance, require_at_least, require_folders,  # noqa: E402
                        require_talus, write_json_atomically)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
PINNED = {"OMP_PROC_BIND": "close", "OMP_PLACES": "cores"}
PHASES = ["sort", "p2g", "grid", "g2p", "remap", "smooth", "stress", "output", "other"]


# "+keep": glibc keeps freed memory (no trimming, no fresh mmap per large buffer), so that a buffer
# allocated anew each step reuses pages instead of faulting fresh ones in. On this VM a fresh page
# can cost ~30 us; the A/B measures what the per-step allocations of the exchange cost.
KEEP = "glibc.malloc.mmap_threshold=1073741824:glibc.malloc.trim_threshold=4294967296"


def layouts(talus):
    bound = ["mpirun", "-np", "2", "--bind-to", "core"]
    return {
        "1x2": ([talus], 2, PINNED),
        "2x1-bound": (bound + [talus], 1, {}),
        "2x1-free": (["mpirun", "-np", "2", "--bind-to", "none", talus], 1, {}),
        "1x1": ([talus], 1, PINNED),
        "1x2+keep": ([talus], 2, dict(PINNED, GLIBC_TUNABLES=KEEP)),
        "2x1-bound+keep": (bound + ["-x", "GLIBC_TUNABLES=" + KEEP, talus], 1, {}),
    }


def clean_env(extra, threads):
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_PROC_BIND", "OMP_PLACES")}
    env.update(MPI_ENV)
    env.update(extra)
    env["OMP_NUM_THREADS"] = str(threads)
    return env


def run(cmd, env):
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stdout}\n{r.stderr}")
    return r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    # from the repository root, as scaling.py's (it was from the current folder)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--bench-args", default="--scene block --particles 1000000 --shape linear --material elastic --mls off --steps 10")
    ap.add_argument("--layouts", default="1x2,2x1-bound,2x1-free,1x1")
    ap.add_argument("--stream", help="binary of ../shared/bench/stream.cpp")
    ap.add_argument("--mpm-limit", help="binary of ../shared/bench/mpm_limit.cpp (run as: 1 colour 20 50 10, linear)")
    ap.add_argument("--message-costs", help="binary of tools/mpi_message_costs.cpp")
    ap.add_argument("--json")
    a = ap.parse_args()
    require_at_least(1, rounds=a.rounds)
    require_talus(a.talus)
    for option, binary in (("--stream", a.stream), ("--mpm-limit", a.mpm_limit), ("--message-costs", a.message_costs)):
        if binary:
            require_talus(binary, option)
    require_folders(json=a.json)
    try:
        bench_args = shlex.split(a.bench_args)
    except ValueError as e:
        sys.exit(f"mpi_bench.py: --bench-args {a.bench_args}: {e}")
    if any(x == "--cpu-time" or x.startswith("--cpu-time=") for x in bench_args):
        # (the layouts are compared on the wall clock; under --cpu-time the bench writes cpu_seconds)
        sys.exit("mpi_bench.py: --bench-args --cpu-time: the layouts are compared on the wall clock: leave it out")
    all_layouts = layouts(a.talus)
    # checked before the reference runs: a wrong name was a KeyError after them
    names = choices_list("--layouts", a.layouts, list(all_layouts))
    results = {"started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), "bench_args": a.bench_args,
               # (not every CPU has a "model name" line: the split was an IndexError there)
               "cpu": cpu_model(),
               "nproc": os.cpu_count(), "references": [], "message_costs": [], "runs": []}
    print(results["started"], "load", os.getloadavg(), flush=True)

    def busy():  # what else holds a CPU now (a shared machine: the lock keeps out builds, not everything)
        ps = subprocess.run(["ps", "-eo", "pcpu,etime,args", "--sort=-pcpu"], capture_output=True, text=True).stdout
        return [line.strip()[:160] for line in ps.splitlines()[1:6]]

    results["busy_at_start"] = busy()

    def references(when):
        for threads in (1, 2):
            env = clean_env(PINNED, threads)
            entry = {"when": when, "threads": threads, "load": os.getloadavg()}
            if a.stream:
                entry["stream_gb_per_s"] = float(run([a.stream], env).split()[-1])
            if a.mpm_limit:
                out = run([a.mpm_limit, "1", "colour", "20", "50", "10"], env)
                entry["mpm_limit_linear_m_per_s"] = float(re.search(r"particle-updates/s: ([0-9.e+]+)", out).group(1)) / 1e6
            results["references"].append(entry)
            # a reference not run is "not measured", not 0.00 GB/s
            stream = f"{entry['stream_gb_per_s']:.2f} GB/s" if "stream_gb_per_s" in entry else "not measured"
            limit = (f"{entry['mpm_limit_linear_m_per_s']:.3f} M/s" if "mpm_limit_linear_m_per_s" in entry
                     else "not measured")
            print(f"  {when} {threads} thread(s): STREAM {stream}, mpm_limit linear {limit}, "
                  f"load {entry['load'][0]:.2f}", flush=True)
        if a.message_costs:
            out = run(["mpirun", "-np", "2", "--bind-to", "core", a.message_costs], clean_env({}, 1))
            costs = json.loads(out)
            costs["when"] = when
            results["message_costs"].append(costs)
            pp = {p["bytes"]: p["seconds"] for p in costs["pingpong"]}
            print(f"  {when} MPI ping-pong: 8 B {pp[8] * 1e6:.2f} us, 2 MiB {2097152 / pp[2097152] / 1e9:.2f} GB/s; "
                  f"allgather 24 B {costs['allgather_24_bytes_seconds'] * 1e6:.2f} us", flush=True)

    references("before")
    with tempfile.TemporaryDirectory() as tmp:
        for rnd in range(a.rounds):
            order = names[rnd % len(names):] + names[:rnd % len(names)]
            for name in order:
                prefix, threads, extra = all_layouts[name]
                out_json = os.path.join(tmp, f"{name}_{rnd}.json")
                load = os.getloadavg()
                run(prefix + ["bench"] + bench_args + ["--threads", str(threads), "--json", out_json],
                    clean_env(extra, threads))
                b = json.load(open(out_json))
                results["runs"].append({"layout": name, "round": rnd, "load": load, "bench": b})
                print(f"round {rnd} {name:10s} {b['particle_updates_per_second'] / 1e6:7.3f} M/s  "
                      f"({b.get('ranks', 1)} x {b['threads']}, {b.get('exchange_bytes_per_step', 0) / 1e3:.1f} kB/step, "
                      f"load {load[0]:.2f})", flush=True)
    references("after")
    results["busy_at_end"] = busy()
    results["ended"] = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())

    def median(v):
        v = sorted(v)
        return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])

    summary = {}
    for name in names:
        runs = [r["bench"] for r in results["runs"] if r["layout"] == name]
        summary[name] = {
            "rates_m_per_s": [r["particle_updates_per_second"] / 1e6 for r in runs],
            "median_m_per_s": median([r["particle_updates_per_second"] / 1e6 for r in runs]),
            "phases_max": {p: median([r["phases_max"][p] for r in runs]) for p in PHASES},
            "phases_mean": {p: median([r["phases_mean"][p] for r in runs]) for p in PHASES},
            "wall_seconds": median([r["wall_seconds"] for r in runs]),
            "exchange_bytes_per_step": median([r["exchange_bytes_per_step"] for r in runs]),
            "imbalance": median([r["imbalance"] for r in runs]),
            "shared_tiles": median([r["shared_tiles"] for r in runs]),
        }
    results["summary"] = summary
    print("summary (medians over the rounds):")
    for name, s in summary.items():
        print(f"  {name:10s} {s['median_m_per_s']:7.3f} M/s  runs " + ", ".join(f"{x:.3f}" for x in s["rates_m_per_s"]))
    if "1x2" in summary:
        for name in ("2x1-bound", "2x1-free"):
            if name in summary:
                ratio = summary[name]["median_m_per_s"] / summary["1x2"]["median_m_per_s"]
                results.setdefault("ratios_to_1x2", {})[name] = ratio
                print(f"  {name} / 1x2 = {ratio:.3f}")
    # the timed steps as the benches report them: splitting the arguments on "--steps" printed the rest
    # of the line when --steps was not last, and nothing when it was left to talus's default
    steps = sorted({r["bench"].get("steps") for r in results["runs"]} - {None})
    steps_text = " or ".join(str(x) for x in steps) if steps else "the timed"
    print(f"  per phase, seconds over {steps_text} steps: max over ranks (mean)")
    print("  " + "phase".ljust(8) + "".join(n.rjust(20) for n in names))
    for p in PHASES:
        print("  " + p.ljust(8) + "".join(f"{summary[n]['phases_max'][p]:10.4f} ({summary[n]['phases_mean'][p]:6.4f})" for n in names))
    print("  " + "wall".ljust(8) + "".join(f"{summary[n]['wall_seconds']:10.4f}         " for n in names))
    print("load", os.getloadavg(), results["ended"])
    if a.json:
        # what measured it, from the first bench's own record (build, vector path, CPU)
        results["provenance"] = provenance(a.talus, results["runs"][0]["bench"] if results["runs"] else None,
                                           results["started"].replace(" UTC", "Z").replace(" ", "T"))
        write_json_atomically(a.json, results)


if __name__ == "__main__":
    sys.exit(main())
