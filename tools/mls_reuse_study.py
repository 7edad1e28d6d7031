#!/usr/bin/env python3
"""What reusing the MLS particle fit's weights costs in accuracy, and what it saves, on a flowing
collapse (docs/performance.md and docs/verification.md, "MLS, the particle fit's weights reused").

Runs inputs/column_collapse_2d.json with the quadratic B-spline to 0.6 s and MLS smoothing (linear
basis, 1.5 cells, axes x and z: the column is one cell thick), once with the particle fit (the
reference) and once with `"variant": "reused"` at each --strains value, all on the same number of
threads, one run after the other. For each run: the share of the smoothing passes that fitted, the
wall time, the front (the largest x of a particle) at 0.6 s and the rms and largest distance of the
particles from where they are in the reference run (matched by id).
Writes OUT/mls_reuse.csv and OUT/mls_reuse.png (OUT: docs/verification by default). A run is
skipped when RUNS/<name>/ holds its final frame and wall time, unless --rerun. About a minute a run on one core.

Usage: /usr/bin/python3 tools/mls_reuse_study.py [--talus build/talus] [--threads 1]
           [--strains 0.001,0.01,0.05] [--runs build/mls_reuse_study] [--out docs/verification] [--rerun]
Needs numpy, matplotlib and VTK's Python module (Debian: python3-numpy python3-matplotlib python3-vtk9).
"""
import argparse
import copy
import json
import os
import re
import sys
import time

import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import finish_axes, main_guard, read_vtu, run_talus, save_figure, series_frames, write_csv_rows  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "inputs", "column_collapse_2d.json")
END = 0.6


def scene(variant, strain=None):
    """The collapse with the B-spline and MLS smoothing, the given variant (and reuse_strain)."""
    with open(SCENE) as f:
        s = copy.deepcopy(json.load(f))
    s["name"] = "mls_reuse_particle" if variant == "particle" else f"mls_reuse_{strain:g}" if strain else "mls_reuse"
    s["time"]["end"] = END
    s["solver"]["shape"] = "bspline2"
    s["solver"]["smoothing"] = {"basis": "linear", "radius_factor": 1.5, "axes": "xz", "variant": variant}
    if strain is not None:
        s["solver"]["smoothing"]["reuse_strain"] = strain
    s["output"] = {"frame_interval": END, "history_interval": 0.01}
    return s


def run(talus, runs, s, threads, rerun):
    """Run the scene into runs/<name> (unless done); returns (positions sorted by id, wall seconds, fitted share)."""
    out = os.path.join(runs, s["name"])
    summary = os.path.join(out, "study.json")
    if rerun or not os.path.exists(summary):
        os.makedirs(runs, exist_ok=True)
        path = os.path.join(runs, s["name"] + ".json")
        with open(path, "w") as f:
            json.dump(s, f, indent=1)
        start = time.time()
        r = run_talus(talus, "run", path, "--out", out, threads=threads, quiet=False, capture=True)
        wall = time.time() - start
        m = re.search(r"(\d+) of the (\d+) passes fitted", r.stdout)
        fitted = int(m.group(1)) / int(m.group(2)) if m else 1.0
        with open(summary, "w") as f:
            json.dump({"wall_s": wall, "fitted": fitted}, f)
    with open(summary) as f:
        info = json.load(f)
    data = read_vtu(series_frames(out)[-1][1], "id")
    return data["points"][np.argsort(data["id"])], info["wall_s"], info["fitted"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--strains", default="0.001,0.01,0.05", help="reuse_strain values, comma-separated")
    ap.add_argument("--runs", default=os.path.join(ROOT, "build", "mls_reuse_study"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"))
    ap.add_argument("--rerun", action="store_true")
    a = ap.parse_args()
    strains = [float(v) for v in a.strains.split(",")]
    cell = scene("particle")["grid"]["cell_size"]
    ref, ref_wall, _ = run(a.talus, a.runs, scene("particle"), a.threads, a.rerun)
    rows = [{"variant": "particle", "reuse_strain": "", "fitted_share": 1.0, "wall_s": round(ref_wall, 2),
             "front_m": ref[:, 0].max(), "rms_distance_m": 0.0, "largest_distance_m": 0.0}]
    print(f"particle fit: front {ref[:, 0].max():.4f} m, {ref_wall:.1f} s", flush=True)
    for strain in strains:
        x, wall, fitted = run(a.talus, a.runs, scene("reused", strain), a.threads, a.rerun)
        d = np.sqrt(((x - ref) ** 2).sum(axis=1))
        rows.append({"variant": "reused", "reuse_strain": strain, "fitted_share": round(fitted, 4),
                     "wall_s": round(wall, 2), "front_m": x[:, 0].max(), "rms_distance_m": np.sqrt((d ** 2).mean()),
                     "largest_distance_m": d.max()})
        print(f"reuse_strain {strain:g}: {100 * fitted:.1f}% of the passes fitted, front {x[:, 0].max():.4f} m, "
              f"rms distance {np.sqrt((d ** 2).mean()):.2e} m, {wall:.1f} s", flush=True)
    os.makedirs(a.out, exist_ok=True)
    write_csv_rows(os.path.join(a.out, "mls_reuse.csv"), rows)

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4))
    s = np.array(strains)
    reused = rows[1:]
    ax0.semilogx(s, [r["wall_s"] / ref_wall for r in reused], "o-", label="wall time / particle fit's")
    ax0.semilogx(s, [r["fitted_share"] for r in reused], "s-", label="share of the passes that fit")
    ax0.axhline(1.0, color="k", lw=0.8, ls="--")
    finish_axes(ax0, "reuse_strain", title=f"cost, {a.threads} thread(s)", fontsize=8)
    ax1.semilogx(s, [(r["front_m"] - rows[0]["front_m"]) / cell for r in reused], "o-", label="front - particle fit's")
    ax1.semilogx(s, [r["rms_distance_m"] / cell for r in reused], "s-", label="rms distance to the particle fit")
    ax1.semilogx(s, [r["largest_distance_m"] / cell for r in reused], "^-", label="largest distance")
    finish_axes(ax1, "reuse_strain", "cells", title=f"positions at {END} s (cell {cell} m)", fontsize=8)
    fig.suptitle("MLS weights reused: plane-strain DP column collapse, B-spline, linear fit at 1.5 cells")
    save_figure(fig, os.path.join(a.out, "mls_reuse.png"), 110)


if __name__ == "__main__":
    main_guard(main)
