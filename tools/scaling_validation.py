#!/usr/bin/env python3
"""Checks the scaling model (tools/scaling_model.py) against measured runs on this machine: records the
work at 1 thread, predicts the speed-up at 2 (or --threads) threads, then measures 1 and 2 threads
`--repeat` times, alternating, and prints prediction and measurements side by side.

    flock -x /work/quiet.lock tools/scaling_validation.py --case block --case shear --case flume \
        [--talus build/talus] [--repeat 2] [--flume-end 0.5] [--out docs/performance/scaling_validation.json]

Cases: block (talus bench, 1 M particles, linear elastic), shear (talus bench --scene shear --material dp
--shape bspline2, 1 M particles), flume (inputs/denlinger_flume.json run to --flume-end seconds of
simulated time, with its outputs). Threads are pinned (OMP_PROC_BIND=close, OMP_PLACES=cores unless
set); OMP_WAIT_POLICY is --wait-policy's (unset by default, whatever the environment says), as in
tools/scaling.py, and the values used are written to the JSON, with what measured it (`provenance`:
the talus build and commit, native or portable, the vector path, CPU, logical CPUs, date, this
command line); the JSON is written whole at the end or not at all. The bench rates are those of the
timed steps; the flume rate is the run's particle-updates per second of wall time, output included
(its run.json's, not the printed line's 0.01 M/s). The prediction for the flume is the run's wall time at 1 thread
split by the record into the steps (scaled by the model's speed-up of the recorded steps, the run loop's
work after them left out) and the rest of the run loop (output, guards: kept serial; the last-good-state
snapshots, copied in parallel: divided by the thread count).
"""
import argparse
import json
import os
import sys
import tempfile
import time
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# from cli_checks, not talus_plot: talus_plot imports numpy, which this tool does not need
from cli_checks import (provenance, refuse, require_at_least, require_folders, require_talus,  # noqa: E402
                        run_or_stop, utc_now, write_json_atomically)
import scaling_model  # noqa: E402
from scaling import ROOT, add_wait_policy_argument, apply_wait_policy  # noqa: E402
from scaling_runs import run_timing  # noqa: E402


def env():
    e = dict(os.environ)
    e.setdefault("OMP_PROC_BIND", "close")
    e.setdefault("OMP_PLACES", "cores")
    return e


def load():
    return os.getloadavg()[0]


MEASURED = {}  # the first bench --json or run.json: the build, vector path and CPU of the provenance


def bench(talus, args, threads, record=None):
    with tempfile.NamedTemporaryFile(suffix=".json") as f:
        cmd = [talus, "bench", "--threads", str(threads), "--json", f.name] + args
        if record:
            cmd += ["--record-work", record]
        run_or_stop(cmd, "talus bench", env=env(), keep_stdout=False)
        result = json.load(open(f.name))
        MEASURED.setdefault("record", result)
        return result


def flume_scene(end, path):
    here = os.path.dirname(os.path.abspath(__file__))
    s = json.load(open(os.path.join(here, "..", "inputs", "denlinger_flume.json")))
    s["time"]["end"] = end
    s["name"] = "flume_validation"
    json.dump(s, open(path, "w"))


def run(talus, scene, threads, out, record=None):
    cmd = [talus, "run", scene, "--threads", str(threads), "--quiet", "--out", out]
    if record:
        cmd += ["--record-work", record, "--record-interval", "37"]
    r = run_or_stop(cmd, "talus run", env=env())
    _, wall, rate, record = run_timing(cmd, out, r.stdout)
    if record:
        MEASURED.setdefault("record", record)
    return rate, wall


def solver_steps_only(record):
    """The recorded steps without the run loop's work after them (output, guards, snapshot)."""
    steps = []
    for step in record["steps"]:
        loop = sum(r["seconds"] for r in step["regions"] if r["name"] in scaling_model.LOOP_REGIONS)
        steps.append(dict(step, seconds=step["seconds"] - loop,
                          regions=[r for r in step["regions"] if r["name"] not in scaling_model.LOOP_REGIONS]))
    return dict(record, steps=steps)


def predicted_speedup(record_path, threads, schedule="recorded"):
    record = solver_steps_only(json.load(open(record_path)))
    barrier = scaling_model.Barrier(record["fork_join_seconds"], 1e-6)
    one = sum(scaling_model.predict(record, 1, barrier, schedule, "robust").values())
    many = sum(scaling_model.predict(record, threads, barrier, schedule, "robust").values())
    return one / many, record


