#!/usr/bin/env python3
"""Compare runs of one scene on different rank counts (docs/performance.md "Distributed runs").

Usage: tools/compare_ranks.py RUN_1RANK RUN_2RANKS ... [--markdown]
       tools/compare_ranks.py --frames RUN_1RANK RUN_2RANKS ... [--markdown]

Each RUN is a `talus run` output folder. Prints, against the first run: the runout (front, tail,
distance beyond the gate; runout.json), the final energy ledger and how well it closes (energy.csv),
the particles left in the last frame plus those that left through open faces (mass conservation),
and the wall time. The rank count, the particles that left and the wall time come from the run's
record (run.json; of a resumed run, its last part's wall time), or from a `talus.log` with talus's
end-of-run lines in a folder written before talus kept that record. Runs whose scene.json differs
from the first's, or that ended at another time (runout.json), are refused in one line.

--frames: for any scene (with or without diagnostics.runout), compares the particles of every frame
the runs share (matched by time, to round-off), particle by particle matched by id: the largest
difference of position and velocity, and the particles in one run's frame but not the other's; and
the last row of energy.csv (its time, total and kinetic energy). Needs VTK's Python module
(python3-vtk9, tools/setup.sh). Runs of another scene, or whose last energy row is of another time,
are refused in one line.
"""
import argparse
import csv
import json
import pathlib
import re
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

def energy_rows(run):
    with open(run / "energy.csv") as f:
        return list(csv.DictReader(f))


def recorded_closure(run):
    """The energy budget's closure the run itself printed (run.json end.energy_budget_gap), or None.
    energy.csv alone misled: a run resumed into another folder (--out) starts its rows at the
    checkpoint, and its first row is not the initial energy (a 4-rank restart read -1.012e-4 for -1.112e-4)."""
    try:
        return float(json.loads((run / "run.json").read_text())["end"]["energy_budget_gap"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def same_scene(runs):
    """Refuse runs that are not of one scene to one time: the table's differences would then be those
    of the scenes (a 960-particle wedge read as "-66% beyond the gate vs 1 rank")."""
    refuse_other_scene(runs)
    first = runs[0]
    time0 = json.loads((first / "runout.json").read_text()).get("time")
    for run in runs[1:]:
        time = json.loads((run / "runout.json").read_text()).get("time")
        if time != time0:
            sys.exit(f"compare_ranks.py: {run} ended at t = {time} s, {first} at t = {time0} s: compare runs that "
                     "ended at the same time (a stopped run: resume it first)")


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


def run_facts(run):
    """(ranks, particles that left through open faces, wall seconds or None) of a run folder."""
    record = run / "run.json"
    if record.is_file():
        try:
            r = json.loads(record.read_text())
            return int(r["ranks"]), int(r["end"]["outflow_particles"]), r.get("wall_seconds")
        except (ValueError, KeyError, TypeError):
            pass  # a record of a run that did not end: the log, if any
    outflow = log_value(run, r"talus: (\d+) particles \([^)]*\) left through open faces")
    ranks = log_value(run, r"(\d+) ranks x")
    wall = log_value(run, r"in ([0-9.]+) s \(")
    if ranks is None and not (run / "talus.log").exists():
        sys.exit(f"compare_ranks.py: {run}: neither run.json of a finished run nor talus.log: cannot tell its ranks "
                 "and outflow")
    return int(ranks or 1), int(outflow or 0), float(wall) if wall else None


def refuse_other_scene(runs):
    """Refuse runs whose scene.json differs from the first's (the differences would be the scenes')."""
    first = runs[0]
    if not (first / "scene.json").is_file():
        return
    scene0 = json.loads((first / "scene.json").read_text())
    for run in runs[1:]:
        if (run / "scene.json").is_file():
            scene = json.loads((run / "scene.json").read_text())
            differ = sorted(k for k in set(scene0) | set(scene) if scene0.get(k) != scene.get(k))
            if differ:
                sys.exit(f"compare_ranks.py: {run} is not a run of {first}'s scene (scene.json differs in "
                         f"{', '.join(differ)}): compare runs of one scene")


def same_time(a, b):
    """Times of two runs that are the same to round-off (a distributed run's differ in the last bits)."""
    return abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))


def frame_particles(path):
    """(ids, positions, velocities) of one frame, sorted by id."""
    import talus_plot  # (VTK: only this mode needs it)
    data = talus_plot.read_vtu(path, "id", "velocity")
    order = data["id"].argsort(kind="stable")
    return data["id"][order], data["points"][order], data["velocity"][order]


def compare_frames(ref, run):
    """The frames `run` shares with `ref`, particle by particle: {frames, matched, max_dx, max_dv, at, unmatched,
    duplicate_ids}."""
    import numpy as np
    import talus_plot
    frames_ref, frames_run = talus_plot.series_frames(str(ref)), talus_plot.series_frames(str(run))
    out = {"frames": len(frames_run), "frames_matched": 0, "max_dx": 0.0, "max_dv": 0.0, "at": None,
           "unmatched_particles": 0, "duplicate_ids": 0}
    for t, path in frames_run:
        t_ref, path_ref = min(frames_ref, key=lambda f: abs(f[0] - t))
        if not same_time(t_ref, t):
            continue
        ids_a, x_a, v_a = frame_particles(path_ref)
        ids_b, x_b, v_b = frame_particles(path)
        out["duplicate_ids"] = max(out["duplicate_ids"], len(ids_b) - len(np.unique(ids_b)))
        common, ia, ib = np.intersect1d(ids_a, ids_b, assume_unique=False, return_indices=True)
        out["unmatched_particles"] = max(out["unmatched_particles"], len(ids_a) + len(ids_b) - 2 * len(common))
        out["frames_matched"] += 1
        if len(common) == 0:
            continue
        dx = float(np.abs(x_a[ia] - x_b[ib]).max())
        dv = float(np.abs(v_a[ia] - v_b[ib]).max())
        if dx > out["max_dx"] or out["at"] is None:
            out["at"] = t
        out["max_dx"], out["max_dv"] = max(out["max_dx"], dx), max(out["max_dv"], dv)
    return out


