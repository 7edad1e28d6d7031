#!/usr/bin/env python3
"""Strong and weak scaling of talus: runs `talus bench` over thread counts, writes CSV, JSON and plots,
with the scaling model's prediction (tools/scaling_model.py) drawn beside the measurement.

    tools/scaling.py [--talus build/talus] [--particles 1000000] [--steps 10] [--max-threads N]
                     [--out runs/scaling] [--name scaling] [--wait-policy unset|active|passive]
                     [-- extra talus bench arguments]

The outputs go to runs/scaling under the current folder unless --out names another folder
(docs/performance holds committed results: name it to replace them).

Strong scaling: fixed particle count, threads 1..N (powers of two and N).
Weak scaling: particles proportional to the thread count.
Threads are pinned with OMP_PROC_BIND=close and OMP_PLACES=cores (set them yourself to override; the
values used are written to the JSON; OMP_WAIT_POLICY is --wait-policy's, unset by default, whatever
the environment says): `close` keeps thread t on core t, so 1..N threads fill the first
socket before the second, and STREAM and talus see the same cores. On a multi-socket node, compare
with OMP_PROC_BIND=spread (threads spread over the sockets: more bandwidth at low counts). The particle
arrays are seeded by one thread, so their pages all land on that thread's NUMA node; the transfers hand
blocks out dynamically, so no thread keeps the same particles anyway. On a multi-socket node run under
`numactl --interleave=all` (Debian package numactl) to spread the pages over every node's memory
controller; docs/performance.md ("Memory placement on a multi-socket node") says why and what is not measured.
Runs unchanged on 2 to 128 cores; thread counts are 1, 2, 4, ... and nproc.
The model: `talus bench --record-work` at 1 thread (strong scaling size) records the work of every
block and region; tools/scaling_model.py replays it for each thread count (its fork/join costs are
measured in the same run up to nproc). The prediction is the 1-thread rate times the model's speed-up.
A record at every other strong-scaling count T gives the per-core slowdown when T cores work,
c(T) = block seconds per particle at T threads / at 1 thread, which the work model leaves out; the
model with c(T) is drawn beside the one without (on the 2026-12-04 node the 1 M benches fell 25-50%
short of the work model at 16 threads: that slowdown).
Each bench also measures the STREAM triad at the same thread count (`talus bench --stream`), so the
CSV shows the MPM speed-up next to the memory-bandwidth speed-up of the same machine in the same run:
`speedup_vs_stream` = (MPM speed-up) / (STREAM speed-up), the issue's target being >= 0.9 at 2 threads.
A scaling study is of wall-clock time: --cpu-time among the bench arguments is refused (its per-core-
second rates make no speed-up, and STREAM's is of the wall clock).
The CSV and JSON record what measured them: the talus build and commit, native or portable, the
vector path that ran, CPU model, logical CPUs, the date (UTC) and this command line.
"""
import argparse
import csv
import json
import os
import shlex
import sys
import tempfile
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# from cli_checks, not talus_plot: talus_plot imports numpy, which this tool does not need
from cli_checks import (output_folder, provenance, refuse, require_at_least, require_talus, run_or_stop,  # noqa: E402
                        utc_now, write_json_atomically)
import scaling_model  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def thread_counts(max_threads):
    counts, t = [], 1
    while t < max_threads:
        counts.append(t)
        t *= 2
    counts.append(max_threads)
    return counts


def speedup_ticks(lo, hi):
    """Ticks for a log axis of speed-ups from lo to hi: 1, 2, 4, ... alone left a x1.23 and a x1.86 on
    2 threads between the only two ticks; readable steps in between, fewer as the range grows."""
    steps = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1, 1.2, 1.4, 1.6, 1.8, 2, 2.5, 3, 4, 5, 6, 8]
    if hi / max(lo, 1e-9) > 8:  # a node's range: 1 2 4 8 16 ...
        steps = [0.125, 0.25, 0.5, 1, 2, 3, 4, 6, 8]
    ticks = []
    scale = 1.0
    while scale <= 1024:
        ticks += [v * scale for v in steps if lo / 1.05 <= v * scale <= hi * 1.05]
        scale *= 10
    return sorted(set(round(t, 6) for t in ticks)) or [1.0]


