#!/usr/bin/env python3
"""Planar column collapse study (issue 21, item 5): runout and deposit height against the aspect ratio,
Drucker-Prager and mu(I), two resolutions, against the laws of Lube et al. 2005.

    /usr/bin/python3 tools/collapse_study.py --talus build/talus            # every run (about an hour on 2 cores)
    /usr/bin/python3 tools/collapse_study.py --talus build/talus --cells 10 --aspects 0.5 2   # a quick look
    /usr/bin/python3 tools/collapse_study.py --talus build/talus --cells 40 --aspects 0.5 1 \
        --out docs/verification --name collapse_refine_h40                  # the refinement in the docs

Scenes come from tools/make_collapse_scene.py (its defaults are the study's parameters,
docs/verification.md "Planar column collapse"). Each run goes to RUNS/<model>_a<a>_n<cells>; a run
that completed (its run.json says so) with the same scene is reused, not run again; one stopped early
(Ctrl-C, --stop-after) is run again. Runs go `--jobs` at a
time, each on `--threads` threads.

Measured per run (L0 = the column's length, the gate at x = L0):
  runout      dL/L0 = (front - L0)/L0 with front = the 0.995 mass quantile of x at the end
              (talus's runout diagnostics, docs/flume.md sec. 4: robust to a few stray grains);
  connected   dL/L0 from the last particle that is still connected to the deposit: particles sorted by
              x, the first gap wider than two cells along x ends the deposit (the edge a ruler sees);
  height      H_inf/L0 = (highest particle beyond two cells from the back wall + half a particle
              spacing)/L0 (exactly a for the column). height_at_wall is the same within those two cells:
              in the tall columns a sliver of particles one cell wide stays pinned to the slip back wall
              above the deposit, creeping down at 1-3 cm/s at the end (docs/verification.md);
  rest        kinetic energy at the end / its peak, and how far the front moved over the last 10% of
              the run (relative to the runout): the deposit must have stopped;
  budget      energy budget gap at the end / potential energy released; outflow (mass that ran off).
Writes OUT/NAME.csv and OUT/NAME.png (NAME = collapse_study) and prints a Markdown table. OUT is
docs/verification for the whole study (the default aspects, cells, models and no --scene-args) and
the --runs folder for any other sweep, so that a quick look does not overwrite the shipped table.
"""
import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, make_collapse_scene
import make_collapse_scene  # noqa: E402
from talus_plot import (ROOT, TalusError, main_guard, read_csv_columns, read_vtu, run_finished, run_status,  # noqa: E402
                        save_figure, series_frames, talus_failure, write_csv_rows)

MODELS = {"dp": "Drucker-Prager", "mu_i": "mu(I)"}


def lube_runout(a):
    """Lube et al. 2005: (L_inf - L0)/L0 = 1.2 a (a below the transition), 1.9 a^(2/3) above; split at
    a = 2.3 as issue 21 states it (the paper gives the transition as 1.8 < a < 2.8)."""
    return np.where(np.asarray(a) <= 2.3, 1.2 * np.asarray(a), 1.9 * np.asarray(a) ** (2.0 / 3.0))


def lube_height(a):
    """Lube et al. 2005: H_inf/L0 = a while the top of the column is not reached by the failure, a^0.4
    above (as tabulated by Lagree, Staron & Popinet 2011, eq. 3.2); the two meet at a = 1."""
    a = np.asarray(a, dtype=float)
    return np.minimum(a, a ** 0.4)


def read_csv_columns_rows(path):
    import csv
    with open(path) as f:
        return list(csv.DictReader(f))


def scene_for(model, a, cells, extra):
    argv = ["--aspect", f"{a:g}", "--model", model, "--cells", str(cells), *extra]
    o = make_collapse_scene.parser().parse_args(argv)
    o.command_line = " ".join(argv)
    return make_collapse_scene.build(o), o


def run_one(talus, scene, run_dir, threads, lock=None):
    os.makedirs(run_dir, exist_ok=True)
    path = os.path.join(run_dir, "input.json")
    text = json.dumps(scene, indent=1)
    done = os.path.join(run_dir, "runout.json")
    same = lambda s: {k: v for k, v in s.items() if k != "comment"}  # the comment names the command line
    # (runout.json alone was taken for done: a Ctrl-C'd run writes it too, and was measured)
    if run_finished(run_dir) and os.path.exists(path):
        with open(path) as f:
            if same(json.load(f)) == same(scene):
                return "reused"
    with open(path, "w") as f:
        f.write(text)
    if os.path.exists(done):
        os.remove(done)
    # (--overwrite: an unfinished run there, with its checkpoint, is run again from the start)
    cmd = [talus, "run", path, "--out", run_dir, "--overwrite", "--threads", str(threads), "--quiet"]
    if lock:  # a shared lock per run (not for the whole study) on a machine whose users time things
        cmd = ["flock", "-s", lock, *cmd]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise TalusError(f"{run_dir}: {talus_failure(cmd, r)}")
    return "ran"