def frames_mode(runs, markdown):
    for run in runs:
        if not (run / "energy.csv").is_file():
            sys.exit(f"compare_ranks.py: {run / 'energy.csv'} not found: give talus run folders")
    refuse_other_scene(runs)
    last0 = energy_rows(runs[0])[-1]
    rows = []
    for run in runs:
        last = energy_rows(run)[-1]
        if not same_time(float(last["time"]), float(last0["time"])):
            sys.exit(f"compare_ranks.py: {run}'s energy.csv ends at t = {last['time']} s, {runs[0]}'s at "
                     f"t = {last0['time']} s: compare runs that ended at the same time (a stopped run: resume it first)")
        ranks, outflow, wall = run_facts(run)
        scale = abs(float(last0["total"])) or 1.0
        row = {"run": str(run), "ranks": ranks, **compare_frames(runs[0], run),
               "energy_time": float(last["time"]),
               "total_diff": (float(last["total"]) - float(last0["total"])) / scale,
               "kinetic_diff": (float(last["kinetic"]) - float(last0["kinetic"])) / (abs(float(last0["kinetic"])) or 1.0),
               "outflow": outflow, "wall": wall}
        rows.append(row)
    if markdown:
        ranks0 = rows[0]["ranks"]
        vs = f"vs {ranks0} rank{'' if ranks0 == 1 else 's'}"
        print(f"| ranks | frames matched | max position diff [m] {vs} | max velocity diff [m/s] | particles unmatched | "
              f"last energy row t [s] | total {vs} | kinetic {vs} | wall [s] |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['ranks']} | {r['frames_matched']} of {r['frames']} | {r['max_dx']:.3g} | {r['max_dv']:.3g} | "
                  f"{r['unmatched_particles']} | {r['energy_time']:.6g} | {r['total_diff']:+.3e} | "
                  f"{r['kinetic_diff']:+.3e} | {'%.2f' % r['wall'] if r['wall'] else '-'} |")
    else:
        json.dump(rows, sys.stdout, indent=1)
        print()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", type=pathlib.Path)
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    ap.add_argument("--frames", action="store_true",
                    help="compare the frames particle by particle and the last energy row (any scene)")
    args = ap.parse_args()
    if args.frames:
        frames_mode(args.runs, args.markdown)
        return
    for run in args.runs:  # checked before the table (was a traceback)
        for needed in ("runout.json", "energy.csv"):
            if not (run / needed).is_file():
                sys.exit(f"compare_ranks.py: {run / needed} not found: give run folders of a scene with diagnostics.runout, or compare the frames with --frames")
    same_scene(args.runs)
    ref = None
    rows = []
    for run in args.runs:
        runout = json.loads((run / "runout.json").read_text())
        closure = recorded_closure(run)
        if closure is None:  # a run without the record's figure: from energy.csv, which starts at t = 0 here
            # on the run's own scale where the CSV allows: the initial kinetic and strain energy plus
            # the most potential energy released by the particles still on the grid (the outflow's
            # share is not in the CSV: close to talus's energy available, not equal, when mass left)
            energy = energy_rows(run)
            first, last = energy[0], energy[-1]
            gravity0 = float(first["gravity"])
            released = max(gravity0 - float(row["gravity"]) for row in energy)
            scale = float(first["kinetic"]) + float(first["strain"]) + max(released, 0.0)
            closure = (float(last["total"]) - float(first["total"])) / (scale if scale > 0.0 else abs(float(first["total"])))
        particles = particles_in_last_frame(run)
        ranks, outflow, wall = run_facts(run)
        if ref is None:
            ref = runout
        row = {
            "run": str(run), "ranks": ranks, "front": runout["front"],
            "front_diff": (runout["front"] - ref["front"]) / ref["front"],
            "from_gate_diff": (runout["from_gate"] - ref["from_gate"]) / ref["from_gate"],
            "tail_diff": (runout["tail"] - ref["tail"]) / ref["tail"],
            "closure": closure, "particles": particles, "outflow": outflow, "kept_plus_out": particles + outflow,
            "wall": wall,
        }
        rows.append(row)
    if args.markdown:
        ranks0 = rows[0]["ranks"]  # the first run's, which need not be 1 (the headers said "vs 1 rank")
        vs = f"vs {ranks0} rank{'' if ranks0 == 1 else 's'}"
        print(f"| ranks | front s [m] | front {vs} | beyond gate {vs} | tail {vs} | budget closes to | "
              "particles kept + out | wall [s] |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['ranks']} | {r['front']:.4f} | {100 * r['front_diff']:+.3f}% | {100 * r['from_gate_diff']:+.3f}% | "
                  f"{100 * r['tail_diff']:+.3f}% | {r['closure']:.3e} | {r['particles']} + {r['outflow']} = "
                  f"{r['kept_plus_out']} | {'%.2f' % r['wall'] if r['wall'] else '-'} |")
    else:
        json.dump(rows, sys.stdout, indent=1)
        print()


if __name__ == "__main__":
    main()
