#!/usr/bin/env python3
"""Plane-strain sand column collapse (issue 5): energy budget and deposit profile.

Runs inputs/column_collapse_2d.json with talus (or reads an existing run folder) and writes
  docs/verification/column_collapse_energy.png   energy terms / released potential energy vs time, and
                                                 the budget error's parts (output.energy_gap_terms)
  docs/verification/column_collapse_deposit.png  initial column and final deposit (x, z); its title and
                                                 the last line give the front (the outermost particle
                                                 centre + half a particle spacing) and the initial
                                                 half-width (the body's box)
Usage: /usr/bin/python3 tools/plot_column_collapse.py --talus build/talus [--run-dir DIR]
"""
import argparse
import json
import math
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import ROOT, main_guard, read_vtu, require_finished, run_talus, series_frames  # noqa: E402

MU_S = 0.3818628674187188  # mu(I)'s default mu_s (tan 20.9 deg, docs/scene-reference.md)


def read_frame_xz(path):
    xyz = read_vtu(path)["points"]
    return xyz[:, 0], xyz[:, 2]


def column_extents(scene, x_initial, x_final):
    """(initial half-width, how it was measured, front, half a particle spacing) along x. The initial
    half-width is the body's box (max x; the symmetry wall is x = 0), else the outermost particle
    centre + half a particle spacing; the front is the outermost particle centre + half a particle
    spacing, the same edge. (Centres alone gave 0.099 m for the 0.1 m column, short by the half spacing.)"""
    body = (scene.get("bodies") or [{}])[0]
    half = 0.5 * scene["grid"]["cell_size"] / body.get("particles_per_cell", 2) if "grid" in scene else 0.0
    if "box" in body:
        initial, how = float(body["box"]["max"][0]), "the body's box"
    else:
        initial, how = float(np.max(x_initial)) + half, "outermost particle centre + half a particle spacing"
    return initial, how, float(np.max(x_final)) + half, half


def material_text(scene):
    """The material of the scene's first body for the title, as "Drucker-Prager phi = 30 deg" or
    "mu(I) mu_s = 0.38 (20.9 deg)" (the title said Drucker-Prager phi = 30 deg for every run)."""
    body = (scene.get("bodies") or [{}])[0]
    m = scene.get("materials", {}).get(body.get("material"), {})
    model = m.get("model", "linear_elastic")
    if model == "drucker_prager":
        return f"Drucker-Prager phi = {m['friction_angle']:g} deg"
    if model == "mu_i":
        mu_s = m.get("mu_s", MU_S)
        return f"mu(I) mu_s = {mu_s:.3g} ({math.degrees(math.atan(mu_s)):.1f} deg)"
    return model.replace("_", " ")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--run-dir", help="use this finished run instead of running the scene")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"))
    args = ap.parse_args()
    run = args.run_dir or os.path.join(ROOT, "runs", "column_collapse_2d")
    if args.run_dir and not os.path.isfile(os.path.join(run, "energy.csv")):
        sys.exit(f"plot_column_collapse.py: --run-dir {run}: no energy.csv there: give the folder of a talus run")
    # (a flume's run was plotted as a collapse, with a "runout" that was the flume's x extent)
    if args.run_dir:  # (a Ctrl-C'd run was plotted as the collapse)
        require_finished(run, "--run-dir")
    if args.run_dir and os.path.isfile(os.path.join(run, "scene.json")):
        with open(os.path.join(run, "scene.json")) as f:
            grid = json.load(f).get("grid", {})
        if "terrain" in grid:
            sys.exit(f"plot_column_collapse.py: --run-dir {run}: a run of a scene with a terrain; this plots a column "
                     "collapse on a flat floor (inputs/column_collapse_2d.json)")
    if not args.run_dir:
        run_talus(args.talus, "run", os.path.join(ROOT, "inputs", "column_collapse_2d.json"), "--out", run, quiet=False)
    d = np.genfromtxt(os.path.join(run, "energy.csv"), delimiter=",", names=True)
    released = d["gravity"][0] - d["gravity"][-1]
    # Every term is shown over the potential energy released: a block sent sliding on a level floor
    # released next to none, or less than none, and was shown "friction -1053.7". A collapse starts at
    # rest; refused unless the fall gave at least a tenth of the energy the run started with.
    initial = d["kinetic"][0] + d["strain"][0]
    if not (released > 0 and released >= 0.1 * initial):
        sys.exit(f"plot_column_collapse.py: {run}: the run released {released:.4g} J of potential energy, "
                 f"against {initial:.4g} J of kinetic and strain energy at the start: not a collapse")
    scene_path = os.path.join(run, "scene.json")  # the scene the run ran (talus writes it)
    if not os.path.isfile(scene_path):
        scene_path = os.path.join(ROOT, "inputs", "column_collapse_2d.json")
    with open(scene_path) as f:
        scene = json.load(f)
    t = d["time"]
    e0 = d["total"][0]
    fig, ax = plt.subplots(figsize=(10, 4.2))
    ax.plot(t, (d["gravity"][0] - d["gravity"]) / released, label="potential energy released")
    ax.plot(t, d["kinetic"] / released, label="kinetic")
    ax.plot(t, d["plastic_work"] / released, label="plastic dissipation")
    ax.plot(t, d["friction_work"] / released, label="floor friction work")
    ax.plot(t, d["strain"] / released, label="stored elastic")
    ax.plot(t, (d["total"] - e0) / released * 100, "k--", label="budget error x 100")
    names = d.dtype.names
    if "transfer_loss" in names:  # output.energy_gap_terms: what the error is made of (docs/theory.md)
        removed = d["outflow_strain"] if "outflow_strain" in names else 0.0
        stress = d["strain"] - d["strain"][0] + removed + d["plastic_work"] - d["grid_stress_work"]
        ax.plot(t, stress / released * 100, ":", color="tab:olive", label="  of it: stress work booked beyond the grid's x 100")
        ax.plot(t, -d["transfer_loss"] / released * 100, ":", color="tab:cyan", label="  of it: transfer loss x 100")
        ax.plot(t, (d["friction_work"] - d["grid_wall_work"]) / released * 100, ":", color="tab:gray",
                label="  of it: walls x 100")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("energy / released potential energy")
    ax.set_title(f"Column collapse, {material_text(scene)}: energy budget")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3)
    os.makedirs(args.out, exist_ok=True)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "column_collapse_energy.png"), dpi=120)
    print(f"budget error at end: {(d['total'][-1] - e0) / released:.3e} of the released energy; "
          f"max {np.max(np.abs(d['total'] - e0)) / released:.3e}")
    print(f"plastic {d['plastic_work'][-1] / released:.3f}, friction {d['friction_work'][-1] / released:.3f}")

    frames = series_frames(run)
    x0, z0 = read_frame_xz(frames[0][1])
    x1, z1 = read_frame_xz(frames[-1][1])
    half_width, how, front, half = column_extents(scene, x0, x1)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.scatter(x0, z0, s=1, c="0.7", label="initial column")
    ax.scatter(x1, z1, s=1, c="tab:brown", label="deposit")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title(f"Column collapse: front {front:.3f} m (initial half-width {half_width:.3f} m)")
    ax.legend(fontsize=8, markerscale=6)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "column_collapse_deposit.png"), dpi=120)
    print(f"runout: front {front:.4f} m (the outermost particle centre + half a particle spacing, {half:.5f} m), "
          f"initial half-width {half_width:.4f} m ({how}); final height {z1.max():.4f} m (the top particle centre)")


if __name__ == "__main__":
    sys.exit(main_guard(main))
