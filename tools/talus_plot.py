"""Reading, writing and plotting helpers shared by the scripts in tools/.

The scripts run as `/usr/bin/python3 tools/X.py` and find this module next to themselves (they put
their own folder on sys.path before importing it).
"""
import csv
import json
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np

from cli_checks import require_folders, require_inputs, require_talus  # noqa: F401 (the scripts import them from here too)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_vtu(path, *arrays):
    """One frame as {"points": n x 3 positions, name: array for each name in arrays}: a .vtu, or the
    .pvtu of a run on several ranks (all its pieces).

    Needs VTK's Python module (python3-vtk9, installed by tools/setup.sh)."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    if str(path).endswith(".pvtu"):
        reader = vtk.vtkXMLPUnstructuredGridReader()
    else:
        reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    data = {"points": vtk_to_numpy(grid.GetPoints().GetData())}
    for name in arrays:
        array = grid.GetPointData().GetArray(name)
        if array is None:
            raise KeyError(f"{path} has no point array '{name}'")
        data[name] = vtk_to_numpy(array)
    return data


def series_frames(run_dir):
    """[(time, path)] of the frames a run's particles.pvd lists, in order: the whole frames (.vtu, or
    .pvtu on several ranks), never one rank's piece of a frame. Stops with one line when there is no
    series there."""
    pvd = os.path.join(run_dir, "particles.pvd")
    if not os.path.isfile(pvd):
        sys.exit(f"{os.path.basename(sys.argv[0])}: {run_dir}: no particles.pvd there: give the folder of a talus run")
    frames = [(float(d.get("timestep")), os.path.join(run_dir, d.get("file")))
              for d in ET.parse(pvd).getroot().iter("DataSet")]
    if not frames:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {pvd} lists no frames")
    return frames


def run_status(run_dir):
    """The status a run's record (run.json) gives: "completed", "interrupted", "unstable", "failed",
    "running" (a killed run), or None when there is no readable record."""
    try:
        with open(os.path.join(run_dir, "run.json")) as f:
            return json.load(f).get("status")
    except (OSError, ValueError, AttributeError):
        return None


def run_finished(run_dir):
    """Whether the run in run_dir ran to its end. A run stopped by --stop-after, Ctrl-C or SIGTERM
    writes runout.json, energy.csv and its frames too, so their presence does not say it finished:
    a reused interrupted flume gave a front clamped at its last row for later times."""
    return run_status(run_dir) == "completed"


def require_finished(run_dir, option=None, hint="resume it (talus run SCENE --restart DIR/checkpoint.h5) or run it again"):
    """Stop with one line unless the run in run_dir completed (`option`, e.g. "--run-dir", names where
    the folder came from; `hint` says what to do). Returns run_dir."""
    if not run_finished(run_dir):
        status = run_status(run_dir)
        why = f"its run.json says '{status}'" if status else "no readable run.json there"
        where = f"{option} {run_dir}" if option else run_dir
        sys.exit(f"{os.path.basename(sys.argv[0])}: {where}: the run did not complete ({why}): {hint}")
    return run_dir


class TalusError(RuntimeError):
    """A talus run or command that failed; its message is one line (see main_guard)."""


def talus_failure(cmd, r):
    """One line for a talus process r that failed: its last line on stderr, else how it stopped (a run
    stopped by a signal says so on stdout, or the process ended by one has no words at all: the
    message was "talus failed (130): ")."""
    said = (r.stderr or "").strip().splitlines()
    stopped = [line for line in (r.stdout or "").splitlines() if "stopped by signal" in line]
    if r.returncode < 0:
        why = f"stopped by signal {-r.returncode}"
    elif said:
        why = said[-1].strip()
    elif stopped:
        why = stopped[-1].strip()
    elif r.returncode > 128:
        why = f"stopped by signal {r.returncode - 128}"
    else:
        why = "no message"
    return f"{' '.join(map(str, cmd))} failed (exit {r.returncode}): {why}"


def main_guard(main):
    """Run a script's main(); a failed talus run (TalusError) ends it with one line and exit 1 instead
    of a traceback. Other exceptions are bugs and keep their traceback. Returns main's exit status."""
    try:
        return main()
    except TalusError as e:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {e}")


