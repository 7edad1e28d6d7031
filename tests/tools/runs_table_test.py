#!/usr/bin/env python3
"""Tests of tools/runs_table.py on the records of real runs: one run of the talus program, and two
copies of its record made to say "unstable" and "running" as a run that went unstable or was killed
leaves them (docs/reliability.md, "run.json").

    python3 tests/tools/runs_table_test.py TALUS      (ctest: RunsTable.ListsEveryRecordAndFlagsTheUnfinished)
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
TOOL = os.path.join(ROOT, "tools", "runs_table.py")
TALUS = None  # the program, from the command line


def table(*args):
    r = subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


class RunsTable(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="talus_runs_table_")
        with open(os.path.join(ROOT, "inputs", "elastic_block_slide.json")) as f:
            scene = json.load(f)
        scene["time"]["end"] = 0.01
        cls.scene = os.path.join(cls.work, "short.json")
        with open(cls.scene, "w") as f:
            json.dump(scene, f)
        cls.sweep = os.path.join(cls.work, "sweep")
        done = os.path.join(cls.sweep, "a_done")
        subprocess.run([TALUS, "run", cls.scene, "--out", done, "--threads", "1", "--quiet"], check=True)
        with open(os.path.join(done, "run.json")) as f:
            cls.record = json.load(f)
        for name, status, message in (("b_unstable", "unstable", "step 12, t = 0.001 s: CFL breach"),
                                      ("c_killed", "running", "")):
            os.makedirs(os.path.join(cls.sweep, name))
            r = dict(cls.record, status=status, message=message, started="2999-01-01T00:00:00Z")
            if status == "running":  # as a killed run leaves it: how far it got, no end
                del r["end"]
                r["progress"] = {"step": 77, "time": 0.005, "updated": "2999-01-01T00:01:00Z"}
            with open(os.path.join(cls.sweep, name, "run.json"), "w") as f:
                json.dump(r, f)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def test_a_sweep_lists_every_run_and_fails_on_the_unfinished(self):
        code, out, err = table(self.sweep)
        self.assertEqual(code, 1, out + err)
        self.assertIn("2 of 3 runs did not complete", err)
        lines = out.splitlines()
        header = lines[0].split()
        self.assertEqual(header[:4], ["run", "scene", "status", "commit"])
        rows = [line.split() for line in lines[1:] if not line.startswith("    ")]
        self.assertEqual([r[0] for r in rows], ["a_done", "b_unstable", "c_killed"])  # oldest first
        self.assertEqual([r[2] for r in rows], ["completed", "unstable", "running"])
        killed = dict(zip(header, rows[2]))
        self.assertEqual((killed["steps"], killed["time"]), ("77", "0.005"))
        self.assertIn("    step 12, t = 0.001 s: CFL breach", lines)  # the message under its run
        done = dict(zip(header, rows[0]))
        self.assertEqual(done["commit"], self.record["talus"]["commit"])
        self.assertEqual(done["ranks_x_threads"], "1x1")
        self.assertEqual(int(done["steps"]), self.record["end"]["step"])
        self.assertAlmostEqual(float(done["m_updates_per_s"]),
                               self.record["end"]["particle_updates_per_second"] / 1e6, places=2)

    def test_a_completed_run_alone_exits_zero_and_the_csv_has_every_column(self):
        out_csv = os.path.join(self.work, "t.csv")
        code, out, err = table(os.path.join(self.sweep, "a_done"), "--csv", out_csv)
        self.assertEqual(code, 0, out + err)
        with open(out_csv) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), 1)
        self.assertEqual(rows[0]["run"], "a_done")
        self.assertEqual(float(rows[0]["wall_seconds"]), self.record["wall_seconds"])
        self.assertEqual(float(rows[0]["energy_gap"]), self.record["end"]["energy_budget_gap"])

    def test_a_resumed_run_counts_the_wall_seconds_of_every_part(self):
        # steps counted every part, wall_seconds the last part's alone
        run = os.path.join(self.work, "resumed")
        os.makedirs(run, exist_ok=True)
        killed = {k: v for k, v in self.record.items() if k not in ("end", "wall_seconds")}
        earlier = [dict(self.record, status="interrupted", wall_seconds=2.5), dict(killed, status="ended_unrecorded")]
        with open(os.path.join(run, "run.json"), "w") as f:
            json.dump(dict(self.record, earlier_parts=earlier), f)
        out_csv = os.path.join(self.work, "resumed.csv")
        code, out, err = table(run, "--csv", out_csv)
        self.assertEqual(code, 0, out + err)
        with open(out_csv) as f:
            r = next(csv.DictReader(f))
        self.assertEqual(r["parts"], "3")
        self.assertAlmostEqual(float(r["wall_seconds"]), self.record["wall_seconds"] + 2.5, places=9)

    def test_help_says_each_paragraph_once(self):
        code, out, err = table("--help")
        self.assertEqual(code, 0, err)
        self.assertEqual(out.count("A table of talus runs"), 1, out)
        self.assertIn("Only the standard library.", out)

    def test_no_record_and_no_folder_are_one_line(self):
        code, out, err = table(self.work + "/nothing_here")
        self.assertEqual((code, err.count("\n")), (2, 1), err)
        empty = os.path.join(self.work, "empty")
        os.makedirs(empty, exist_ok=True)
        code, out, err = table(empty)
        self.assertEqual((code, err.count("\n")), (1, 1), err)
        self.assertIn("no run.json", err)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: runs_table_test.py TALUS")
    TALUS = sys.argv.pop(1)
    unittest.main()
