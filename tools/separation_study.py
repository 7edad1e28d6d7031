#!/usr/bin/env python3
"""How loose the resting deposit is, against the separation rule's volume ratio (docs/flume.md,
"The sand loosens as it flows").

A granular particle whose volume V exceeds `separation_volume_ratio` x V0 (its seeded volume) is
stress-free (docs/drucker-prager.md sec. 7b): Dunatunga & Kamrin's (2015) disconnected state, with the
critical density rho0 / ratio. Below that density, compaction meets no resistance. The default ratio
1.5 lets sand that the flow loosened by up to 50% carry stress again, so it never re-compacts; a
ratio near 1 makes it compact under gravity down to about its seeded density.

For each scene and ratio this runs `talus run` (skipped when RUNS/<scene>_sepRRR/energy.csv exists,
unless --rerun) and measures, at the last frame:
  packing      the grid's density in the deposit's interior over the seeded density: the mass that the
               particles give the nodes (linear weights, as talus's P2G with the linear shape) over the
               node's volume h^3, median over the nodes whose every adjacent cell holds a particle.
               This is the packing the particles' positions make, whatever their own volumes say.
               Cells are taken in the grid's terrain-following coordinates (x, y, z - z_bed(x)),
               which keep volumes; the plane-strain column sums its one cell across y.
  volume       sum of V over sum of V0 (the particles' own volumes)
  no_pressure  share of the particles with mean stress >= 0 (stress-free or in tension)
  runout       flume: front beyond the gate (runout.json from_gate); column: the 0.995 quantile of x
  budget_gap   (total energy at the end - at the start) / potential energy released
  steps        steps to the end time
Writes OUT/separation_study.csv and OUT/separation_study.png. OUT is docs/flume for the whole study
(the defaults); any other choice of scenes or ratios writes to RUNS unless --out is given.

Usage: /usr/bin/python3 tools/separation_study.py [--talus build/talus] [--ratios 1.5 1.2 1.1 1.05 1.02]
           [--scenes flume column] [--threads 2] [--runs build/separation_study] [--out DIR] [--rerun]
"""
import argparse
import itertools
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import (finish_axes, main_guard, read_csv_columns, read_vtu, run_talus, save_figure,  # noqa: E402
                        series_frames, write_csv_rows)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RATIOS = [1.5, 1.2, 1.1, 1.05, 1.02]
SCENES = {  # name: (input file, plane strain, frames over the run)
    "flume": ("inputs/denlinger_flume.json", False, 8),
    "column": ("inputs/column_collapse_2d.json", True, 10),
}


def scene_with_ratio(path, ratio, frames):
    """The scene of `path` with every granular material at this separation ratio and `frames` frames."""
    with open(os.path.join(ROOT, path)) as f:
        scene = json.load(f)
    for m in scene["materials"].values():
        if m.get("model") in ("drucker_prager", "mu_i"):
            m["separation_volume_ratio"] = ratio
    scene["output"]["frame_interval"] = scene["time"]["end"] / frames
    scene["name"] += f"_sep{ratio:g}"
    return scene


def bed_height(run_dir, x):
    """z of the bed under x: the run's terrain.vtu (sampled at h/4 along x), 0 without a terrain."""
    path = os.path.join(run_dir, "terrain.vtu")
    if not os.path.exists(path):
        return np.zeros_like(x)
    points = read_vtu(path)["points"]
    order = np.argsort(points[:, 0], kind="stable")
    return np.interp(x, points[order, 0], points[order, 2])


def interior_packing(positions, mass, origin, h, plane_strain):
    """Nodal mass / h^3 (linear weights) at the nodes whose adjacent cells all hold a particle."""
    axes = [0, 2] if plane_strain else [0, 1, 2]
    g = (positions[:, axes] - np.asarray(origin)[axes]) / h
    cell = np.floor(g).astype(int)
    frac = g - cell
    cell -= cell.min(axis=0) - 1  # one empty layer of cells around the particles
    shape = tuple(cell.max(axis=0) + 2)
    nodal_mass = np.zeros(shape)
    occupied = np.zeros(shape, bool)
    occupied[tuple(cell.T)] = True
    for corner in itertools.product([0, 1], repeat=len(axes)):
        w = np.prod([frac[:, k] if c else 1.0 - frac[:, k] for k, c in enumerate(corner)], axis=0)
        np.add.at(nodal_mass, tuple((cell + np.array(corner)).T), w * mass)
    interior = np.ones(shape, bool)  # node n touches the cells n - 1 ... n along each axis
    for corner in itertools.product([0, 1], repeat=len(axes)):
        interior &= np.roll(occupied, shift=corner, axis=tuple(range(len(axes))))
    return nodal_mass[interior] / h ** 3


