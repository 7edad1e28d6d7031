#!/usr/bin/env python3
"""The thin spots of a flume flow: where the flowing layer has no particles left, at one time.

    /usr/bin/python3 tools/flume_thin_spots.py RUN [RUN ...] [--time 1.0] [--cell 0.02]
                                              [--csv OUT.csv] [--png OUT.png]

For each run folder (a `talus run` output with particles.pvd and scene.json) it reads the frame
nearest to --time and reports, in plan view (x, y) on square cells of --cell metres:
  enclosed_empty_m2   the area of the empty cells that lie between occupied cells along the flow
                      (per y row, from the first to the last occupied cell in x): holes and necks
                      inside the flow, not the bare bed around it;
  separated           particles with exactly zero stress (the separation rule, V > ratio V0);
  front_x             the largest x of any particle.
With --png, a plan view of each run's particles coloured by density (docs/flume.md shows one).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from talus_plot import read_vtu, require_folders, series_frames, write_csv_rows  # noqa: E402


def frame_near(run, time):
    """(time, path) of the frame in run/particles.pvd nearest to `time`."""
    return min(series_frames(run), key=lambda f: abs(f[0] - time))


def read_particles(path):
    """Positions, stress (n x 6) and density of one .vtu frame."""
    d = read_vtu(path, "stress", "density")
    return d["points"], d["stress"], d["density"]


def enclosed_empty_area(x, y, cell):
    """Area of the empty plan cells between the first and last occupied cell of each y row."""
    ix = np.floor(x / cell).astype(int)
    iy = np.floor(y / cell).astype(int)
    empty = 0
    for row in np.unique(iy):
        occupied = np.unique(ix[iy == row])
        empty += (occupied[-1] - occupied[0] + 1) - len(occupied)
    return empty * cell * cell


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="talus run output folders")
    ap.add_argument("--time", type=float, default=1.0, help="time of the frame to read [s] (default 1)")
    ap.add_argument("--cell", type=float, default=0.02, help="plan cell size of the area count [m] (default 0.02)")
    ap.add_argument("--csv", help="write the table here")
    ap.add_argument("--png", help="plan views of the runs, coloured by density")
    a = ap.parse_args()
    require_folders(csv=a.csv, png=a.png)

    rows, views = [], []
    for run in a.runs:
        for needed in ("scene.json", "particles.pvd"):
            if not os.path.isfile(os.path.join(run, needed)):
                sys.exit(f"{run}: no {needed}; expected the output folder of `talus run`")
        scene = json.load(open(os.path.join(run, "scene.json")))
        t, path = frame_near(run, a.time)
        pos, stress, density = read_particles(path)
        separated = int(np.count_nonzero(np.all(stress == 0.0, axis=1)))
        row = {"run": os.path.basename(os.path.normpath(run)), "shape": scene["solver"].get("shape", "linear"),
               "cell_size": scene["grid"]["cell_size"], "particles": len(pos), "time": t,
               "enclosed_empty_m2": enclosed_empty_area(pos[:, 0], pos[:, 1], a.cell),
               "separated": separated, "front_x": float(pos[:, 0].max())}
        rows.append(row)
        views.append((row, pos, density))
        print(f"{row['run']:>24}  {row['shape']:>8}  h = {row['cell_size']:.4f} m  t = {t:.3f} s  "
              f"enclosed empty {row['enclosed_empty_m2'] * 1e4:6.0f} cm2  separated {separated:5d} of {len(pos)}  "
              f"front x = {row['front_x']:.3f} m")
    if a.csv:
        write_csv_rows(a.csv, rows)
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(len(views), 1, figsize=(8, 2.0 * len(views)), sharex=True, squeeze=False,
                                 constrained_layout=True)
        for ax, (row, pos, density) in zip(axes[:, 0], views):
            sc = ax.scatter(pos[:, 0], pos[:, 1], c=density, s=0.3, cmap="viridis", vmin=300, vmax=1700)
            ax.set_aspect("equal")
            ax.set_ylabel("y (m)")
            ax.set_title(f"{row['run']}: {row['shape']}, h = {row['cell_size'] * 1000:g} mm, t = {row['time']:.2f} s: "
                         f"enclosed empty {row['enclosed_empty_m2'] * 1e4:.0f} cm², {row['separated']} separated",
                         fontsize=9)
        axes[-1, 0].set_xlabel("x (m)")
        fig.colorbar(sc, ax=axes[:, 0].tolist(), label="density (kg/m³)", shrink=0.6, location="bottom", aspect=40)
        fig.savefig(a.png, dpi=130)
        plt.close(fig)
        print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
