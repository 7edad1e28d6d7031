#!/usr/bin/env python3
"""Tests of the scaling and benchmark tools (tools/scaling.py, scaling_runs.py, bench_kernels.py,
mpi_bench.py, plot_node_scaling.py) and their shared provenance helpers (tools/cli_checks.py), from
a user review: bad input refused before the runs, the rates as recorded, a real median, what measured
a result recorded beside it, and no committed file replaced by a plain run.

    python3 tests/tools/scaling_tools_test.py TALUS      (ctest: Tools.ScalingToolsRefuseEarlyAndRecordProvenance)
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
TOOLS = os.path.join(ROOT, "tools")
sys.path.insert(0, TOOLS)
TALUS = None  # the program, from the command line

# A talus that notes every call in "calls" beside itself and fails: a tool that refuses its input
# before any run never calls it.
FAKE_TALUS = """#!/bin/sh
echo "$@" >> "$(dirname "$0")/calls"
exit 3
"""


def tool(name, *args, cwd=None):
    r = subprocess.run([sys.executable, os.path.join(TOOLS, name), *map(str, args)], capture_output=True,
                       text=True, timeout=120, cwd=cwd)
    return r.returncode, r.stdout, r.stderr


class Work(unittest.TestCase):
    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="talus_scaling_tools_")
        self.fake = os.path.join(self.work, "talus")
        with open(self.fake, "w") as f:
            f.write(FAKE_TALUS)
        os.chmod(self.fake, 0o755)

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def path(self, name, content=None):
        p = os.path.join(self.work, name)
        if content is not None:
            with open(p, "w") as f:
                f.write(content)
        return p

    def assertRefused(self, result, code, text):
        self.assertEqual(result[0], code, result[2])
        self.assertNotIn("Traceback", result[2])
        self.assertEqual(len(result[2].strip().splitlines()), 1, result[2])
        self.assertIn(text, result[2])
        self.assertFalse(os.path.exists(self.path("calls")), "talus ran before the refusal")


class RefusedBeforeTheRuns(Work):
    def test_scaling_runs_reads_every_scene_first(self):
        # a bad scene after a good one was a traceback after the good one's runs, with nothing written
        good = self.path("good.json", json.dumps({"name": "good", "time": {"end": 1.0}}))
        for name, content, text in (("broken.json", '{"name": ', "broken.json: not a readable JSON scene"),
                                    ("list.json", "[1, 2]", "list.json: a scene is a JSON object ({...}), not a list")):
            out = os.path.join(self.work, "out")
            self.assertRefused(tool("scaling_runs.py", good, self.path(name, content), "--talus", self.fake,
                                    "--out", out), 1, text)
            self.assertFalse(os.path.exists(out))
        a_file = self.path("a_file", "")
        self.assertRefused(tool("scaling_runs.py", good, "--talus", self.fake, "--out", a_file), 1,
                           f"--out {a_file}: is a file, not a folder")

    def test_scaling_refuses_cpu_time(self):
        # per-core-second rates were reported as a speed-up and divided by STREAM's wall-clock one
        out = os.path.join(self.work, "out")
        self.assertRefused(tool("scaling.py", "--talus", self.fake, "--out", out, "--", "--cpu-time"), 2,
                           "a scaling study is of wall-clock time")
        self.assertFalse(os.path.exists(out))

    def test_bench_kernels_refuses_a_folder_as_its_json(self):
        self.assertRefused(tool("bench_kernels.py", "--talus", self.fake, "--json", self.work), 1,
                           f"--json {self.work}: is a folder; give a file name")


class RecordsAndMedians(Work):
    def test_scaling_runs_takes_the_rate_from_run_json(self):
        # the printed line rounds to 0.01 M/s: 0.2937 M/s was stored as 290000.0
        from scaling_runs import run_timing
        out = os.path.join(self.work, "run")
        os.makedirs(out)
        printed = "talus: done: 13 steps to t = 0.002 s in 0.09 s (0.29 M particle-updates/s)\n"
        self.assertEqual(run_timing(["talus"], out, printed), (13, 0.09, 290000.0, None))  # no run.json
        record = {"wall_seconds": 0.0884, "end": {"steps_this_part": 13, "particle_updates_per_second": 293712.5}}
        with open(os.path.join(out, "run.json"), "w") as f:
            json.dump(record, f)
        self.assertEqual(run_timing(["talus"], out, printed)[:3], (13, 0.0884, 293712.5))  # a record before 2026-12-07
        # the stepping loop's seconds, which the rate divides by, not the whole command's
        record["wall_seconds"] = 0.12
        record["end"]["stepping_wall_seconds"] = 0.0884
        with open(os.path.join(out, "run.json"), "w") as f:
            json.dump(record, f)
        self.assertEqual(run_timing(["talus"], out, printed)[:3], (13, 0.0884, 293712.5))

    def test_bench_kernels_median_of_an_even_count_is_the_mean_of_the_middle_two(self):
        from bench_kernels import median
        self.assertEqual(median([4.0, 2.0]), 3.0)  # it took the upper of two rounds
        self.assertEqual(median([3.0, 1.0, 2.0]), 2.0)
        self.assertEqual(median(iter([1.0, 4.0, 2.0, 3.0])), 2.5)

    def test_cpu_model_without_a_model_name_line(self):
        # /proc/cpuinfo's "model name" was assumed: an IndexError on CPUs without it
        from cli_checks import cpu_model
        self.assertEqual(cpu_model(self.path("x86", "processor\t: 0\nmodel name\t: AMD EPYC 9R14\n")), "AMD EPYC 9R14")
        self.assertEqual(cpu_model(self.path("arm", "processor\t: 0\nBogoMIPS\t: 50.00\n\nHardware\t: BCM2835\n")),
                         "BCM2835")
        self.assertEqual(cpu_model(self.path("none", "processor\t: 0\n")), "unknown")
        self.assertEqual(cpu_model(self.path("missing")), "unknown")

    def test_provenance_takes_what_the_bench_recorded(self):
        from cli_checks import provenance
        bench = {"build": {"commit": "abc123", "native": True, "version": "0.1.0"}, "isa": "avx2", "cpu": "X"}
        p = provenance(self.fake, bench, "2026-12-07T07:00:00Z")
        self.assertEqual((p["talus"]["commit"], p["build"], p["isa"], p["cpu"], p["date_utc"]),
                         ("abc123", "native", "avx2", "X", "2026-12-07T07:00:00Z"))
        self.assertEqual(p["logical_cpus"], os.cpu_count())
        self.assertEqual(p["command"], sys.argv)
        self.assertFalse(os.path.exists(self.path("calls")), "talus --version asked although the bench said it")

    def test_provenance_from_talus_version(self):
        from cli_checks import provenance
        p = provenance(TALUS)
        self.assertRegex(p["talus"].get("commit", ""), r"^[0-9a-f]{7,}")
        self.assertIn(p["build"], ("native", "portable"))
        self.assertIsNone(p["isa"])  # nothing ran: not known, not guessed

    def test_a_json_that_cannot_be_written_keeps_the_old_file(self):
        from cli_checks import write_json_atomically
        path = self.path("r.json")
        write_json_atomically(path, {"a": 1})
        with self.assertRaises(TypeError):
            write_json_atomically(path, {"a": object()})
        with open(path) as f:
            self.assertEqual(json.load(f), {"a": 1})
        self.assertEqual(sorted(os.listdir(self.work)), ["r.json", "talus"])


class Outputs(Work):
    def test_mpi_bench_says_not_measured_and_the_steps_the_benches_ran(self):
        # "STREAM 0.00 GB/s" without --stream; "--steps" not last garbled the phase table's header
        out = self.path("mpi.json")
        code, stdout, stderr = tool("mpi_bench.py", "--talus", TALUS, "--rounds", "1", "--layouts", "1x1",
                                    "--bench-args", "--particles 1000 --steps 2 --scene block", "--json", out)
        self.assertEqual(code, 0, stderr)
        self.assertIn("1 thread(s): STREAM not measured, mpm_limit linear not measured", stdout)
        self.assertIn("per phase, seconds over 2 steps:", stdout)
        with open(out) as f:
            prov = json.load(f)["provenance"]
        self.assertTrue(prov["isa"] and prov["talus"]["commit"] and prov["date_utc"].endswith("Z"))
        self.assertIn("--bench-args", prov["command"])

    def test_plot_node_scaling_leaves_the_committed_figure(self):
        committed = os.path.join(ROOT, "docs", "performance", "node16_2026-12-04", "summary.png")
        before = os.stat(committed).st_mtime_ns
        code, stdout, stderr = tool("plot_node_scaling.py", cwd=self.work)
        self.assertEqual(code, 0, stderr)
        self.assertTrue(os.path.isfile(os.path.join(self.work, "runs", "scaling", "node16_2026-12-04_summary.png")))
        self.assertEqual(os.stat(committed).st_mtime_ns, before)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: scaling_tools_test.py TALUS")
    TALUS = sys.argv.pop(1)
    unittest.main()
