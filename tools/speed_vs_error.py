#!/usr/bin/env python3
"""Speed against error for the papers' elastic benchmarks (docs/verification.md).

Runs `talus run` on variants of the scenes in inputs/benchmarks/ (shape function, update scheme,
cell size, particles per cell), measures the error of each run and its time (CPU time by default, wall time with --wall), and writes
    docs/verification/speed_vs_error.csv       one row per run
    docs/verification/column_convergence.csv   column error against cell size
    docs/verification/*.png                    error vs time, convergence, energy histories
(when every run succeeded: a failed run prints talus's error, and then nothing is written, exit 1).
Usage:  /usr/bin/python3 tools/speed_vs_error.py [--talus build/talus] [--threads 1] [--quick] [--wall]
        [--mls off,cubic]   MLS axis: each column / bar run once per basis listed (Edo & Matsubara 2015, eq. 54;
                            the bars are 2 particles across, so the fit spans x only, radius 2 cells)
Needs numpy, matplotlib and VTK's Python module (Debian: python3-numpy python3-matplotlib python3-vtk9).
"""
import argparse
import json
import math
import os
import resource
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from talus_plot import finish_axes, read_vtu, run_talus, save_figure, series_frames, write_csv_rows  # noqa: E402
from cli_checks import choices_list, require_at_least  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "docs", "verification")
SHAPES = ["linear", "ugimp", "cpgimp", "bspline2"]
SCHEMES = ["musl", "usl", "usf", "usavg"]
MLS_BASES = ["off", "linear", "quadratic", "cubic"]
MARKERS = {"linear": "o", "ugimp": "s", "cpgimp": "^", "bspline2": "D"}
E, RHO0, L0 = 1.0e6, 1.0, 50.0
TIME_KEY = "cpu"  # what the rates and plots use: "cpu" (1 thread) or "wall" (main() sets it)


def find_talus(given):
    for p in ([given] if given else []) + ["build/talus", "build-shape/talus", "build-release/talus"]:
        path = os.path.join(ROOT, p) if not os.path.isabs(p) else p
        if os.path.exists(path):
            return path
    sys.exit("talus not found: build it (cmake --build build) or pass --talus")


def benchmark_parser(doc, scratch_when=None):
    """The command line shared by the benchmark drivers: the script's docstring as help, --talus, --threads,
    --out. `scratch_when` names the partial sweeps that the driver writes to build/ (see out_folder)."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus")
    ap.add_argument("--threads", type=int, default=1)
    scratch = f"; {scratch_when}: build/verification_scratch" if scratch_when else ""
    ap.add_argument("--out", help=f"folder of the CSV files and plots (default: {os.path.relpath(OUT, ROOT)}, the ones the "
                                  f"docs show{scratch})")
    return ap


def out_folder(a, scratch=False):
    """Where a driver writes: --out, else the docs' folder; `scratch` (a partial sweep such as --quick)
    defaults to build/ so that it does not replace the files the docs show."""
    folder = a.out or (os.path.join(ROOT, "build", "verification_scratch") if scratch else OUT)
    os.makedirs(folder, exist_ok=True)
    return folder


def parse_benchmark_args(ap):
    """Parse a benchmark driver's command line; returns (args, the talus program)."""
    a = ap.parse_args()
    require_at_least(1, threads=a.threads)
    talus = find_talus(a.talus)
    return a, talus


def load(name):
    with open(os.path.join(ROOT, "inputs", "benchmarks", name + ".json")) as f:
        return json.load(f)


def variant(scene, shape, scheme, h=None, ppc=None, mls="off"):
    s = json.loads(json.dumps(scene))
    if mls != "off":
        s["solver"]["smoothing"] = {"basis": mls, "radius_factor": 2.0, "axes": "x"}
    s["solver"]["shape"] = shape
    s["solver"]["scheme"] = scheme
    s["output"]["frame_interval"] = 0.0  # first and last frame only
    if h is not None:  # refine along the bar, keep a one-cell cross-section
        s["grid"]["cell_size"] = h
        axis = 2 if s["name"] == "elastic_free_fall" else 0
        for d in range(3):
            if d != axis:
                s["grid"]["size"][d] = h
                for b in s["bodies"]:
                    b["box"]["max"][d] = b["box"]["min"][d] + h
        n = round(s["grid"]["size"][axis] / h)
        s["grid"]["size"][axis] = n * h
    if ppc is not None:
        for b in s["bodies"]:
            b["particles_per_cell"] = ppc
    return s


