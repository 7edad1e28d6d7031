#!/usr/bin/env python3
"""The energy warning, the energy guard and the resume from checkpoint_earlier.h5, on one scene
(docs/reliability.md, "The energy guard on a shipped scene").

Runs inputs/terrain/energy_guard_kink.json (an elastic block thrown down a 75-degree terrain slope
into a sharp kink, coarse cells, Courant 0.3). The scheme creates energy at the kink: the run warns
once where the growth passes guards.energy_warning_factor of the energy available, then the energy
guard (guards.energy_growth_factor) stops it (exit 3), and the periodic checkpoint from before the
blow-up is kept as checkpoint_earlier.h5. The script then resumes that checkpoint with a smaller
time.courant (a scene file with that one key changed, given with --restart: a restart may change
time.courant) into a folder of its own, to the scene's end, and writes
  docs/verification/energy_guard_kink.png   the total energy's growth as a share of the energy
                                            available against time, for the run and the resumed run,
                                            with the warning factor, the guard's factor, the
                                            warning, the trip and the resume point marked
and prints the warning's and the trip's step, time and share, and the resumed run's final energy gap.

The share is talus's own: (E(t) - E(0)) / A(t), A(t) = initial kinetic + strain energy + the most
potential energy released so far (less what left through open faces: the column outflow_gravity) +
1e-3 M |g| h (stability_guards.cpp), computed from the rows of energy.csv; the floor 1e-3 M |g| h is
taken from the guard's own line at the trip. The shares at the trip and the warning, and the resumed
run's energy available and final gap, are checked against what talus printed and recorded. A --scene
of one's own needs output.checkpoint_interval (the checkpoint to resume) and output.energy_gap_terms
(the outflow_gravity column); the right panel of the plot zooms on the blow-up.

Usage: /usr/bin/python3 tools/energy_guard_demo.py [--talus build/talus] [--threads 1]
           [--runs runs/energy_guard_demo] [--out docs/verification] [--courant 0.1]
(about 3 s of CPU on one thread of the 2-vCPU VM, 24 s of wall time while it compiled: 128 particles,
4 424 steps and 8 010 resumed)
"""
import argparse
import json
import os
import re
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import (ROOT, TalusError, main_guard, read_csv_columns, require_talus,  # noqa: E402
                        run_talus, save_figure, talus_failure)
from cli_checks import output_folder, refuse, require_at_least, require_inputs  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "terrain", "energy_guard_kink.json")
PNG = "energy_guard_kink.png"
NUMBER = r"([-+0-9.eE]+|inf|nan)"
WARNING = re.compile(r"talus: warning: after step (\d+), t = " + NUMBER + r" s: the total energy grew by " + NUMBER +
                     r" J, " + NUMBER + r"% of the energy available")
TRIP = re.compile(r"after step (\d+), t = " + NUMBER + r" s: total energy = " + NUMBER + r" J grew by " + NUMBER +
                  r" J, more than guards\.energy_growth_factor = " + NUMBER + r" times the energy available \(" +
                  NUMBER + r" J\)")
KEPT = re.compile(r"the checkpoint of t = " + NUMBER + r" s kept as checkpoint_earlier\.h5")
GOOD = re.compile(r"last good state \(after step (\d+), t = " + NUMBER + r" s\)")
RESTART = re.compile(r"talus: restart from .* at step (\d+), t = " + NUMBER + r" s")


class Ledger:
    """The energy guard's ledger over energy.csv rows: the initial budget, the running most potential
    energy released, and the floor 1e-3 M |g| h (set from the guard's line at the trip)."""

    def __init__(self, first):
        self.total0 = first["total"][0]
        self.gravity0 = first["gravity"][0]
        self.ramp0 = first["gravity_ramp"][0]
        self.base = first["kinetic"][0] + first["strain"][0]
        self.max_released = 0.0
        self.floor = 0.0

    def released(self, rows):
        """The running most potential energy released at each row (the guard's max_released_),
        continuing from the rows given before. The potential energy carried out through open faces
        counts as not released: its column, outflow_gravity, is one of output.energy_gap_terms."""
        out = []
        for g, outflow, ramp in zip(rows["gravity"], rows["outflow_gravity"], rows["gravity_ramp"]):
            self.max_released = max(self.max_released, self.gravity0 - (g + outflow) - (ramp - self.ramp0))
            out.append(self.max_released)
        return np.array(out)

    def share(self, rows, released):
        return (rows["total"] - self.total0) / (self.base + released + self.floor)


def number(text):
    return float(text)


def parse_first_run(out, err):
    """(warning, trip, kept time, (step, time) of the last good state) from the first run's stderr;
    each None when not said."""
    warning = trip = kept = None
    if (m := WARNING.search(err)):
        warning = {"step": int(m[1]), "time": number(m[2]), "joules": number(m[3]), "share": number(m[4]) / 100}
    if (m := TRIP.search(err)):
        trip = {"step": int(m[1]), "time": number(m[2]), "total": number(m[3]), "joules": number(m[4]),
                "factor": number(m[5]), "available": number(m[6])}
        trip["share"] = trip["joules"] / trip["available"]
    if (m := KEPT.search(err)):
        kept = number(m[1])
    good = (int(m[1]), number(m[2])) if (m := GOOD.search(err)) else None
    return warning, trip, kept, good


