#!/usr/bin/env python3
"""Do two talus binaries give the same bits? Runs short versions of a set of scenes with both and
compares every output file byte for byte (all but scene.json and run.json, the run's record, which
name the binary's run).

    tools/compare_binaries.py OLD_TALUS NEW_TALUS [--end 0.02] [--threads 2] [--new-threads N]
                              [--work /tmp/compare] [--scene FILE ... | --all-inputs] [--variants]

By default the scenes are the flumes (colour passes and block buffers), the collapses, the terrain
slope, the walls and bar benchmarks with and without MLS, the elastic block, and the elastic block
with 3D linear MLS fits (per particle at 1 and 2 cells, per cell at 1). --variants adds,
for the default flume and the block between walls, every scheme (musl, usl, usf, usavg) with each
scatter (colour passes, block buffers). Each run ends at --end seconds of simulated time (frames
every end/2). Exit status 1 when any file differs or a run fails on one side only.
Used for refactors that must not change results (docs/performance.md). With one binary on both
sides and --new-threads, it checks that the results do not depend on the thread count:
`tools/compare_binaries.py build/talus build/talus --threads 1 --new-threads 16 --all-inputs`.
"""
import argparse
import filecmp
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import require_talus  # noqa: E402

DEFAULT_SCENES = [
    "inputs/denlinger_flume.json",
    "inputs/denlinger_flume_block_buffers.json",
    "inputs/denlinger_flume_bspline2.json",
    "inputs/column_collapse_2d.json",
    "inputs/column_collapse_mu_i.json",
    "inputs/elastic_block_slide.json",
    "inputs/terrain/slope_to_runout_ugimp.json",
    "inputs/benchmarks/block_between_walls.json",
    "inputs/benchmarks/block_between_walls_mls.json",
    "inputs/benchmarks/dynamic_bar.json",
    "inputs/benchmarks/column_w12500_mls.json",
]
VARIANT_SCENES = ["inputs/denlinger_flume.json", "inputs/benchmarks/block_between_walls.json"]


# 3D fits (every other MLS scene fits along one axis): the elastic block (3D, no terrain grid,
# which MLS does not run on) smoothed with a linear basis, one fit per particle and one per cell.
MLS_3D_CASES = [("particle", 1.0), ("particle", 2.0), ("cell", 1.0)]


def short_scene(path, end, scheme=None, scatter=None, mls=None, name=None):
    with open(path) as f:
        s = json.load(f)
    s.setdefault("time", {})["end"] = end
    out = s.setdefault("output", {})
    out["frame_interval"] = end / 2
    out["history_interval"] = end / 10
    tag = ""
    if scheme or scatter:
        solver = s.setdefault("solver", {})
        if scheme:
            solver["scheme"] = scheme
        if scatter:
            solver["scatter"] = scatter
        tag = f"_{scheme}_{scatter}"
    if mls:
        variant, radius = mls
        s.setdefault("solver", {})["smoothing"] = {"basis": "linear", "radius_factor": radius, "variant": variant}
        tag += f"_mls3d_{variant}_{radius:g}"
    s["name"] = (name or s.get("name", os.path.splitext(os.path.basename(path))[0])) + tag
    return s


def run(talus, scene_file, out, threads):
    r = subprocess.run([talus, "run", scene_file, "--out", out, "--threads", str(threads), "--quiet",
                        "--foreground-frames"], capture_output=True, text=True)
    return r.returncode, (r.stderr.strip().splitlines() or [""])[-1]


RECORDS = ("scene.json", "run.json")  # what names a run, not what it computed


