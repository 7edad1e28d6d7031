#!/usr/bin/env python3
"""A table of talus runs from their records (run.json, README "What the files hold"): for a
parameter sweep or a scaling study, which runs finished, which build and settings made each, and
what each cost.

    tools/runs_table.py [FOLDER ...] [--csv FILE]

Each FOLDER is a run's output folder, or a folder searched for them (every run.json below it).
Default: runs/. One row a run, oldest first: the folder, scene, status, commit, ranks x threads,
vector path, steps, simulated time reached of the end time, wall seconds, million particle-updates
per second and the energy budget's gap (completed runs), and for a run that did not complete its
message. A run still going (or killed) shows the step and time it last recorded. A resumed run
counts its earlier parts (`parts`): its steps and wall seconds are all the parts' (a killed part
recorded no wall time and adds none), its rate is the last part's (as talus's closing line). Exit status 1 when no record is found,
or when a run's status is not "completed" (so that a sweep's script can stop on it); a folder
that does not exist is one line and exit 2.
Only the standard library.
"""
import argparse
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import require_folders  # noqa: E402

COLUMNS = ["run", "scene", "status", "commit", "ranks_x_threads", "isa", "steps", "time", "end_time",
           "wall_seconds", "m_updates_per_s", "energy_gap", "parts", "started", "message"]


def find_records(folders):
    """The run.json files in or below each folder, in the order found (sorted within a folder)."""
    found = []
    for folder in folders:
        if not os.path.isdir(folder):
            sys.exit(f"runs_table.py: {folder}: no such folder")
        for root, dirs, files in os.walk(folder):
            dirs.sort()
            if "run.json" in files:
                found.append(os.path.join(root, "run.json"))
    return found


def row(path, base):
    """One row of the table from a record; a file that is no record gives a row that says so."""
    run = os.path.relpath(os.path.dirname(path), base)
    try:
        with open(path) as f:
            r = json.load(f)
        if not isinstance(r, dict) or "record_version" not in r:
            raise ValueError("not a talus run record")
    except (OSError, ValueError) as e:
        return {"run": run, "status": "unreadable", "message": str(e)}
    end = r.get("end", {})
    start = r.get("start", {})
    if not end and "progress" in r:  # a run still going (or killed): how far it got, and when
        end = r["progress"]
    rate = end.get("particle_updates_per_second")
    gap = end.get("energy_budget_gap")
    # steps count from the start of the whole run, wall_seconds only this part's: a resumed run's
    # earlier parts add theirs (the column read as the whole run's time, with the whole run's steps)
    parts = [*r.get("earlier_parts", []), r]
    walls = [p["wall_seconds"] for p in parts if isinstance(p.get("wall_seconds"), (int, float))]
    return {
        "run": run,
        "scene": r.get("scene", {}).get("name", ""),
        "status": r.get("status", ""),
        "commit": r.get("talus", {}).get("commit", ""),
        "ranks_x_threads": f"{r.get('ranks', '?')}x{r.get('threads', '?')}",
        "isa": r.get("isa", ""),
        "steps": end.get("step", start.get("step", "")),
        "time": end.get("time", start.get("time", "")),
        "end_time": r.get("end_time", ""),
        "wall_seconds": sum(walls) if walls else "",
        "m_updates_per_s": rate / 1e6 if rate is not None else "",
        "energy_gap": gap if gap is not None else "",
        "parts": len(parts),
        "started": r.get("started", ""),
        "message": r.get("message", ""),
    }


def text(value, column):
    if isinstance(value, float):
        if column in ("time", "end_time"):
            return f"{value:.6g}"
        if column == "energy_gap":
            return f"{value:.2e}"
        return f"{value:.2f}"
    return str(value)


def print_table(rows):
    shown = [c for c in COLUMNS if c != "message"]
    cells = [[text(r.get(c, ""), c) for c in shown] for r in rows]
    widths = [max(len(c), *(len(line[i]) for line in cells)) for i, c in enumerate(shown)]
    print("  ".join(c.ljust(w) for c, w in zip(shown, widths)).rstrip())
    for r, line in zip(rows, cells):
        print("  ".join(v.ljust(w) for v, w in zip(line, widths)).rstrip())
        if r.get("message"):
            print(f"    {r['message']}")


def main():
    summary, _, details = __doc__.partition("\n\n")  # (the epilog was the whole text: --help said the first paragraph twice)
    p = argparse.ArgumentParser(description=summary, formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=details)
    p.add_argument("folders", nargs="*", default=["runs"], metavar="FOLDER")
    p.add_argument("--csv", metavar="FILE", help="also write the table as CSV (every column, the message too)")
    a = p.parse_args()
    require_folders(csv=a.csv)
    missing = [f for f in a.folders if not os.path.isdir(f)]
    if missing:
        print(f"runs_table.py: {missing[0]}: no such folder", file=sys.stderr)
        sys.exit(2)
    records = find_records(a.folders)
    if not records:
        print(f"runs_table.py: no run.json in or below {', '.join(a.folders)}", file=sys.stderr)
        sys.exit(1)
    base = os.path.commonpath([os.path.abspath(f) for f in a.folders])
    base = base if len(a.folders) > 1 or not os.path.isfile(os.path.join(base, "run.json")) else os.path.dirname(base)
    rows = sorted((row(os.path.abspath(path), base) for path in records), key=lambda r: r.get("started", ""))
    print_table(rows)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS)
            w.writeheader()
            for r in rows:
                w.writerow({c: r.get(c, "") for c in COLUMNS})
    unfinished = [r for r in rows if r.get("status") != "completed"]
    if unfinished:
        print(f"runs_table.py: {len(unfinished)} of {len(rows)} runs did not complete", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