def measure(scene, run_dir, plane_strain):
    """The row of this run (see the module's doc)."""
    last = read_vtu(series_frames(run_dir)[-1][1], "volume", "density", "stress")
    x = last["points"].astype(float)
    volume, density = last["volume"], last["density"]
    mass = density * volume
    material = next(iter(scene["materials"].values()))
    rho0 = material["density"]
    h = scene["grid"]["cell_size"]
    following = x.copy()
    following[:, 2] -= bed_height(run_dir, x[:, 0])  # the grid's w = z - z_bed(x)
    packing = interior_packing(following, mass, scene["grid"]["origin"], h, plane_strain)
    stress = last["stress"]
    mean_stress = (stress[:, 0] + stress[:, 1] + stress[:, 2]) / 3.0
    energy = read_csv_columns(os.path.join(run_dir, "energy.csv"))
    released = energy["gravity"][0] - energy["gravity"][-1]
    runout_path = os.path.join(run_dir, "runout.json")
    if os.path.exists(runout_path):
        with open(runout_path) as f:
            runout = json.load(f)["from_gate"]
    else:
        runout = float(np.quantile(x[:, 0], 0.995))
    return {
        "packing": float(np.median(packing) / rho0),
        "interior_nodes": int(packing.size),
        "volume": float(volume.sum() / (mass.sum() / rho0)),
        "no_pressure": float(np.mean(mean_stress >= 0.0)),
        "runout": float(runout),
        "budget_gap": float((energy["total"][-1] - energy["total"][0]) / released),
        "steps": int(energy["step"][-1]),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--ratios", type=float, nargs="+", default=RATIOS)
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", default=os.path.join(ROOT, "build", "separation_study"))
    ap.add_argument("--out", help="folder for the CSV and the plot (default: docs/flume for the whole study, "
                                  "else --runs: a partial sweep does not overwrite the shipped table)")
    ap.add_argument("--rerun", action="store_true")
    a = ap.parse_args()
    for r in a.ratios:
        if not (r > 1.0 or r == 0.0):
            ap.error(f"--ratios: {r} must be above 1, or 0 (off)")
    whole = sorted(a.ratios) == sorted(RATIOS) and sorted(a.scenes) == sorted(SCENES)
    out = a.out or (os.path.join(ROOT, "docs", "flume") if whole else a.runs)
    os.makedirs(a.runs, exist_ok=True)
    os.makedirs(out, exist_ok=True)
    rows = []
    for name in a.scenes:
        path, plane_strain, frames = SCENES[name]
        for ratio in a.ratios:
            scene = scene_with_ratio(path, ratio, frames)
            run_dir = os.path.join(a.runs, f"{name}_sep{ratio:g}")
            if a.rerun or not os.path.exists(os.path.join(run_dir, "energy.csv")):
                scene_path = run_dir + ".json"
                with open(scene_path, "w") as f:
                    json.dump(scene, f, indent=1)
                print(f"separation_study: {name}, ratio {ratio:g} ...", flush=True)
                run_talus(a.talus, "run", scene_path, "--out", run_dir, threads=a.threads)
            row = measure(scene, run_dir, plane_strain)
            rows.append({"scene": name, "ratio": ratio, **{k: (f"{v:.4g}" if isinstance(v, float) else v)
                                                              for k, v in row.items()}})
            print(", ".join(f"{k} {v}" for k, v in rows[-1].items()), flush=True)
    write_csv_rows(os.path.join(out, "separation_study.csv"), rows)

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, marker, colour in (("flume", "o", "C0"), ("column", "s", "C3")):
        mine = [r for r in rows if r["scene"] == name]
        if not mine:
            continue
        ratios = [r["ratio"] for r in mine]
        left.plot(ratios, [1.0 / float(r["packing"]) for r in mine], marker + "-", color=colour, label=f"{name}: grid packing (1 / packing)")
        left.plot(ratios, [float(r["volume"]) for r in mine], marker + "--", color=colour, mfc="none", label=f"{name}: particle volumes")
        base = next((float(r["runout"]) for r in mine if r["ratio"] == 1.5), float(mine[0]["runout"]))
        right.plot(ratios, [float(r["runout"]) / base for r in mine], marker + "-", color=colour, label=f"{name}: runout / ratio 1.5's")
        right.plot(ratios, [float(r["no_pressure"]) for r in mine], marker + ":", color=colour, mfc="none",
                   label=f"{name}: share with no pressure")
    left.axhline(1.0, color="k", lw=0.8)
    finish_axes(left, "separation_volume_ratio", "deposit volume / seeded volume, at rest",
                "How loose the deposit rests", fontsize=8)
    finish_axes(right, "separation_volume_ratio", "ratio", "Runout and stress-free share at rest", fontsize=8,
                loc="lower right", bbox_to_anchor=(1.0, 0.1))
    save_figure(fig, os.path.join(out, "separation_study.png"), 110)
    print(f"separation_study: {os.path.join(out, 'separation_study.csv')}, separation_study.png")


if __name__ == "__main__":
    main_guard(main)
