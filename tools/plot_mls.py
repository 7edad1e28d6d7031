#!/usr/bin/env python3
"""MLS strain smoothing (Edo & Matsubara 2015, sec. 4, Fig. 6-7, 9-10, 12-13) on the papers' elastic benchmarks.

Runs `talus run` on the scenes in inputs/benchmarks/ with linear MPM, uGIMP and cpGIMP, each without
and with MLS smoothing of the strain increments, and writes into docs/verification/:
    mls_column_w12500.png        stress profiles x/Delta vs sigma/s0 with the exact eq. 61 (Fig. 6-7)
    mls_dynamic_bar.png          stress along the bar at 80% crossing with -E v0/c (Fig. 9-10)
    mls_block_between_walls.png  total and strain energy / initial vs time (Fig. 12-13)
    mls_benchmarks.csv           the numbers (L2, roughness, bar ratio, energy drift, wall time)
Usage:  /usr/bin/python3 tools/plot_mls.py [--talus build/talus] [--threads 1] [--basis cubic]
        [--radius 2.0] [--skip-walls] [--variants particle,cell --tag _variants]
With --variants particle,cell every "with MLS" run is made with both fits (the reference, one per
particle, and the cheaper one per cell: solver.smoothing.variant) and --tag is appended to the output
names (docs/verification.md "MLS, one fit per cell" uses mls_*_variants.png/.csv).
The plots and the CSV are written when every run succeeded: a failed run prints talus's error, and then
nothing is written, exit 1 (as speed_vs_error.py).
Needs numpy, matplotlib and VTK's Python module (Debian: python3-numpy python3-matplotlib python3-vtk9).
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from speed_vs_error import E, RHO0, L0, benchmark_parser, out_folder, parse_benchmark_args, load, variant, run, profile, column_metrics  # noqa: E402
from talus_plot import finish_axes, save_figure, write_csv_rows  # noqa: E402
from cli_checks import choices_list, refuse  # noqa: E402

SHAPES = ["linear", "ugimp", "cpgimp"]
FITS = ["particle", "cell", "reused"]  # solver.smoothing.variant


def with_mls(scene, mode, radius, axes, reuse_strain=None):
    """mode: "off", a basis (the per-particle fit), "<basis>-cell" (one fit per cell) or "<basis>-reused"
    (the particle fit's weights reused until the strain since the fit passes reuse_strain)."""
    s = json.loads(json.dumps(scene))
    # The wall-contact energy gain (docs/verification.md) would trip the run's energy guard; these
    # runs are here to show it, so the guard is opened wide.
    s.setdefault("guards", {})["energy_growth_factor"] = 1.0e6
    if mode != "off":
        basis, _, fit = mode.partition("-")
        s["solver"]["smoothing"] = {"basis": basis, "radius_factor": radius, "axes": axes,
                                    "variant": fit or "particle"}
        if fit == "reused" and reuse_strain is not None:
            s["solver"]["smoothing"]["reuse_strain"] = reuse_strain
    return s


def marker(mode):
    return "o-" if mode == "off" else "^-" if mode.endswith("-cell") else "x-" if mode.endswith("-reused") else "s-"


def shape_runs(talus, base, axes, modes, a, what, failed):
    """Per panel: (panel, shape, [(mode, result), ...]), the talus runs of the benchmark `base` with that
    shape and each MLS mode (a run that failed is reported, appended to failed and left out)."""
    for ax, shape in zip(axes, SHAPES):
        results = []
        for mode in modes:
            res = run(talus, with_mls(variant(base, shape, "musl"), mode, a.radius, a.axes, a.reuse_strain), a.threads)
            if res is None:
                print(f"{what} {shape} {mode}: run failed", flush=True)
                failed.append(f"{what} {shape} {mode}")
                continue
            results.append((mode, res))
        yield ax, shape, results


def main():
    ap = benchmark_parser(__doc__, scratch_when="with other --basis, --radius, --axes, --variants or --skip-walls "
                          "and no --tag")
    ap.add_argument("--basis", default="cubic", choices=["linear", "quadratic", "cubic"],
                    help="MLS basis for the 'with MLS' runs (the paper: cubic)")
    ap.add_argument("--radius", type=float, default=2.0, help="radius factor (h / cell size), 0.5 to 8")
    ap.add_argument("--axes", default="x", choices=["xyz", "xy", "xz", "yz", "x", "y", "z"],
                    help="basis axes; the bars are 2 particles across, so 1D: x")
    ap.add_argument("--skip-walls", action="store_true", help="leave out the block between walls (the longest runs)")
    ap.add_argument("--variants", default="particle",
                    help="the MLS fits to run, comma-separated: particle, cell, reused (e.g. particle,reused)")
    ap.add_argument("--reuse-strain", type=float, default=None,
                    help="with the reused variant: solver.smoothing.reuse_strain (default: talus's)")
    ap.add_argument("--tag", default="", help="appended to the names of the plots and the CSV")
    a, talus = parse_benchmark_args(ap)
    # Checked before any run: a value talus refuses failed every "with MLS" run, one after the other
    # (solver.smoothing's ranges, docs/scene-reference.md)
    fits = choices_list("--variants", a.variants, FITS)
    if not 0.5 <= a.radius <= 8.0:
        refuse("--radius", f"{a.radius:g}", "give 0.5 to 8 (solver.smoothing.radius_factor)")
    if a.reuse_strain is not None and not 0.0 <= a.reuse_strain <= 1.0:
        refuse("--reuse-strain", f"{a.reuse_strain:g}", "give 0 to 1 (solver.smoothing.reuse_strain)")
    changed = any(getattr(a, k) != ap.get_default(k) for k in ("basis", "radius", "axes", "variants", "skip_walls"))
    folder = out_folder(a, scratch=changed and not a.tag)  # a tagged run writes its own names beside the docs' files
    print(f"writing into {folder}", flush=True)
    rows, failed, figures = [], [], []  # the figures are saved at the end, when no run failed
    modes = ["off"] + [a.basis if fit == "particle" else f"{a.basis}-{fit}" for fit in fits]
    label = {"off": "without MLS", a.basis: f"MLS {a.basis} ({a.axes}), h = {a.radius:g} cells",
             f"{a.basis}-cell": f"MLS {a.basis} ({a.axes}), one fit per cell",
             f"{a.basis}-reused": f"MLS {a.basis} ({a.axes}), weights reused"}

    def out(name, ext):
        return os.path.join(folder, f"{name}{a.tag}.{ext}")

    # 1. Column W = 12500 (Edo & Matsubara 2015, Fig. 6-7).
    base = load("column_w12500")
    b = base["gravity"][0]
    delta = L0 + RHO0 * b * L0 ** 2 / (2 * E)
    s0 = RHO0 * b * L0  # b m / A
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharey=True)
    for ax, shape, results in shape_runs(talus, base, axes, modes, a, "column", failed):
        for mode, res in results:
            l2, rough = column_metrics(res, b)
            rows.append({"benchmark": "column_w12500", "shape": shape, "mls": mode, "l2": l2, "roughness": rough,
                         "wall_s": round(res["wall"], 3)})
            print(f"column {shape:7s} {mode:9s} L2 {l2:.5f} roughness {rough:.5f} ({res['wall']:.1f} s)", flush=True)
            xp, sp = profile(res["x"], res["stress"][:, 0])
            ax.plot(xp / delta, sp / s0, marker(mode), ms=2.5, lw=0.8,
                    label=f"{label[mode]}: L2 {100 * l2:.2f}%, rough. {rough:.2g}")
        xs = np.linspace(0, 1, 200)
        ax.plot(xs, E * (np.sqrt(2 * RHO0 * b * (delta - xs * delta) / E + 1) - 1) / s0, "k--", lw=1, label="exact (eq. 61)")
        finish_axes(ax, "x / Delta", title=f"column W = 12500, {shape}", fontsize=7)
    axes[0].set_ylabel("sigma / s0")
    figures.append((fig, out("mls_column_w12500", "png")))

    # 2. Dynamic bar (Fig. 9-10).
    base = load("dynamic_bar")
    v0 = base["bodies"][0]["velocity"][0]
    c = math.sqrt(E / RHO0)
    exact = -E * abs(v0) / c  # Edo & Matsubara 2015, eq. 63
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharey=True)
    for ax, shape, results in shape_runs(talus, base, axes, modes, a, "bar", failed):
        for mode, res in results:
            xp, sp = profile(res["x"], res["stress"][:, 0])
            t = res["energy"]["time"][-1]
            sel = (xp > 3.0) & (xp < c * t - 6.0)
            ratio = float(sp[sel].mean() / exact)
            rough = float(np.sqrt(np.mean((sp[2:] - 2 * sp[1:-1] + sp[:-2])[sel[1:-1]] ** 2)) / abs(exact))
            rows.append({"benchmark": "dynamic_bar", "shape": shape, "mls": mode, "ratio": ratio, "roughness": rough,
                         "wall_s": round(res["wall"], 3)})
            print(f"bar    {shape:7s} {mode:9s} mean/exact {ratio:.4f} roughness {rough:.4f}", flush=True)
            ax.plot(xp, sp / abs(exact), marker(mode), ms=2.5, lw=0.8,
                    label=f"{label[mode]}: mean/exact {ratio:.3f}")
        ax.axhline(-1.0, color="k", ls="--", lw=1, label="exact behind the front (eq. 63)")
        finish_axes(ax, "x [m]", title=f"dynamic bar at 80% crossing, {shape}", fontsize=7)
    axes[0].set_ylabel("sigma / (E |v0| / c)")
    figures.append((fig, out("mls_dynamic_bar", "png")))

    # 3. Block between walls (Fig. 12-13): energy histories.
    if not a.skip_walls:
        base = load("block_between_walls")
        fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))  # own scales: linear MPM with MLS can grow 10x
        for ax, shape, results in shape_runs(talus, base, axes, modes, a, "walls", failed):
            for mode, res in results:
                e = res["energy"]
                tot = e["total"] / e["total"][0]
                worst = float(np.max(np.abs(tot - 1.0)))
                rows.append({"benchmark": "block_between_walls", "shape": shape, "mls": mode, "max_drift": worst,
                             "final_drift": float(tot[-1] - 1.0), "wall_s": round(res["wall"], 3)})
                print(f"walls  {shape:7s} {mode:9s} max |E/E0 - 1| {worst:.4f} final {tot[-1] - 1:+.4f}", flush=True)
                ax.plot(e["time"], tot, lw=1, label=f"total, {label[mode]}")
                ax.plot(e["time"], e["strain"] / e["total"][0], lw=0.7, ls=":", label=f"strain, {label[mode]}")
            finish_axes(ax, "time [s]", title=f"block between walls, {shape}", fontsize=6)
        axes[0].set_ylabel("energy / initial")
        figures.append((fig, out("mls_block_between_walls", "png")))

    if failed:
        # a partial set replaced the files the docs show (a --tag writes into docs/verification too)
        for fig, _ in figures:
            plt.close(fig)
        sys.exit(f"plot_mls.py: {len(failed)} of {len(failed) + len(rows)} runs failed (the first: {failed[0]}); "
                 f"nothing written into {folder}")
    for fig, path in figures:
        save_figure(fig, path, 110)
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    write_csv_rows(out("mls_benchmarks", "csv"), rows, keys)


if __name__ == "__main__":
    main()
