#!/usr/bin/env python3
"""The column under body force in compression, as Edo & Matsubara 2015 load it (sec. 4(1), Fig. 4: the body
force towards the fixed end, b < 0 in eq. 61-62): the sweep that tools/speed_vs_error.py makes of the
tension columns, on inputs/benchmarks/column_w10000_compression.json and column_w12500_compression.json.

Each column is run over shape (linear, uGIMP, cpGIMP, B-spline) x cell size (2, 1, 0.5, 0.25; 2 particles
per cell, and 1, 2, 3 at cell 1), MUSL; the error is the relative L2 of the layer-averaged stress against
eq. 61 at the end of the load ramp. Writes (when every run succeeded: a failed run prints talus's error,
and then nothing is written, exit 1)
    docs/verification/column_compression.csv                      one row per run (speed_vs_error.csv's columns)
    docs/verification/column_w10000_compression_error_vs_time.png  error against run time, a marker per shape
    docs/verification/column_w12500_compression_error_vs_time.png
Usage:  /usr/bin/python3 tools/column_compression.py [--talus build/talus] [--threads 1] [--quick] [--wall]
        [--out DIR]   (--quick: linear and cpGIMP, cells 2, 1, 0.5; it writes into build/verification_scratch
                       unless --out is given)
Needs numpy, matplotlib and VTK's Python module (Debian: python3-numpy python3-matplotlib python3-vtk9).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import speed_vs_error as sve  # noqa: E402
from talus_plot import write_csv_rows  # noqa: E402

COLUMNS = ["column_w10000_compression", "column_w12500_compression"]


def main():
    ap = sve.benchmark_parser(__doc__, scratch_when="with --quick")
    ap.add_argument("--quick", action="store_true", help="fewer variants (a smoke test of the driver)")
    sve.add_time_option(ap)
    a, talus = sve.parse_benchmark_args(ap)
    out = sve.out_folder(a, scratch=a.quick)
    print(f"writing into {out}", flush=True)
    sve.set_time_key(a)
    rows, failed = [], []
    shapes = ["linear", "cpgimp"] if a.quick else sve.SHAPES
    for name in COLUMNS:
        sve.column_sweep(talus, name, shapes, a.quick, ["off"], a.threads, rows, failed)
    if failed:
        sys.exit(f"column_compression.py: {len(failed)} of {len(failed) + len(rows)} runs failed (the first: {failed[0]}); "
                 f"nothing written into {out}")
    write_csv_rows(os.path.join(out, "column_compression.csv"), rows)
    for name in COLUMNS:
        sve.plot_error_vs_time(rows, name, os.path.join(out, f"{name}_error_vs_time.png"), a.threads, ["off"])
    time_col = sve.TIME_KEY + "_s"
    print(f"{len(rows)} runs, {sum(r[time_col] for r in rows):.1f} s of {sve.TIME_KEY} time in all", flush=True)


if __name__ == "__main__":
    main()
