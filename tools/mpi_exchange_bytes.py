#!/usr/bin/env python3
"""Bytes of node sums a distributed run exchanges per step, read from `talus run` under mpirun.

The weak-scaling model of docs/performance.md ("Distributed runs (MPI)") needs the tiles a rank sends
to a slab neighbour a step. It is measured here, not guessed: `talus run` under `mpirun -np 2` and `-np 3`
prints "... kB a step" at the end (node sums sent by all ranks, all steps, over the steps). Per step and
per pair of neighbours each side sends, twice (7 fields after P2G, 3 after the MUSL remap, 64 nodes x
8 bytes a field), the tiles it shares with the other; since main f6b7c33 only those its own particles
reached, after one flag byte per shared tile:
    bytes a step = 2 x (ranks - 1) x sent tiles x 10 x 512 (+ the flags, < 0.2%).
"sent tiles" below is that figure (per pair and direction, the mean of the two); divided by the active
tiles of the body's y-z cross-section (the tiles its colour blocks reach) it gives the band in tile
columns. (All shared tiles were sent before f6b7c33: the band of shared tiles is 2 tile columns.)

Scenes: a bar of elastic material (constant cross-section, y 0.20 m x z 0.10 m at h = 0.01 m) sliding
along x at 0.5 m/s on a floor, so that particles cross the slab boundaries; with the linear shape and
with the quadratic B-spline; and the default flume (inputs/denlinger_flume.json) cut to 0.3 s.

  /usr/bin/python3 tools/mpi_exchange_bytes.py --talus build/talus --json docs/performance/mpi_exchange_bytes.json
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

H = 0.01
TILE = 4  # nodes per tile edge
PAD = 2   # ghost cells (grid.hpp kPad)
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def bar_scene(shape):
    return {
        "name": f"mpi_bar_{shape}",
        "grid": {"origin": [0, 0, 0], "size": [1.2, 0.3, 0.2], "cell_size": H},
        "gravity": [0, 0, -9.81],
        "time": {"end": 0.01, "courant": 0.3},
        "solver": {"scheme": "musl", "shape": shape},
        "materials": {"m": {"model": "linear_elastic", "density": 2000.0, "young": 1.0e7, "poisson": 0.3}},
        "bodies": [{"name": "bar", "material": "m", "box": {"min": [0.05, 0.05, 0.0], "max": [1.0, 0.25, 0.1]},
                    "particles_per_cell": 2, "velocity": [0.5, 0, 0]}],
        "boundaries": {"x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                       "z-": {"type": "friction", "friction_coefficient": 0.3}, "z+": "open"},
        "output": {"frame_interval": 1.0, "history_interval": 1.0},
    }


# Colour blocks (CellSort): edge B cells, slack s = (B - reach_low - reach_high) / 2; a block makes active
# every tile holding a node from its origin - s - reach_low to its end + s + reach_high (activate_tiles).
SHAPES = {"linear": (4, 0, 1), "bspline2": (8, 1, 2)}  # B (automatic), reach_low, reach_high


def tiles_spanned(first_cell, end_cell, shape, domain_cells):
    """Active tiles along one axis over a body in the scene's cells [first, end)."""
    B, rl, rh = SHAPES[shape]
    slack = (B - rl - rh) // 2
    first_block, last_block = (first_cell + PAD) // B, (end_cell - 1 + PAD) // B
    lo = max(0, first_block * B - slack - rl)
    hi = min(domain_cells + 2 * PAD, last_block * B + B - 1 + slack + rh)  # the last node index of the grid
    return hi // TILE - lo // TILE + 1


def run(talus, scene_path, ranks, out):
    cmd = ["mpirun", "-np", str(ranks), "--oversubscribe", "--bind-to", "none", talus, "run", scene_path, "--quiet",
           "--threads", "1", "--out", out]
    r = subprocess.run(cmd, env=dict(os.environ, **MPI_ENV), capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{r.stdout}\n{r.stderr}")
    kb = float(re.search(r"\(([0-9.e+]+) kB a step\)", r.stdout).group(1))
    steps = int(re.search(r"done: (\d+) steps", r.stdout).group(1))
    particles = int(re.search(r"talus: (\d+) particles", r.stdout).group(1))
    return {"ranks": ranks, "kB_per_step": kb, "steps": steps, "particles": particles,
            "sent_tiles_per_interface_and_direction": kb * 1e3 / (2 * 10 * TILE ** 3 * 8) / (ranks - 1),
            "stdout_tail": r.stdout[-600:]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--talus", default="build/talus")
    ap.add_argument("--json")
    a = ap.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for shape in SHAPES:
            scene = bar_scene(shape)
            path = os.path.join(tmp, scene["name"] + ".json")
            json.dump(scene, open(path, "w"))
            cross = tiles_spanned(5, 25, shape, 30) * tiles_spanned(0, 10, shape, 20)
            for ranks in (2, 3):
                r = run(a.talus, path, ranks, os.path.join(tmp, f"out_{shape}_{ranks}"))
                r.update(scene=scene["name"], shape=shape, cross_section_tiles=cross,
                         cross_section_m2=0.2 * 0.1, band_tile_columns=r["sent_tiles_per_interface_and_direction"] / cross)
                results.append(r)
                print(f"{scene['name']:16s} {ranks} ranks: {r['kB_per_step']:8.1f} kB a step, "
                      f"{r['sent_tiles_per_interface_and_direction']:6.1f} tiles sent per interface and direction, "
                      f"cross-section {cross} tiles, "
                      f"band {r['band_tile_columns']:.2f} tile columns", flush=True)
        flume = json.load(open(os.path.join(os.path.dirname(__file__), "..", "inputs", "denlinger_flume.json")))
        flume["time"]["end"] = 0.3
        flume["output"] = {"frame_interval": 1.0, "history_interval": 1.0}
        path = os.path.join(tmp, "flume.json")
        json.dump(flume, open(path, "w"))
        for ranks in (2, 3):
            r = run(a.talus, path, ranks, os.path.join(tmp, f"out_flume_{ranks}"))
            r.update(scene="denlinger_flume (0.3 s)", shape="linear")
            results.append(r)
            print(f"{'flume 0.3 s':16s} {ranks} ranks: {r['kB_per_step']:8.1f} kB a step, "
                  f"{r['sent_tiles_per_interface_and_direction']:6.1f} tiles sent per interface and direction (mean over the steps)",
                  flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
