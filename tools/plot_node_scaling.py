#!/usr/bin/env python3
"""Every measurement of one node session against the scaling model, in one figure
(docs/performance.md, "Measured on a 16-core node").

    /usr/bin/python3 tools/plot_node_scaling.py [DIR] [--out runs/scaling/NAME_summary.png]

The figure goes to runs/scaling/NAME_summary.png under the current folder (NAME: DIR's own name)
unless --out names a file: DIR is a folder of committed data, whose summary.png a plain run replaced.
To redraw the committed figure, name it: --out DIR/summary.png.

DIR (default docs/performance/node16_2026-12-04 in the repository) holds what tools/node_scaling.sh (or the session's
script, DIR/run1.sh) wrote: scaling_runs_node.json (tools/scaling_runs.py), scaling_node_block.json and
scaling_node_shear.json (tools/scaling.py), bench_{colour_passes,block_buffers}_{1,N}.json (talus bench
--json), and optionally run2_log.txt (the printed lines of a second sitting: repeats of the same
commands, read back with the regular expressions below). Left: the whole runs (talus run), measured
speed-up (best of the repeats) against the model with the measured c(N). Right: the 1 M-particle
benches, strong scaling of every sitting, and the model without and with the measured c(T).
"""
import argparse
import glob
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for cli_checks, next to this script
from cli_checks import output_folder, require_folders  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

RUNS_LINE = re.compile(r"^\s*(\d+) threads\s+best\s+([0-9.]+) M/s\s+speed-up\s+([0-9.]+)\s+model\s+([0-9.]+)\s+with c\s+([0-9.]+)")
RUNS_HEAD = re.compile(r"^(\S+) \((\d+) particles, to ([0-9.]+) s\): c\((\d+)\) = ([0-9.]+)")
BENCH_LINE = re.compile(r"^(strong|weak)\s+threads=\s*(\d+)\s+particles=\s*(\d+)\s+([0-9.]+) M/s")


def second_sitting(path):
    """{'runs': {scene: [(T, speed-up, model with c)]}, 'strong': [(T, M/s)]} from a printed log."""
    runs, strong, scene = {}, [], None
    if not os.path.exists(path):
        return {"runs": runs, "strong": strong}
    for line in open(path):
        if m := RUNS_HEAD.match(line):
            scene = m.group(1)
            runs[scene] = []
        elif (m := RUNS_LINE.match(line)) and scene:
            runs[scene].append((int(m.group(1)), float(m.group(3)), float(m.group(5))))
        elif (m := BENCH_LINE.match(line)) and m.group(1) == "strong":
            strong.append((int(m.group(2)), float(m.group(4))))
    return {"runs": runs, "strong": strong}


