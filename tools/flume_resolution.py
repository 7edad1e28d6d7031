#!/usr/bin/env python3
"""Resolution study of the sand flume (docs/flume.md "Resolution study").

For each cell size, writes the flume scene with tools/make_flume_scene.py (the defaults otherwise),
runs it with `talus run` (skipped when RUNS/flume_hNNNN/runout.json says the run completed, unless
--rerun), and collects the front at three times, the final runout, the share of the mass that left
over the open sides, the final kinetic energy over its peak and the run time. Writes
    docs/flume/resolution.csv      one row per cell size
    docs/flume/resolution.png      front vs time for every cell size
Usage: /usr/bin/python3 tools/flume_resolution.py [--talus build/talus] [--cells 0.02 0.0125 0.01]
                                                  [--threads 2] [--runs runs] [--rerun]
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import finish_axes, run_flume, save_figure, write_csv_rows  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMES = (0.5, 1.0, 2.0)  # [s] front positions compared between resolutions


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--cells", type=float, nargs="+", default=[0.02, 0.0125, 0.01])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "flume"))
    ap.add_argument("--rerun", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows, histories = [], {}
    for h in a.cells:
        name = f"flume_h{round(h * 1e4):04d}"
        run_dir, runout, energy, result, wall = run_flume(a.talus, a.runs, name, h, a.threads, rerun=a.rerun)
        histories[h] = runout
        fronts = [float(np.interp(t, runout["time"], runout["front"])) - result["gate_s"] for t in TIMES]
        mass0 = runout["mass"][0]
        kinetic = energy["kinetic"]
        row = {"cell_size": h, "wall_seconds": wall,
               **{f"front_from_gate_t{t:g}": round(v, 4) for t, v in zip(TIMES, fronts)},
               "runout_from_gate": round(result["from_gate"], 4),
               "onto_runout_plane": round(result["beyond_runout_plane"], 4) if result.get("beyond_runout_plane") is not None else None,
               "mass_left_open_sides": round(1.0 - runout["mass"][-1] / mass0, 4),
               "final_kinetic_over_peak": float(f"{kinetic[-1] / kinetic.max():.3e}"),
               "budget_gap": float(f"{(energy['total'][-1] - energy['total'][0]) / abs(energy['total'][0]):.3e}")}
        rows.append(row)
        print(row, flush=True)
    write_csv_rows(os.path.join(a.out, "resolution.csv"), rows)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for h, r in histories.items():
        ax.plot(r["time"], r["front"], label=f"front, h = {h:g} m")
        ax.plot(r["time"], r["tail"], "--", lw=0.8, label=f"tail, h = {h:g} m")
    finish_axes(ax, "time [s]", "s along the flume [m]", "sand flume: front and tail at three cell sizes", fontsize=7)
    save_figure(fig, os.path.join(a.out, "resolution.png"), 120)
    print("wrote", os.path.join(a.out, "resolution.csv"), "and resolution.png")


if __name__ == "__main__":
    main()
