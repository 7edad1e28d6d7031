#!/usr/bin/env python3
"""MLS radius sweep on the column W = 12500 (Edo & Matsubara 2015, Fig. 6-7; the paper leaves the radius open:
"the radius of influence is the cell size times an arbitrary constant").

For linear MPM, uGIMP and cpGIMP, runs the column without MLS and with each basis spanning x (linear,
quadratic, cubic: 2, 3 and 4 terms; the bar is 2 particles across) at each radius, and writes into
docs/verification/:
    mls_column_radius_sweep.csv   L2 error and roughness of every run, and the reduction factor
    mls_column_radius_sweep.png   roughness reduction and L2 error against the radius
The issue's target (roughness >= 5x lower, L2 not worse) is drawn on both panels.
Usage:  /usr/bin/python3 tools/mls_radius_sweep.py [--talus build/talus] [--threads 1]
        [--radii 1.5,2,2.5,3,4,6] [--shapes linear,ugimp,cpgimp]      (about 2 minutes on 1 core)
Needs numpy, matplotlib and VTK's Python module (Debian: python3-numpy python3-matplotlib python3-vtk9).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from speed_vs_error import benchmark_parser, out_folder, find_talus, load, variant, run, column_metrics  # noqa: E402
from plot_mls import with_mls  # noqa: E402
from talus_plot import finish_axes, save_figure, write_csv_rows  # noqa: E402

BASES = ["linear", "quadratic", "cubic"]


def main():
    ap = benchmark_parser(__doc__, scratch_when="with other --radii or --shapes")
    ap.add_argument("--radii", default="1.5,2,2.5,3,4,6", help="radius factors (h / cell size), comma-separated")
    ap.add_argument("--shapes", default="linear,ugimp,cpgimp")
    a = ap.parse_args()
    talus = find_talus(a.talus)
    radii = [float(r) for r in a.radii.split(",")]
    shapes = a.shapes.split(",")
    # radii or shapes other than the defaults are a partial sweep: not into the docs' folder unless --out says so
    out = out_folder(a, scratch=(a.radii, a.shapes) != (ap.get_default("radii"), ap.get_default("shapes")))
    print(f"writing into {out}", flush=True)
    base = load("column_w12500")
    b = base["gravity"][0]

    def measure(shape, basis, radius):
        res = run(talus, with_mls(variant(base, shape, "musl"), basis, radius, "x"), a.threads)
        if res is None:
            sys.exit(f"column {shape} {basis} radius {radius}: run failed")
        return column_metrics(res, b)

    rows = []
    fig, axes = plt.subplots(2, len(shapes), figsize=(4.3 * len(shapes), 7), sharex=True, squeeze=False)
    for col, shape in enumerate(shapes):
        l2_off, rough_off = measure(shape, "off", 0.0)
        rows.append({"shape": shape, "basis": "off", "radius": "", "l2": l2_off, "roughness": rough_off,
                     "reduction": 1.0, "target_met": ""})
        print(f"{shape:7s} off                 L2 {l2_off:.4f} roughness {rough_off:.5f}", flush=True)
        for basis in BASES:
            red, l2s = [], []
            for radius in radii:
                l2, rough = measure(shape, basis, radius)
                met = rough_off / rough >= 5.0 and l2 <= l2_off
                rows.append({"shape": shape, "basis": basis, "radius": radius, "l2": l2, "roughness": rough,
                             "reduction": rough_off / rough, "target_met": int(met)})
                print(f"{shape:7s} {basis:9s} r = {radius:<4g}  L2 {l2:.4f} roughness {rough:.5f}"
                      f" reduction {rough_off / rough:5.1f}x{'  (target met)' if met else ''}", flush=True)
                red.append(rough_off / rough)
                l2s.append(l2)
            axes[0][col].plot(radii, red, "o-", ms=3, label=f"{basis} (x)")
            axes[1][col].plot(radii, [100 * v for v in l2s], "o-", ms=3, label=f"{basis} (x)")
        axes[0][col].axhline(5.0, color="k", ls="--", lw=0.8, label="target: 5x")
        axes[0][col].set_yscale("log")
        axes[1][col].axhline(100 * l2_off, color="k", ls="--", lw=0.8, label="without MLS (target: not worse)")
        axes[1][col].set_yscale("log")
        finish_axes(axes[0][col], None, "roughness without / with MLS" if col == 0 else None,
                    f"{shape}: column W = 12500, t = {base['time']['end']} s", fontsize=7)
        finish_axes(axes[1][col], "MLS radius [cells]", "L2 error [%]" if col == 0 else None, None, fontsize=7)
    save_figure(fig, os.path.join(out, "mls_column_radius_sweep.png"), 110)
    write_csv_rows(os.path.join(out, "mls_column_radius_sweep.csv"), rows)


if __name__ == "__main__":
    main()
