#!/usr/bin/env python3
"""The tools read the output folder of a run on several ranks as they read a 1-rank one: the frames
through particles.pvd (a frame of an N-rank run is a .pvtu and N pieces, and one piece is not the
frame), and the ranks and outflow from run.json (tools/compare_ranks.py took them from a talus.log
that talus never writes, and so called a 2-rank run 1 rank with nothing lost through open faces),
and compare_ranks.py --frames compares the frames of any scene, particle by particle.

    python3 tests/tools/rank_folders_test.py TALUS MPIEXEC     (ctest: Mpi.ToolsReadTheRunFoldersOfRanks)
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import talus_plot  # noqa: E402

TALUS = MPIEXEC = None  # from the command line


class RankFolders(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="talus_rank_folders_")
        with open(os.path.join(ROOT, "inputs", "denlinger_flume.json")) as f:
            scene = json.load(f)
        # the flume to 0.3 s with its runout plane cut short, so that sand leaves through the open face
        scene["time"]["end"] = 0.3
        scene["output"]["frame_interval"] = 0.1
        scene["grid"]["size"][0] = 0.4375
        scene["diagnostics"]["runout"]["runout_plane_x"] = 0.1
        cls.scene = os.path.join(cls.work, "flume.json")
        with open(cls.scene, "w") as f:
            json.dump(scene, f)
        cls.one, cls.two = os.path.join(cls.work, "one"), os.path.join(cls.work, "two")
        run = [TALUS, "run", cls.scene, "--threads", "1", "--quiet", "--out"]
        subprocess.run(run + [cls.one], check=True)
        subprocess.run([MPIEXEC, "-np", "2", "--oversubscribe", *run, cls.two], check=True)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def test_frames_of_two_ranks_are_the_whole_frames(self):
        one, two = talus_plot.series_frames(self.one), talus_plot.series_frames(self.two)
        self.assertEqual(len(one), len(two))
        for (ta, _), (tb, _) in zip(one, two):
            self.assertAlmostEqual(ta, tb, delta=1e-12)  # the same frames (times to round-off: docs/architecture.md)
        self.assertTrue(two[-1][1].endswith(".pvtu"), two[-1][1])
        for (_, a), (_, b) in zip(one, two):
            da, db = talus_plot.read_vtu(a, "id"), talus_plot.read_vtu(b, "id")
            self.assertEqual(len(da["id"]), len(db["id"]))  # every rank's piece, not one
            pa, pb = da["points"][da["id"].argsort()], db["points"][db["id"].argsort()]
            self.assertLess(abs(pa - pb).max(), 1e-9)  # the 1-rank result to round-off

    def test_compare_ranks_reads_ranks_and_outflow_from_the_record(self):
        r = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "compare_ranks.py"), self.one, self.two],
                           capture_output=True, text=True, check=True)
        rows = json.loads(r.stdout)
        self.assertEqual([row["ranks"] for row in rows], [1, 2])
        for row, folder in zip(rows, (self.one, self.two)):
            with open(os.path.join(folder, "run.json")) as f:
                outflow = json.load(f)["end"]["outflow_particles"]
            self.assertGreater(outflow, 0)  # the cut runout plane lets sand out
            self.assertEqual(row["outflow"], outflow)
            self.assertEqual(row["kept_plus_out"], row["particles"] + outflow)
            self.assertIsNotNone(row["wall"])
        self.assertEqual(rows[0]["kept_plus_out"], rows[1]["kept_plus_out"])

    def test_compare_ranks_compares_the_frames_of_any_scene(self):
        # a scene without diagnostics.runout (its runout.json removed): refused with the way out,
        # and --frames compares the frames particle by particle and the last energy row
        other = os.path.join(self.work, "no_runout")
        shutil.copytree(self.two, other)
        os.remove(os.path.join(other, "runout.json"))
        tool = [sys.executable, os.path.join(ROOT, "tools", "compare_ranks.py")]
        r = subprocess.run(tool + [self.one, other], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("--frames", r.stderr)
        r = subprocess.run(tool + ["--frames", self.one, other], capture_output=True, text=True, check=True)
        rows = json.loads(r.stdout)
        self.assertEqual([row["ranks"] for row in rows], [1, 2])
        two = rows[1]
        self.assertGreater(two["frames"], 1)
        self.assertEqual(two["frames_matched"], two["frames"])
        self.assertEqual(two["unmatched_particles"], 0)  # the same particles in every frame (outflow alike)
        self.assertEqual(two["duplicate_ids"], 0)
        self.assertLess(two["max_dx"], 1e-9)  # the 1-rank result to round-off
        self.assertLess(abs(two["total_diff"]), 1e-9)
        self.assertAlmostEqual(two["energy_time"], 0.3, delta=1e-9)
        r = subprocess.run(tool + ["--frames", "--markdown", self.one, other], capture_output=True, text=True,
                           check=True)
        self.assertIn(f"| 2 | {two['frames']} of {two['frames']} |", r.stdout)
        # a run that ended earlier (its last energy rows cut) is refused in one line
        energy = os.path.join(other, "energy.csv")
        with open(energy) as f:
            lines = f.readlines()
        with open(energy, "w") as f:
            f.writelines(lines[:-3])
        r = subprocess.run(tool + ["--frames", self.one, other], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("compare runs that ended at the same time", r.stderr)
        shutil.rmtree(other)

    def test_compare_ranks_refuses_runs_of_another_scene_or_time(self):
        other = os.path.join(self.work, "other")
        shutil.copytree(self.two, other)
        scene_path = os.path.join(other, "scene.json")
        with open(scene_path) as f:
            scene = json.load(f)
        scene["time"]["end"] = 0.2
        with open(scene_path, "w") as f:
            json.dump(scene, f)
        tool = [sys.executable, os.path.join(ROOT, "tools", "compare_ranks.py")]
        r = subprocess.run(tool + [self.one, other], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("is not a run of", r.stderr)
        self.assertIn("scene.json differs in time", r.stderr)
        shutil.copy(os.path.join(self.two, "scene.json"), scene_path)  # the same scene, stopped earlier
        runout_path = os.path.join(other, "runout.json")
        with open(runout_path) as f:
            runout = json.load(f)
        runout["time"] = 0.2
        with open(runout_path, "w") as f:
            json.dump(runout, f)
        r = subprocess.run(tool + [self.one, other], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("ended at t = 0.2 s", r.stderr)
        shutil.rmtree(other)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: rank_folders_test.py TALUS MPIEXEC")
    TALUS, MPIEXEC = sys.argv.pop(1), sys.argv.pop(1)
    unittest.main()
