#!/usr/bin/env python3
"""Momentum balance of a sliding sand layer (docs/verification.md, "The sand flume" and "Near the
sliding threshold"): while the whole layer slides, its centre of mass accelerates along the plane at
g (sin theta - mu cos theta), the Coulomb friction of the bed (Abe, Johansson & Konagai 2005, eq. 14-16).

Runs inputs/benchmarks/sand_slide_incline.json (31.4 degrees, bed tan 29 degrees) and
sand_slide_near_threshold.json (30 degrees, bed mu = 0.55, just below tan 30) with talus and writes
  docs/verification/sand_slide.png   the centre of mass's velocity along the plane against time, with
                                     the rigid acceleration through the fit's value at 0.1 s
and prints each fitted acceleration (least squares over [0.1 s, end], as
FlumeMomentum.* do) and the effective friction tan theta - a / (g cos theta) against mu.
Usage: /usr/bin/python3 tools/plot_sand_slide.py --talus build/talus [--runs runs/sand_slide] [--out DIR]
(about 10 s on one thread)
"""
import argparse
import json
import math
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import ROOT, finish_axes, main_guard, read_csv_columns, require_talus, run_talus, save_figure  # noqa: E402
from cli_checks import require_at_least  # noqa: E402

SCENES = ("sand_slide_incline", "sand_slide_near_threshold")
FIT_FROM = 0.1  # s: after the settling of the initially stress-free layer


def slope_and_friction(scene):
    """(theta, mu, g) of a sand-slide scene: the plane's angle from the tilted gravity, the bed's mu."""
    gx, _, gz = scene["gravity"]
    return math.atan2(gx, -gz), scene["boundaries"]["z-"]["friction_coefficient"], math.hypot(gx, gz)


def fitted_acceleration(t, v):
    """Least-squares slope of v(t) over t >= FIT_FROM, and the fit's value at FIT_FROM."""
    keep = t >= FIT_FROM
    slope, intercept = np.polyfit(t[keep], v[keep], 1)
    return slope, intercept + slope * FIT_FROM


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "sand_slide"))
    ap.add_argument("--threads", type=int, default=1, help="threads of each talus run (default 1)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"))
    args = ap.parse_args()
    require_at_least(1, threads=args.threads)
    require_talus(args.talus)
    os.makedirs(args.out, exist_ok=True)

    fig, ax = plt.subplots(figsize=(6.5, 4))
    for name, colour in zip(SCENES, ("C0", "C1")):
        path = os.path.join(ROOT, "inputs", "benchmarks", name + ".json")
        with open(path) as f:
            theta, mu, g = slope_and_friction(json.load(f))
        out = os.path.join(args.runs, name)
        run_talus(args.talus, "run", path, "--out", out, threads=args.threads)
        history = read_csv_columns(os.path.join(out, "runout.csv"))
        t, v = history["time"], history["centre_velocity_s"]
        a, v_fit = fitted_acceleration(t, v)
        rigid = g * (math.sin(theta) - mu * math.cos(theta))
        mu_effective = math.tan(theta) - a / (g * math.cos(theta))
        label = f"{math.degrees(theta):.1f} deg, mu = {mu:.3f}"
        print(f"{name}: acceleration {a:.4f} m/s^2, rigid {rigid:.4f} ({100 * (a / rigid - 1):+.2f}%); "
              f"effective mu {mu_effective:.4f} ({mu_effective - mu:+.4f})")
        ax.plot(t, v, "o", ms=3, color=colour, label=f"MPM, {label}: a = {a:.4f} m/s^2")
        tr = np.array([FIT_FROM, t[-1]])
        ax.plot(tr, v_fit + rigid * (tr - FIT_FROM), "-", lw=3, alpha=0.35, color=colour,
                label=f"rigid g (sin - mu cos) = {rigid:.4f} m/s^2")
    finish_axes(ax, "time [s]", "centre-of-mass velocity along the plane [m/s]",
                "Sand layer sliding on a Coulomb bed (h = 0.01 m)")
    save_figure(fig, os.path.join(args.out, "sand_slide.png"), 120)


if __name__ == "__main__":
    main_guard(main)