def value_at_step(rows, released, step):
    i = int(np.searchsorted(rows["step"], step))
    if i >= len(rows["step"]) or rows["step"][i] != step:
        raise TalusError(f"energy.csv has no row at step {step}")
    return i, released[i]


def draw(path, scene, courant, first, resumed, warning, trip, good, resume, end_gap):
    """The figure: the growth's share against time for the run (first: times, shares) and the resumed
    run, with the two factors, the warning, the trip, the last good state and the resume point; the
    right panel zooms on the blow-up."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    guards = scene.get("guards", {})
    warn_factor = guards.get("energy_warning_factor", 0.1)
    stop_factor = guards.get("energy_growth_factor", 1.0)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), gridspec_kw={"width_ratios": [3, 2]})
    for ax, whole in zip(axes, (True, False)):
        ax.plot(first[0], 100 * first[1], ".-" if not whole else "-", ms=3, color="C3",
                label=f"Courant {scene['time'].get('courant', 0.3)}: stopped by the guard")
        ax.plot(resumed[0], 100 * resumed[1], ".-" if not whole else "-", ms=3, color="C0",
                label=f"resumed from checkpoint_earlier.h5 with Courant {courant}")
        ax.axhline(100 * warn_factor, color="C1", ls="--", lw=1, label=f"guards.energy_warning_factor = {warn_factor}")
        ax.axhline(100 * stop_factor, color="k", ls="--", lw=1, label=f"guards.energy_growth_factor = {stop_factor}")
        if warning:
            ax.plot([warning["time"]], [100 * warning["share"]], "o", color="C1", ms=9, mfc="none", mew=2,
                    label=f"warned: step {warning['step']}, t = {warning['time']:.4g} s, {100 * warning['share']:.3g}%")
        ax.plot([trip["time"]], [100 * trip["share"]], "X", color="k", ms=10,
                label=f"guard tripped: step {trip['step']}, t = {trip['time']:.4g} s, {100 * trip['share']:.3g}%")
        if good:
            ax.axvline(good[1], color="C3", ls=":", lw=1,
                       label=f"last good state (checkpoint.h5): step {good[0]}, t = {good[1]:.4g} s")
        ax.axvline(resume[0], color="C0", ls=":", lw=1)
        ax.plot([resume[0]], [100 * resume[1]], "s", color="C0", ms=6,
                label=f"resume point: checkpoint_earlier.h5, t = {resume[0]:.4g} s")
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("time [s]")
    axes[0].annotate(f"end: {100 * end_gap:+.2g}%", (resumed[0][-1], 100 * resumed[1][-1]), textcoords="offset points",
                     xytext=(-5, 10), ha="right", color="C0")
    axes[0].set_ylabel("energy growth [% of the energy available]")
    axes[0].set_title("Elastic block into a 75° kink, h = 0.25 m")
    axes[0].legend(loc="upper left", fontsize=7.5)
    lo = min(t for t in (warning and warning["time"], good and good[1], trip["time"]) if t) - 0.012
    axes[1].set_xlim(lo, trip["time"] + 0.006)
    axes[1].set_ylim(-5, 100 * max(trip["share"], stop_factor) + 5)
    axes[1].set_title("the blow-up at the kink (a row every 0.001 s)")
    save_figure(fig, path, 120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--threads", type=int, default=1, help="threads of each talus run (default 1)")
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "energy_guard_demo"),
                    help="folder of the two runs (run/ and resumed/, replaced) and the resumed scene")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"), help="folder of " + PNG)
    ap.add_argument("--courant", type=float, default=0.1,
                    help="time.courant of the resumed run (default 0.1; the scene's is 0.3)")
    ap.add_argument("--scene", default=SCENE, help="the scene (default inputs/terrain/energy_guard_kink.json)")
    args = ap.parse_args()
    require_at_least(1, threads=args.threads)
    if not (0.0 < args.courant <= 1.0):  # (talus's own range for time.courant)
        refuse("--courant", args.courant, "give a number in (0, 1]")
    require_inputs(scene=args.scene)
    require_talus(args.talus)
    with open(args.scene) as f:
        scene = json.load(f)
    guards = scene.get("guards", {})
    warn_factor = guards.get("energy_warning_factor", 0.1)
    for key, why in (("checkpoint_interval", "the run keeps no earlier checkpoint to resume from"),
                     ("energy_gap_terms", "energy.csv lacks the outflow_gravity column the guard's ledger needs")):
        if not scene.get("output", {}).get(key):
            sys.exit(f"energy_guard_demo.py: --scene {args.scene}: no output.{key}: {why}")
    output_folder("--out", args.out)
    output_folder("--runs", args.runs)

    # 1. The run: warned, then stopped by the energy guard (exit 3).
    first = os.path.join(args.runs, "run")
    r = run_talus(args.talus, "run", args.scene, "--out", first, threads=args.threads, capture=True, check=False)
    if r.returncode != 3:
        raise TalusError(f"the run was meant to trip the energy guard (exit 3), but: {talus_failure(r.args, r)}"
                         if r.returncode else "the run was meant to trip the energy guard (exit 3), but it completed")
    warning, trip, kept, good = parse_first_run(r.stdout, r.stderr)
    if trip is None or kept is None:
        raise TalusError(f"the run stopped, but not at the energy guard with an earlier checkpoint kept: "
                         f"{talus_failure(r.args, r)}")
    earlier = os.path.join(first, "checkpoint_earlier.h5")
    if not os.path.isfile(earlier):
        raise TalusError(f"{earlier}: not written, though the run's line names it")

    # 2. The resume from the earlier checkpoint with a smaller time.courant, into a folder of its own.
    resumed_scene = dict(scene)
    resumed_scene["time"] = dict(scene["time"], courant=args.courant)
    scene_file = os.path.join(args.runs, "resumed_scene.json")
    with open(scene_file, "w") as f:
        json.dump(resumed_scene, f, indent=2)
    resumed = os.path.join(args.runs, "resumed")
    shutil.rmtree(resumed, ignore_errors=True)  # (a restart refuses a folder holding another run's files)
    r2 = run_talus(args.talus, "run", scene_file, "--restart", earlier, "--out", resumed, threads=args.threads,
                   capture=True)
    m = RESTART.search(r2.stdout)
    if not m:
        raise TalusError(f"the resumed run did not say where it started: {r2.stdout.strip()[-200:]}")
    resume_step, resume_time = int(m[1]), number(m[2])
    resumed_warned = "talus: warning: after step" in r2.stderr
    with open(os.path.join(resumed, "run.json")) as f:
        record = json.load(f)

    # 3. The shares, as the guard computes them.
    rows = read_csv_columns(os.path.join(first, "energy.csv"))
    rows2 = read_csv_columns(os.path.join(resumed, "energy.csv"))
    ledger = Ledger(rows)
    released = ledger.released(rows)
    i_trip, released_trip = value_at_step(rows, released, trip["step"])
    ledger.floor = trip["available"] - ledger.base - released_trip
    share = ledger.share(rows, released)
    i_resume, _ = value_at_step(rows, released, resume_step)
    ledger.max_released = released[i_resume]  # (the checkpoint carries the guard's most released)
    released2 = ledger.released(rows2)
    share2 = ledger.share(rows2, released2)
    available_end = ledger.base + released2[-1] + ledger.floor
    checks = [("share at the trip", share[i_trip], trip["share"], 1e-6)]
    if warning:
        i_warn, _ = value_at_step(rows, released, warning["step"])
        checks.append(("share at the warning", share[i_warn], warning["share"], 5e-3 * warning["share"]))
    checks.append(("energy available at the end", available_end, record["end"]["energy_available_joules"],
                   1e-6 * available_end))
    checks.append(("gap at the end", share2[-1], record["end"]["energy_budget_gap"], 1e-6))
    for what, ours, theirs, tolerance in checks:
        if not abs(ours - theirs) <= tolerance:
            raise TalusError(f"{what}: {ours:.6g} from energy.csv against {theirs:.6g} from talus")

    # 4. What the run did, in numbers.
    if warning:
        print(f"warning: after step {warning['step']}, t = {warning['time']:.6g} s: {100 * warning['share']:.3g}% of "
              f"the energy available (more than energy_warning_factor = {warn_factor})")
    else:
        print(f"warning: none before the trip (energy_warning_factor = {warn_factor})")
    print(f"trip: after step {trip['step']}, t = {trip['time']:.6g} s: grew by {trip['joules']:.6g} J of "
          f"{trip['available']:.6g} J available, {100 * trip['share']:.3g}% (energy_growth_factor = {trip['factor']})")
    print(f"kept: checkpoint_earlier.h5 of t = {kept:.6g} s; resumed there (step {resume_step}) with time.courant "
          f"{args.courant} (the scene's {scene['time'].get('courant', 0.3)})")
    end = record["end"]
    print(f"resumed: {'warned' if resumed_warned else 'no warning'}, {record['status']} at step {end['step']}, "
          f"t = {end['time']:.6g} s; energy budget gap {100 * end['energy_budget_gap']:+.3g}% of the "
          f"{end['energy_available_joules']:.6g} J available; largest growth after the resume "
          f"{100 * max(share2.max(), share[i_resume]):.3g}%")

    # 5. The plot: the whole run, and the blow-up at the kink.
    t2 = np.concatenate([[rows["time"][i_resume]], rows2["time"]])
    s2 = np.concatenate([[share[i_resume]], share2])
    draw(os.path.join(args.out, PNG), scene, args.courant, (rows["time"], share), (t2, s2), warning, trip, good,
         (resume_time, share[i_resume]), end["energy_budget_gap"])
    print(f"wrote {os.path.join(args.out, PNG)}")
    return 0


if __name__ == "__main__":
    sys.exit(main_guard(main))
