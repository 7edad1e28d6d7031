#!/usr/bin/env python3
"""Unbounded dilation without the separation rule, and the warning that says so (docs/reliability.md,
"Unbounded dilation").

Runs inputs/column_collapse_2d_unbounded_dilation.json (the plane-strain column collapse at a 1 cm
cell with associated flow once flowing, psi = phi = 30 deg, and `separation_volume_ratio` 0: nothing
bounds a granular particle's dilation) and the same scene with the rule at its default, 1.5. From
each run's frames it takes every particle's V/V0 (the `volume` array over the particle's volume in
the first frame, matched by `id`) and from energy.csv the time step, and writes
  OUT/unbounded_dilation.csv   per frame and run: time, the largest V/V0, the 99th percentile, the
                               median, the share of particles past 10 V0, the time step there
  OUT/unbounded_dilation.png   the largest V/V0 and the time step against time, both runs, with the
                               warning's threshold (10 V0) and the step and time where talus warned
and prints where the run without the rule warned and how far each run's dilation and time step went.

Checked against what talus printed: the run without the rule must warn exactly once ("has dilated
to"), at a time where the frames' largest V/V0 crosses 10 between the frames around it; the run with
the rule must not warn (the warning is for bodies without it). With the rule a particle past 1.5 V0 is
stress-free and its wave speed is taken at 1.5 V0, so the time step holds; its volume still follows
the flow (such loose particles reach several V0 at the surface). A failed check ends the script with
exit 1.

Usage: /usr/bin/python3 tools/dilation_study.py [--talus build/talus] [--threads 1]
           [--runs runs/dilation_study] [--out docs/verification] [--end 0.4]
(18 s of wall time for both runs on one thread of the 2-vCPU AMD EPYC VM, 2026-12-07: 1 600 particles,
40 603 steps without the rule and 6 759 with it)
"""
import argparse
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import (ROOT, main_guard, read_csv_columns, read_vtu, require_talus, run_talus,  # noqa: E402
                        save_figure, series_frames, write_csv_rows)
from cli_checks import output_folder, require_at_least, require_inputs  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "column_collapse_2d_unbounded_dilation.json")
NAME = "unbounded_dilation"
THRESHOLD = 10.0  # the warning's V/V0 (solver/dilation_check.hpp)
WARNING = re.compile(r"talus: warning: in step (\d+), from t = ([-+0-9.eE]+) s: particle (\d+) \(body \"[^\"]*\"\) "
                     r"has dilated to ([0-9.eE+-]+) times its seeded volume")
RUNS = {  # label: separation_volume_ratio
    "separation rule off (0)": 0.0,
    "separation rule at 1.5 (default)": 1.5,
}


def scene_with_ratio(ratio, end):
    with open(SCENE) as f:
        scene = json.load(f)
    scene["materials"]["sand"]["separation_volume_ratio"] = ratio
    scene["time"]["end"] = end
    scene["name"] += f"_sep{ratio:g}"
    return scene


def dilation_per_frame(run_dir):
    """[(time, V/V0 of every particle)] over the run's frames, V0 from the first frame by id."""
    frames = series_frames(run_dir)
    first = read_vtu(frames[0][1], "id", "volume")
    seeded = dict(zip(first["id"].tolist(), first["volume"].tolist()))
    out = []
    for time, path in frames:
        f = read_vtu(path, "id", "volume")
        v0 = np.array([seeded[i] for i in f["id"].tolist()])
        out.append((time, f["volume"] / v0))
    return out


