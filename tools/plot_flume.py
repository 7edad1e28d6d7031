#!/usr/bin/env python3
"""Plots of a flume run's runout diagnostics (docs/flume.md "Runout diagnostics").

Reads RUN_DIR/runout.csv, runout.json, deposit.csv and scene.json (written by `talus run` for a
scene with diagnostics.runout) and writes into RUN_DIR (or --out):
  front_tail.png       front, tail and centre of mass along the flume vs time, and the front velocity
  deposit_profile.png  deposit thickness along the centre line vs s (the rows within one cell of the
                       mass centre's y), gate and runout plane marked
  deposit_map.png      plan-view thickness map in (s, y)
Usage: /usr/bin/python3 tools/plot_flume.py runs/denlinger_flume [--out DIR]
"""
import argparse
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import read_csv_columns  # noqa: E402
from cli_checks import output_folder  # noqa: E402

QUANTILES = {"front_quantile": 0.995, "tail_quantile": 0.005}  # diagnostics.runout's defaults (docs/scene-reference.md)


def reference_s(run_dir, runout):
    """s of the gate and of the runout plane's start, as the run measured them (runout.json)."""
    path = os.path.join(run_dir, "runout.json")
    if not os.path.exists(path):
        return float(runout["front"][0]), None
    with open(path) as f:
        r = json.load(f)
    return r["gate_s"], r.get("runout_plane_s")


def quantile_labels(scene):
    """The legend's words for the front and the tail: the mass quantiles the run measured them at
    (diagnostics.runout.front_quantile, tail_quantile; the legend said 99.5% and 0.5% whatever they were)."""
    runout = dict(QUANTILES, **scene.get("diagnostics", {}).get("runout", {}))
    return (f"front ({100 * runout['front_quantile']:g}% mass quantile)",
            f"tail ({100 * runout['tail_quantile']:g}% mass quantile)")


def band_centre(runout, y_values, thickness):
    """The y the deposit profile is centred on: the mass centre's y at the last row of runout.csv
    that has one (centre_y; nan once every particle has left), else the deposit's volume-weighted y,
    else 0. (A band fixed at y = 0 held no deposit in a scene whose grid starts at y = 0.)"""
    centre_y = runout.get("centre_y")
    if centre_y is not None:
        finite = np.asarray(centre_y, dtype=float)
        finite = finite[np.isfinite(finite)]
        if finite.size:
            return float(finite[-1])
    per_y = thickness.sum(axis=0)
    return float((per_y * y_values).sum() / per_y.sum()) if per_y.sum() > 0 else 0.0


def centre_line_band(y_values, centre):
    """The raster rows whose centres lie within one cell of y = centre (the nearest row if none), and
    the cell's width in y."""
    dy_cell = y_values[1] - y_values[0] if len(y_values) > 1 else 1.0
    distance = np.abs(y_values - centre)
    band = distance <= dy_cell * (1 + 1e-9)
    if not band.any():
        band = distance == distance.min()
    return band, dy_cell


