#!/usr/bin/python3
"""Steady inclined flow of a mu(I) layer against the Bagnold profile (docs/mu-i.md, sec. 8).

Runs inputs/inclined_flow_bagnold.json (16 cells over the depth h) and, with --cells, the same
scene at other resolutions (the cell size h/N; the grid keeps 4 x 4 cells across, 4 above the
layer), reads the last frame of each run, averages the velocity along the slope per row of
particles and compares it with

  u(z) = (2/3) (I_theta / d) sqrt(phi g cos theta) (h^1.5 - (h - z)^1.5),
  I_theta = I0 (tan theta - mu_s) / (mu_2 - tan theta)          (GDR MiDi 2004; Jop et al. 2005)

Writes bagnold_profile.png (the profiles, and the surface row's error against time: the approach to
the steady state) and bagnold_profile.csv (per resolution: the surface row's error and the relative L2
error of the profile at the end). They go to docs/verification for the study the docs show (--cells
8 16 32) and to the --work folder for any other set, so that a quick look does not overwrite them.

Usage (from the repository root):
  /usr/bin/python3 tools/plot_bagnold.py --talus build/talus --cells 8 16 32 --threads 1
  /usr/bin/python3 tools/plot_bagnold.py --no-run --cells 8 16 32     # plot runs already in --work
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from talus_plot import (ROOT, main_guard, read_vtu, require_finished, require_folders, run_talus,  # noqa: E402
                        series_frames, write_csv_rows)
from cli_checks import require_at_least  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "inclined_flow_bagnold.json")
STUDY_CELLS = [8, 16, 32]  # the resolutions of the shipped plot and table (docs/mu-i.md sec. 8)
# the mu(I) defaults (MuIParameters, docs/mu-i.md sec. 2): the scene's material sets none of them
DEFAULTS = {"mu_s": math.tan(math.radians(20.9)), "mu_2": math.tan(math.radians(32.76)), "i0": 0.279,
            "grain_diameter": 0.53e-3, "grain_density": 2450.0}


class Setup:
    """The analytic problem the scene poses: angle, layer thickness, material."""

    def __init__(self, scene):
        g = scene["gravity"]
        self.g = math.hypot(g[0], g[2])
        self.theta = math.atan2(g[0], -g[2])
        body = scene["bodies"][0]["box"]
        self.h = body["max"][2] - body["min"][2]
        m = dict(DEFAULTS, **scene["materials"]["beads"])
        self.m = m
        self.phi = m["density"] / m["grain_density"]
        t = math.tan(self.theta)
        self.i_theta = m["i0"] * (t - m["mu_s"]) / (m["mu_2"] - t)

    def u(self, z):
        depth = np.clip(self.h - np.asarray(z, dtype=float), 0.0, None)
        return (2.0 / 3.0 * self.i_theta / self.m["grain_diameter"] * math.sqrt(self.phi * self.g * math.cos(self.theta))
                * (self.h ** 1.5 - depth ** 1.5))


def scene_at(base, cells):
    """The scene with `cells` cells over the layer's depth (4 x 4 across, 4 above)."""
    s = json.loads(json.dumps(base))
    h = s["bodies"][0]["box"]["max"][2]
    cell = h / cells
    s["name"] = f"inclined_flow_bagnold_n{cells}"
    s["grid"]["cell_size"] = cell
    s["grid"]["size"] = [4 * cell, 4 * cell, h + 4 * cell]
    s["bodies"][0]["box"]["max"] = [4 * cell, 4 * cell, h]
    if cells != 16:  # the input's description says 16 cells over the depth
        s["description"] = s["description"].replace("16 cells over the depth (cell h/16)",
                                                    f"{cells} cells over the depth (cell h/{cells}; tools/plot_bagnold.py --cells)")
    return s


def rows(frame, cells, h):
    """Mean velocity along the slope per row of particles: (z, u) arrays, bottom to top."""
    d = read_vtu(frame, "velocity")
    z, u = d["points"][:, 2], d["velocity"][:, 0]
    key = np.floor(z / (h / cells / 2.0)).astype(int)  # rows at (k + 1/4) and (k + 3/4) cells
    zs, us = [], []
    for k in np.unique(key):
        sel = key == k
        zs.append(z[sel].mean())
        us.append(u[sel].mean())
    return np.array(zs), np.array(us)


def errors(setup, z, u):
    a = setup.u(z)
    return u[-1] / a[-1] - 1.0, math.sqrt(np.mean((u - a) ** 2) / np.mean(a ** 2))


MARKERS = ["s", "o", "^", "D"]


