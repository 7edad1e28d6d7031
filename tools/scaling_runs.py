#!/usr/bin/env python3
"""Strong scaling of whole runs (`talus run SCENE`), as users run them, with the scaling model beside
the measurement: the companion of tools/scaling.py (which times `talus bench`) for the flume scenes.

    tools/scaling_runs.py SCENE[@END] [SCENE[@END] ...] [--end 0.1] [--talus build/talus]
                          [--max-threads N] [--repeat 2] [--out docs/performance] [--name scaling_runs]
                          [--contention-at every|max] [--wait-policy unset|active|passive]

For each scene (its `time.end` replaced by END, or by --end, so that a node's time is not spent on a
4 s run):
  1. a run on 1 thread with `--record-work` (every --record-interval-th step): the model's input;
  2. runs on 1, 2, 4, ... and N threads, --repeat times each, alternating the thread counts, timed by
     the rate the run prints (particle-updates per second of wall time, outputs included);
  3. a run with `--record-work` at each thread count T > 1 (--contention-at every, the default; `max`:
     at N alone, as on the 2026-12-04 node): the per-core slowdown when T cores work,
     c(T) = block seconds per particle at T threads / at 1 thread (tools/scaling_model.py
     --measure-contention), which the work model leaves out;
  4. the model's speed-up at every thread count from the 1-thread record (the run loop's work as its
     run mean), without and with c(T), printed and drawn beside the best measured speed-up. (With c
     measured at N alone, the model takes c = 1 below N: on the node the small flume's 2- and 4-thread
     runs fell 18-31% short of the model, which a c(2), c(4) would show or rule out.)
Threads are pinned as in tools/scaling.py (OMP_PROC_BIND=close, OMP_PLACES=cores unless set; the wait
policy is --wait-policy's, unset by default). Writes
OUT/NAME.json and OUT/NAME.png. On a 16-core node with the default flume with block buffers and the
h = 0.005 m flume (tools/make_flume_scene.py --cell 0.005 --scatter block_buffers) at --end 0.1 and
0.004, it takes a few minutes.
"""
import argparse
import json
import os
import re
import sys
import tempfile
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# from cli_checks, not talus_plot: talus_plot imports numpy, which this tool does not need
from cli_checks import refuse, require_at_least, require_talus, run_or_stop  # noqa: E402
import scaling_model  # noqa: E402
from scaling import add_wait_policy_argument, apply_wait_policy, contention as slowdown, pinned_env, thread_counts  # noqa: E402

RATE = re.compile(r"done: (\d+) steps to t = \S+ s in ([0-9.]+) s \(([0-9.]+) M particle-updates/s\)")


def run(talus, scene, threads, workdir, record=None, interval=7):
    """One `talus run`; returns (steps, wall seconds, particle-updates per second)."""
    cmd = [talus, "run", scene, "--threads", str(threads), "--quiet", "--out", os.path.join(workdir, "out")]
    if record:
        cmd += ["--record-work", record, "--record-interval", str(interval)]
    out = run_or_stop(cmd, "talus run", env=pinned_env()).stdout
    m = RATE.search(out)
    if not m:
        sys.exit(f"no rate in the output of {' '.join(cmd)}:\n{out}")
    return int(m.group(1)), float(m.group(2)), float(m.group(3)) * 1e6


def scene_with_end(path, end, workdir):
    scene = json.load(open(path))
    if end > 0:
        scene.setdefault("time", {})["end"] = end
    copy = os.path.join(workdir, os.path.basename(path))
    json.dump(scene, open(copy, "w"), indent=1)
    return copy, scene.get("name", os.path.basename(path))


def model_speedups(record, counts, contention=None):
    barrier = scaling_model.Barrier(record["fork_join_seconds"], 1e-6)
    rows = scaling_model.model(scaling_model.with_run_mean_output(record), counts, barrier, "recorded", "robust",
                               contention=contention)
    return {r["threads"]: r["speedup"] for r in rows}


def scene_spec(spec, default_end):
    """SCENE[@END] as (path, end), checked before any run: a missing scene file was a FileNotFoundError
    and SCENE@abc a ValueError, after the runs of the scenes before it."""
    path, at, end = spec.partition("@")
    if not os.path.isfile(path):
        what = "is a folder, not a file" if os.path.isdir(path) else "no such file"
        refuse("SCENE", spec, what if path == spec else f"{path}: {what}")
    if not at:
        return path, default_end
    try:
        value = float(end)
    except ValueError:
        value = -1.0
    if not value >= 0 or value == float("inf"):
        refuse("SCENE@END", spec, "END is the simulated seconds of the run, a number 0 or more (0: the scene's own)")
    return path, value


