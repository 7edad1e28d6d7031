"""Argument checks shared by the scripts in tools/: one line and exit 1 for a wrong path, exit 2 for a
value out of range (argparse's status for a bad argument), right after parsing, before any work.

Also provenance(), the record of what measured a result (build, vector path, CPU, date, arguments),
which the benchmark and scaling tools write beside their figures.

Only the standard library: the scripts that run without numpy (bench_kernels, compare_binaries,
check_scene_schema) use it too. They put their own folder on sys.path before importing it.
"""
import json
import os
import re
import subprocess
import sys
import time


def require_talus(path, option="--talus"):
    """Stop with one line when `path` is no executable file (a wrong --talus gave a subprocess
    traceback, often after other work). Returns the path."""
    path = str(path)
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        hint = " (build it: bash tools/build.sh)" if path.endswith(os.path.join("build", "talus")) else ""
        sys.exit(f"{os.path.basename(sys.argv[0])}: {option} {path}: no executable file there{hint}")
    return path


def _option(option):
    return "--" + option.replace("_", "-")


def require_folders(**outputs):
    """Stop with one line when the folder of an output file does not exist, or the file is a folder
    (`option=path`; an empty path is no output). Checked right after parsing: the write at the end
    came after all the work."""
    for option, path in outputs.items():
        if not path:
            continue
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            sys.exit(f"{os.path.basename(sys.argv[0])}: {_option(option)} {path}: the folder {folder} does not exist")
        if os.path.isdir(path):
            sys.exit(f"{os.path.basename(sys.argv[0])}: {_option(option)} {path}: is a folder; give a file name")


def output_folder(option, path):
    """Create the output folder `path` (with its parents), or stop with one line when it is a file or
    cannot be made (a parent that is a file, no permission): os.makedirs raised a traceback, in some
    scripts only after the work. Call it before the work. Returns path."""
    if os.path.exists(path) and not os.path.isdir(path):
        sys.exit(f"{os.path.basename(sys.argv[0])}: {option} {path}: is a file, not a folder")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as e:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {option} {path}: cannot create the folder ({e.strerror})")
    return path


def require_inputs(**inputs):
    """Stop with one line when an input file given does not exist or is a folder (`option=path`; an
    empty path is no input), before any work (a missing file was a traceback)."""
    for option, path in inputs.items():
        if path and not os.path.isfile(path):
            what = "is a folder, not a file" if os.path.isdir(path) else "no such file"
            sys.exit(f"{os.path.basename(sys.argv[0])}: {_option(option)} {path}: {what}")


def refuse(option, value, allowed):
    """Stop with one line naming the option, the value given and what it allows; exit 2, as argparse
    does for a bad argument (a value out of range gave a traceback, or a silent empty result, later)."""
    print(f"{os.path.basename(sys.argv[0])}: {option} {value}: {allowed}", file=sys.stderr)
    sys.exit(2)


def require_at_least(minimum, **values):
    """Refuse each `option=value` below minimum (None: not given)."""
    for option, value in values.items():
        if value is not None and value < minimum:
            refuse(_option(option), value, f"give {minimum} or more")


def int_list(option, text, minimum=1):
    """A comma-separated list of whole numbers, each at least minimum (empty items, as in a trailing
    comma, are skipped); refused with one line otherwise."""
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or any(v < minimum for v in values):
        refuse(option, text, f"give whole numbers separated by commas, each {minimum} or more")
    return values


def choices_list(option, text, allowed):
    """A comma-separated list whose every item is one of allowed; refused with one line otherwise."""
    values = text.split(",")
    wrong = [v for v in values if v not in allowed]
    if wrong:
        refuse(option, text, f"{wrong[0]} is not one of {', '.join(allowed)}")
    return values


