#!/usr/bin/python3
"""Abe 1996, Fig. 7 and Fig. 8 from talus's static hexagonal-assembly analysis.

Runs the GoogleTest sweep (HexAssemblySweep.ReproducesAbe1996Fig7AndFig8 in talus_dem_tests) with
TALUS_DEM_SWEEP_CSV set, then draws

  docs/verification/dem_poisson_fig7.png   nu (eq. 35) against kT/kN, with eq. 22
  docs/verification/dem_modulus_fig8.png   2G/((1 - nu) kN) (eq. 36) against kT/kN, with eq. 37

and prints the largest deviations quoted in docs/dem.md.

    /usr/bin/python3 tools/plot_dem_verification.py --build-dir build
    /usr/bin/python3 tools/plot_dem_verification.py --csv sweep.csv      # plot an existing sweep
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import finish_axes, require_inputs, save_figure  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER = "equal_end_forces"
EXACT = "uniform_stress_tractions"


def run_sweep(build_dir, csv_path):
    binary = os.path.join(build_dir, "talus_dem_tests")
    if not os.path.exists(binary):
        sys.exit(f"{binary} not found: build it with cmake --build {build_dir} --target talus_dem_tests")
    env = dict(os.environ, TALUS_DEM_SWEEP_CSV=csv_path)
    subprocess.run([binary, "--gtest_filter=HexAssemblySweep.*"], env=env, check=True)


def read_sweep(csv_path):
    rows = []
    with open(csv_path, newline="") as f:
        for row in csv.DictReader(f):
            parsed = {k: (v if k == "loading" else float(v)) for k, v in row.items()}
            rows.append(parsed)
    return rows


def series(rows, loading, key, keep=lambda r: True):
    chosen = [r for r in rows if r["loading"] == loading and r["solved"] == 1.0 and keep(r)]
    chosen.sort(key=lambda r: r["kT_over_kN"])
    return [r["kT_over_kN"] for r in chosen], [r[key] for r in chosen]


def clipped(xs, ys, low, high):
    """Points inside the axes, and those outside drawn on its edge."""
    inside = [(x, y) for x, y in zip(xs, ys) if low <= y <= high]
    above = [(x, high) for x, y in zip(xs, ys) if y > high]
    below = [(x, low) for x, y in zip(xs, ys) if y < low]
    return inside, above, below


def scatter(ax, points, **style):
    if points:
        ax.plot([p[0] for p in points], [p[1] for p in points], linestyle="none", **style)


def block_label(rows, loading):
    sizes = {int(r["rows"]) for r in rows if r["loading"] == loading}
    size = sizes.pop() if len(sizes) == 1 else "?"
    return f"{size} rows x {size} discs"


def plot_fig7(rows, path):
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    low, high = -0.15, 0.65
    curve_x = [-1.0 + 0.01 * i for i in range(201)]
    ax.plot(curve_x, [0.25 * (1.0 - x) for x in curve_x], "k-", lw=1.2, label="eq. 22: (1 - kT/kN)/4")
    ax.axvspan(-1.0, -1.0 / 3.0, color="0.92", zorder=0)
    ax.text(-0.98, -0.13, "kT/kN < -1/3: alternating-row\nmode unstable, results scatter\n(open triangles: off scale)",
            fontsize=8, va="bottom")

    xs, ys = series(rows, PAPER, "nu_measured")
    inside, above, below = clipped(xs, ys, low, high)
    scatter(ax, inside, marker="o", color="C0", ms=5,
            label=f"static analysis, Abe 1996 loading ({block_label(rows, PAPER)})")
    scatter(ax, above, marker="^", color="C0", ms=6, mfc="none")
    scatter(ax, below, marker="v", color="C0", ms=6, mfc="none")
    xs, ys = series(rows, EXACT, "nu_measured")
    inside, _, _ = clipped(xs, ys, low, high)
    scatter(ax, inside, marker="x", color="C3", ms=5,
            label=f"uniform-state boundary tractions ({block_label(rows, EXACT)})")

    ax.set_xlim(-1.0, 1.0)
    ax.set_ylim(low, high)
    finish_axes(ax, "kT / kN", "Poisson's ratio nu (eq. 35, plane strain)",
                "Abe 1996, Fig. 7: nu of a hexagonal disc block", fontsize=8, loc="upper right")
    save_figure(fig, path, 150)


def plot_fig8(rows, path):
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    positive = lambda r: r["kT_over_kN"] > 0.0  # noqa: E731  (the range of Abe 1996, Fig. 8)
    curve_x = [0.005 * i for i in range(1, 201)]
    ax.plot(curve_x, [2.0 * math.sqrt(3.0) * (1.0 + x) / (3.0 + x) for x in curve_x], "k-", lw=1.2,
            label="eq. 37: 2 sqrt3 (1 + kT/kN)/(3 + kT/kN)")
    xs, ys = series(rows, PAPER, "stiffness_measured", positive)
    ax.plot(xs, ys, "o", color="C0", ms=5,
            label=f"eq. 36, sigma11 = end forces / height ({block_label(rows, PAPER)})")
    xs, ys = series(rows, PAPER, "stiffness_eq50_centre", positive)
    ax.plot(xs, ys, "s", color="C2", ms=4, mfc="none", label="eq. 36 with sigma11 from eq. 50 on the middle disc")
    xs, ys = series(rows, EXACT, "stiffness_measured", positive)
    ax.plot(xs, ys, "x", color="C3", ms=5, label=f"uniform-state boundary tractions ({block_label(rows, EXACT)})")
    ax.set_xlim(0.0, 1.02)
    finish_axes(ax, "kT / kN", "2G / ((1 - nu) kN) = sigma11 / (kN eps11)",
                "Abe 1996, Fig. 8: stiffness of a hexagonal disc block", fontsize=8, loc="lower right")
    save_figure(fig, path, 150)


def summary(rows):
    def max_abs(loading, key, reference, keep, relative=False):
        worst = 0.0
        for r in rows:
            if r["loading"] != loading or r["solved"] != 1.0 or not keep(r):
                continue
            error = r[key] - r[reference]
            worst = max(worst, abs(error / r[reference]) if relative else abs(error))
        return worst

    good_nu = lambda r: r["kT_over_kN"] >= -0.3 - 1e-12  # noqa: E731
    between = lambda r: -1.0 / 3.0 < r["kT_over_kN"] < -0.3 - 1e-12  # noqa: E731
    positive = lambda r: r["kT_over_kN"] > 0.0  # noqa: E731
    scatter_band = lambda r: -0.5 - 1e-12 <= r["kT_over_kN"] <= -0.35 + 1e-12  # noqa: E731
    for loading in (PAPER, EXACT):
        print(f"{loading} ({block_label(rows, loading)}):")
        print(f"  max |nu - eq.22|, kT/kN >= -0.3          : {max_abs(loading, 'nu_measured', 'nu_eq22', good_nu):.3g}")
        print(f"  max |nu - eq.22|, -1/3 < kT/kN < -0.3     : {max_abs(loading, 'nu_measured', 'nu_eq22', between):.3g}")
        print(f"  max |nu - eq.22|, -0.5 <= kT/kN <= -0.35  : "
              f"{max_abs(loading, 'nu_measured', 'nu_eq22', scatter_band):.3g}")
        print(f"  max rel. error eq.36 vs eq.37, 0 < kT/kN <= 1: "
              f"{max_abs(loading, 'stiffness_measured', 'stiffness_eq37', positive, True):.3g}")
        print(f"  same with eq.50 stress of the middle disc : "
              f"{max_abs(loading, 'stiffness_eq50_centre', 'stiffness_eq37', positive, True):.3g}")
        worst_law = max((r["law_mismatch"] for r in rows
                         if r["loading"] == loading and r["solved"] == 1.0 and good_nu(r)), default=float("nan"))
        print(f"  max |eq.50 - eq.52| / |sigma|, kT/kN >= -0.3: {worst_law:.3g}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build-dir", default=os.path.join(REPO, "build"), help="where talus_dem_tests is")
    parser.add_argument("--csv", help="plot this sweep instead of running the tests")
    parser.add_argument("--out-dir", default=os.path.join(REPO, "docs", "verification"))
    args = parser.parse_args()
    require_inputs(csv=args.csv)

    if args.csv:
        csv_path = args.csv
    else:
        csv_path = os.path.join(tempfile.mkdtemp(prefix="talus_dem_"), "dem_sweep.csv")
        run_sweep(args.build_dir, csv_path)
    rows = read_sweep(csv_path)
    os.makedirs(args.out_dir, exist_ok=True)
    plot_fig7(rows, os.path.join(args.out_dir, "dem_poisson_fig7.png"))
    plot_fig8(rows, os.path.join(args.out_dir, "dem_modulus_fig8.png"))
    summary(rows)
    print(f"wrote {args.out_dir}/dem_poisson_fig7.png and dem_modulus_fig8.png (sweep: {csv_path})")


if __name__ == "__main__":
    main()
