#!/usr/bin/env python3
"""The sand flume with Drucker-Prager and with mu(I), back to back (issue 21, item 6; docs/flume.md,
"The flume with mu(I)").

    /usr/bin/python3 tools/flume_models.py --talus build/talus [--cell 0.02] [--threads 1]

Writes the two scenes with tools/make_flume_scene.py (the same geometry, bed and cell; only the sand's
model differs), runs them one after the other into RUNS/<model>_h<cell in 0.1 mm> (a finished run is
reused), and writes docs/flume/models_h<cell in 0.1 mm>.csv and .png (front and tail against time,
deposit profiles along the centre line).
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import ROOT, finish_axes, main_guard, read_csv_columns, run_flume, save_figure, value_at, write_csv_rows  # noqa: E402

MODELS = {"drucker_prager": "Drucker-Prager, phi = 40 deg", "mu_i": "mu(I), mu_s = tan 40 deg"}


def centre_line(run_dir, cell):
    """Deposit thickness along s: the mean of the raster rows within one raster cell of y = 0."""
    d = read_csv_columns(os.path.join(run_dir, "deposit.csv"))
    near = np.abs(d["y"]) <= cell
    s = np.unique(d["s"][near])
    return s, np.array([d["thickness"][near & (d["s"] == v)].mean() for v in s])


def front_at(runout, t, run_dir):
    """The front at time t; one line when the run's history does not reach t (np.interp clamped it)."""
    try:
        return value_at(runout["time"], runout["front"], t, run_dir)
    except ValueError as e:
        sys.exit(f"flume_models.py: {e}: nothing written")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--cell", type=float, default=0.02)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "flume_mu_i"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "flume"))
    a = ap.parse_args()
    os.makedirs(a.runs, exist_ok=True)
    os.makedirs(a.out, exist_ok=True)
    rows, runs = [], {}
    tag = f"h{round(a.cell * 1e4):04d}"
    for model in MODELS:
        name = f"{model}_{tag}"
        run_dir, runout, energy, result, wall = run_flume(a.talus, a.runs, name, a.cell, a.threads, ("--model", model))
        runs[model] = (run_dir, runout, result)
        released = energy["gravity"][0] - energy["gravity"][-1]
        row = {"model": model, "cell_size": a.cell,
               "wall_seconds": wall,
               "front_from_gate_t1": round(front_at(runout, 1.0, run_dir) - result["gate_s"], 4),
               "runout_from_gate": round(result["from_gate"], 4),
               "onto_runout_plane": round(result["beyond_runout_plane"], 4),
               "tail_s": round(result["tail"], 4),
               "mass_left_open_sides": round(1.0 - runout["mass"][-1] / runout["mass"][0], 4),
               "final_kinetic_over_peak": float(f"{energy['kinetic'][-1] / energy['kinetic'].max():.3e}"),
               "plastic_over_released": round(energy["plastic_work"][-1] / released, 4),
               "bed_friction_over_released": round(energy["friction_work"][-1] / released, 4),
               "budget_gap": float(f"{(energy['total'][-1] - energy['total'][0]) / abs(energy['total'][0]):.3e}")}
        rows.append(row)
        print(row, flush=True)
    write_csv_rows(os.path.join(a.out, f"models_{tag}.csv"), rows)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.2))
    for (model, (run_dir, r, result)), colour in zip(runs.items(), ("tab:blue", "tab:red")):
        ax.plot(r["time"], r["front"] - result["gate_s"], color=colour, label=f"front, {MODELS[model]}")
        ax.plot(r["time"], r["tail"] - result["gate_s"], "--", color=colour, lw=0.8, label=f"tail, {MODELS[model]}")
        s, thick = centre_line(run_dir, 2 * a.cell)
        bx.plot(s - result["gate_s"], 100 * thick, color=colour, label=MODELS[model])
    plane = runs["drucker_prager"][2]["runout_plane_s"] - runs["drucker_prager"][2]["gate_s"]
    ax.axhline(plane, color="0.5", lw=0.6)
    bx.axvline(plane, color="0.5", lw=0.6)
    finish_axes(ax, "time [s]", "distance from the gate along the flume [m]",
                f"front and tail (h = {a.cell:g} m; grey: start of the runout plane)", fontsize=7)
    finish_axes(bx, "distance from the gate along the flume [m]", "deposit thickness, centre line [cm]",
                "deposit at rest", fontsize=7)
    save_figure(fig, os.path.join(a.out, f"models_{tag}.png"), 120)
    print("wrote", os.path.join(a.out, f"models_{tag}.csv"), "and .png")


if __name__ == "__main__":
    main_guard(main)