def draw_profiles(ax, setup, results):
    """The profiles panel: the analytic profile and each run's rows. The u axis starts at 0 unless a
    row is slower: the lowest row, a quarter cell above the base, carries a FLIP velocity of about
    -u_a (docs/mu-i.md sec. 8), and an axis cut at 0 hid it."""
    zf = np.linspace(0.0, setup.h, 200)
    ax.plot(setup.u(zf), zf / setup.h, "k-", lw=1.4, label="Bagnold profile (GDR MiDi 2004)")
    for k, r in enumerate(results):
        ax.plot(r["u"], r["z"] / setup.h, MARKERS[k % 4], ms=4, mfc="none", color=f"C{k}",
                label=f"talus, {r['cells']} cells over h: surface {100 * r['surface']:+.1f}%, L2 {100 * r['l2']:.1f}%")
    ax.set_xlabel("velocity along the slope u [m/s]")
    ax.set_ylabel("z / h")
    ax.set_ylim(0, 1.05)
    lowest = min([0.0] + [float(np.min(r["u"])) for r in results])
    if lowest < 0.0:  # room for the rows below 0, and the line u = 0
        ax.axvline(0.0, color="0.6", lw=0.6)
        ax.set_xlim(lowest - 0.03 * (float(setup.u(setup.h)) - lowest), None)
    else:
        ax.set_xlim(0, None)
    ax.legend(loc="upper left", fontsize=7.5)
    ax.set_title(f"μ(I) layer on a rough incline, θ = {math.degrees(setup.theta):.0f}°, h = {setup.h / setup.m['grain_diameter']:.0f} d",
                 fontsize=10)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--cells", type=int, nargs="+", default=[16], help="cells over the depth, one run each")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--work", default=os.path.join(ROOT, "runs", "bagnold"), help="folder for the runs")
    ap.add_argument("--no-run", action="store_true", help="plot the runs already in --work")
    ap.add_argument("--out", help="the plot (default: bagnold_profile.png in docs/verification for --cells "
                    f"{' '.join(map(str, STUDY_CELLS))}, in --work otherwise)")
    ap.add_argument("--csv", help="the table (default: bagnold_profile.csv beside the default plot)")
    args = ap.parse_args()
    for n in args.cells:  # (0 divided by zero; -2 wrote a scene talus refused, after a traceback)
        require_at_least(1, cells=n)
    require_at_least(1, threads=args.threads)
    folder = os.path.join(ROOT, "docs", "verification") if args.cells == STUDY_CELLS else args.work
    args.out = args.out or os.path.join(folder, "bagnold_profile.png")
    args.csv = args.csv or os.path.join(folder, "bagnold_profile.csv")
    os.makedirs(args.work, exist_ok=True)  # before the check: the default outputs of a partial set go there
    require_folders(out=args.out, csv=args.csv)
    with open(SCENE) as f:
        base = json.load(f)
    setup = Setup(base)

    results = []
    for n in args.cells:
        out = os.path.join(args.work, f"n{n}")
        if not args.no_run:
            path = os.path.join(args.work, f"n{n}.json")
            with open(path, "w") as f:
                json.dump(scene_at(base, n), f, indent=2)
            run_talus(args.talus, "run", path, "--out", out, threads=args.threads)
        if not os.path.isfile(os.path.join(out, "particles.pvd")):
            sys.exit(f"plot_bagnold.py: {out} holds no run: run it without --no-run first")
        # (an interrupted run's last frame is no steady state; a run this script made has completed)
        require_finished(out, hint="run it without --no-run")
        times, frames = zip(*series_frames(out))
        if len(frames) < 2:  # (was an IndexError)
            sys.exit(f"plot_bagnold.py: {out} holds {len(frames)} frames: run it without --no-run first")
        history = []
        for t, fr in zip(times[1:], frames[1:]):
            z, u = rows(fr, n, setup.h)
            history.append((t, *errors(setup, z, u)))
        z, u = rows(frames[-1], n, setup.h)
        surface, l2 = errors(setup, z, u)
        results.append({"cells": n, "z": z, "u": u, "history": history, "surface": surface, "l2": l2})
        change = (f"; surface change over the last frame interval {100 * (history[-1][1] - history[-2][1]):+.3f}%"
                  if len(history) > 1 else "")  # (2 frames, the first and the last: was an IndexError)
        print(f"{n} cells over h: surface row {u[-1]:.4f} m/s against {setup.u(z[-1]):.4f} "
              f"({100 * surface:+.2f}%), L2 {100 * l2:.2f}%{change}")

    write_csv_rows(args.csv, [{"cells_over_depth": r["cells"], "surface_row_error": f"{r['surface']:+.5f}",
                               "l2_error": f"{r['l2']:.5f}"} for r in results])

    fig, (ax, ax_t) = plt.subplots(1, 2, figsize=(10.5, 4.6), gridspec_kw={"width_ratios": [1, 1.25]})
    draw_profiles(ax, setup, results)
    for k, r in enumerate(results):
        t = [x[0] for x in r["history"]]
        ax_t.plot(t, [100 * x[1] for x in r["history"]], "-" + MARKERS[k % 4], ms=3, color=f"C{k}",
                  label=f"surface row, {r['cells']} cells")
        ax_t.plot(t, [100 * x[2] for x in r["history"]], ":", color=f"C{k}", label=f"L2, {r['cells']} cells")
    for y in (-3, 3):
        ax_t.axhline(y, color="0.5", ls="--", lw=0.8)
    ax_t.axhline(5, color="0.5", ls="-.", lw=0.8)
    ax_t.text(0.02, 5.3, "L2 target 5%", fontsize=7, color="0.4")
    ax_t.text(0.02, 3.3, "surface target ±3%", fontsize=7, color="0.4")
    ax_t.set_ylim(-40, 15)
    ax_t.set_xlabel("time [s] (from rest)")
    ax_t.set_ylabel("error against the steady profile [%]")
    ax_t.legend(fontsize=7, loc="lower right")
    ax_t.set_title("approach to the steady state", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out} and {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main_guard(main))