def pinned_env():
    env = dict(os.environ)
    env.setdefault("OMP_PROC_BIND", "close")
    env.setdefault("OMP_PLACES", "cores")
    return env


def add_wait_policy_argument(ap):
    ap.add_argument("--wait-policy", choices=["unset", "active", "passive"], default="unset",
                    help="OMP_WAIT_POLICY of every run; unset (the default): libgomp's own, threads spin a while "
                         "before they sleep, as users run. An OMP_WAIT_POLICY in the environment is ignored "
                         "unless given here: with PASSIVE every parallel region wakes sleeping threads, which "
                         "cost 11-15 us at 2 and 38-218 us at 16 threads on the 16-core VM of 2026-12-04, and "
                         "the measurement is then of that, not of talus")


def apply_wait_policy(policy):
    """Sets (or removes) OMP_WAIT_POLICY for the runs this process starts; returns the value used."""
    inherited = os.environ.pop("OMP_WAIT_POLICY", None)
    if policy != "unset":
        os.environ["OMP_WAIT_POLICY"] = policy.upper()
    elif inherited:
        print(f"note: OMP_WAIT_POLICY={inherited} from the environment is not used (--wait-policy unset)",
              file=sys.stderr)
    return os.environ.get("OMP_WAIT_POLICY", "unset")


def contention(record_1, record_t):
    """c(T): block seconds per particle of a record at T threads over those of one at 1 thread
    (tools/scaling_model.py --measure-contention)."""
    return scaling_model.block_seconds_per_particle(record_t) / scaling_model.block_seconds_per_particle(record_1)


def bench(talus, particles, threads, steps, extra, record=None):
    with tempfile.NamedTemporaryFile(suffix=".json") as f:
        cmd = [talus, "bench", "--particles", str(particles), "--threads", str(threads), "--steps", str(steps),
               "--json", f.name, "--stream"] + extra
        if record:
            cmd += ["--record-work", record, "--record-steps", "3"]
        run_or_stop(cmd, "talus bench", env=pinned_env(), keep_stdout=False)
        return json.load(open(f.name))


