#!/usr/bin/env python3
"""Strong scaling of whole runs (`talus run SCENE`), as users run them, with the scaling model beside
the measurement: the companion of tools/scaling.py (which times `talus bench`) for the flume scenes.

    tools/scaling_runs.py SCENE[@END] [SCENE[@END] ...] [--end 0.1] [--talus build/talus]
                          [--max-threads N] [--repeat 2] [--out runs/scaling] [--name scaling_runs]
                          [--contention-at every|max] [--wait-policy unset|active|passive]

For each scene (its `time.end` replaced by END, or by --end, so that a node's time is not spent on a
4 s run):
  1. a run on 1 thread with `--record-work` (every --record-interval-th step): the model's input;
  2. runs on 1, 2, 4, ... and N threads, --repeat times each, alternating the thread counts, timed by
     the rate the run records in its run.json (end.particle_updates_per_second: particle-updates per
     second of wall time, outputs included; the printed line, rounded to 0.01 M/s, only for a talus
     that writes no run.json);
  3. a run with `--record-work` at each thread count T > 1 (--contention-at every, the default; `max`:
     at N alone, as on the 2026-12-04 node): the per-core slowdown when T cores work,
     c(T) = block seconds per particle at T threads / at 1 thread (tools/scaling_model.py
     --measure-contention), which the work model leaves out;
  4. the model's speed-up at every thread count from the 1-thread record (the run loop's work as its
     run mean), without and with c(T), printed and drawn beside the best measured speed-up. (With c
     measured at N alone, the model takes c = 1 below N: on the node the small flume's 2- and 4-thread
     runs fell 18-31% short of the model, which a c(2), c(4) would show or rule out.)
Threads are pinned as in tools/scaling.py (OMP_PROC_BIND=close, OMP_PLACES=cores unless set; the wait
policy is --wait-policy's, unset by default). Every scene file is read and checked before the first
run. Writes OUT/NAME.json (with what measured it: the talus build and commit, the vector path, CPU,
date, this command line) and OUT/NAME.png; OUT is runs/scaling under the current folder unless given
(docs/performance holds committed results: name it to replace them). On a 16-core node with the default flume with block buffers and the
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
from cli_checks import (output_folder, provenance, refuse, require_at_least, require_talus, run_or_stop,  # noqa: E402
                        utc_now, write_json_atomically)
import scaling_model  # noqa: E402
from scaling import (ROOT, add_wait_policy_argument, apply_wait_policy, contention as slowdown, pinned_env,  # noqa: E402
                     speedup_ticks, thread_counts)

RATE = re.compile(r"done: (\d+) steps to t = \S+ s in ([0-9.]+) s \(([0-9.]+) M particle-updates/s\)")


def run(talus, scene, threads, workdir, record=None, interval=7):
    """One `talus run`; returns (steps, wall seconds, particle-updates per second, its run.json or None).
    The rate is run.json's: the printed line rounds it to 0.01 M/s (0.29 M/s, stored as 290000.0, for
    a small scene's 0.2937)."""
    out_dir = os.path.join(workdir, "out")
    cmd = [talus, "run", scene, "--threads", str(threads), "--quiet", "--out", out_dir]
    if record:
        cmd += ["--record-work", record, "--record-interval", str(interval)]
    return run_timing(cmd, out_dir, run_or_stop(cmd, "talus run", env=pinned_env()).stdout)


def run_timing(cmd, out_dir, stdout):
    """(steps, wall seconds, particle-updates per second, run.json or None) of a finished `talus run`
    (cmd) into out_dir: from its run.json, else from the line it printed (stdout)."""
    try:
        with open(os.path.join(out_dir, "run.json")) as f:
            rec = json.load(f)
        end = rec["end"]
        # the stepping loop's seconds, which the rate divides by (the record's wall_seconds adds the
        # setup and the closing outputs; records before 2026-12-07 have only that)
        wall = end.get("stepping_wall_seconds", rec["wall_seconds"])
        return int(end["steps_this_part"]), float(wall), float(end["particle_updates_per_second"]), rec
    except (OSError, ValueError, KeyError, TypeError):
        pass  # a talus that writes no run.json (or an older one without these keys): the printed line
    m = RATE.search(stdout)
    if not m:
        sys.exit(f"{os.path.basename(sys.argv[0])}: no rate in run.json nor in the output of {' '.join(cmd)}")
    return int(m.group(1)), float(m.group(2)), float(m.group(3)) * 1e6, None


def scene_with_end(path, scene, end, workdir):
    """A copy of the (parsed) scene in workdir with its time.end replaced by end (> 0)."""
    scene = json.loads(json.dumps(scene))
    if end > 0:
        scene.setdefault("time", {})["end"] = end
    copy = os.path.join(workdir, os.path.basename(path))
    with open(copy, "w") as f:
        json.dump(scene, f, indent=1)
    return copy, scene.get("name", os.path.basename(path))


def model_speedups(record, counts, contention=None):
    barrier = scaling_model.Barrier(record["fork_join_seconds"], 1e-6)
    rows = scaling_model.model(scaling_model.with_run_mean_output(record), counts, barrier, "recorded", "robust",
                               contention=contention)
    return {r["threads"]: r["speedup"] for r in rows}