def run_talus(talus, *args, threads=None, quiet=True, capture=False, check=True):
    """Run the talus program (`talus run SCENE --out DIR`, `talus element-test ...`): the arguments
    as given, then --threads and --quiet for `run` when asked. Returns the CompletedProcess; with
    check, a failure raises TalusError with talus's own one-line error (see talus_failure). capture
    keeps stdout and stderr."""
    require_talus(talus)
    cmd = [talus, *map(str, args)]
    if args and args[0] == "run":
        if threads is not None:
            cmd += ["--threads", str(threads)]
        if quiet:
            cmd.append("--quiet")
    r = subprocess.run(cmd, capture_output=True, text=True)
    if check and r.returncode != 0:
        raise TalusError(talus_failure(cmd, r))
    if not capture and r.stdout and not quiet:
        print(r.stdout, end="")
    return r


def run_flume(talus, runs, name, cell, threads=1, scene_args=(), rerun=False):
    """The flume scene of tools/make_flume_scene.py at cell size `cell` (extra generator arguments in
    scene_args), run into runs/name unless a finished run is there (or rerun): one that did not
    complete (run.json, see run_finished) is run again, as a missing one. Returns
    (run_dir, runout columns, energy columns, runout.json, wall seconds or None)."""
    run_dir = os.path.join(runs, name)
    wall_path = os.path.join(run_dir, "wall_seconds.txt")
    if rerun or not run_finished(run_dir) or not os.path.exists(os.path.join(run_dir, "runout.json")):
        os.makedirs(runs, exist_ok=True)
        scene = os.path.join(runs, name + ".json")
        with open(scene, "w") as f:
            subprocess.run([sys.executable, os.path.join(ROOT, "tools", "make_flume_scene.py"), "--cell", str(cell),
                            *map(str, scene_args), "--name", name], check=True, stdout=f)
        t0 = time.perf_counter()
        # (--overwrite: an unfinished run there, with its checkpoint, is run again from the start)
        run_talus(talus, "run", scene, "--out", run_dir, "--overwrite", threads=threads)
        with open(wall_path, "w") as f:
            f.write(f"{time.perf_counter() - t0:.1f}\n")
    with open(os.path.join(run_dir, "runout.json")) as f:
        result = json.load(f)
    wall = None
    if os.path.exists(wall_path):
        with open(wall_path) as f:
            wall = float(f.read())
    return (run_dir, read_csv_columns(os.path.join(run_dir, "runout.csv")),
            read_csv_columns(os.path.join(run_dir, "energy.csv")), result, wall)


def value_at(times, values, t, what="the run"):
    """values (a history over times) at time t, interpolated; a time outside the history is refused
    (ValueError) rather than clamped: np.interp gave a run stopped at 0.8 s the front of 0.8 s for
    t = 1 and 2 s."""
    times = np.asarray(times)
    if len(times) == 0 or not times[0] <= t <= times[-1] * (1 + 1e-9):
        span = f"{times[0]:g} to {times[-1]:g} s" if len(times) else "no rows"
        raise ValueError(f"{what} has no value at t = {t:g} s (its history runs {span})")
    return float(np.interp(t, times, values))


def read_csv_columns(path):
    """A CSV file of numbers as {column name: numpy array} ({} for a file without rows)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def write_csv_rows(path, rows, fieldnames=None):
    """Rows (dicts) as a CSV file; the columns are those of the first row unless fieldnames are given.
    No rows is an error, and the file is written beside and renamed into place: a sweep whose runs all
    failed truncated a committed CSV to nothing, then failed on rows[0]."""
    if not rows:
        raise ValueError(f"{path}: no rows to write (the file is left as it was)")
    part = path + ".part"
    try:
        with open(part, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fieldnames if fieldnames is not None else list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        os.replace(part, path)
    finally:
        if os.path.exists(part):
            os.remove(part)


def finish_axes(ax, xlabel=None, ylabel=None, title=None, **legend_options):
    """Label a panel (the labels not None), draw its legend (with legend_options) and a light grid."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title)
    ax.legend(**legend_options)
    ax.grid(True, alpha=0.3)


def save_figure(fig, path, dpi):
    """Lay out a figure, write it to path and close it (the scripts draw many figures in one run)."""
    import matplotlib.pyplot as plt
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