def run_or_stop(cmd, what, env=None, keep_stdout=True):
    """Run a program; when it fails, show its own error (stderr, else stdout) and stop with one line
    naming `what` and the command (exit 1), not a CalledProcessError traceback. Returns the finished
    process (stdout as text, or None with keep_stdout False); a success's stderr is passed on."""
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE if keep_stdout else subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        print((r.stderr or r.stdout or "").strip(), file=sys.stderr)
        sys.exit(f"{os.path.basename(sys.argv[0])}: {what} failed (exit {r.returncode}): {' '.join(map(str, cmd))}")
    if r.stderr:
        print(r.stderr, end="", file=sys.stderr)
    return r


def cpu_model(cpuinfo="/proc/cpuinfo"):
    """The CPU's model as /proc/cpuinfo names it ("model name", as talus records it; "Model" or
    "Hardware" on CPUs without that line, e.g. some ARM ones), else "unknown": reading the first
    "model name" line by split()[1] was an IndexError there."""
    try:
        with open(cpuinfo) as f:
            lines = f.read().splitlines()
    except OSError:
        return "unknown"
    for key in ("model name", "Model", "Hardware", "cpu model"):
        for line in lines:
            name, colon, value = line.partition(":")
            if colon and name.strip() == key and value.strip():
                return value.strip()
    return "unknown"


VERSION_LINE = re.compile(r"talus (\S+) \(commit (\S+), (.+?), (\w+), (native|portable)[^,]*, (MPI|no MPI); "
                          r"vector paths here: ([^)]*)\)")


def talus_build(talus):
    """The build of a talus binary from `talus --version`, with the keys of `talus bench --json`'s
    `build` and run.json's `talus` (version, commit, compiler, build_type, native, mpi,
    vector_paths); {"version_line": ...} alone when the line has another form."""
    r = subprocess.run([str(talus), "--version"], capture_output=True, text=True)
    line = (r.stdout or "").strip().splitlines()[0] if (r.stdout or "").strip() else ""
    m = VERSION_LINE.search(line)
    if not m:
        return {"version_line": line}
    return {"version": m.group(1), "commit": m.group(2), "compiler": m.group(3), "build_type": m.group(4),
            "native": m.group(5) == "native", "mpi": m.group(6) == "MPI",
            "vector_paths": [p.strip() for p in m.group(7).split(",") if p.strip()]}


def utc_now():
    """The date and time now, UTC, as talus's run.json writes it (2026-12-07T07:31:45Z)."""
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def provenance(talus, measured=None, started=None):
    """What a result was measured with, for the JSON (and CSV) the tools write: the talus build
    (commit, version, compiler, ...), `build` (native or portable), the vector path that ran (`isa`),
    the CPU model, the logical CPUs, the date (UTC) and the exact command line of the tool.

    measured: what a talus process wrote about itself, where the tool ran one: a `talus bench --json`
    result (its `build`, `isa`, `cpu`) or a run.json (its `talus`, `isa`, `host`). Without it the
    build comes from `talus --version` and the vector path is None (not known: the paths a binary
    offers are not the one a run took). started: utc_now() when the measurement began (the date
    recorded; default now)."""
    measured = measured or {}
    build = measured.get("build") or measured.get("talus")
    if not isinstance(build, dict):
        build = talus_build(talus)
    host = measured.get("host") if isinstance(measured.get("host"), dict) else {}
    native = build.get("native")
    return {"talus": build,
            "build": None if native is None else ("native" if native else "portable"),
            "isa": measured.get("isa"),
            # (talus says "unknown" where /proc/cpuinfo has no "model name": then this script's own reading)
            "cpu": next((c for c in (measured.get("cpu"), host.get("cpu")) if c and c != "unknown"), None) or cpu_model(),
            "logical_cpus": host.get("logical_cpus") or os.cpu_count(),
            "date_utc": started or utc_now(),
            "command": list(sys.argv), "working_directory": os.getcwd()}


def write_json_atomically(path, data):
    """data as JSON at path, written beside and renamed into place: a failure (or a value JSON cannot
    hold) leaves the old file, or none, never a half-written one."""
    part = path + ".part"
    try:
        with open(part, "w") as f:
            json.dump(data, f, indent=1)
            f.write("\n")
        os.replace(part, path)
    finally:
        if os.path.exists(part):
            os.remove(part)
