#!/usr/bin/env python3
"""Block between walls (Edo & Matsubara 2015, sec. 4(3), Fig. 12-13) at four cell sizes: which part of the energy
error is the wall contact's and which is the cell crossing's that MLS smoothing removes.

Runs inputs/benchmarks/block_between_walls.json refined along the bar (cell 0.5, 0.25, 0.125,
0.0625; one cell across, 2 particles per cell along each axis) with uGIMP and cpGIMP, without and
with MLS (cubic along x, radius 2 cells), up to t = 31 s: the first impact (11.25 s, contact about
0.45 s) and the flight back, before the second impact (33.75 s). For each run:
    impact change  E(12.5 s) / E(11.0 s) - 1    what the first impact gains or loses
    flight drift   E(31 s) / E(12.5 s) - 1      what the flight between impacts gains or loses
and writes into docs/verification/:
    mls_walls_resolution.png   total energy / initial vs time (cpGIMP), and both measures vs cell size
    mls_walls_resolution.csv   the numbers
Usage:  /usr/bin/python3 tools/mls_walls_resolution.py [--talus build/talus] [--jobs 2]
The finest runs take about 1-2 minutes each on one core.
"""
import os
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from speed_vs_error import benchmark_parser, out_folder, parse_benchmark_args, load, variant, run  # noqa: E402
from talus_plot import finish_axes, save_figure, value_at, write_csv_rows  # noqa: E402

CELLS = [0.5, 0.25, 0.125, 0.0625]
SHAPES = ["ugimp", "cpgimp"]
MODES = ["off", "cubic"]
T_BEFORE, T_AFTER, T_END = 11.0, 12.5, 31.0


def scene(base, h, shape, mode):
    s = variant(base, shape, "musl", h=h, mls=mode)  # mls: cubic along x, radius 2 cells
    s["time"]["end"] = T_END
    s["output"]["history_interval"] = 0.01
    return s


def main():
    ap = benchmark_parser(__doc__)
    ap.add_argument("--jobs", type=int, default=2, help="runs at the same time (each on --threads threads)")
    a, talus = parse_benchmark_args(ap)
    out = out_folder(a)
    print(f"writing into {out}", flush=True)
    base = load("block_between_walls")
    cases = [(h, shape, mode) for h in CELLS for shape in SHAPES for mode in MODES]

    def go(case):
        return case, run(talus, scene(base, *case), a.threads)

    rows, histories = [], {}
    with ThreadPoolExecutor(a.jobs) as pool:
        for (h, shape, mode), res in pool.map(go, cases):
            if res is None:
                sys.exit(f"walls h = {h} {shape} {mode}: run failed")
            t, total = res["energy"]["time"], res["energy"]["total"] / res["energy"]["total"][0]
            # (refused, not clamped, at a time the run did not reach: talus_plot.value_at)
            at = lambda when: value_at(t, total, when, f"walls h = {h} {shape} {mode}")  # noqa: E731
            impact, flight = at(T_AFTER) / at(T_BEFORE) - 1.0, at(T_END) / at(T_AFTER) - 1.0
            histories[(h, shape, mode)] = (t, total)
            rows.append({"cell": h, "shape": shape, "mls": mode, "impact_change": round(impact, 5),
                         "flight_drift": round(flight, 5), "wall_s": round(res["wall"], 2)})
            print(f"h {h:<6g} {shape:6s} {mode:5s} impact {impact:+.4f} flight {flight:+.4f} ({res['wall']:.0f} s)",
                  flush=True)
    write_csv_rows(os.path.join(out, "mls_walls_resolution.csv"), rows)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.3))
    colours = dict(zip(CELLS, ["C0", "C1", "C2", "C3"]))
    for h in CELLS:
        for mode, ls in zip(MODES, ["--", "-"]):
            t, total = histories[(h, "cpgimp", mode)]
            axes[0].plot(t, total, ls, color=colours[h], lw=0.9,
                         label=f"cell {h:g}, {'without' if mode == 'off' else 'with'} MLS")
    axes[0].axvline(11.25, color="k", lw=0.5)
    finish_axes(axes[0], "time [s]", "total energy / initial", "cpGIMP: first impact at 11.25 s", fontsize=6)
    marker = {"ugimp": "o", "cpgimp": "s"}
    for shape in SHAPES:
        for mode, ls in zip(MODES, ["--", "-"]):
            sel = [r for r in rows if r["shape"] == shape and r["mls"] == mode]
            hs = [r["cell"] for r in sel]
            lab = f"{shape}, {'without' if mode == 'off' else 'with'} MLS"
            axes[1].loglog(hs, [-r["impact_change"] for r in sel], ls, marker=marker[shape], ms=4, label=lab)
            axes[2].semilogx(hs, [100 * r["flight_drift"] for r in sel], ls, marker=marker[shape], ms=4, label=lab)
    hs = np.array(CELLS)
    axes[1].loglog(hs, 0.2 * hs, "k:", lw=1, label="slope 1 (loss ∝ cell size)")
    finish_axes(axes[1], "cell size [m]", "energy lost at the first impact / energy before", "wall contact",
                fontsize=6)
    axes[2].axhline(0.0, color="k", lw=0.5)
    finish_axes(axes[2], "cell size [m]", "energy change in the flight 12.5-31 s [%]", "cell crossing", fontsize=6)
    for ax in axes[1:]:
        ax.set_xticks(CELLS)
        ax.set_xticklabels([f"{h:g}" for h in CELLS])
        ax.minorticks_off()
    save_figure(fig, os.path.join(out, "mls_walls_resolution.png"), 110)


if __name__ == "__main__":
    main()