def wait_policy(runs, directory):
    """The JSON's omp_wait_policy; before the tools recorded it, the value the session's script exported."""
    if "omp_wait_policy" in runs:
        return runs["omp_wait_policy"]
    for script in sorted(glob.glob(os.path.join(directory, "*.sh"))):
        if m := re.search(r"OMP_WAIT_POLICY=(\w+)", open(script).read()):
            return f"{m.group(1)} (from {os.path.basename(script)})"
    return "not recorded"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    # from the repository root, not the current folder
    ap.add_argument("dir", nargs="?", default=os.path.join(ROOT, "docs", "performance", "node16_2026-12-04"))
    ap.add_argument("--out", help="the figure (default: runs/scaling/NAME_summary.png under the current folder)")
    a = ap.parse_args()
    # before the output folder is made: a wrong DIR left an empty runs/scaling behind
    runs_path = os.path.join(a.dir, "scaling_runs_node.json")
    if not os.path.exists(runs_path):
        sys.exit(f"plot_node_scaling.py: {runs_path} missing (written by tools/node_scaling.sh: unpack its "
                 "results.tar.gz into the folder given)")
    if not a.out:
        name = os.path.basename(os.path.normpath(a.dir))
        a.out = os.path.join(output_folder("--out", os.path.join("runs", "scaling")), f"{name}_summary.png")
    require_folders(out=a.out)  # (a missing folder was a traceback from savefig, after the plotting)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = json.load(open(runs_path))
    second = second_sitting(os.path.join(a.dir, "run2_log.txt"))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    top = runs["nproc"]
    for i, res in enumerate(runs["results"]):
        t = [r["threads"] for r in res["rows"]]
        c = list(res["contention"].items())[-1]  # the largest count's c
        ax1.plot(t, [r["best_speedup"] for r in res["rows"]], "o-", color=f"C{i}",
                 label=f"{res['scene']} ({res['particles']} p.): measured")
        ax1.plot(t, [r["model_speedup_with_contention"] for r in res["rows"]], "x:", color=f"C{i}",
                 label=f"model, c({c[0]}) = {c[1]:.2f}")
        if res["scene"] in second["runs"]:
            rows = second["runs"][res["scene"]]
            ax1.plot([r[0] for r in rows], [r[1] for r in rows], "o-", mfc="none", color=f"C{i}", alpha=0.6,
                     label="second sitting: measured")
            ax1.plot([r[0] for r in rows], [r[2] for r in rows], "x:", color=f"C{i}", alpha=0.6,
                     label="second sitting: model")

    for i, (name, label) in enumerate((("scaling_node_block", "block"), ("scaling_node_shear", "shear"))):
        if not os.path.exists(os.path.join(a.dir, name + ".json")):  # a phase the budget left out
            continue
        d = json.load(open(os.path.join(a.dir, name + ".json")))
        strong = [r for r in d["rows"] if r["kind"] == "strong"]
        weak = [r for r in d["rows"] if r["kind"] == "weak"]
        t = [r["threads"] for r in strong]
        ax2.plot(t, [r["speedup"] for r in strong], "o-", color=f"C{i}", label=f"{label} 1 M, strong: measured")
        ax2.plot(t, [r["model_speedup"] for r in strong], "x--", color=f"C{i}", label=f"{label}: model (no c)")
        if all("model_speedup_with_contention" in r for r in strong):  # older JSONs lack it
            ax2.plot(t, [r["model_speedup_with_contention"] for r in strong], "+", ls=(0, (1, 1)), color=f"C{i}",
                     label=f"{label}: model with c(T)")
        ax2.plot([r["threads"] for r in weak], [r["speedup"] for r in weak], "s-.", color=f"C{i}", alpha=0.7,
                 label=f"{label}, weak (1 M per thread): measured")
        ax2.plot(t, [r["stream_speedup"] for r in strong], ":", color=f"C{i}", lw=0.9, label=f"STREAM ({label} runs)")
    if second["strong"]:
        base = second["strong"][0][1]
        ax2.plot([r[0] for r in second["strong"]], [r[1] / base for r in second["strong"]], "o-", mfc="none",
                 color="C0", alpha=0.6, label="block, second sitting (best of 3)")
    for scatter, marker in (("colour_passes", "D"), ("block_buffers", "^")):
        one = glob.glob(os.path.join(a.dir, f"bench_{scatter}_1.json"))
        many = [p for p in glob.glob(os.path.join(a.dir, f"bench_{scatter}_*.json")) if not p.endswith("_1.json")]
        if one and many:
            r1 = json.load(open(one[0]))["particle_updates_per_second"]
            for p in many:
                rn = json.load(open(p))
                n = int(re.search(r"_(\d+)\.json$", p).group(1))
                ax2.plot([n], [rn["particle_updates_per_second"] / r1], marker, color="C2", ms=8,
                         label=f"block, {scatter} (bench, one run each)")
    for ax, title in ((ax1, "talus run: flumes (strong scaling)"), (ax2, "talus bench: 1 M particles")):
        ax.plot([1, top], [1, top], "k--", lw=0.8, label="ideal")
        ax.set(xscale="log", yscale="log", xlabel="threads", ylabel="speed-up over 1 thread", title=title)
        ticks = [x for x in (1, 2, 4, 8) if x < top] + [top]  # 8 on a 2-core node stretched the axes
        ax.set_xticks(ticks, [str(x) for x in ticks])
        ax.set_yticks(ticks, [str(x) for x in ticks])
        ax.minorticks_off()
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper left")
    fig.suptitle(f"{top}-core node, OMP_PROC_BIND={runs['omp_proc_bind']} OMP_PLACES={runs['omp_places']} "
                 f"OMP_WAIT_POLICY={wait_policy(runs, a.dir)}", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