def plot(results, path, title):
    """Measured speed-ups (every run) beside the model's, per case."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for i, e in enumerate(results):
        ax.plot([i - 0.1] * len(e["measured_speedup"]), e["measured_speedup"], "o", color="C0",
                label="measured" if i == 0 else None)
        ax.plot([i + 0.1], [e["predicted_speedup"]], "x", color="C3", ms=9, label="model" if i == 0 else None)
    ax.set_xticks(range(len(results)))
    ax.set_xticklabels([e["case"] for e in results])
    ax.set(ylabel=f"speed-up at {results[0]['threads']} threads", xlim=(-0.5, len(results) - 0.5))
    ax.set_title(title, fontsize=8)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print("wrote", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    # the defaults from the repository root, as scaling.py's (they were from the current folder)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--case", action="append", choices=["block", "shear", "flume"])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--particles", type=int, default=1000000)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--flume-end", type=float, default=0.5)
    ap.add_argument("--workdir", default=os.path.join(ROOT, "build", "validation"))
    ap.add_argument("--out", default="")
    add_wait_policy_argument(ap)
    a = ap.parse_args()
    require_at_least(1, threads=a.threads, repeat=a.repeat, particles=a.particles, steps=a.steps)
    if not 0 < a.flume_end < float("inf"):
        refuse("--flume-end", a.flume_end, "give the simulated seconds of the flume run, above 0")
    require_talus(a.talus)
    # the workdir first: an --out inside a workdir this tool was about to create was refused
    os.makedirs(a.workdir, exist_ok=True)
    require_folders(out=a.out)
    wait_policy = apply_wait_policy(a.wait_policy)
    started = utc_now()
    results = []
    for case in a.case or ["block", "shear", "flume"]:
        rec = os.path.join(a.workdir, f"{case}_record_1thread.json")
        t0 = time.time()
        entry = {"case": case, "threads": a.threads, "load_before": load()}
        if case in ("block", "shear"):
            args = ["--particles", str(a.particles), "--steps", str(a.steps)]
            if case == "shear":
                args += ["--scene", "shear", "--material", "dp", "--shape", "bspline2"]
            # the particles as the bench seeded them (--particles is approximate: 20000 gave 21952)
            particles = bench(a.talus, args + ["--record-steps", "3"], 1, rec)["particles"]
            ones, manys = [], []
            for _ in range(a.repeat):
                ones.append(bench(a.talus, args, 1)["particle_updates_per_second"])
                manys.append(bench(a.talus, args, a.threads)["particle_updates_per_second"])
            speedup, _ = predicted_speedup(rec, a.threads)
            base = sum(ones) / len(ones)
            entry.update(command="talus bench " + " ".join(args), particles=particles, steps=a.steps)
        else:
            scene = os.path.join(a.workdir, "flume_validation.json")
            flume_scene(a.flume_end, scene)
            run(a.talus, scene, 1, os.path.join(a.workdir, "flume_run"), rec)
            ones, manys, walls1 = [], [], []
            for _ in range(a.repeat):
                r1, w1 = run(a.talus, scene, 1, os.path.join(a.workdir, "flume_run"))
                ones.append(r1)
                walls1.append(w1)
                manys.append(run(a.talus, scene, a.threads, os.path.join(a.workdir, "flume_run"))[0])
            step_speedup, record = predicted_speedup(rec, a.threads)
            solver_s, other_s = record["run_solver_seconds"], record["run_other_seconds"]
            snapshot_s = record.get("run_snapshot_seconds", 0.0)  # parallel copies: taken as ideal at T
            share = solver_s / (solver_s + other_s)  # the steps' share of the recorded run's loop
            speedup = (solver_s + other_s) / (solver_s / step_speedup + (other_s - snapshot_s) + snapshot_s / a.threads)
            base = sum(ones) / len(ones)
            entry.update(command=f"talus run inputs/denlinger_flume.json with time.end = {a.flume_end}",
                         step_speedup=step_speedup, steps_share=share, particles=record["steps"][0]["particles"])
        entry.update(measured_1=ones, measured_n=manys, predicted_speedup=speedup, predicted_n=base * speedup,
                     measured_speedup=[m / base for m in manys], load_after=load(), seconds=time.time() - t0)
        err = [(base * speedup - m) / m for m in manys]
        entry["prediction_error"] = err
        results.append(entry)
        print(f"{case}: 1 thread {', '.join(f'{x / 1e6:.3f}' for x in ones)} M/s; {a.threads} threads "
              f"{', '.join(f'{x / 1e6:.3f}' for x in manys)} M/s (x{', '.join(f'{m / base:.2f}' for m in manys)}); "
              f"model x{speedup:.2f} -> {base * speedup / 1e6:.3f} M/s, error {', '.join(f'{100 * e:+.1f}%' for e in err)}; "
              f"load {entry['load_before']:.2f} -> {entry['load_after']:.2f}", flush=True)
    if a.out:
        prov = provenance(a.talus, MEASURED.get("record"), started)
        sizes = ", ".join(f"{e['case']} {e['particles']} particles" for e in results)
        plot(results, a.out.rsplit(".", 1)[0] + ".png",
             f"{prov['cpu']}, {prov['logical_cpus']} CPUs; {sizes}\n"
             f"commit {prov['talus'].get('commit', '?')} {prov['build']}, {prov['isa']}, {prov['date_utc'][:10]}")
        e = env()
        # the dict built first, then the file written whole: it was opened before, and a failure left
        # it empty; the CPU without assuming a "model name" line (an IndexError without one)
        write_json_atomically(a.out, {"provenance": prov, "cpu": prov["cpu"],
                                      "omp_proc_bind": e["OMP_PROC_BIND"], "omp_places": e["OMP_PLACES"],
                                      "omp_wait_policy": wait_policy, "nproc": os.cpu_count(), "results": results})
        print("wrote", a.out)


if __name__ == "__main__":
    main()