def band_text(centre, dy_cell, band):
    """'|y - 0.2| <= 0.04 m (2 rows)'; '|y|' for a centre within round-off of 0."""
    y = "|y|" if abs(centre) < 1e-6 * dy_cell else f"|y - {centre:.3g}|"
    rows = int(band.sum())
    return f"{y} <= {dy_cell:.3g} m ({rows} row{'' if rows == 1 else 's'})"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir")
    p.add_argument("--out", help="folder for the PNGs (default: the run folder)")
    a = p.parse_args()
    # (runout.json comes at the end of a run: a killed run's history is plotted without it)
    for needed in ("runout.csv", "scene.json"):  # checked before any plot (was a traceback)
        if not os.path.isfile(os.path.join(a.run_dir, needed)):
            sys.exit(f"plot_flume.py: {os.path.join(a.run_dir, needed)} not found: give the folder of a run of a scene "
                     "with diagnostics.runout (talus run SCENE --out DIR)")
    runout = read_csv_columns(os.path.join(a.run_dir, "runout.csv"))
    if not runout:  # (a run stopped before its first row: was KeyError 'front')
        sys.exit(f"plot_flume.py: {os.path.join(a.run_dir, 'runout.csv')} holds no rows: nothing to plot")
    out = output_folder("--out", a.out) if a.out else a.run_dir
    with open(os.path.join(a.run_dir, "scene.json")) as f:
        scene = json.load(f)
    gate, plane = reference_s(a.run_dir, runout)
    if not os.path.isfile(os.path.join(a.run_dir, "runout.json")):
        print("runout.json missing (the run did not reach its end): the gate drawn is the initial front")
    name = scene.get("name", os.path.basename(a.run_dir.rstrip("/")))

    t = runout["time"]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    front_label, tail_label = quantile_labels(scene)
    ax1.plot(t, runout["front"], label=front_label)
    ax1.plot(t, runout["centre_s"], label="centre of mass")
    ax1.plot(t, runout["tail"], label=tail_label)
    ax1.plot(t, runout["s_max"], ":", color="grey", lw=0.8, label="foremost particle")
    ax1.axhline(gate, color="k", lw=0.6, ls="--", label="gate")
    if plane is not None:
        ax1.axhline(plane, color="brown", lw=0.6, ls="--", label="start of runout plane")
    ax1.set_ylabel("s along the flume [m]")
    ax1.legend(fontsize=8)
    ax1.set_title(f"{name}: front and tail")
    ax2.plot(t, runout["front_velocity"], label="front velocity d(front)/dt")
    ax2.plot(t, runout["centre_velocity_s"], label="centre-of-mass velocity along the bed")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("velocity [m/s]")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "front_tail.png"), dpi=130)
    plt.close(fig)

    deposit_path = os.path.join(a.run_dir, "deposit.csv")
    if not os.path.exists(deposit_path):
        print(f"{deposit_path} missing (the run did not reach its end): only front_tail.png written")
        return
    d = read_csv_columns(deposit_path)
    s_values = np.unique(d["s"])
    y_values = np.unique(d["y"])
    thickness = d["thickness"].reshape(len(s_values), len(y_values))  # rows of constant s
    centre = band_centre(runout, y_values, thickness)
    band, dy_cell = centre_line_band(y_values, centre)
    profile = thickness[:, band].mean(axis=1)
    if thickness.any() and not profile.any():
        print(f"plot_flume.py: warning: the deposit profile's band ({band_text(centre, dy_cell, band)}) holds no "
              "deposit: deposit_profile.png shows a zero line", file=sys.stderr)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.plot(s_values, profile * 1000, drawstyle="steps-mid",
            label=f"current volume: mean over {band_text(centre, dy_cell, band)}")
    if "thickness_seeded" in d:  # the same mass at its seeded density (docs/flume.md "The sand loosens")
        seeded = d["thickness_seeded"].reshape(len(s_values), len(y_values))
        ax.plot(s_values, seeded[:, band].mean(axis=1) * 1000, drawstyle="steps-mid", color="C2",
                label="seeded volume (the same mass at its seeded density)")
    ax.axvline(gate, color="k", lw=0.6, ls="--", label="gate")
    if plane is not None:
        ax.axvline(plane, color="brown", lw=0.6, ls="--", label="start of runout plane")
    occupied = np.nonzero(thickness.max(axis=1) > 0)[0]
    if occupied.size:
        pad = 5 * (s_values[1] - s_values[0]) if len(s_values) > 1 else 0.1
        ax.set_xlim(s_values[occupied[0]] - pad, s_values[occupied[-1]] + pad)
    ax.set_xlabel("s along the flume [m]")
    ax.set_ylabel("deposit thickness [mm]")
    ax.set_title(f"{name}: deposit along the centre line (volume per bed area)")
    ax.set_ylim(top=ax.get_ylim()[1] * 1.4)  # room for the legend above the deposit
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "deposit_profile.png"), dpi=130)
    plt.close(fig)

    ds = s_values[1] - s_values[0] if len(s_values) > 1 else 1.0
    dy = y_values[1] - y_values[0] if len(y_values) > 1 else 1.0
    extent = [s_values[0] - ds / 2, s_values[-1] + ds / 2, y_values[0] - dy / 2, y_values[-1] + dy / 2]
    # Crop to the deposit (plus a margin), and size the figure to its aspect ratio.
    s_lo, s_hi, y_lo, y_hi = extent
    occupied_y = np.nonzero(thickness.max(axis=0) > 0)[0]
    if occupied.size and occupied_y.size:
        s_lo, s_hi = s_values[occupied[0]] - pad, s_values[occupied[-1]] + pad
        y_lo, y_hi = y_values[occupied_y[0]] - 3 * dy, y_values[occupied_y[-1]] + 3 * dy
    ratio = (s_hi - s_lo) / max(y_hi - y_lo, 1e-9)
    fig, ax = plt.subplots(figsize=(min(12.0, max(4.0, 2.8 * ratio)) + 1.5, 3.6))
    masked = np.ma.masked_where(thickness <= 0, thickness * 1000)
    im = ax.imshow(masked.T, origin="lower", extent=extent, aspect="equal", cmap="viridis", interpolation="nearest")
    fig.colorbar(im, ax=ax, label="thickness [mm]", shrink=0.9)
    ax.axvline(gate, color="k", lw=0.6, ls="--", label="gate")
    if plane is not None:
        ax.axvline(plane, color="brown", lw=0.6, ls="--", label="start of runout plane")
    ax.set_xlim(s_lo, s_hi)
    ax.set_ylim(y_lo, y_hi)
    ax.set_xlabel("s along the flume [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{name}: deposit thickness, plan view")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "deposit_map.png"), dpi=130)
    plt.close(fig)
    print(f"wrote {out}/front_tail.png, deposit_profile.png, deposit_map.png")


if __name__ == "__main__":
    main()