def step_at(times, dts, t):
    """The time step of the energy.csv row at or just before t."""
    i = max(0, int(np.searchsorted(times, t, side="right")) - 1)
    return dts[i]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--threads", type=int, default=1, help="threads of each talus run (default 1)")
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "dilation_study"), help="folder of the runs")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"), help="folder of the CSV and PNG")
    ap.add_argument("--end", type=float, default=0.4, help="end time of both runs [s] (default 0.4, the scene's)")
    args = ap.parse_args()
    require_at_least(1, threads=args.threads)
    require_at_least(0.05, end=args.end)
    require_inputs(scene=SCENE)
    require_talus(args.talus)
    output_folder("--out", args.out)
    output_folder("--runs", args.runs)

    rows, curves, failures = [], {}, []
    warned = None
    for label, ratio in RUNS.items():
        scene = scene_with_ratio(ratio, args.end)
        scene_file = os.path.join(args.runs, scene["name"] + ".json")
        with open(scene_file, "w") as f:
            json.dump(scene, f, indent=2)
        run_dir = os.path.join(args.runs, scene["name"])
        r = run_talus(args.talus, "run", scene_file, "--out", run_dir, "--overwrite", threads=args.threads, capture=True)
        warnings = WARNING.findall(r.stderr)
        history = read_csv_columns(os.path.join(run_dir, "energy.csv"))
        times, dts = np.asarray(history["time"]), np.asarray(history["dt"])
        end_time = times[-1]
        # (the row at t = 0 precedes the first step: dt 0; the last step is cut to reach time.end)
        times, dts = times[dts > 0][:-1], dts[dts > 0][:-1]
        frames = dilation_per_frame(run_dir)
        largest = np.array([ratios.max() for _, ratios in frames])
        frame_times = np.array([t for t, _ in frames])
        for (t, ratios), top in zip(frames, largest):
            rows.append({"run": label, "separation_volume_ratio": ratio, "time": f"{t:.6g}",
                         "largest_V_over_V0": f"{top:.6g}", "p99_V_over_V0": f"{np.percentile(ratios, 99):.6g}",
                         "median_V_over_V0": f"{np.median(ratios):.6g}",
                         "share_past_10": f"{np.mean(ratios > THRESHOLD):.6g}",
                         "dt": f"{step_at(times, dts, t):.6g}"})
        curves[label] = (frame_times, largest, times, dts)
        steps = int(history["step"][-1])
        print(f"{label}: {steps} steps to t = {end_time:.4g} s; largest V/V0 {largest.max():.4g} "
              f"(at t = {frame_times[int(np.argmax(largest))]:.3g} s); time step {dts[0]:.3e} s at the start, "
              f"{dts.min():.3e} s at the least; {len(warnings)} dilation warning(s)")
        if ratio == 0.0:
            if len(warnings) != 1:
                failures.append(f"{label}: {len(warnings)} dilation warnings, expected exactly 1")
            else:
                step, t, particle, value = int(warnings[0][0]), float(warnings[0][1]), int(warnings[0][2]), float(warnings[0][3])
                warned = (t, step, particle, value)
                print(f"  warned in step {step}, t = {t:.6g} s: particle {particle} at V/V0 = {value:.4g}")
                before = largest[frame_times <= t]
                after = largest[frame_times > t]
                if before.size and before.max() > THRESHOLD:
                    failures.append(f"{label}: a frame before the warning (t <= {t:.4g} s) already had V/V0 = "
                                    f"{before.max():.4g} > {THRESHOLD:g}")
                if after.size and after[0] < THRESHOLD:
                    failures.append(f"{label}: the first frame after the warning has V/V0 = {after[0]:.4g} < {THRESHOLD:g}")
        elif warnings:
            failures.append(f"{label}: warned of dilation {len(warnings)} time(s), expected none")

    csv_path = os.path.join(args.out, NAME + ".csv")
    write_csv_rows(csv_path, rows)
    plot(curves, warned, os.path.join(args.out, NAME + ".png"))
    print(f"wrote {csv_path} and {os.path.join(args.out, NAME + '.png')}")
    for f in failures:
        print(f"check failed: {f}", file=sys.stderr)
    return 1 if failures else 0


def plot(curves, warned, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_v, ax_dt) = plt.subplots(1, 2, figsize=(11, 4.2))
    for (label, (ft, largest, t, dt)), colour in zip(curves.items(), ["tab:red", "tab:blue"]):
        ax_v.semilogy(ft, largest, "o-", ms=3, color=colour, label=label)
        ax_dt.semilogy(t, dt, "-", color=colour, label=label)
    ax_v.axhline(THRESHOLD, color="0.4", ls="--", lw=1, label=f"warning threshold ({THRESHOLD:g} V0)")
    if warned:
        t, step, particle, value = warned
        ax_v.axvline(t, color="tab:red", ls=":", lw=1)
        ax_v.annotate(f"warned: step {step}\nt = {t:.3g} s, particle {particle}", (t, THRESHOLD),
                      xytext=(6, 18), textcoords="offset points", fontsize=8, color="tab:red")
    ax_v.set_xlabel("time [s]")
    ax_v.set_ylabel("largest V / V0 over the particles")
    ax_v.set_title("Dilation of the loosest particle")
    ax_v.legend(fontsize=8, loc="upper left")
    ax_v.grid(True, which="both", alpha=0.3)
    ax_dt.set_xlabel("time [s]")
    ax_dt.set_ylabel("time step [s]")
    ax_dt.set_title("Time step (energy.csv)")
    ax_dt.legend(fontsize=8, loc="lower left")
    ax_dt.grid(True, which="both", alpha=0.3)
    fig.suptitle("Plane-strain column, psi = phi = 30 deg once flowing, 1 cm cell", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, 120)


if __name__ == "__main__":
    sys.exit(main_guard(main))