def differing(a, b):
    diffs = []
    for root, _, files in os.walk(a):
        for name in files:
            if name in RECORDS:
                continue
            pa = os.path.join(root, name)
            pb = os.path.join(b, os.path.relpath(pa, a))
            if not os.path.exists(pb) or not filecmp.cmp(pa, pb, shallow=False):
                diffs.append(os.path.relpath(pa, a))
    for root, _, files in os.walk(b):
        for name in files:
            pb = os.path.join(root, name)
            if name in RECORDS:
                continue
            if not os.path.exists(os.path.join(a, os.path.relpath(pb, b))):
                diffs.append(os.path.relpath(pb, b) + " (only in the new run)")
    return diffs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--end", type=float, default=0.02, help="simulated seconds per run (default 0.02)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--new-threads", type=int, help="threads of the NEW run (default: --threads); with the same "
                    "binary on both sides, a check that the results do not depend on the thread count")
    ap.add_argument("--all-inputs", action="store_true",
                    help="every scene under inputs/ (the element tests aside) instead of the set above")
    ap.add_argument("--work", default="/tmp/talus_compare")
    ap.add_argument("--scene", action="append", help="a scene file (repeatable; default: the set above)")
    ap.add_argument("--variants", action="store_true", help="every scheme with each scatter, on two scenes")
    a = ap.parse_args()
    require_talus(a.old, "OLD")
    require_talus(a.new, "NEW")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the defaults are the repo's inputs
    in_repo = lambda path: os.path.join(root, path)
    if a.all_inputs and a.scene:
        sys.exit("compare_binaries.py: --all-inputs and --scene: give one of them")
    scenes = a.scene or [in_repo(p) for p in DEFAULT_SCENES]
    if a.all_inputs:
        scenes = sorted(os.path.join(d, f) for d, _, files in os.walk(in_repo("inputs")) for f in files
                        if f.endswith(".json") and "element_tests" not in d)
    for threads in (a.threads, a.new_threads):
        if threads is not None and threads < 1:
            sys.exit(f"compare_binaries.py: threads {threads}: give 1 or more")
    new_threads = a.new_threads or a.threads
    cases = [(p, None, None, None) for p in scenes]
    if not a.scene:
        cases += [(in_repo("inputs/elastic_block_slide.json"), None, None, mls) for mls in MLS_3D_CASES]
    if a.variants:
        cases += [(in_repo(p), scheme, scatter, None) for p in VARIANT_SCENES for scheme in ("musl", "usl", "usf", "usavg")
                  for scatter in ("colour_passes", "block_buffers")]
    for path, *_ in cases:
        if not os.path.isfile(path):
            sys.exit(f"compare_binaries.py: scene {path} does not exist")
    if os.path.exists(a.work) and not os.path.isdir(a.work):  # (was a FileExistsError traceback)
        sys.exit(f"compare_binaries.py: --work {a.work}: is a file; give a folder")
    os.makedirs(a.work, exist_ok=True)
    bad = failed = 0
    for path, scheme, scatter, mls in cases:
        # (--all-inputs: named by the file, as two scenes in inputs/ may share a name)
        name = os.path.relpath(path, in_repo("inputs"))[:-len(".json")].replace(os.sep, "_") if a.all_inputs else None
        scene = short_scene(path, a.end, scheme, scatter, mls, name)
        scene_file = os.path.join(a.work, scene["name"] + ".json")
        with open(scene_file, "w") as f:
            json.dump(scene, f)
        outs = [os.path.join(a.work, side, scene["name"]) for side in ("old", "new")]
        for o in outs:  # no frames left from an earlier, longer comparison
            shutil.rmtree(o, ignore_errors=True)
        results = [run(t, scene_file, o, n) for t, o, n in zip((a.old, a.new), outs, (a.threads, new_threads))]
        if results[0][0] != results[1][0]:
            print(f"DIFFER {scene['name']}: exit {results[0][0]} (old) against {results[1][0]} (new): {results[1][1]}")
            bad += 1
            continue
        if results[0][0] != 0:
            print(f"both fail {scene['name']} (exit {results[0][0]}): {results[0][1]}")
            failed += 1
            continue
        diffs = differing(*outs)
        files = sum(len(f) for _, _, f in os.walk(outs[0]))
        print(f"{'DIFFER' if diffs else 'same  '} {scene['name']}: {files} files" + (f"; {', '.join(diffs[:5])}" if diffs else ""))
        bad += bool(diffs)
    print(f"{len(cases) - bad - failed} of {len(cases)} scenes give the same bits"
          + (f"; {failed} failed on both sides (nothing compared)" if failed else ""))
    sys.exit(1 if bad or failed else 0)  # a scene that failed on both sides compared nothing


if __name__ == "__main__":
    main()