def measure(run_dir, o):
    L0 = o.length
    h = L0 / o.cells
    spacing = h / o.particles_per_cell
    res = json.load(open(os.path.join(run_dir, "runout.json")))
    xyz = read_vtu(series_frames(run_dir)[-1][1])["points"]
    away = xyz[:, 0] > 2 * h  # the height away from the back wall: see height_at_wall in the docstring
    x = np.sort(xyz[:, 0])
    gaps = np.nonzero(np.diff(x) > 2 * h)[0]
    connected = x[gaps[0]] if len(gaps) else x[-1]
    e = read_csv_columns(os.path.join(run_dir, "energy.csv"))
    released = e["gravity"][0] - e["gravity"][-1]
    ro = read_csv_columns(os.path.join(run_dir, "runout.csv"))
    t_end = ro["time"][-1]
    late = ro["time"] >= 0.9 * t_end
    front_drift = (ro["front"][-1] - ro["front"][late][0]) / max(ro["front"][-1] - L0, 1e-12)
    return {
        "runout": (res["front"] - L0) / L0,
        "runout_connected": (connected - L0) / L0,
        "runout_max": (x[-1] - L0) / L0,
        "height": (xyz[away, 2].max() + spacing / 2) / L0,
        "height_at_wall": (xyz[~away, 2].max() + spacing / 2) / L0,
        "kinetic_end_over_peak": e["kinetic"][-1] / e["kinetic"].max(),
        "front_drift_last_10pct": front_drift,
        "budget_gap": (e["total"][-1] - e["total"][0]) / released,
        "outflow_J": e["outflow"][-1],
        "steps": int(e["step"][-1]),
        "end_time": t_end,
        "particles": len(x),
    }


