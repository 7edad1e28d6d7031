#!/usr/bin/python3
"""Reproduce Abe, Johansson & Konagai 2005, Fig. 13 with the Drucker-Prager element tests.

Runs `talus element-test` on inputs/element_tests/fig13a_*.json (uniaxial compression, several
hardening settings) and fig13b_*.json (simple shear, several dilatancy angles), then writes

  docs/verification/dp_hardening.png   axial stress vs axial strain (Fig. 13 left)
  docs/verification/dp_dilatancy.png   volumetric vs shear strain, stress ratio (Fig. 13 right)

with the closed forms of docs/drucker-prager.md drawn dashed over the computed curves.

Usage (from the repository root):
  /usr/bin/python3 tools/plot_element_tests.py --talus build/talus
  /usr/bin/python3 tools/plot_element_tests.py --no-run --csv-dir DIR   # plot CSVs already written

The CSVs go to OUT_DIR/element_tests (--out-dir, default docs/verification) unless --csv-dir says
otherwise: beside the plots they were made for, not in the build tree, which a clean rebuild removes.
"""
import argparse
import csv
import glob
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for talus_plot, next to this script
from talus_plot import ROOT, main_guard, run_talus  # noqa: E402


def cone(fit, angle_deg, cohesion):
    """alpha and k of a Drucker-Prager cone fit (docs/drucker-prager.md, sec. 2)."""
    a = math.radians(angle_deg)
    s, c, t = math.sin(a), math.cos(a), math.tan(a)
    if fit == "plane_strain":
        d = math.sqrt(9.0 + 12.0 * t * t)
        return t / d, 3.0 * cohesion / d
    if fit == "compression":
        return 2 * s / (math.sqrt(3) * (3 - s)), 6 * cohesion * c / (math.sqrt(3) * (3 - s))
    if fit == "extension":
        return 2 * s / (math.sqrt(3) * (3 + s)), 6 * cohesion * c / (math.sqrt(3) * (3 + s))
    if fit == "inscribed":
        d = math.sqrt(9.0 + 3.0 * s * s)
        return s / d, 3.0 * cohesion * c / d
    raise ValueError(fit)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    cols = {}
    for key in rows[0]:
        if key == "regime":
            cols[key] = [r[key] for r in rows]
        else:
            cols[key] = [float(r[key]) for r in rows]
    return cols


def run_specs(talus, specs, csv_dir):
    os.makedirs(csv_dir, exist_ok=True)
    for spec in specs:
        out = os.path.join(csv_dir, os.path.basename(spec).replace(".json", ".csv"))
        run_talus(talus, "element-test", spec, "--out", out)


def load(spec, csv_dir):
    with open(spec) as f:
        s = json.load(f)
    out = os.path.join(csv_dir, os.path.basename(spec).replace(".json", ".csv"))
    return s, read_csv(out)


def plot_hardening(specs, csv_dir, png):
    order = ["perfect", "isotropic", "kinematic", "combined"]
    styles = {"perfect": ("k", "-", 1.6), "isotropic": ("tab:blue", "-", 3.5),
              "kinematic": ("tab:red", "-", 1.6), "combined": ("tab:green", "--", 1.6)}
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    named = {os.path.basename(s).split("_")[-1].replace(".json", ""): s for s in specs}
    reference = None
    for name in order:
        if name not in named:
            continue
        spec, d = load(named[name], csv_dir)
        m = spec["material"]
        label = {
            "perfect": "perfect plasticity (H = 0)",
            "isotropic": f"isotropic (H = {m['hardening_modulus']:.0e} Pa, m = 0)",
            "kinematic": f"kinematic (H = {m['hardening_modulus']:.0e} Pa, m = 1)",
            "combined": f"combined (m = {m['kinematic_fraction']}, seed M = {1 - m['kinematic_fraction']:.1f})",
        }[name]
        color, ls, lw = styles[name]
        ax.plot([-100 * e for e in d["eps_yy"]], [-s / 1e3 for s in d["sig_yy"]], color=color,
                ls=ls, lw=lw, label=label)
        reference = reference or (m, d)
    # Closed forms: unconfined strength k/(1/sqrt3 - alpha) and the hardening tangent modulus.
    if reference:
        m, _ = reference
        alpha, k = cone(m.get("cone", "plane_strain"), m["friction_angle"], m["cohesion"])
        alpha_g, _ = cone(m.get("cone", "plane_strain"), m.get("dilatancy_angle", 0.0), 0.0)
        r3 = 1 / math.sqrt(3)
        qu = k / (r3 - alpha)
        ax.axhline(qu / 1e3, color="0.5", ls=":", lw=1.0,
                   label=f"closed form: strength k/(1/√3 − α) = {qu / 1e3:.2f} kPa")
        h = 2.0e5
        for s in specs:
            mm = json.load(open(s))["material"]
            if mm.get("hardening_modulus", 0) > 0:
                h = mm["hardening_modulus"]
                break
        et = 1.0 / (1.0 / m["young"] + (r3 - alpha) * (r3 - alpha_g) / h)
        e0 = qu / m["young"]
        xs = [100 * e0, 100 * 0.02]
        ax.plot(xs, [qu / 1e3, (qu + et * (0.02 - e0)) / 1e3], color="0.5", ls="-.", lw=1.0,
                label=f"closed form: hardening slope E_t = {et / 1e3:.0f} kPa")
    ax.axhline(0.0, color="0.8", lw=0.8)
    ax.set_xlabel("axial shortening  −ε_yy  [%]")
    ax.set_ylabel("axial compressive stress  −σ_yy  [kPa]")
    ax.set_title("Uniaxial compression, Drucker–Prager hardening settings\n"
                 "(Abe, Johansson & Konagai 2005, Fig. 13 left; load to 2 %, back to 0, reload to 3 %)", fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=130)
    plt.close(fig)


