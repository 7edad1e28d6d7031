#!/usr/bin/env python3
"""Tests of the helpers the tools share (tools/talus_plot.py, tools/cli_checks.py): a CSV writer that
never leaves a truncated file, and the one-line refusals of bad arguments.

    python3 tests/tools/tool_outputs_test.py      (ctest: Tools.KeepOutputsAndRefuseInOneLine)
"""
import os
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools")
sys.path.insert(0, TOOLS)
from talus_plot import write_csv_rows  # noqa: E402


class WriteCsvRows(unittest.TestCase):
    def test_no_rows_is_refused_and_the_old_file_kept(self):
        # a sweep whose runs all failed truncated docs/verification/speed_vs_error.csv to nothing
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "results.csv")
            write_csv_rows(path, [{"a": 1, "b": 2}, {"a": 3, "b": 4}])
            with open(path) as f:
                before = f.read()
            with self.assertRaises(ValueError):
                write_csv_rows(path, [])
            with open(path) as f:
                self.assertEqual(f.read(), before)
            self.assertEqual(os.listdir(tmp), ["results.csv"])  # no .part left behind

    def test_a_failed_write_keeps_the_old_file(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "results.csv")
            write_csv_rows(path, [{"a": 1}])
            with self.assertRaises(ValueError):  # a key outside the columns: DictWriter fails mid-file
                write_csv_rows(path, [{"a": 2}, {"a": 3, "z": 4}])
            with open(path) as f:
                self.assertEqual(f.read().split(), ["a", "1"])
            self.assertEqual(os.listdir(tmp), ["results.csv"])


class Refusals(unittest.TestCase):
    def test_cli_checks_refuse_in_one_line_with_exit_2(self):
        code = ("import sys; sys.path.insert(0, sys.argv[1]); import cli_checks as c; "
                "{}")
        for call, naming in [("c.require_at_least(1, threads=0)", "--threads 0: give 1 or more"),
                             ("c.int_list('--threads', '1,x')", "--threads 1,x"),
                             ("c.choices_list('--mls', 'off,foo', ['off', 'cubic'])", "foo is not one of off, cubic")]:
            r = subprocess.run([sys.executable, "-c", code.format(call), TOOLS], capture_output=True, text=True,
                               timeout=30)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertIn(naming, r.stderr)


if __name__ == "__main__":
    unittest.main()
