#!/usr/bin/env python3
"""Compare runs of one scene on different rank counts (docs/performance.md "Distributed runs").

Usage: tools/compare_ranks.py RUN_1RANK RUN_2RANKS ... [--markdown]

Each RUN is a `talus run` output folder. Prints, against the first run: the runout (front, tail,
distance beyond the gate; runout.json), the final energy ledger and how well it closes (energy.csv),
the particles left in the last frame plus those that left through open faces (mass conservation),
and the wall time if the folder holds a `talus.log` with talus's end-of-run lines.
"""
import argparse
import csv
import json
import pathlib
import re
import sys


def last_energy_row(run):
    with open(run / "energy.csv") as f:
        rows = list(csv.DictReader(f))
    return rows[0], rows[-1]


def particles_in_last_frame(run):
    """Points of the last frame (.vtu or .pvtu pieces), read from the files' headers."""
    pvd = (run / "particles.pvd").read_text()
    last = re.findall(r'file="([^"]+)"', pvd)[-1]
    path = run / last
    if path.suffix == ".pvtu":
        pieces = re.findall(r'Source="([^"]+)"', path.read_text())
        files = [path.parent / p for p in pieces]
    else:
        files = [path]
    total = 0
    for f in files:
        head = f.read_bytes()[:4096].decode("latin-1")
        total += int(re.search(r'NumberOfPoints="(\d+)"', head).group(1))
    return total


def log_value(run, pattern):
    log = run / "talus.log"
    if not log.exists():
        return None
    m = re.search(pattern, log.read_text())
    return m.group(1) if m else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", type=pathlib.Path)
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args()
    for run in args.runs:  # checked before the table (was a traceback)
        for needed in ("runout.json", "energy.csv"):
            if not (run / needed).is_file():
                sys.exit(f"compare_ranks.py: {run / needed} not found: give run folders of a scene with diagnostics.runout")
    ref = None
    rows = []
    for run in args.runs:
        runout = json.loads((run / "runout.json").read_text())
        first, last = last_energy_row(run)
        e0 = float(first["total"])
        closure = (float(last["total"]) - e0) / e0
        particles = particles_in_last_frame(run)
        outflow = log_value(run, r"talus: (\d+) particles \([^)]*\) left through open faces")
        outflow = int(outflow) if outflow else 0
        ranks = log_value(run, r"(\d+) ranks x") or "1"
        wall = log_value(run, r"in ([0-9.]+) s \(")
        if ref is None:
            ref = runout
        row = {
            "run": str(run), "ranks": int(ranks), "front": runout["front"],
            "front_diff": (runout["front"] - ref["front"]) / ref["front"],
            "from_gate_diff": (runout["from_gate"] - ref["from_gate"]) / ref["from_gate"],
            "tail_diff": (runout["tail"] - ref["tail"]) / ref["tail"],
            "closure": closure, "particles": particles, "outflow": outflow, "kept_plus_out": particles + outflow,
            "wall": float(wall) if wall else None,
        }
        rows.append(row)
    if args.markdown:
        print("| ranks | front s [m] | front vs 1 rank | beyond gate vs 1 rank | tail vs 1 rank | budget closes to | "
              "particles kept + out | wall [s] |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['ranks']} | {r['front']:.4f} | {100 * r['front_diff']:+.3f}% | {100 * r['from_gate_diff']:+.3f}% | "
                  f"{100 * r['tail_diff']:+.3f}% | {r['closure']:.3e} | {r['particles']} + {r['outflow']} = "
                  f"{r['kept_plus_out']} | {r['wall'] if r['wall'] else '-'} |")
    else:
        json.dump(rows, sys.stdout, indent=1)
        print()


if __name__ == "__main__":
    main()