def run(talus, scene, threads):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "scene.json")
        with open(path, "w") as f:
            json.dump(scene, f)
        out = os.path.join(tmp, "out")
        # The children's CPU time (user + system) besides the wall clock: on a shared machine a
        # 1-thread run is then not charged for waiting for a core (talus bench --cpu-time does the same).
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        r = run_talus(talus, "run", path, "--out", out, threads=threads, check=False)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        if r.returncode != 0:
            # talus's own reason: the caller's "run failed" alone did not say why
            for line in (r.stderr.strip() or r.stdout.strip() or f"exit status {r.returncode}").splitlines()[-3:]:
                print(f"  {line}", file=sys.stderr, flush=True)
            return None
        energy = np.genfromtxt(os.path.join(out, "energy.csv"), delimiter=",", names=True)
        last = read_vtu(series_frames(out)[-1][1], "stress")
        x, stress = last["points"], last["stress"]
        steps = int(energy["step"][-1])
        return {"wall": wall, "cpu": cpu, "energy": energy, "x": x, "stress": stress, "steps": steps, "particles": len(x)}


def profile(x, sxx, axis=0):
    """Stress averaged over each cross-section layer (a thin bar is 1D), ordered along the bar."""
    order = np.argsort(x[:, axis], kind="stable")
    xs, ss = x[order, axis], sxx[order]
    groups = np.split(np.arange(len(xs)), np.nonzero(np.diff(xs) > 1e-6)[0] + 1)
    return np.array([xs[g].mean() for g in groups]), np.array([ss[g].mean() for g in groups])


def column_metrics(res, b):
    delta = L0 + RHO0 * b * L0 ** 2 / (2 * E)
    xp, sp = profile(res["x"], res["stress"][:, 0])
    exact = E * (np.sqrt(2 * RHO0 * b * (delta - np.minimum(xp, delta)) / E + 1) - 1)  # Edo & Matsubara 2015, eq. 61
    l2 = math.sqrt(np.sum((sp - exact) ** 2) / np.sum(exact ** 2))
    rough = math.sqrt(np.mean((sp[2:] - 2 * sp[1:-1] + sp[:-2]) ** 2)) / (RHO0 * abs(b) * L0)  # b < 0: compression
    return l2, rough


def bar_metrics(res, v0):
    c = math.sqrt(E / RHO0)
    t = res["energy"]["time"][-1]
    exact = -E * abs(v0) / c  # Edo & Matsubara 2015, eq. 63
    x, s = res["x"][:, 0], res["stress"][:, 0]
    sel = (x > 3.0) & (x < c * t - 6.0)
    return abs(s[sel].mean() / exact - 1.0)


def energy_drift(res):
    tot = res["energy"]["total"]
    return float(np.max(np.abs(tot - tot[0])) / abs(tot[0])), float((tot[-1] - tot[0]) / abs(tot[0]))


def add_time_option(ap):
    """--wall: what the rates and the plots' time axis use (set_time_key reads it)."""
    ap.add_argument("--wall", action="store_true",
                    help="rate and plots from the wall clock (default: the run's CPU time, which a shared machine does "
                         "not inflate at 1 thread; with more threads CPU time sums the threads, so use --wall there)")


def set_time_key(a):
    """TIME_KEY from --wall and --threads (CPU time sums the threads: more than one takes the wall clock)."""
    global TIME_KEY
    TIME_KEY = "wall" if a.wall or a.threads > 1 else "cpu"


def run_failed(failed, what):
    print(f"{what}: run failed", flush=True)
    failed.append(what)


