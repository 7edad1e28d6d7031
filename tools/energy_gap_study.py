#!/usr/bin/env python3
"""What the energy budget's gap is made of on the plane-strain Drucker-Prager column collapse
(docs/drucker-prager.md sec. 7b; the terms: docs/theory.md, "Where the budget's gap comes from").

Runs inputs/column_collapse_2d.json (energy_gap_terms on, 0.8 s) over the cell size for three
shape functions, and at the test's cell (0.01 m) with a smaller time step, more particles per cell
and USL. Each run's gap (total - initial total) splits, to round-off, into
  stress    strain change + plastic_work - grid_stress_work: stress work booked at the particles
            beyond what the stresses took from the grid's motion
  walls     friction_work - grid_wall_work
  gravity   gravity change + grid_gravity_work
  transfer  -transfer_loss: the kinetic energy of the nodes' velocity increments that the FLIP
            update does not give the particles
(with the stored and potential energy of any particle removed at an open face counted in the
stress and gravity parts), each over the potential energy released. A run is skipped when RUNS/<name>/energy.csv exists, unless --rerun.
Writes OUT/energy_gap.csv and OUT/energy_gap.png (OUT: docs/verification by default).

Usage: /usr/bin/python3 tools/energy_gap_study.py [--talus build/talus] [--threads 2]
           [--runs build/energy_gap_study] [--out docs/verification] [--rerun]
"""
import argparse
import copy
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import finish_axes, main_guard, read_csv_columns, run_talus, save_figure, write_csv_rows  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "inputs", "column_collapse_2d.json")
CELLS = [0.02, 0.01, 0.005]
SHAPES = ["linear", "bspline2", "cpgimp"]
# at the test's cell, linear MUSL: one setting changed at a time
VARIANTS = [("courant 0.1", {"courant": 0.1}), ("4 particles per cell and axis", {"ppc": 4}),
            ("USL", {"scheme": "usl"})]
PARTS = {"stress": "C1", "walls": "C2", "gravity": "C4", "transfer": "C0"}  # and their colours


def column(cell, shape="linear", scheme="musl", courant=0.3, ppc=2):
    """inputs/column_collapse_2d.json at this cell (one cell thick), shape, scheme, Courant number and
    particles per cell and axis, to 0.8 s, with the energy gap terms."""
    with open(SCENE) as f:
        scene = json.load(f)
    s = copy.deepcopy(scene)
    s["grid"]["size"][1] = cell
    s["grid"]["size"][2] = 0.3  # a whole number of cells for every cell size here
    s["grid"]["cell_size"] = cell
    s["bodies"][0]["box"]["max"][1] = cell
    s["bodies"][0]["particles_per_cell"] = ppc
    s["time"] = {"end": 0.8, "courant": courant}
    s["solver"] = {"scheme": scheme, "shape": shape}
    s["output"] = {"frame_interval": 0.8, "history_interval": 0.01, "compression": "lz4", "energy_gap_terms": True}
    return s


def parts(run_dir):
    """The gap and its parts at the last row, over the released potential energy."""
    e = read_csv_columns(os.path.join(run_dir, "energy.csv"))
    first = {k: float(v[0]) for k, v in e.items()}
    last = {k: float(v[-1]) for k, v in e.items()}
    released = first["gravity"] - last["gravity"]
    p = {
        "stress": (last["strain"] - first["strain"] + last["outflow_strain"] + last["plastic_work"]
                   - last["grid_stress_work"]),
        "walls": last["friction_work"] - last["grid_wall_work"],
        "gravity": last["gravity"] - first["gravity"] + last["outflow_gravity"] + last["grid_gravity_work"],
        "transfer": -last["transfer_loss"],
    }
    gap = last["total"] - first["total"]
    out = {"released_J": released, "gap": gap / released}
    out.update({k: v / released for k, v in p.items()})
    out["residual"] = (gap - sum(p.values())) / released
    out["steps"] = int(last["step"])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", default=os.path.join(ROOT, "build", "energy_gap_study"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification"))
    ap.add_argument("--rerun", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.runs, exist_ok=True)
    os.makedirs(a.out, exist_ok=True)
    cases = [(f"{shape}_h{cell:g}", {"cell": cell, "shape": shape}, f"{shape}, cell {cell:g} m")
             for shape in SHAPES for cell in CELLS]
    cases += [(f"linear_h0.01_{label.split()[0].lower()}", {"cell": 0.01, **kw}, f"linear, cell 0.01 m, {label}")
              for label, kw in VARIANTS]
    rows = []
    for name, kw, label in cases:
        run_dir = os.path.join(a.runs, name)
        if a.rerun or not os.path.exists(os.path.join(run_dir, "energy.csv")):
            scene = column(**kw)
            scene["name"] = "column_gap_" + name
            scene_path = run_dir + ".json"
            with open(scene_path, "w") as f:
                json.dump(scene, f, indent=1)
            print(f"energy_gap_study: {label} ...", flush=True)
            run_talus(a.talus, "run", scene_path, "--out", run_dir, threads=a.threads)
        row = {"case": label, "shape": kw.get("shape", "linear"), "cell_m": kw["cell"], **parts(run_dir)}
        rows.append({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()})
        print(", ".join(f"{k} {v}" for k, v in rows[-1].items()), flush=True)
    write_csv_rows(os.path.join(a.out, "energy_gap.csv"), rows)

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1, 1.4]})
    markers = {"linear": "o", "bspline2": "s", "cpgimp": "^"}
    for shape in SHAPES:
        mine = [r for r in rows if r["shape"] == shape and r["case"].endswith(" m")]
        cells = [float(r["cell_m"]) for r in mine]
        m = markers[shape]
        left.loglog(cells, [-float(r["transfer"]) for r in mine], m + "-", color="C0", label=f"{shape}: transfer loss")
        left.loglog(cells, [float(r["stress"]) for r in mine], m + "--", color="C1", label=f"{shape}: stress work booked beyond the grid's")
        left.loglog(cells, [-float(r["gap"]) for r in mine], m + ":", color="k", label=f"{shape}: −gap")
    finish_axes(left, "cell size [m]", "share of the released potential energy", "Over the cell size (MUSL)", fontsize=6,
                loc="lower right")
    x = range(len(rows))
    bottom_pos = [0.0] * len(rows)
    bottom_neg = [0.0] * len(rows)
    for part, colour in PARTS.items():
        values = [100 * float(r[part]) for r in rows]
        base = [bottom_pos[j] if v >= 0 else bottom_neg[j] for j, v in enumerate(values)]
        right.bar(x, values, bottom=base, color=colour, label=part)
        for j, v in enumerate(values):
            if v >= 0:
                bottom_pos[j] += v
            else:
                bottom_neg[j] += v
    right.plot(x, [100 * float(r["gap"]) for r in rows], "k_", markersize=14, mew=2, label="gap (their sum)")
    right.axhline(0.0, color="k", lw=0.6)
    right.set_xticks(list(x))
    right.set_xticklabels([r["case"] for r in rows], rotation=60, ha="right", fontsize=7)
    finish_axes(right, None, "% of the released potential energy", "The gap's parts at 0.8 s", fontsize=7)
    save_figure(fig, os.path.join(a.out, "energy_gap.png"), 110)
    print(f"energy_gap_study: {os.path.join(a.out, 'energy_gap.csv')}, energy_gap.png")


if __name__ == "__main__":
    main_guard(main)