def plot(rows, out_png, overlays=()):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    aa = np.geomspace(0.4, 10, 200)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    style = {("dp", "coarse"): ("s", "tab:blue", "none"), ("dp", "fine"): ("s", "tab:blue", "tab:blue"),
             ("mu_i", "coarse"): ("o", "tab:red", "none"), ("mu_i", "fine"): ("o", "tab:red", "tab:red")}
    cells = sorted({r["cells"] for r in rows})
    label_of = {c: ("coarse" if c == cells[0] and len(cells) > 1 else "fine") for c in cells}
    for ax, key, law, ylabel in ((axes[0], "runout", lube_runout, "(L_inf - L0) / L0"),
                                 (axes[1], "height", lube_height, "H_inf / L0")):
        ax.plot(aa, law(aa), "k-", lw=1.5, label="Lube et al. 2005")
        if key == "runout":
            ax.fill_between(aa, 0.85 * law(aa), 1.15 * law(aa), color="0.85", label="Lube +-15% (issue 21 target)")
        for model in ("dp", "mu_i"):
            for c in cells:
                sel = sorted((r for r in rows if r["model"] == model and r["cells"] == c), key=lambda r: r["aspect"])
                if not sel:
                    continue
                m, col, face = style[(model, label_of[c])]
                ax.plot([r["aspect"] for r in sel], [r[key] for r in sel], marker=m, color=col, mfc=face, ls="-" if
                        label_of[c] == "fine" else ":", label=f"{MODELS[model]}, h = L0/{c}")
        for path, label in overlays:  # another study's CSV (e.g. the rate-independent control), grey
            o = sorted(read_csv_columns_rows(path), key=lambda r: float(r["aspect"]))
            ax.plot([float(r["aspect"]) for r in o], [float(r[key]) for r in o], "^--", color="0.45", mfc="none",
                    lw=0.8, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("a = H0 / L0")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title("Runout (front: 0.995 mass quantile)")
    axes[1].set_title("Deposit height")
    save_figure(fig, out_png, 120)


def whole_study(ap, args):
    """True when the sweep is the study docs/verification.md shows: only then is it written there."""
    return all(getattr(args, k) == ap.get_default(k) for k in ("aspects", "cells", "models", "scene_args"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--runs", default=os.path.join(ROOT, "runs", "collapse_study"))
    ap.add_argument("--out", help="folder for NAME.csv and NAME.png (default: docs/verification for the whole "
                    "study, the --runs folder for a partial sweep)")
    ap.add_argument("--name", default="collapse_study", help="base name of the CSV and the plot (default %(default)s)")
    ap.add_argument("--aspects", type=float, nargs="+", default=[0.5, 1, 2, 3, 5, 8])
    ap.add_argument("--cells", type=int, nargs="+", default=[10, 20], help="cells per L0")
    ap.add_argument("--models", nargs="+", default=["dp", "mu_i"], choices=list(MODELS))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--scene-args", default="", help="more options for make_collapse_scene.py, e.g. '--shape linear'")
    ap.add_argument("--lock", help="run each talus under `flock -s LOCK` (a lock file, e.g. /tmp/talus.lock, that timed jobs on a shared machine hold exclusively)")
    ap.add_argument("--overlay", nargs=2, action="append", default=[], metavar=("CSV", "LABEL"),
                    help="also plot the runs of another study's collapse_study.csv (e.g. a control), in grey")
    ap.add_argument("--no-run", action="store_true", help="only measure the runs that are there")
    args = ap.parse_args()
    if args.lock and not os.path.isdir(os.path.dirname(os.path.abspath(args.lock))):  # was a traceback after the first run
        sys.exit(f"collapse_study.py: --lock {args.lock}: the folder {os.path.dirname(os.path.abspath(args.lock))} does not exist")
    extra = args.scene_args.split()
    cases = []
    for model in args.models:
        for c in args.cells:
            for a in args.aspects:
                scene, o = scene_for(model, a, c, extra)
                cases.append((model, a, c, scene, o, os.path.join(args.runs, f"{model}_a{a:g}_n{c}")))
    # coarse before fine, small a before large: the cheap runs give a first table early
    cases.sort(key=lambda k: (k[2], k[1], k[0]))
    if not args.no_run:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            futures = {pool.submit(run_one, args.talus, k[3], k[5], args.threads, args.lock): k for k in cases}
            for f, k in futures.items():
                print(f"{k[5]}: {f.result()}", flush=True)
    rows = []
    for model, a, c, scene, o, run_dir in cases:
        if not run_finished(run_dir):  # (with --no-run: missing, or stopped early)
            if run_status(run_dir):
                print(f"{run_dir}: not measured: the run did not complete (run.json says "
                      f"'{run_status(run_dir)}')", file=sys.stderr)
            continue
        m = measure(run_dir, o)
        ref = float(lube_runout(a))
        rows.append({"model": model, "aspect": a, "cells": c, **m, "lube_runout": ref,
                     "runout_deviation": m["runout"] / ref - 1, "lube_height": float(lube_height(a))})
    if not rows:  # (was an IndexError when the CSV was written)
        sys.exit(f"collapse_study.py: no finished run in {args.runs}: run it without --no-run first")
    rows.sort(key=lambda r: (r["model"], r["cells"], r["aspect"]))
    out = args.out or (os.path.join(ROOT, "docs", "verification") if whole_study(ap, args) else args.runs)
    os.makedirs(out, exist_ok=True)
    csv_path, png_path = (os.path.join(out, args.name + ext) for ext in (".csv", ".png"))
    write_csv_rows(csv_path, [{k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows])
    plot(rows, png_path, args.overlay)
    print(f"wrote {csv_path} and {png_path}")
    print("| model | h | a | dL/L0 (0.995 quantile) | Lube | deviation | dL/L0 connected | H/L0 | Lube H/L0 | "
          "H/L0 at the wall | E_kin end/peak | front drift last 10% | budget gap |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {MODELS[r['model']]} | L0/{r['cells']} | {r['aspect']:g} | {r['runout']:.3f} | {r['lube_runout']:.2f} | "
              f"{100 * r['runout_deviation']:+.0f}% | {r['runout_connected']:.3f} | {r['height']:.3f} | "
              f"{r['lube_height']:.2f} | {r['height_at_wall']:.3f} | {r['kinetic_end_over_peak']:.1e} | {100 * r['front_drift_last_10pct']:.2f}% | "
              f"{r['budget_gap']:+.1e} |")
    for model in args.models:
        for c in args.cells:
            dev = [abs(r["runout_deviation"]) for r in rows if r["model"] == model and r["cells"] == c]
            if dev:
                print(f"{MODELS[model]}, h = L0/{c}: largest |deviation| from Lube et al. 2005 {100 * max(dev):.0f}% "
                      f"over {len(dev)} aspect ratios")


if __name__ == "__main__":
    sys.exit(main_guard(main))