def result_row(bench, shape, scheme, h, ppc, res, error, metric, extra="", mls="off"):
    """The CSV row of one run (printed as it comes); the rate is per second of TIME_KEY."""
    ups = res["particles"] * res["steps"] / res[TIME_KEY]
    print(f"{bench:20s} {shape:8s} {scheme:6s} mls={mls:9s} h={h:<6g} ppc={ppc} err={error:.4g} ({metric}) "
          f"{res['wall']:.2f} s wall {res['cpu']:.2f} s CPU {ups / 1e6:.2f} M/s {extra}", flush=True)
    return {"benchmark": bench, "shape": shape, "scheme": scheme, "mls": mls, "cell_size": h, "ppc": ppc,
            "particles": res["particles"], "steps": res["steps"], "wall_s": round(res["wall"], 4),
            "cpu_s": round(res["cpu"], 4), "particle_updates_per_s": round(ups), "error": error,
            "metric": metric, "note": extra}


def column_sweep(talus, name, shapes, quick, mls_modes, threads, rows, failed):
    """The column `name` (inputs/benchmarks/NAME.json) over shape x cell size x particles per cell x MLS
    (MUSL): a row per run appended to rows, the runs that failed to failed (talus's reason printed)."""
    base = load(name)
    b = base["gravity"][0]
    for shape in shapes:
        for h in ([2.0, 1.0, 0.5] if quick else [2.0, 1.0, 0.5, 0.25]):
            for ppc in ([2] if (quick or h != 1.0) else [1, 2, 3]):
                for mls in mls_modes:
                    res = run(talus, variant(base, shape, "musl", h, ppc, mls), threads)
                    if res is None:
                        run_failed(failed, f"{name} {shape} h={h} ppc={ppc} mls={mls}")
                        continue
                    l2, rough = column_metrics(res, b)
                    rows.append(result_row(name, shape, "musl", h, ppc, res, l2, "L2 stress", f"roughness={rough:.4g}", mls))


def plot_error_vs_time(rows, bench, path, threads, mls_modes):
    """Error against run time of the rows of one benchmark, a marker per shape (cell size h in metres and
    particles per cell written beside the columns' points); nothing when it has no rows."""
    sel = [r for r in rows if r["benchmark"] == bench]
    if not sel:
        return
    time_col = TIME_KEY + "_s"
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for shape in SHAPES:
        for scheme in SCHEMES:
            for mls in mls_modes:
                pts = [r for r in sel if r["shape"] == shape and r["scheme"] == scheme and r["mls"] == mls]
                if not pts:
                    continue
                ax.scatter([r[time_col] for r in pts], [max(r["error"], 1e-5) for r in pts],
                           marker=MARKERS[shape], facecolors="none" if mls != "off" else None,
                           edgecolors="C3" if mls != "off" else None,
                           label=f"{shape} {scheme}" + (f" MLS {mls}" if mls != "off" else ""))
                for r in pts:
                    if bench.startswith("column"):
                        # h is grid.cell_size, in metres (the column is 50 m long); "h=2,2" gave no unit and
                        # left the second number unnamed
                        ax.annotate(f"h={r['cell_size']:g} m, {r['ppc']} ppc", (r[time_col], max(r["error"], 1e-5)),
                                    fontsize=6)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"{'wall' if TIME_KEY == 'wall' else 'CPU'} time [s] ({threads} thread{'s' if threads > 1 else ''})")
    ax.set_ylabel(sel[0]["metric"])
    ax.set_title(f"{bench}: error vs time")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    save_figure(fig, path, 110)


