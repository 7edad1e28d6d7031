"""Argument checks shared by the scripts in tools/: one line and exit 1 for a wrong path, right after
parsing, before any work.

Only the standard library: the scripts that run without numpy (bench_kernels, compare_binaries,
check_scene_schema) use it too. They put their own folder on sys.path before importing it.
"""
import os
import sys


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


def require_inputs(**inputs):
    """Stop with one line when an input file given does not exist or is a folder (`option=path`; an
    empty path is no input), before any work (a missing file was a traceback)."""
    for option, path in inputs.items():
        if path and not os.path.isfile(path):
            what = "is a folder, not a file" if os.path.isdir(path) else "no such file"
            sys.exit(f"{os.path.basename(sys.argv[0])}: {_option(option)} {path}: {what}")