def model_speedups(record_path, counts, contention_by_threads=None):
    record = json.load(open(record_path))
    barrier = scaling_model.Barrier(record["fork_join_seconds"], 1e-6)
    rows = scaling_model.model(record, counts, barrier, "recorded", "robust", contention=contention_by_threads)
    return {r["threads"]: r for r in rows}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    # the defaults from the repository root, as speed_vs_error.py's (they were from the current folder)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--particles", type=int, default=1000000)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--max-threads", type=int, default=os.cpu_count())
    ap.add_argument("--out", default=os.path.join("runs", "scaling"), help="folder of the outputs "
                    "(default: runs/scaling under the current folder; it was docs/performance, whose committed "
                    "results the documented command replaced)")
    ap.add_argument("--name", default="scaling", help="file stem of the CSV, JSON and PNG")
    ap.add_argument("--repeat", type=int, default=1, help="runs per point (the best is kept; all are in the JSON)")
    add_wait_policy_argument(ap)
    ap.add_argument("bench_args", nargs="*", help="extra arguments for talus bench (after --)")
    a = ap.parse_args()
    require_at_least(1, particles=a.particles, steps=a.steps, max_threads=a.max_threads, repeat=a.repeat)
    if any(x == "--cpu-time" or x.startswith("--cpu-time=") for x in a.bench_args):
        # per-core-second rates make no speed-up, and they were divided by STREAM's wall-clock one
        refuse("--cpu-time", "(a bench argument)", "a scaling study is of wall-clock time: leave --cpu-time out")
    scene = next((x.split("=", 1)[1] for x in a.bench_args if x.startswith("--scene=")), None)
    if "--scene" in a.bench_args[:-1]:
        scene = a.bench_args[a.bench_args.index("--scene") + 1]
    if scene == "update":
        # the model needs a work record, which talus bench --scene update does not write
        refuse("--scene", scene, "talus bench --scene update writes no work record (--record-work), which the "
                                 "model needs: use talus bench --scene update --threads T directly")
    require_talus(a.talus)
    output_folder("--out", a.out)  # (a file of that name was a traceback; checked before the note below)
    wait_policy = apply_wait_policy(a.wait_policy)
    counts = thread_counts(a.max_threads)
    started = utc_now()
    first_bench = None
    record_path = os.path.join(a.out, a.name + "_record.json")
    record_t_path = os.path.join(a.out, a.name + "_record_t.json")
    rows = []
    predicted, with_c, c_t = {}, {}, {}
    for kind in ("strong", "weak"):
        for t in counts:
            n = a.particles if kind == "strong" else a.particles * t
            # strong scaling records at 1 thread (the model's input) and at every T > 1 (c(T), below)
            record = (record_path if t == 1 else record_t_path) if kind == "strong" else None
            runs = [bench(a.talus, n, t, a.steps, a.bench_args, record if i == 0 else None) for i in range(a.repeat)]
            if kind == "strong" and t == 1:
                predicted = model_speedups(record_path, counts)
            elif kind == "strong":
                # the per-core slowdown when T cores work, which the work model leaves out
                c_t[t] = contention(json.load(open(record_path)), json.load(open(record_t_path)))
            if kind == "strong" and t == counts[-1]:
                with_c = model_speedups(record_path, counts, c_t or None)
                if os.path.exists(record_t_path):
                    os.remove(record_t_path)
            r = max(runs, key=lambda x: x["particle_updates_per_second"])
            first_bench = first_bench or r
            rows.append({"kind": kind, "threads": t, "particles": r["particles"],
                         "updates_per_second": r["particle_updates_per_second"],
                         "all_updates_per_second": [x["particle_updates_per_second"] for x in runs],
                         "stream_triad_gb_per_s": r["stream_triad_bytes_per_second"] / 1e9, "cpu": r["cpu"],
                         # the vector path this bench ran (each bench says its own)
                         "isa": r.get("isa")})
            base = [x for x in rows if x["kind"] == kind][0]
            mpm_speedup = rows[-1]["updates_per_second"] / base["updates_per_second"]
            stream_speedup = rows[-1]["stream_triad_gb_per_s"] / base["stream_triad_gb_per_s"]
            rows[-1]["speedup"] = mpm_speedup
            rows[-1]["stream_speedup"] = stream_speedup
            rows[-1]["speedup_vs_stream"] = mpm_speedup / stream_speedup
            if kind == "strong":
                rows[-1]["model_speedup"] = predicted[t]["speedup"]
                rows[-1]["model_limit"] = predicted[t]["limit"]
            print(f"{kind:6} threads={t:3} particles={r['particles']:9} {r['particle_updates_per_second'] / 1e6:8.3f} M/s"
                  f"  speed-up {mpm_speedup:5.2f}  STREAM {rows[-1]['stream_triad_gb_per_s']:6.2f} GB/s"
                  f" (speed-up {stream_speedup:5.2f})  ratio {mpm_speedup / stream_speedup:5.2f}", flush=True)
    # what measured it, from the first bench's own record (build, vector path, CPU)
    prov = provenance(a.talus, first_bench, started)
    path = os.path.join(a.out, a.name + ".csv")
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields and k != "all_updates_per_second"]
    # the provenance on every row, so that the CSV alone says what measured it
    csv_prov = {"commit": prov["talus"].get("commit"), "build": prov["build"], "logical_cpus": prov["logical_cpus"],
                "date_utc": prov["date_utc"], "command": shlex.join(prov["command"])}
    fields += list(csv_prov)
    try:  # written beside and renamed into place: no half-written CSV
        with open(path + ".part", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
            w.writeheader()
            w.writerows(dict(r, **csv_prov) for r in rows)
        os.replace(path + ".part", path)
    finally:
        if os.path.exists(path + ".part"):
            os.remove(path + ".part")
    print("wrote", path)
    for r in rows:
        if r["kind"] == "strong":
            r["model_speedup_with_contention"] = with_c[r["threads"]]["speedup"]
    print("strong scaling, the measured per-core slowdown: " + (", ".join(f"c({t}) = {c:.3f}" for t, c in c_t.items())
                                                                or "none (1 thread)"))
    print("the model with it: " + ", ".join(f"{t}: {with_c[t]['speedup']:.2f}" for t in counts))
    env = pinned_env()
    write_json_atomically(os.path.join(a.out, a.name + ".json"), {
        "provenance": prov, "omp_proc_bind": env["OMP_PROC_BIND"], "omp_places": env["OMP_PLACES"],
        "omp_wait_policy": wait_policy, "nproc": os.cpu_count(),
        "bench_args": a.bench_args, "particles": a.particles, "steps": a.steps, "rows": rows,
        "contention": {str(t): c for t, c in c_t.items()},
        "model": {str(t): v for t, v in predicted.items()},
        "model_with_contention": {str(t): v for t, v in with_c.items()}})
    print("wrote", os.path.join(a.out, a.name + ".json"))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    # one colour per kind in both panels (the automatic cycle gave "weak" C2 on the left, C1 on the right)
    for kind, marker, colour in (("strong", "o", "C0"), ("weak", "s", "C1")):
        rs = [r for r in rows if r["kind"] == kind]
        base = rs[0]["updates_per_second"]
        threads = [r["threads"] for r in rs]
        speedup = [r["updates_per_second"] / base for r in rs]
        ax1.plot(threads, speedup, marker=marker, color=colour, label=kind)
        ax2.plot(threads, [s / t for s, t in zip(speedup, threads)], marker=marker, color=colour, label=kind)
        stream = [r["stream_speedup"] for r in rs]
        ax1.plot(threads, stream, marker=marker, ls=":", lw=0.9, color=colour, alpha=0.6, label=f"STREAM ({kind})")
    threads = counts
    model = [predicted[t]["speedup"] for t in threads]
    ax1.plot(threads, model, "x--", color="C3", label="model (strong)")
    ax2.plot(threads, [m / t for m, t in zip(model, threads)], "x--", color="C3", label="model (strong)")
    model_c = [with_c[t]["speedup"] for t in threads]
    label_c = "model with the measured c(T)" + (f" (c({counts[-1]}) = {c_t[counts[-1]]:.2f})" if c_t else "")
    ax1.plot(threads, model_c, ":", color="C3", label=label_c)
    ax2.plot(threads, [m / t for m, t in zip(model_c, threads)], ":", color="C3", label=label_c)
    ax1.plot(threads, threads, "k--", lw=0.8, label="ideal")
    ax1.set(xlabel="threads", ylabel="speed-up over 1 thread (ratio of particle-updates/s)", title="talus scaling")
    ax2.set(xlabel="threads", ylabel="efficiency", ylim=(0, 1.1))
    for ax in (ax1, ax2):
        ax.legend()
        ax.grid(alpha=0.3)
    fig.suptitle(f"talus bench {' '.join(a.bench_args) or 'block, linear, elastic'}: {a.particles} particles "
                 f"(strong; weak: per thread), {a.steps} steps; commit {prov['talus'].get('commit', '?')} "
                 f"{prov['build']}, {prov['isa']}, {prov['date_utc'][:10]}\n"
                 f"{rows[0]['cpu']}, {prov['logical_cpus']} CPUs, OMP_PROC_BIND={env['OMP_PROC_BIND']} "
                 f"OMP_PLACES={env['OMP_PLACES']} OMP_WAIT_POLICY={wait_policy}", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, a.name + ".png"), dpi=120)
    print("wrote", os.path.join(a.out, a.name + ".png"))


if __name__ == "__main__":
    main()