def main():
    ap = benchmark_parser(__doc__, scratch_when="with --quick")
    ap.add_argument("--quick", action="store_true", help="fewer variants (a smoke test of the driver)")
    ap.add_argument("--mls", default="off", type=lambda t: choices_list("--mls", t, MLS_BASES),
                    help="comma-separated MLS bases for the column and bar runs: off,linear,quadratic,cubic")
    add_time_option(ap)
    a, talus = parse_benchmark_args(ap)
    out = out_folder(a, scratch=a.quick)
    print(f"writing into {out}", flush=True)
    set_time_key(a)
    rows = []
    histories = {}

    mls_modes = a.mls
    failed = []

    def record(*args, **kwargs):
        rows.append(result_row(*args, **kwargs))

    shapes = SHAPES if not a.quick else ["linear", "cpgimp"]
    # 1. Column, W = 10000 and 12500: shape x cell size x ppc (MUSL).
    for name in ["column_w10000", "column_w12500"]:
        column_sweep(talus, name, shapes, a.quick, mls_modes, a.threads, rows, failed)
    # 2. Dynamic bar: shape x ppc.
    base = load("dynamic_bar")
    for shape in shapes:
        for ppc in ([2] if a.quick else [1, 2, 3]):
            for mls in mls_modes:
                res = run(talus, variant(base, shape, "musl", None, ppc, mls), a.threads)
                if res is None:
                    run_failed(failed, f"dynamic_bar {shape} ppc={ppc} mls={mls}")
                else:
                    record("dynamic_bar", shape, "musl", base["grid"]["cell_size"], ppc, res,
                           bar_metrics(res, base["bodies"][0]["velocity"][0]), "|mean/exact - 1|", "", mls)
    # 3. Block between walls and 4. free fall: energy histories, shape x scheme.
    for name, combos in [("block_between_walls", [(s, "musl") for s in shapes] + [("cpgimp", "usavg"), ("cpgimp", "usf")]),
                         ("elastic_free_fall", [("linear", s) for s in ["musl", "usf", "usavg"]] +
                          ([] if a.quick else [("cpgimp", s) for s in ["musl", "usf", "usavg"]]))]:
        base = load(name)
        for shape, scheme in combos:
            res = run(talus, variant(base, shape, scheme), a.threads)
            if res is None:
                run_failed(failed, f"{name} {shape} {scheme}")
                continue
            worst, final = energy_drift(res)
            histories[(name, shape, scheme)] = res["energy"]
            record(name, shape, scheme, base["grid"]["cell_size"], 2, res, worst, "max |E - E0| / E0",
                   f"final={final:+.4g}")

    if failed:
        # a partial sweep replaced the committed CSV and plots (13 rows of 73, the PNGs with them)
        sys.exit(f"speed_vs_error.py: {len(failed)} of {len(failed) + len(rows)} runs failed (the first: {failed[0]}); "
                 f"nothing written into {out}")
    write_csv_rows(os.path.join(out, "speed_vs_error.csv"), rows)

    # Plots: error vs time per benchmark.
    for bench in ["column_w10000", "column_w12500", "dynamic_bar", "block_between_walls", "elastic_free_fall"]:
        plot_error_vs_time(rows, bench, os.path.join(out, f"{bench}_error_vs_time.png"), a.threads, mls_modes)

    # Convergence of the column error with cell size (ppc 2).
    conv = []
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for shape in shapes:
        pts = sorted([(r["cell_size"], r["error"]) for r in rows
                      if r["benchmark"] == "column_w10000" and r["shape"] == shape and r["ppc"] == 2
                      and r["mls"] == "off"])
        if len(pts) >= 2:
            hs, es = np.array([p[0] for p in pts]), np.array([p[1] for p in pts])
            rate = np.polyfit(np.log(hs), np.log(es), 1)[0]
            conv.append({"shape": shape, "rate": round(float(rate), 3),
                         **{f"L2_h{h:g}": round(float(e), 6) for h, e in zip(hs, es)}})
            ax.loglog(hs, es, marker=MARKERS[shape], label=f"{shape} (rate {rate:.2f})")
    ax.set_xlabel("cell size h [m]")
    ax.set_ylabel("relative L2 stress error")
    ax.set_title("column W = 10000: convergence")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    save_figure(fig, os.path.join(out, "column_convergence.png"), 110)
    if conv:
        keys = sorted({k for c in conv for k in c}, key=lambda k: (k != "shape", k != "rate", k))
        write_csv_rows(os.path.join(out, "column_convergence.csv"), conv, keys)
        for c in conv:
            print("convergence", c)

    # Energy histories.
    for name in ["block_between_walls", "elastic_free_fall"]:
        fig, ax = plt.subplots(figsize=(6.5, 4))
        for (n, shape, scheme), e in histories.items():
            if n == name:
                ax.plot(e["time"], e["total"] / e["total"][0], label=f"{shape} {scheme}", lw=1)
        finish_axes(ax, "time [s]", "total energy / initial", f"{name}: energy history", fontsize=7)
        save_figure(fig, os.path.join(out, f"{name}_energy.png"), 110)


if __name__ == "__main__":
    main()
