#!/usr/bin/env python3
"""Soft (hourglass) modes that MLS strain smoothing adds to a bar, against the radius.

Why the column and the bars go unstable at wide radii (docs/verification.md, "MLS radius"): this
builds the semi-discrete stiffness of a 1D uGIMP bar, K = B^T V E S B, where B maps nodal
displacements to particle strains (uGIMP gradients, Edo & Matsubara 2015, eq. 31) and S is the MLS smoothing of
the particle strains (Edo & Matsubara 2015, eq. 39-46, basis along the bar). It solves M^-1 K phi = lambda phi
with the lumped nodal mass M, and compares each lambda with lambda_1, the bar's fundamental without
smoothing. A mode far softer than lambda_1 carries almost no stress: a displacement pattern that
the body force or an impact can grow without resistance.

The bar is the one of Edo & Matsubara's (2015) benchmarks, in units of the cell: 50 cells, 2 particles per cell,
uGIMP half width 1/4 cell, fixed at x = 0 and free at the other end, E = rho = 1. The configuration
is the undeformed one, so this is the stiffness at the start of a run, not along it.

Writes into docs/verification/:
    mls_soft_modes.csv   per basis and radius: lambda_min / lambda_1, the modes softer than
                         lambda_1 / 2, the largest growth rate (non-zero only for complex lambda)
    mls_soft_modes.png   lambda_min / lambda_1 and the growth rate against the radius
Usage:  /usr/bin/python3 tools/mls_soft_modes.py [--cells 50] [--radii 1.5:6:0.25]   (seconds)
Needs numpy and matplotlib (Debian: python3-numpy python3-matplotlib).
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from talus_plot import finish_axes, save_figure, write_csv_rows  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "docs", "verification")
BASES = {"linear": 1, "quadratic": 2, "cubic": 3}
PPC = 2
HALF_WIDTH = 0.25  # uGIMP l_p for 2 particles per cell of size 1


def mls_weight(s):
    """Cubic spline of Edo & Matsubara 2015, eq. 39 (standard form)."""
    s = np.abs(s)
    inner = 2.0 / 3.0 - 4.0 * s ** 2 + 4.0 * s ** 3
    outer = 4.0 / 3.0 - 4.0 * s + 4.0 * s ** 2 - 4.0 / 3.0 * s ** 3
    return np.where(s < 0.5, inner, np.where(s < 1.0, outer, 0.0))


def ugimp(d, lp=HALF_WIDTH):
    """uGIMP weight and gradient of a node at distance d = x_p - x_i (cell size 1; Edo & Matsubara 2015, eq. 30-31)."""
    a = np.abs(d)
    sign = np.sign(d)
    w = np.where(a < lp, 1.0 - (d * d + lp * lp) / (2.0 * lp),
                 np.where(a < 1.0 - lp, 1.0 - a, np.where(a < 1.0 + lp, (1.0 + lp - a) ** 2 / (4.0 * lp), 0.0)))
    g = np.where(a < lp, -d / lp,
                 np.where(a < 1.0 - lp, -sign, np.where(a < 1.0 + lp, -sign * (1.0 + lp - a) / (2.0 * lp), 0.0)))
    return w, g


def smoothing_matrix(xp, radius, degree):
    """S[p, q] = Phi_q(x_p): the MLS fit at particle p of its neighbours' values (eq. 42-46)."""
    S = np.zeros((len(xp), len(xp)))
    for p in range(len(xp)):
        u = (xp - xp[p]) / radius
        w = mls_weight(u)
        F = np.vstack([u ** k for k in range(degree + 1)])
        a = np.linalg.solve((F * w) @ F.T, np.eye(degree + 1)[:, 0])
        S[p] = w * (a @ F)
    return S


def bar_eigenvalues(cells, radius=None, degree=1):
    """Eigenvalues of M^-1 K for the bar; radius None: no smoothing."""
    xp = (np.arange(cells * PPC) + 0.5) / PPC
    nodes = np.arange(cells + 2, dtype=float)
    w, g = ugimp(xp[:, None] - nodes[None, :])
    volume, mass = 1.0 / PPC, 1.0 / PPC
    S = np.eye(len(xp)) if radius is None else smoothing_matrix(xp, radius, degree)
    K = g.T @ (volume * S) @ g
    m = (w * mass).sum(axis=0)
    keep = [i for i in range(len(nodes)) if m[i] > 1e-12 and i != 0]  # node 0 fixed
    Kk = K[np.ix_(keep, keep)] / m[keep][:, None]
    return np.linalg.eigvals(Kk)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, default=50)
    ap.add_argument("--radii", default="1.5:6:0.25", help="first:last:step, in cells")
    ap.add_argument("--out", default=OUT, help=f"folder of the CSV and the plot (default: {os.path.relpath(OUT, ROOT)}, "
                                               "the ones the docs show)")
    a = ap.parse_args()
    first, last, step = (float(v) for v in a.radii.split(":"))
    radii = np.arange(first, last + 0.5 * step, step)
    lam1 = np.min(np.real(bar_eigenvalues(a.cells)))
    print(f"fundamental without smoothing: lambda_1 = {lam1:.5g} (continuum (pi / 2L)^2 = {(np.pi / (2 * a.cells)) ** 2:.5g})")
    rows = []
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(6.5, 6.5), sharex=True)
    for name, degree in BASES.items():
        ratios, growths = [], []
        for r in radii:
            lam = bar_eigenvalues(a.cells, r, degree)
            growth = float(np.max(np.abs(np.real(np.sqrt(-lam.astype(complex))))))
            ratio = float(np.min(np.real(lam)) / lam1)
            soft = int(np.sum(np.real(lam) < 0.5 * lam1))
            rows.append({"basis": name, "radius": float(r), "lambda_min_over_lambda_1": ratio, "modes_softer_than_half": soft,
                         "growth_rate": growth})
            print(f"{name:9s} radius {r:4.2f}: lambda_min / lambda_1 = {ratio:.3g}, {soft} modes softer than lambda_1 / 2,"
                  f" growth rate {growth:.3g}", flush=True)
            ratios.append(ratio)
            growths.append(growth)
        ax.plot(radii, ratios, "o-", ms=3, label=f"{name} (x)")
        bx.plot(radii, growths, "o-", ms=3, label=f"{name} (x)")
    ax.axhline(1.0, color="k", ls="--", lw=0.8, label="the bar's fundamental")
    ax.set_yscale("symlog", linthresh=1e-3)  # negative: a mode with negative stiffness
    finish_axes(ax, None, "softest mode / fundamental",
                f"uGIMP bar, {a.cells} cells, {PPC} per cell, undeformed: stiffness with MLS", fontsize=7)
    finish_axes(bx, "MLS radius [cells]", "largest growth rate [c / cell]", None, fontsize=7)
    os.makedirs(a.out, exist_ok=True)
    save_figure(fig, os.path.join(a.out, "mls_soft_modes.png"), 110)
    write_csv_rows(os.path.join(a.out, "mls_soft_modes.csv"), rows)


if __name__ == "__main__":
    main()