def measure(a, spec, counts, workdir):
    path, end = spec
    scene, _ = scene_with_end(path, end, workdir)
    name = os.path.splitext(os.path.basename(path))[0]
    rec1, recn = os.path.join(workdir, "record_1.json"), os.path.join(workdir, "record_t.json")
    run(a.talus, scene, 1, workdir, rec1, a.record_interval)
    rates = {t: [] for t in counts}
    for _ in range(a.repeat):
        for t in counts:
            rates[t].append(run(a.talus, scene, t, workdir)[2])
    r1 = json.load(open(rec1))
    contention = {}
    for t in (counts[1:] if a.contention_at == "every" else counts[-1:]):
        if t > 1:
            run(a.talus, scene, t, workdir, recn, a.record_interval)
            contention[t] = slowdown(r1, json.load(open(recn)))
    plain = model_speedups(r1, counts)
    with_c = model_speedups(r1, counts, contention) if contention else plain
    base = max(rates[1])
    rows = [{"threads": t, "rates": rates[t], "best_speedup": max(rates[t]) / base, "model_speedup": plain[t],
             "model_speedup_with_contention": with_c[t]} for t in counts]
    return {"scene": name, "file": path, "end": end, "particles": r1["steps"][0]["particles"],
            "contention": {str(t): c for t, c in contention.items()} or {"1": 1.0},
            "fork_join_seconds": r1["fork_join_seconds"], "rows": rows}


def plot(results, path, env):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for i, res in enumerate(results):
        t = [r["threads"] for r in res["rows"]]
        ax.plot(t, [r["best_speedup"] for r in res["rows"]], "o-", color=f"C{i}", label=f"{res['scene']}: measured")
        ax.plot(t, [r["model_speedup"] for r in res["rows"]], "x--", color=f"C{i}", label="model")
        top_t, top_c = list(res["contention"].items())[-1]
        ax.plot(t, [r["model_speedup_with_contention"] for r in res["rows"]], ":", color=f"C{i}",
                label=f"model with c(T) ({len(res['contention'])} measured; c({top_t}) = {top_c:.2f})")
    top = max(r["threads"] for res in results for r in res["rows"])
    ax.plot([1, top], [1, top], "k--", lw=0.8, label="ideal")
    ticks = sorted({r["threads"] for res in results for r in res["rows"]})
    ax.set(xscale="log", yscale="log", xlabel="threads", ylabel="speed-up (particle-updates/s of the run)")
    ax.set_xticks(ticks, [str(t) for t in ticks])
    ax.set_yticks(ticks, [str(t) for t in ticks])
    ax.minorticks_off()
    ax.set_title(f"talus run, strong scaling\nOMP_PROC_BIND={env['OMP_PROC_BIND']} OMP_PLACES={env['OMP_PLACES']} "
                 f"OMP_WAIT_POLICY={env.get('OMP_WAIT_POLICY', 'unset')}, "
                 f"{os.cpu_count()} CPUs", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print("wrote", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+", help="scene files (JSON), each optionally with @END (simulated seconds)")
    ap.add_argument("--talus", default="build/talus")
    ap.add_argument("--end", type=float, default=0.1, help="simulated seconds of each run (0: the scene's own)")
    ap.add_argument("--max-threads", type=int, default=os.cpu_count())
    ap.add_argument("--repeat", type=int, default=2, help="runs per thread count (all kept; the best is compared)")
    ap.add_argument("--record-interval", type=int, default=7, help="steps between recorded steps")
    ap.add_argument("--contention-at", choices=["every", "max"], default="every",
                    help="thread counts with a record for c(T): every count above 1, or the largest alone")
    ap.add_argument("--out", default="docs/performance")
    ap.add_argument("--name", default="scaling_runs", help="file stem of the JSON and PNG")
    add_wait_policy_argument(ap)
    a = ap.parse_args()
    require_at_least(1, max_threads=a.max_threads, repeat=a.repeat, record_interval=a.record_interval)
    require_at_least(0, end=a.end)
    specs = [scene_spec(s, a.end) for s in a.scenes]
    require_talus(a.talus)
    wait_policy = apply_wait_policy(a.wait_policy)
    counts = thread_counts(a.max_threads)
    os.makedirs(a.out, exist_ok=True)
    results = []
    for spec in specs:
        with tempfile.TemporaryDirectory() as workdir:
            res = measure(a, spec, counts, workdir)
        results.append(res)
        cs = ", ".join(f"c({t}) = {c:.3f}" for t, c in res["contention"].items())
        print(f"{res['scene']} ({res['particles']} particles, to {res['end']} s): {cs}")
        for r in res["rows"]:
            print(f"  {r['threads']:4} threads  best {max(r['rates']) / 1e6:7.3f} M/s  speed-up {r['best_speedup']:6.2f}"
                  f"  model {r['model_speedup']:6.2f}  with c {r['model_speedup_with_contention']:6.2f}", flush=True)
    env = pinned_env()
    out = os.path.join(a.out, a.name + ".json")
    with open(out, "w") as f:
        json.dump({"omp_proc_bind": env["OMP_PROC_BIND"], "omp_places": env["OMP_PLACES"],
                   "omp_wait_policy": wait_policy, "nproc": os.cpu_count(), "results": results}, f, indent=1)
    print("wrote", out)
    plot(results, os.path.join(a.out, a.name + ".png"), env)


if __name__ == "__main__":
    main()