def scene_spec(spec, default_end):
    """SCENE[@END] as (path, end, the parsed scene), checked before any run: a missing scene file was a
    FileNotFoundError and SCENE@abc a ValueError, and a scene that is not JSON (or a JSON list) a
    traceback, after the runs of the scenes before it, with nothing written."""
    path, at, end = spec.partition("@")
    if not os.path.isfile(path):
        what = "is a folder, not a file" if os.path.isdir(path) else "no such file"
        refuse("SCENE", spec, what if path == spec else f"{path}: {what}")
    try:
        with open(path) as f:
            scene = json.load(f)
    except (OSError, UnicodeDecodeError, ValueError) as e:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {path}: not a readable JSON scene ({str(e).splitlines()[0]})")
    if not isinstance(scene, dict):
        sys.exit(f"{os.path.basename(sys.argv[0])}: {path}: a scene is a JSON object ({{...}}), not a "
                 f"{type(scene).__name__}")
    if not isinstance(scene.get("time", {}), dict):
        sys.exit(f"{os.path.basename(sys.argv[0])}: {path}: its \"time\" is not an object: END cannot be set")
    if not at:
        return path, default_end, scene
    try:
        value = float(end)
    except ValueError:
        value = -1.0
    if not value >= 0 or value == float("inf"):
        refuse("SCENE@END", spec, "END is the simulated seconds of the run, a number 0 or more (0: the scene's own)")
    return path, value, scene


def measure(a, spec, counts, workdir):
    """The runs of one scene; returns (its results, the run.json of its first run or None)."""
    path, end, parsed = spec
    scene, _ = scene_with_end(path, parsed, end, workdir)
    name = os.path.splitext(os.path.basename(path))[0]
    rec1, recn = os.path.join(workdir, "record_1.json"), os.path.join(workdir, "record_t.json")
    run_record = run(a.talus, scene, 1, workdir, rec1, a.record_interval)[3]
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
            "fork_join_seconds": r1["fork_join_seconds"], "rows": rows}, run_record


def plot(results, path, env, prov):
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
    ax.set(xscale="log", yscale="log", xlabel="threads",
           ylabel="speed-up over 1 thread (particle-updates/s of the run, ratio)")
    ax.set_xticks(ticks, [str(t) for t in ticks])
    # ticks between the thread counts too: on 2 threads the axis had 1 and 2 alone, and a x1.23 or a
    # x1.86 could not be read off it
    speedups = [v for res in results for r in res["rows"]
                for v in (r["best_speedup"], r["model_speedup"], r["model_speedup_with_contention"])]
    yticks = speedup_ticks(min(speedups + [1.0]), max(speedups + [float(top)]))
    ax.set_yticks(yticks, [f"{v:g}" for v in yticks])
    ax.minorticks_off()
    commit = prov["talus"].get("commit", "?")
    ax.set_title(f"talus run, strong scaling: commit {commit}, {prov['build']}, {prov['isa']}, {prov['date_utc'][:10]}\n"
                 f"{prov['cpu']}, {prov['logical_cpus']} CPUs, OMP_PROC_BIND={env['OMP_PROC_BIND']} "
                 f"OMP_PLACES={env['OMP_PLACES']} OMP_WAIT_POLICY={env.get('OMP_WAIT_POLICY', 'unset')}", fontsize=8)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print("wrote", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+", help="scene files (JSON), each optionally with @END (simulated seconds)")
    # the defaults from the repository root, as scaling.py's (they were from the current folder)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--end", type=float, default=0.1, help="simulated seconds of each run (0: the scene's own)")
    ap.add_argument("--max-threads", type=int, default=os.cpu_count())
    ap.add_argument("--repeat", type=int, default=2, help="runs per thread count (all kept; the best is compared)")
    ap.add_argument("--record-interval", type=int, default=7, help="steps between recorded steps")
    ap.add_argument("--contention-at", choices=["every", "max"], default="every",
                    help="thread counts with a record for c(T): every count above 1, or the largest alone")
    ap.add_argument("--out", default=os.path.join("runs", "scaling"),
                    help="folder of the outputs (default: runs/scaling under the current folder; it was "
                         "docs/performance, whose committed results a plain run replaced)")
    ap.add_argument("--name", default="scaling_runs", help="file stem of the JSON and PNG")
    add_wait_policy_argument(ap)
    a = ap.parse_args()
    require_at_least(1, max_threads=a.max_threads, repeat=a.repeat, record_interval=a.record_interval)
    require_at_least(0, end=a.end)
    specs = [scene_spec(s, a.end) for s in a.scenes]
    require_talus(a.talus)
    # before the runs: an --out that is a file was a traceback from os.makedirs
    output_folder("--out", a.out)
    wait_policy = apply_wait_policy(a.wait_policy)
    counts = thread_counts(a.max_threads)
    started = utc_now()
    results, first_record = [], None
    for spec in specs:
        with tempfile.TemporaryDirectory() as workdir:
            res, run_record = measure(a, spec, counts, workdir)
        first_record = first_record or run_record
        results.append(res)
        cs = ", ".join(f"c({t}) = {c:.3f}" for t, c in res["contention"].items())
        print(f"{res['scene']} ({res['particles']} particles, to {res['end']} s): {cs}")
        for r in res["rows"]:
            print(f"  {r['threads']:4} threads  best {max(r['rates']) / 1e6:7.3f} M/s  speed-up {r['best_speedup']:6.2f}"
                  f"  model {r['model_speedup']:6.2f}  with c {r['model_speedup_with_contention']:6.2f}", flush=True)
    env = pinned_env()
    # what measured it, from the first run's own record (build, vector path, CPU) where it wrote one
    prov = provenance(a.talus, first_record, started)
    out = os.path.join(a.out, a.name + ".json")
    write_json_atomically(out, {"provenance": prov, "omp_proc_bind": env["OMP_PROC_BIND"], "omp_places": env["OMP_PLACES"],
                                "omp_wait_policy": wait_policy, "nproc": os.cpu_count(), "results": results})
    print("wrote", out)
    plot(results, os.path.join(a.out, a.name + ".png"), env, prov)


if __name__ == "__main__":
    main()
