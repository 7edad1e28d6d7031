#!/usr/bin/env python3
"""Terrain-following grid and bed friction (issue 6, Abe, Johansson & Konagai 2005, eq. 14-22): the elastic-block checks.

Runs the scenes of inputs/terrain/ with talus (or reuses finished runs under --runs) and writes
  docs/verification/terrain_horizontal_plane.png  centre travel on a horizontal plane vs eq. 21
  docs/verification/terrain_incline30.png         horizontal travel on a 30-degree plane vs eq. 22
                                                  (terrain grid coarse/fine, flat grid with rotated
                                                  gravity, mu = 0.7 sticking)
  docs/verification/terrain_incline30_near_threshold.png  mu = 0.55 on 30 degrees (just below tan 30),
                                                  gravity ramped: travel at h = 0.25 and 0.125 against
                                                  the ramped rigid block, and the effective friction
  docs/verification/terrain_slope_to_runout.png   block through a slope-to-runout transition:
                                                  snapshots over the bed and the energy budget
  docs/verification/terrain_trench.png            block in a trench between two slip x walls on the
                                                  30-degree bed, and on a flat grid with rotated
                                                  gravity: strain and kinetic energy against time
and prints the measured numbers (docs/verification.md "Terrain").
Usage: /usr/bin/python3 tools/plot_terrain.py --talus build/talus [--runs runs/terrain] [--reuse]
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
from talus_plot import (ROOT, finish_axes, main_guard, read_csv_columns, read_vtu, require_talus, run_finished,  # noqa: E402
                        run_talus, save_figure, series_frames)
from cli_checks import require_at_least  # noqa: E402
G = 9.81
THETA = math.radians(30.0)


def run(args, name):
    out = os.path.join(args.runs, name)
    # reused only when it completed (an interrupted run has an energy.csv too: run.json says how it ended)
    if not (args.reuse and run_finished(out)):
        run_talus(args.talus, "run", os.path.join(ROOT, "inputs", "terrain", name + ".json"), "--out", out,
                  threads=args.threads)
    return out


def run_refined(args, name, h):
    """The scene inputs/terrain/NAME.json at cell size h (one cell across, as the input): written
    under --runs as NAME_h<h>.json and run (or reused)."""
    tag = f"{name}_h{h:g}"
    out = os.path.join(args.runs, tag)
    if not (args.reuse and run_finished(out)):
        with open(os.path.join(ROOT, "inputs", "terrain", name + ".json")) as f:
            scene = json.load(f)
        scene["name"] = tag
        scene["grid"]["cell_size"] = h
        scene["grid"]["size"][1] = h
        for body in scene["bodies"]:
            body["box"]["max"][1] = h
        os.makedirs(args.runs, exist_ok=True)
        path = os.path.join(args.runs, tag + ".json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=2)
        run_talus(args.talus, "run", path, "--out", out, threads=args.threads)
    return out


def ramped_rigid_travel(mu, theta, ramp, t):
    """Along-slope travel of a rigid block released from rest when gravity grows linearly to g over
    `ramp` seconds (solver.gravity_ramp_time) and tan theta > mu: a(t) = g(t) (sin - mu cos) from t = 0,
    so s = a t^3 / (6 ramp) during the ramp and a ((t - ramp/2)^2 / 2 + ramp^2 / 24) after it."""
    a = G * (math.sin(theta) - mu * math.cos(theta))
    t = np.asarray(t, dtype=float)
    if ramp <= 0.0:
        return a * t ** 2 / 2
    return a * np.where(t < ramp, t ** 3 / (6 * ramp), (t - ramp / 2) ** 2 / 2 + ramp ** 2 / 24)


def effective_mu(travel, theta, ramp, t):
    """The friction coefficient with which the ramped rigid block travels `travel` (along the slope) in t."""
    per_acceleration = ramped_rigid_travel(0.0, theta, ramp, t) / (G * math.sin(theta))  # travel / a
    return math.tan(theta) - travel / per_acceleration / (G * math.cos(theta))


def frames(run_dir):
    """(time, xyz array, mass weights) of every particle frame of a run."""
    result = []
    for time, path in series_frames(run_dir):
        d = read_vtu(path, "density", "volume")
        result.append((time, d["points"], d["density"] * d["volume"]))
    return result


def centre_track(run_dir):
    f = frames(run_dir)
    t = np.array([x[0] for x in f])
    c = np.array([(x[1] * x[2][:, None]).sum(axis=0) / x[2].sum() for x in f])
    return t, c - c[0], f


def scene_of(run_dir, name):
    """The scene a run ran (its scene.json), else the input file."""
    path = os.path.join(run_dir, "scene.json")
    if not os.path.isfile(path):
        path = os.path.join(ROOT, "inputs", "terrain", name + ".json")
    with open(path) as f:
        return json.load(f)


def rigid_incline(scene, t):
    """(mu, theta, horizontal travel at t) of a rigid block released from rest on the scene's plane:
    mu the bed's friction coefficient (z-), theta the terrain's slope, else the tilt of the gravity
    (flat grid, x along the slope). Eq. 22 while it slides; 0 when it sticks (mu >= tan theta)."""
    mu = scene["boundaries"]["z-"]["friction_coefficient"]
    terrain = scene["grid"].get("terrain")
    if terrain:
        (x0, z0), (x1, z1) = terrain["points"][:2]
        theta = math.atan2(abs(z1 - z0), x1 - x0)
    else:
        g = scene["gravity"]
        theta = math.atan2(abs(g[0]), -g[2])
    if mu >= math.tan(theta):
        return mu, theta, 0.0
    return mu, theta, G * (math.sin(theta) - mu * math.cos(theta)) * math.cos(theta) * t ** 2 / 2


def rigid_text(scene, t):
    """The rigid answer a run's line quotes, with the run's own friction coefficient."""
    mu, theta, travel = rigid_incline(scene, t)
    state = f" >= tan {math.degrees(theta):.0f}, sticks" if travel == 0.0 else ""
    return f"rigid mu = {mu:g}{state}: {travel:.4f} m"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "terrain"))
    ap.add_argument("--reuse", action="store_true", help="reuse finished runs under --runs (a run that did not "
                    "complete is run again)")
    # (without it each run took every core: these 128-512-particle scenes then wait at the barriers,
    # and on a busy 2-core machine the nine runs took minutes instead of seconds)
    ap.add_argument("--threads", type=int, default=1, help="threads of each talus run (default 1)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"))
    args = ap.parse_args()
    require_at_least(1, threads=args.threads)  # talus refused --threads 0 after a traceback
    require_talus(args.talus)
    os.makedirs(args.out, exist_ok=True)

    # 1. horizontal plane, Abe, Johansson & Konagai 2005, eq. 21
    mu, v0 = 0.3, 10.0
    fig, ax = plt.subplots(figsize=(6.5, 4))
    tr = np.linspace(0, 4.0, 400)
    ts = v0 / (mu * G)
    ax.plot(tr, np.where(tr < ts, v0 * tr - mu * G * tr ** 2 / 2, v0 ** 2 / (2 * mu * G)), "k-", lw=3, alpha=0.3,
            label="rigid block (eq. 21)")
    for tag, style in (("coarse", "o-"), ("fine", "s--")):
        t, c, _ = centre_track(run(args, f"horizontal_plane_{tag}"))
        ax.plot(t, c[:, 0], style, ms=3, label=f"MPM, {tag}")
        print(f"horizontal plane {tag}: stopping distance {c[-1, 0]:.4f} m, rigid {v0 ** 2 / (2 * mu * G):.4f} m "
              f"({100 * (c[-1, 0] / (v0 ** 2 / (2 * mu * G)) - 1):+.2f}%)")
    finish_axes(ax, "time [s]", "centre travel [m]", "Block on a horizontal plane, mu = 0.3, v0 = 10 m/s")
    save_figure(fig, os.path.join(args.out, "terrain_horizontal_plane.png"), 120)

    # 2. 30-degree plane, Abe, Johansson & Konagai 2005, eq. 22
    fig, ax = plt.subplots(figsize=(6.5, 4))
    tr = np.linspace(0, 2.0, 200)
    ax.plot(tr, G * (math.sin(THETA) - mu * math.cos(THETA)) * math.cos(THETA) * tr ** 2 / 2, "k-", lw=3, alpha=0.3,
            label=f"rigid block, mu = {mu} (eq. 22)")
    for name, label, scale, style in (("incline30_coarse", "terrain grid, h = 0.25", 1.0, "o-"),
                                      ("incline30_fine", "terrain grid, h = 0.125", 1.0, "s--"),
                                      ("incline30_flat_rotated_gravity", "flat grid, rotated gravity", math.cos(THETA), "^:"),
                                      ("incline30_stick", "terrain grid, mu = 0.7 (sticks)", 1.0, "x-")):
        rd = run(args, name)
        t, c, _ = centre_track(rd)
        ax.plot(t, c[:, 0] * scale, style, ms=3, label=label)
        i = np.argmin(np.abs(t - 1.5))
        print(f"{name}: horizontal travel at t = {t[i]:.2f} s {c[i, 0] * scale:.4f} m ({rigid_text(scene_of(rd, name), t[i])})")
    finish_axes(ax, "time [s]", "horizontal travel of the centre [m]", "Block on a 30-degree plane from rest", fontsize=8)
    save_figure(fig, os.path.join(args.out, "terrain_incline30.png"), 120)

    # 2b. near the sliding threshold: mu = 0.55 < tan 30 = 0.577, gravity ramped over 0.5 s
    name = "incline30_near_threshold"
    with open(os.path.join(ROOT, "inputs", "terrain", name + ".json")) as f:
        near = json.load(f)
    mu_near, ramp = near["boundaries"]["z-"]["friction_coefficient"], near["solver"]["gravity_ramp_time"]
    fig, ax = plt.subplots(figsize=(6.5, 4))
    tr = np.linspace(0, near["time"]["end"], 200)
    for m, style in ((mu_near, "k-"), (mu_near - 0.01, "k--"), (mu_near - 0.02, "k:")):
        ax.plot(tr, ramped_rigid_travel(m, THETA, ramp, tr) * math.cos(THETA), style, lw=2 if m == mu_near else 1,
                alpha=0.4, label=f"rigid block, mu = {m:.2f}, gravity ramped")
    for h, style in ((0.25, "o-"), (0.125, "s-")):
        rd = run(args, name) if h == near["grid"]["cell_size"] else run_refined(args, name, h)
        t, c, _ = centre_track(rd)
        mu_eff = effective_mu(c[-1, 0] / math.cos(THETA), THETA, ramp, t[-1])
        ax.plot(t, c[:, 0], style, ms=3, label=f"MPM, h = {h}: mu_eff = {mu_eff:.4f}")
        rigid = ramped_rigid_travel(mu_near, THETA, ramp, t[-1]) * math.cos(THETA)
        print(f"{name}, h = {h}: horizontal travel at t = {t[-1]:.2f} s {c[-1, 0]:.4f} m, ramped rigid block "
              f"{rigid:.4f} m ({100 * (c[-1, 0] / rigid - 1):+.1f}%): effective mu {mu_eff:.4f} "
              f"({mu_eff - mu_near:+.4f})")
    finish_axes(ax, "time [s]", "horizontal travel of the centre [m]",
                f"Near the threshold: mu = {mu_near} on 30 degrees (tan 30 = 0.577)", fontsize=8)
    save_figure(fig, os.path.join(args.out, "terrain_incline30_near_threshold.png"), 120)

    # 3. slope to runout through a circular transition
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 7))
    xs = np.linspace(0, 12, 600)
    # the profile: 30-degree slope to (6, 0), fillet of radius 2, flat runout
    r, tan = 2.0, 2.0 * math.tan(THETA / 2)
    xa, xb = 6 - tan * math.cos(THETA), 6 + tan
    cx, cz = xb, r
    zb = np.where(xs < xa, (6 - xs) * math.tan(THETA), np.where(xs < xb, cz - np.sqrt(np.maximum(r * r - (xs - cx) ** 2, 0)), 0))
    a1.fill_between(xs, zb - 0.3, zb, color="0.8")
    a1.plot(xs, zb, "k-", lw=1)
    for shape, colour in (("linear", "C0"), ("ugimp", "C1"), ("bspline2", "C2")):
        rd = run(args, f"slope_to_runout_{shape}")
        d = np.genfromtxt(os.path.join(rd, "energy.csv"), delimiter=",", names=True)
        released = np.max(d["gravity"][0] - d["gravity"])
        gap = (d["total"] - d["total"][0]) / released
        a2.plot(d["time"], 100 * gap, color=colour, label=f"{shape}: budget gap")
        print(f"slope to runout {shape}: energy gap at the end {100 * gap[-1]:+.2f}%, largest {100 * np.max(np.abs(gap)):.2f}% "
              f"of the {released:.0f} J released")
        if shape == "linear":
            a2b = a2.twinx()
            for key, style in (("kinetic", "-"), ("friction_work", "--")):
                a2b.plot(d["time"], d[key] / released, "k" + style, lw=0.8, alpha=0.6, label=f"linear: {key} / released")
            a2b.set_ylabel("energy / released")
            a2b.legend(loc="center right", fontsize=7)
            _, _, f = centre_track(rd)
            for k in range(0, len(f), 10):
                a1.plot(f[k][1][:, 0], f[k][1][:, 2], ".", ms=1.5, color=colour)
    a1.set_aspect("equal")
    a1.set_xlim(0, 12)
    a1.set_title("Slope to runout (transition r = 2 m), linear shapes, every 0.5 s")
    a1.set_xlabel("x [m]")
    a1.set_ylabel("z [m]")
    a2.set_xlabel("time [s]")
    a2.set_ylabel("(total - initial) / released [%]")
    a2.legend(loc="lower left", fontsize=8)
    a2.grid(alpha=0.3)
    save_figure(fig, os.path.join(args.out, "terrain_slope_to_runout.png"), 120)

    # 4. a block filling a trench between two slip x walls on the 30-degree bed (docs/theory.md, "Where the
    # bed meets an x wall"; TerrainSlide.ABlockBetweenSlipWallsOnASlopeStaysBounded), and on a flat grid
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.5, 6), sharex=True)
    for name, label, colour in (("trench_slip_walls", "terrain grid, 30-degree bed", "C0"),
                                ("trench_slip_walls_flat_rotated_gravity", "flat grid, rotated gravity", "C1")):
        d = read_csv_columns(os.path.join(run(args, name), "energy.csv"))
        peak = int(np.argmax(d["strain"]))
        a1.plot(d["time"], d["strain"], color=colour, lw=1,
                label=f"{label}: peak {d['strain'][peak]:.2f} J at {d['time'][peak]:.2f} s")
        a2.plot(d["time"], d["kinetic"], color=colour, lw=1, label=f"{label}: peak {np.max(d['kinetic']):.2f} J")
        print(f"{name}: peak strain energy {d['strain'][peak]:.4f} J at t = {d['time'][peak]:.3f} s, at the end "
              f"{d['strain'][-1]:.4f} J; peak kinetic energy {np.max(d['kinetic']):.4f} J; friction work at the end "
              f"{d['friction_work'][-1]:+.4f} J")
    finish_axes(a1, None, "strain energy [J]", "Block between slip x walls on a 30-degree bed, mu = 0.3", fontsize=8)
    finish_axes(a2, "time [s]", "kinetic energy [J]", fontsize=8)
    save_figure(fig, os.path.join(args.out, "terrain_trench.png"), 120)


if __name__ == "__main__":
    main_guard(main)