def plot_dilatancy(specs, csv_dir, png):
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.6))
    colors = plt.cm.viridis([i / max(1, len(specs) - 1) for i in range(len(specs))])
    for spec_path, color in zip(sorted(specs), colors):
        spec, d = load(spec_path, csv_dir)
        psi = spec["material"].get("dilatancy_angle", 0.0)
        sn = spec["path"]["normal_stress"]
        g = [100 * x for x in d["gamma_xy"]]
        ev = [100 * x for x in d["eps_v"]]
        ax.plot(g, ev, color=color, lw=1.8, label=f"ψ = {psi:g}°")
        # Closed form at steady flow: d eps_v / d gamma = tan(psi) (plane-strain cone).
        t = math.tan(math.radians(psi))
        g1, e1 = g[-1], ev[-1]
        g0 = g1 - 8.0
        ax.plot([g0, g1], [e1 - t * 8.0, e1], color="k", ls=":", lw=1.0)
        ax2.plot(g, [x / sn for x in d["sig_xy"]], color=color, lw=1.8, label=f"ψ = {psi:g}°")
    ax.plot([], [], color="k", ls=":", lw=1.0, label="closed form: slope tan ψ")
    phi = spec["material"]["friction_angle"]
    ax2.axhline(math.tan(math.radians(phi)), color="k", ls=":", lw=1.0,
                label=f"closed form, ψ = φ: tan φ = {math.tan(math.radians(phi)):.3f}")
    ax.set_xlabel("shear strain  γ_xy  [%]")
    ax.set_ylabel("volumetric strain  ε_v  [%]  (dilation positive)")
    ax.set_title("Simple shear: volumetric vs shear strain (Abe, Johansson & Konagai 2005, Fig. 13 right)", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    ax2.set_xlabel("shear strain  γ_xy  [%]")
    ax2.set_ylabel("stress ratio  τ_xy / σ_n")
    ax2.set_title("Simple shear: stress ratio (φ = 40°, σ_n = 10 kPa held)", fontsize=10)
    ax2.legend(fontsize=8, loc="lower right")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=130)
    plt.close(fig)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"), help="talus program")
    p.add_argument("--csv-dir", help="where the CSVs are written / read (default: OUT_DIR/element_tests, beside the "
                                     "plots; it was next to --talus, inside the build tree)")
    p.add_argument("--no-run", action="store_true", help="only plot CSVs already in --csv-dir")
    p.add_argument("--out-dir", default=os.path.join(ROOT, "docs", "verification"))
    a = p.parse_args()
    csv_dir = a.csv_dir or os.path.join(a.out_dir, "element_tests")
    spec_dir = os.path.join(ROOT, "inputs", "element_tests")
    hardening = sorted(glob.glob(os.path.join(spec_dir, "fig13a_*.json")))
    dilatancy = sorted(glob.glob(os.path.join(spec_dir, "fig13b_*.json")))
    if not a.no_run:
        if not os.access(a.talus, os.X_OK):
            sys.exit(f"plot_element_tests: {a.talus} is not an executable; pass --talus")
        run_specs(a.talus, hardening + dilatancy, csv_dir)
    else:
        for spec in hardening + dilatancy:  # (a missing CSV was a traceback)
            csv = os.path.join(csv_dir, os.path.basename(spec).replace(".json", ".csv"))
            if not os.path.isfile(csv):
                sys.exit(f"plot_element_tests: --no-run: {csv} not found: run it without --no-run first, or give --csv-dir")
    os.makedirs(a.out_dir, exist_ok=True)
    plot_hardening(hardening, csv_dir, os.path.join(a.out_dir, "dp_hardening.png"))
    plot_dilatancy(dilatancy, csv_dir, os.path.join(a.out_dir, "dp_dilatancy.png"))
    print(f"wrote {a.out_dir}/dp_hardening.png and dp_dilatancy.png (CSVs in {csv_dir})")


if __name__ == "__main__":
    main_guard(main)
