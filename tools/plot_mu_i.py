#!/usr/bin/python3
"""Plot the mu(I) element test against the analytic friction law (docs/mu-i.md, sec. 5).

Runs `talus element-test inputs/element_tests/mu_i_simple_shear.json` (steady simple shear at
constant pressure and imposed shear rate, I = 1e-4 ... 1) and writes

  docs/verification/mu_i_simple_shear.png   tau/p against I with mu(I) (Jop et al. 2006, the friction law)
                                            drawn over it, and |tau/p / mu(I) - 1| below

Usage (from the repository root):
  /usr/bin/python3 tools/plot_mu_i.py --talus build/talus
  /usr/bin/python3 tools/plot_mu_i.py --no-run --csv FILE.csv    # plot a CSV already written
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import output_folder, refuse, require_inputs, require_talus  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLUMNS = ("I", "tau_over_p", "relative_error")  # of the element test's CSV

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPEC = os.path.join(ROOT, "inputs", "element_tests", "mu_i_simple_shear.json")


def mu_of_i(i, mu_s, mu_2, i0):
    """The friction law of Jop, Forterre & Pouliquen 2006."""
    return mu_s + (mu_2 - mu_s) / (1.0 + i0 / i)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default=os.path.join(ROOT, "build", "talus"))
    ap.add_argument("--no-run", action="store_true")
    ap.add_argument("--csv", help="CSV to write (or read with --no-run)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "verification", "mu_i_simple_shear.png"),
                    help="the plot (.png; added when the name has no extension; default: %(default)s)")
    args = ap.parse_args()
    if args.no_run:
        if not args.csv:
            ap.error("--no-run plots the CSV of an earlier run: give it with --csv")
        require_inputs(csv=args.csv)
    # The plot's name and folder, checked before the run (an unknown extension was a traceback from savefig)
    out = args.out if os.path.splitext(args.out)[1] else args.out + ".png"  # what matplotlib writes
    formats = plt.figure().canvas.get_supported_filetypes()
    plt.close("all")
    if os.path.splitext(out)[1][1:].lower() not in formats:
        refuse("--out", args.out, f"give a name ending in one of .{', .'.join(sorted(formats))}")
    output_folder("--out", os.path.dirname(os.path.abspath(out)))
    csv_path = args.csv or os.path.join(tempfile.mkdtemp(prefix="talus_mu_i_"), "mu_i_simple_shear.csv")
    if not args.no_run:
        require_talus(args.talus)  # was a subprocess traceback
        if subprocess.run([args.talus, "element-test", SPEC, "--out", csv_path]).returncode != 0:
            sys.exit("plot_mu_i.py: talus element-test failed (its error is above)")
    with open(SPEC) as f:
        m = json.load(f)["material"]
    with open(csv_path, newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
    missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
    if missing or not rows:  # (another CSV was a KeyError 'I')
        what = f"no column {missing[0]}" if missing else "no rows"
        sys.exit(f"plot_mu_i.py: --csv {csv_path}: {what}: give the CSV of talus element-test {os.path.relpath(SPEC, ROOT)}")
    i = [float(r["I"]) for r in rows]
    ratio = [float(r["tau_over_p"]) for r in rows]
    err = [max(abs(float(r["relative_error"])), 1e-17) for r in rows]

    n = 400
    fine = [10 ** (-4.5 + 5.0 * k / (n - 1)) for k in range(n)]
    fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True,
                                     gridspec_kw={"height_ratios": [3, 1.4]})
    ax.plot(fine, [mu_of_i(x, m["mu_s"], m["mu_2"], m["i0"]) for x in fine], "k-", lw=1.2,
            label=r"$\mu(I)$, Jop et al. 2006")
    ax.plot(i, ratio, "o", ms=5, mfc="none", color="C3", label=r"talus element test, $\tau/p$")
    ax.axhline(m["mu_s"], color="0.6", ls=":", lw=1)
    ax.axhline(m["mu_2"], color="0.6", ls=":", lw=1)
    ax.text(2e-5, m["mu_s"] + 0.005, r"$\mu_s$", color="0.4")
    ax.text(2e-5, m["mu_2"] - 0.02, r"$\mu_2$", color="0.4")
    ax.set_xscale("log")
    ax.set_ylabel(r"$\tau / p$")
    ax.set_title("μ(I) steady simple shear, glass beads, p = 1 kPa")
    ax.legend(loc="center left")
    ax_err.semilogy(i, err, "o", ms=4, color="C3")
    ax_err.axhline(1e-10, color="k", ls="--", lw=1, label="target 1e-10")
    ax_err.set_xlabel("inertial number $I$")
    ax_err.set_ylabel(r"$|\tau/p\,/\,\mu(I) - 1|$")
    ax_err.text(0.99, 0.05, "exact zeros drawn at 1e-17", transform=ax_err.transAxes, ha="right", fontsize=8,
                color="0.4")
    ax_err.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}; largest relative error {max(err):.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
