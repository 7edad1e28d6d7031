#!/usr/bin/env python3
"""Tests of what the plotting tools and the scene generators show and write, from user reviews: the
Bagnold plot's axis, the flume's deposit profile, the terrain tool's rigid answers, the flume scene
generator's refusals and the column collapse's initial half-width.

    python3 tests/tools/plot_tools_test.py TALUS      (ctest: Tools.PlotsShowWhatTheRunsDid)
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
TOOLS = os.path.join(ROOT, "tools")
sys.path.insert(0, TOOLS)
TALUS = None  # the program, from the command line


def scene(path):
    with open(os.path.join(ROOT, path)) as f:
        return json.load(f)


def tool(name, *args):
    r = subprocess.run([sys.executable, os.path.join(TOOLS, name), *map(str, args)], capture_output=True,
                       text=True, timeout=120)
    return r.returncode, r.stdout, r.stderr


class BagnoldPlot(unittest.TestCase):
    def test_the_profile_axis_shows_a_row_slower_than_zero(self):
        # the lowest row carries about -u_a (docs/mu-i.md sec. 8); an axis cut at u = 0 hid it
        import plot_bagnold
        setup = plot_bagnold.Setup(scene("inputs/inclined_flow_bagnold.json"))
        z = np.array([0.25, 0.75, 1.25, 1.75]) * setup.h / 2
        u = setup.u(z)
        u[0] = -0.013
        fig, ax = plt.subplots()
        plot_bagnold.draw_profiles(ax, setup, [{"cells": 2, "z": z, "u": u, "surface": 0.0, "l2": 0.0}])
        lo, hi = ax.get_xlim()
        plt.close(fig)
        self.assertLess(lo, -0.013)
        self.assertGreater(hi, float(setup.u(setup.h)))
        # a profile without such a row keeps its axis from 0
        fig, ax = plt.subplots()
        plot_bagnold.draw_profiles(ax, setup, [{"cells": 2, "z": z, "u": setup.u(z), "surface": 0.0, "l2": 0.0}])
        self.assertEqual(ax.get_xlim()[0], 0.0)
        plt.close(fig)



class FlumeDepositProfile(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="talus_plot_tools_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def test_the_band_follows_a_deposit_away_from_y_0(self):
        # elastic_block_slide's grid starts at y = 0, the block spans 0.1..0.3: the band |y| <= one
        # cell held no mass and the profile was a zero line labelled "(1 rows)"
        s = scene("inputs/elastic_block_slide.json")
        s["time"]["end"] = 0.02
        s["output"]["frame_interval"] = 0.02
        s["diagnostics"] = {"runout": {"deposit_cell": 0.04}}
        path, run = os.path.join(self.work, "block.json"), os.path.join(self.work, "block")
        with open(path, "w") as f:
            json.dump(s, f)
        subprocess.run([TALUS, "run", path, "--out", run, "--threads", "1", "--quiet"], check=True, timeout=120)
        code, out, err = tool("plot_flume.py", run, "--out", os.path.join(self.work, "plots"))
        self.assertEqual(code, 0, err)
        self.assertNotIn("warning", err)
        import plot_flume
        from talus_plot import read_csv_columns
        d = read_csv_columns(os.path.join(run, "deposit.csv"))
        ys = np.unique(d["y"])
        thickness = d["thickness"].reshape(len(np.unique(d["s"])), len(ys))
        centre = plot_flume.band_centre(read_csv_columns(os.path.join(run, "runout.csv")), ys, thickness)
        self.assertAlmostEqual(centre, 0.2, places=6)  # the block's centre, from runout.csv's centre_y
        band, cell = plot_flume.centre_line_band(ys, centre)
        self.assertEqual(list(ys[band]), [0.18, 0.22])
        self.assertGreater(thickness[:, band].mean(axis=1).max(), 0.1)  # the block's 0.2 m, not a zero line
        self.assertEqual(plot_flume.band_text(centre, cell, band), "|y - 0.2| <= 0.04 m (2 rows)")
        # without centre_y (an older runout.csv) the deposit's own centre
        self.assertAlmostEqual(plot_flume.band_centre({}, ys, thickness), 0.2, places=6)

    def test_one_row_and_a_band_without_deposit_are_said(self):
        import plot_flume
        self.assertEqual(plot_flume.band_text(0.0, 0.04, np.array([False, True, False])), "|y| <= 0.04 m (1 row)")
        # two strips either side of the centre line: the mass centre's band holds nothing, and the tool says so
        run = os.path.join(self.work, "strips")
        os.makedirs(run)
        with open(os.path.join(run, "scene.json"), "w") as f:
            json.dump({"name": "strips"}, f)
        with open(os.path.join(run, "runout.csv"), "w") as f:
            f.write("time,front,tail,s_max,centre_s,centre_y,centre_velocity_s,front_velocity\n"
                    "0,1,0,1,0.5,0,0,0\n1,1,0,1,0.5,0,0,0\n")
        with open(os.path.join(run, "deposit.csv"), "w") as f:
            f.write("s,y,x,thickness\n")
            for s_ in (0.5, 1.5):
                for y in (-2.0, -1.0, 0.0, 1.0, 2.0):
                    f.write(f"{s_},{y},{s_},{0.1 if abs(y) == 2.0 else 0.0}\n")
        code, out, err = tool("plot_flume.py", run)
        self.assertEqual(code, 0, err)
        self.assertEqual(len(err.strip().splitlines()), 1, err)
        self.assertIn("warning: the deposit profile's band (|y| <= 1 m (3 rows)) holds no deposit", err)



class TerrainRigidAnswers(unittest.TestCase):
    def test_each_incline_run_is_quoted_its_own_friction_and_rigid_travel(self):
        # the mu = 0.7 run was quoted "(rigid mu = 0.3: 2.2957 m)"; a rigid block sticks when mu >= tan theta
        import plot_terrain
        stick = scene("inputs/terrain/incline30_stick.json")
        self.assertEqual(plot_terrain.rigid_incline(stick, 1.5)[0], 0.7)
        self.assertEqual(plot_terrain.rigid_incline(stick, 1.5)[2], 0.0)
        self.assertEqual(plot_terrain.rigid_text(stick, 1.5), "rigid mu = 0.7 >= tan 30, sticks: 0.0000 m")
        for name in ("incline30_coarse", "incline30_fine", "incline30_flat_rotated_gravity"):  # eq. 22, as before
            self.assertEqual(plot_terrain.rigid_text(scene(f"inputs/terrain/{name}.json"), 1.5),
                             "rigid mu = 0.3: 2.2957 m", name)

    def test_the_ramped_rigid_block_and_its_effective_friction(self):
        # gravity ramped over T: s = a t^3 / (6 T) during the ramp, a ((t - T/2)^2 / 2 + T^2 / 24) after;
        # effective_mu inverts it
        import math
        import plot_terrain
        theta = math.radians(30.0)
        a = 9.81 * (math.sin(theta) - 0.55 * math.cos(theta))
        self.assertAlmostEqual(float(plot_terrain.ramped_rigid_travel(0.55, theta, 0.5, 0.25)), a * 0.25 ** 3 / 3.0, 12)
        self.assertAlmostEqual(float(plot_terrain.ramped_rigid_travel(0.55, theta, 0.5, 2.0)), a * (1.75 ** 2 / 2 + 0.25 / 24), 12)
        self.assertAlmostEqual(float(plot_terrain.ramped_rigid_travel(0.55, theta, 0.0, 2.0)), a * 2.0, 12)
        for mu in (0.45, 0.55):
            travel = float(plot_terrain.ramped_rigid_travel(mu, theta, 0.5, 2.0))
            self.assertAlmostEqual(plot_terrain.effective_mu(travel, theta, 0.5, 2.0), mu, 12)



class FlumeSceneRefusals(unittest.TestCase):
    def test_a_scene_talus_would_refuse_or_a_changed_height_is_refused_in_one_line(self):
        # --height 0.1 was raised to 0.275 without a word; --slope 89 and --width 0.1 wrote scenes talus refused
        for args, naming in ((["--height", "0.1"], "--height 0.1: give at least 0.2682 m"),
                             (["--slope", "89"], "--slope 89: give more than 0 and at most 81.15 degrees"),
                             (["--width", "0.1"], "--width 0.1: give at least the wedge's width (--wedge-width 0.2)"),
                             (["--model", "mu_i", "--density", "3000"], "--density 3000: give at most --grain-density 2650")):
            code, out, err = tool("make_flume_scene.py", *args)
            self.assertEqual((code, out), (2, ""), err)
            self.assertEqual(len(err.strip().splitlines()), 1, err)
            self.assertIn(naming, err)

    def test_the_limits_given_are_scenes_talus_accepts(self):
        work = tempfile.mkdtemp(prefix="talus_flume_scene_")
        try:
            for args in (["--height", "0.2682"], ["--slope", "81.15"], ["--width", "0.2"], ["--slope", "45"]):
                code, out, err = tool("make_flume_scene.py", *args)
                self.assertEqual(code, 0, err)
                path = os.path.join(work, "scene.json")
                with open(path, "w") as f:
                    f.write(out)
                r = subprocess.run([TALUS, "check", path], capture_output=True, text=True, timeout=60)
                self.assertEqual(r.returncode, 0, f"{args}: {r.stderr}")
                if args[0] == "--slope":  # no --height: the default 0.3, raised to 1.5 x the wedge's height
                    self.assertGreater(json.loads(out)["grid"]["size"][2], 0.3)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        code, out, err = tool("make_flume_scene.py")  # the defaults: the shipped scene, byte for byte
        with open(os.path.join(ROOT, "inputs", "denlinger_flume.json")) as f:
            self.assertEqual(out, f.read())


    def test_values_out_of_range_are_refused_by_the_generators_option(self):
        # --bed-friction 95 wrote a negative friction_coefficient, --end inf "Infinity", --aspect inf an OverflowError
        for name, args, naming in (
                ("make_flume_scene.py", ["--bed-friction", "95"], "--bed-friction 95: give 0 to 89.42 degrees"),
                ("make_flume_scene.py", ["--wedge-length", "-0.1"], "--wedge-length -0.1: give more than 0 m"),
                ("make_flume_scene.py", ["--headroom", "-1"], "--headroom -1: give 0 or more"),
                ("make_flume_scene.py", ["--end", "inf"], "--end inf: give a finite number"),
                ("make_collapse_scene.py", ["--model", "dp", "--aspect", "inf"], "--aspect inf: give a finite number")):
            code, out, err = tool(name, *args)
            self.assertEqual((code, out), (2, ""), err)
            self.assertEqual(err.strip(), f"{name}: {naming}" + (" (its tangent, the bed's friction_coefficient, at most 100)"
                                                                if "bed" in naming else ""))
        code, out, err = tool("make_flume_scene.py", "--frame-interval", "0")  # talus: the first and last frame
        self.assertEqual(code, 0, err)
        self.assertEqual(json.loads(out)["output"]["frame_interval"], 0.0)

    def test_the_shipped_scenes_are_the_generators_output_byte_for_byte(self):
        # each names its command line in its comment
        import glob
        import shlex
        made = 0
        for path in sorted(glob.glob(os.path.join(ROOT, "inputs", "**", "*.json"), recursive=True)):
            with open(path) as f:
                text = f.read()
            comment = json.loads(text).get("comment", "")
            for name in ("make_flume_scene.py", "make_collapse_scene.py"):
                if comment.startswith(f"written by tools/{name}"):
                    code, out, err = tool(name, *shlex.split(comment[len(f"written by tools/{name}"):]))
                    self.assertEqual((code, out), (0, text), f"{path}: {err}")
                    made += 1
        self.assertGreaterEqual(made, 7)


class ColumnCollapseExtents(unittest.TestCase):
    def test_the_initial_half_width_is_the_box_and_the_front_its_particle_edge(self):
        # particle centres gave "initial half-width 0.099 m" for the 0.1 m column
        work = tempfile.mkdtemp(prefix="talus_column_collapse_")
        try:
            s = scene("inputs/column_collapse_2d.json")
            s["time"]["end"] = 0.01
            s["output"]["frame_interval"] = 0.01
            path, run = os.path.join(work, "column.json"), os.path.join(work, "column")
            with open(path, "w") as f:
                json.dump(s, f)
            subprocess.run([TALUS, "run", path, "--out", run, "--threads", "1", "--quiet"], check=True, timeout=120)
            code, out, err = tool("plot_column_collapse.py", "--run-dir", run, "--out", work)
            self.assertEqual(code, 0, err)
            self.assertIn("initial half-width 0.1000 m (the body's box)", out)
            self.assertIn("the outermost particle centre + half a particle spacing, 0.00125 m", out)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        import plot_column_collapse
        centres = np.array([0.00125, 0.09875])  # 2 particles per 5 mm cell
        s = scene("inputs/column_collapse_2d.json")
        width, how, front, half = plot_column_collapse.column_extents(s, centres, centres + 0.2)
        self.assertEqual((width, how), (0.1, "the body's box"))
        self.assertAlmostEqual(front, 0.3, places=12)
        del s["bodies"][0]["box"]  # no box: the initial column's particle edge, as the front's
        width, how, front, half = plot_column_collapse.column_extents(s, centres, centres + 0.2)
        self.assertAlmostEqual(width, 0.1, places=12)
        self.assertEqual((how, half), ("outermost particle centre + half a particle spacing", 0.00125))


# A stand-in for `talus run SCENE --out DIR`: notes the folder in CALLS beside itself, and writes a
# completed run's record and the flume's runout files, their rows up to FAKE_END (default the scene's end).
FAKE_TALUS = """#!/usr/bin/python3
import json, os, sys
args = sys.argv[1:]
out = args[args.index("--out") + 1]
# as talus refuses a fresh run into an unfinished run's folder with its checkpoint, unless --overwrite
try:
    with open(os.path.join(out, "run.json")) as f:
        status = json.load(f).get("status")
except OSError:
    status = None
if status not in (None, "completed") and os.path.exists(os.path.join(out, "checkpoint.h5")) and "--overwrite" not in args:
    sys.exit("talus: error: output folder holds an unfinished run; give --overwrite")
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "calls"), "a") as f:
    f.write(out + "\\n")
with open(args[1]) as f:
    end = float(os.environ.get("FAKE_END", json.load(f)["time"]["end"]))
os.makedirs(out, exist_ok=True)
times = [end * k / 10 for k in range(11)]
with open(os.path.join(out, "runout.csv"), "w") as f:
    f.write("time,front,tail,mass\\n" + "".join(f"{t},{1 + t},{t / 2},1\\n" for t in times))
with open(os.path.join(out, "energy.csv"), "w") as f:
    f.write("time,step,kinetic,total\\n" + "".join(f"{t},{k},{10 - k},10\\n" for k, t in enumerate(times)))
with open(os.path.join(out, "runout.json"), "w") as f:
    json.dump({"gate_s": 1.0, "from_gate": end, "beyond_runout_plane": None}, f)
with open(os.path.join(out, "run.json"), "w") as f:
    json.dump({"status": "completed"}, f)
"""


def fake_talus(folder):
    path = os.path.join(folder, "talus")
    with open(path, "w") as f:
        f.write(FAKE_TALUS)
    os.chmod(path, 0o755)
    return path


def calls(fake):
    path = os.path.join(os.path.dirname(fake), "calls")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return f.read().split()


def write_record(run_dir, status):
    os.makedirs(run_dir, exist_ok=True)
    with open(os.path.join(run_dir, "run.json"), "w") as f:
        json.dump({"status": status, "message": ""}, f)


class UnfinishedRuns(unittest.TestCase):
    """A run stopped by --stop-after, Ctrl-C or SIGTERM writes runout.json, energy.csv and frames too:
    only run.json's status says it completed. Reusing scripts measured such runs (a clamped front)."""

    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="talus_unfinished_")

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def test_only_a_completed_record_is_a_finished_run(self):
        import talus_plot
        for status, finished in (("completed", True), ("interrupted", False), ("running", False),
                                 ("unstable", False), ("failed", False)):
            run = os.path.join(self.work, status)
            write_record(run, status)
            self.assertEqual(talus_plot.run_finished(run), finished, status)
        self.assertFalse(talus_plot.run_finished(os.path.join(self.work, "none")))  # no record
        with self.assertRaises(SystemExit) as e:
            talus_plot.require_finished(os.path.join(self.work, "interrupted"), "--run-dir")
        self.assertIn("--run-dir", str(e.exception.code))
        self.assertIn("the run did not complete (its run.json says 'interrupted')", str(e.exception.code))
        self.assertEqual(talus_plot.require_finished(os.path.join(self.work, "completed")),
                         os.path.join(self.work, "completed"))

    def test_a_value_after_the_end_of_a_history_is_refused_not_clamped(self):
        from talus_plot import value_at
        self.assertAlmostEqual(value_at([0.0, 0.8], [1.0, 2.6], 0.4), 1.8)
        self.assertEqual(value_at([0.0, 0.8], [1.0, 2.6], 0.8), 2.6)
        with self.assertRaisesRegex(ValueError, r"run has no value at t = 2 s \(its history runs 0 to 0.8 s\)"):
            value_at([0.0, 0.8], [1.0, 2.6], 2.0, "run")

    def test_run_flume_runs_an_interrupted_run_again_and_reuses_a_completed_one(self):
        import talus_plot
        fake = fake_talus(self.work)
        runs = os.path.join(self.work, "runs")
        run = os.path.join(runs, "flume")
        write_record(run, "interrupted")
        for name in ("runout.json", "runout.csv", "energy.csv", "checkpoint.h5"):  # as --stop-after leaves them
            with open(os.path.join(run, name), "w") as f:
                f.write("{}" if name.endswith("json") else "time,front\n0,1\n")
        result = talus_plot.run_flume(fake, runs, "flume", 0.05)
        self.assertEqual(calls(fake), [run])
        self.assertEqual(result[1]["time"][-1], 4.0)  # the rerun's rows, to the scene's end
        talus_plot.run_flume(fake, runs, "flume", 0.05)
        self.assertEqual(calls(fake), [run])  # completed now: reused

    def test_flume_resolution_refuses_a_front_at_a_time_the_run_did_not_reach(self):
        fake = fake_talus(self.work)
        out = os.path.join(self.work, "out")
        r = subprocess.run([sys.executable, os.path.join(TOOLS, "flume_resolution.py"), "--talus", fake, "--cells", "0.05",
                            "--runs", os.path.join(self.work, "runs"), "--out", out], capture_output=True, text=True,
                           timeout=60, env=dict(os.environ, FAKE_END="1.5"))
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn("has no value at t = 2 s (its history runs 0 to 1.5 s): nothing written", r.stderr)
        self.assertEqual(os.listdir(out), [])

    def test_collapse_study_runs_an_interrupted_run_again(self):
        import collapse_study
        fake = fake_talus(self.work)
        scene, o = collapse_study.scene_for("dp", 0.5, 10, [])
        run = os.path.join(self.work, "dp_a0.5_n10")
        self.assertEqual(collapse_study.run_one(fake, scene, run, 1), "ran")
        write_record(run, "interrupted")  # Ctrl-C'd: runout.json, the same scene and a checkpoint are there
        open(os.path.join(run, "checkpoint.h5"), "w").close()
        self.assertEqual(collapse_study.run_one(fake, scene, run, 1), "ran")
        self.assertEqual(collapse_study.run_one(fake, scene, run, 1), "reused")
        self.assertEqual(calls(fake), [run, run])

    def test_plot_terrain_reuses_only_a_completed_run(self):
        import argparse
        import plot_terrain
        fake = fake_talus(self.work)
        args = argparse.Namespace(talus=fake, runs=self.work, reuse=True, threads=1)
        run = os.path.join(self.work, "horizontal_plane_coarse")
        write_record(run, "interrupted")
        with open(os.path.join(run, "energy.csv"), "w") as f:
            f.write("time,total\n0,1\n")
        self.assertEqual(plot_terrain.run(args, "horizontal_plane_coarse"), run)
        self.assertEqual(plot_terrain.run(args, "horizontal_plane_coarse"), run)
        self.assertEqual(calls(fake), [run])  # run again once, then reused

    def test_plot_column_collapse_refuses_an_unfinished_run_and_a_run_that_released_nothing(self):
        run, out = os.path.join(self.work, "run"), os.path.join(self.work, "plots")
        write_record(run, "interrupted")
        with open(os.path.join(run, "energy.csv"), "w") as f:  # the elastic block sent along a level floor
            f.write("time,kinetic,strain,gravity,friction_work,plastic_work,total\n"
                    "0,16,0,7.848,0,0,23.848\n1,0.2,0.01,7.85,15.8,0,23.86\n")
        code, out_text, err = tool("plot_column_collapse.py", "--run-dir", run, "--out", out)
        self.assertEqual((code, out_text), (1, ""), err)
        self.assertIn(f"--run-dir {run}: the run did not complete (its run.json says 'interrupted')", err)
        write_record(run, "completed")
        code, out_text, err = tool("plot_column_collapse.py", "--run-dir", run, "--out", out)
        self.assertEqual((code, out_text), (1, ""), err)
        self.assertEqual(len(err.strip().splitlines()), 1, err)
        self.assertIn("released -0.002 J of potential energy, against 16 J of kinetic and strain energy at the "
                      "start: not a collapse", err)
        self.assertFalse(os.path.exists(out))

    def test_plot_bagnold_no_run_refuses_an_unfinished_run(self):
        run = os.path.join(self.work, "n16")
        write_record(run, "interrupted")
        with open(os.path.join(run, "particles.pvd"), "w") as f:
            f.write('<VTKFile type="Collection"><Collection></Collection></VTKFile>')
        code, out, err = tool("plot_bagnold.py", "--no-run", "--work", self.work)
        self.assertEqual((code, out), (1, ""), err)
        self.assertIn(f"{run}: the run did not complete (its run.json says 'interrupted'): run it without --no-run", err)
        for args, naming in ((["--cells", "0"], "--cells 0: give 1 or more"), (["--cells", "-2"], "--cells -2: give 1 or more"),
                             (["--threads", "0"], "--threads 0: give 1 or more")):
            code, out, err = tool("plot_bagnold.py", "--no-run", "--work", self.work, *args)
            self.assertEqual((code, out), (2, ""), err)
            self.assertEqual(err.strip(), f"plot_bagnold.py: {naming}")

    def test_plot_bagnold_plots_a_run_of_two_frames(self):
        # the first and the last frame (frame_interval 0): the surface change over the last interval was an IndexError
        import plot_bagnold
        s = plot_bagnold.scene_at(scene("inputs/inclined_flow_bagnold.json"), 4)
        s["time"]["end"] = 0.02
        s["output"]["frame_interval"] = 0.0
        path, run = os.path.join(self.work, "n4.json"), os.path.join(self.work, "n4")
        with open(path, "w") as f:
            json.dump(s, f)
        subprocess.run([TALUS, "run", path, "--out", run, "--threads", "1", "--quiet"], check=True, timeout=120)
        code, out, err = tool("plot_bagnold.py", "--no-run", "--cells", "4", "--work", self.work)
        self.assertEqual(code, 0, err)
        self.assertIn("4 cells over h: surface row", out)
        self.assertNotIn("surface change", out)
        self.assertTrue(os.path.isfile(os.path.join(self.work, "bagnold_profile.png")))


class MlsPlotsAllOrNothing(unittest.TestCase):
    def test_bad_values_are_refused_before_any_run(self):
        work = tempfile.mkdtemp(prefix="talus_plot_mls_")
        try:
            for args, naming in ((["--variants", "particle,cel"], "--variants particle,cel: cel is not one of particle, cell, reused"),
                                 (["--radius", "9"], "--radius 9: give 0.5 to 8"),
                                 (["--reuse-strain", "2"], "--reuse-strain 2: give 0 to 1"),
                                 (["--basis", "quartic"], "argument --basis: invalid choice: 'quartic'")):
                code, out, err = tool("plot_mls.py", "--talus", TALUS, "--out", os.path.join(work, "out"), *args)
                self.assertEqual((code, out), (2, ""), err)
                self.assertIn(naming, err)
                self.assertFalse(os.path.exists(os.path.join(work, "out")))
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def test_a_failed_run_writes_nothing(self):
        # the runs that succeeded were written, a --tag's into docs/verification beside the shipped files
        work = tempfile.mkdtemp(prefix="talus_plot_mls_")
        try:
            wrapper = os.path.join(work, "talus")  # talus, but every run with MLS fails as talus does
            with open(wrapper, "w") as f:
                f.write("#!/usr/bin/python3\nimport os, sys\n"
                        "if sys.argv[1] == 'run' and 'smoothing' in open(sys.argv[2]).read():\n"
                        "    sys.exit('talus: solver.smoothing: refused for this test')\n"
                        f"os.execv({os.path.abspath(TALUS)!r}, [{os.path.abspath(TALUS)!r}] + sys.argv[1:])\n")
            os.chmod(wrapper, 0o755)
            out = os.path.join(work, "out")
            code, text, err = tool("plot_mls.py", "--talus", wrapper, "--skip-walls", "--tag", "_t", "--out", out)
            self.assertEqual(code, 1, err)
            self.assertRegex(text, r"column linear +off +L2")  # the runs without MLS ran
            self.assertIn("talus: solver.smoothing: refused for this test", err)
            self.assertIn("plot_mls.py: 6 of 12 runs failed (the first: column linear cubic); nothing written into", err)
            self.assertEqual(os.listdir(out), [])
        finally:
            shutil.rmtree(work, ignore_errors=True)


class OneLineErrors(unittest.TestCase):
    """What was a traceback: a failed talus run, an output path that is a file or has no folder, an
    unknown plot format, a CSV of another kind, a runout.csv without rows."""

    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="talus_one_line_")

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def assertOneLine(self, result, code, text):
        self.assertEqual((result[0], result[1]), (code, ""), result[2])
        self.assertEqual(len(result[2].strip().splitlines()), 1, result[2])
        self.assertIn(text, result[2])

    def test_a_failed_talus_run_is_its_last_line_or_the_signal(self):
        from talus_plot import talus_failure
        r = subprocess.CompletedProcess(["talus"], 2, "", "talus: scene.json:\ntalus: time.end: give more than 0\n")
        self.assertEqual(talus_failure(["talus", "run", "s.json"], r),
                         "talus run s.json failed (exit 2): talus: time.end: give more than 0")
        r = subprocess.CompletedProcess(["talus"], 130, "talus: stopped by signal 2 at step 9, t = 0.1 s; checkpoint c.h5\n"
                                        "talus: resume with: ...\n", "")
        self.assertIn("failed (exit 130): talus: stopped by signal 2 at step 9", talus_failure(["talus"], r))
        for code, text in ((-9, "stopped by signal 9"), (143, "stopped by signal 15"), (1, "no message")):
            self.assertIn(f"(exit {code}): {text}", talus_failure(["talus"], subprocess.CompletedProcess([], code, "", "")))
        # a script ends on it with one line (talus_plot.main_guard), not a traceback
        killed = os.path.join(self.work, "talus")
        with open(killed, "w") as f:
            f.write("#!/usr/bin/python3\nimport os\nos.kill(os.getpid(), 9)\n")
        os.chmod(killed, 0o755)
        self.assertOneLine(tool("plot_terrain.py", "--talus", killed, "--runs", self.work, "--out", os.path.join(self.work, "out")),
                           1, "failed (exit -9): stopped by signal 9")

    def test_output_paths_that_cannot_be_written_are_refused_before_the_work(self):
        run = os.path.join(self.work, "run")
        os.makedirs(run)
        with open(os.path.join(run, "scene.json"), "w") as f:
            json.dump({"name": "x"}, f)
        with open(os.path.join(run, "runout.csv"), "w") as f:
            f.write("time,front,tail,s_max,centre_s,centre_y,centre_velocity_s,front_velocity\n0,1,0,1,0.5,0,0,0\n")
        a_file = os.path.join(run, "run.json")
        with open(a_file, "w") as f:
            f.write("{}")
        self.assertOneLine(tool("plot_flume.py", run, "--out", a_file), 1, f"--out {a_file}: is a file, not a folder")
        self.assertOneLine(tool("scaling.py", "--talus", TALUS, "--out", a_file), 1, f"--out {a_file}: is a file, not a folder")
        self.assertOneLine(tool("plot_node_scaling.py", os.path.join(ROOT, "docs", "performance", "node16_2026-12-04"),
                                "--out", os.path.join(self.work, "nodir", "x.png")), 1, "/nodir does not exist")
        self.assertOneLine(tool("plot_mu_i.py", "--talus", TALUS, "--out", os.path.join(self.work, "x.foo")), 2,
                           "x.foo: give a name ending in one of ")
        self.assertOneLine(tool("plot_mu_i.py", "--talus", TALUS, "--out", os.path.join(a_file, "x.png")), 1,
                           "is a file, not a folder")
        self.assertEqual(os.listdir(self.work), ["run"])
        self.assertEqual(sorted(os.listdir(run)), ["run.json", "runout.csv", "scene.json"])

    def test_inputs_of_another_kind_are_refused(self):
        with open(os.path.join(self.work, "energy.csv"), "w") as f:
            f.write("time,kinetic\n0,1\n")
        self.assertOneLine(tool("plot_mu_i.py", "--no-run", "--csv", os.path.join(self.work, "energy.csv"),
                                "--out", os.path.join(self.work, "mu.png")), 1, "energy.csv: no column I: give the CSV of talus element-test")
        with open(os.path.join(self.work, "scene.json"), "w") as f:
            json.dump({"name": "x"}, f)
        with open(os.path.join(self.work, "runout.csv"), "w") as f:  # a run stopped before its first row
            f.write("time,front,tail,s_max,centre_s,centre_y,centre_velocity_s,front_velocity\n")
        self.assertOneLine(tool("plot_flume.py", self.work), 1, "runout.csv holds no rows: nothing to plot")
        self.assertFalse(os.path.exists(os.path.join(self.work, "mu.png")))


class FlumeLegend(unittest.TestCase):
    def test_the_front_and_tail_are_labelled_with_the_runs_quantiles(self):
        # "front (99.5% mass quantile)" was written whatever diagnostics.runout said
        import plot_flume
        self.assertEqual(plot_flume.quantile_labels({}), ("front (99.5% mass quantile)", "tail (0.5% mass quantile)"))
        s = {"diagnostics": {"runout": {"front_quantile": 0.99, "tail_quantile": 0.01}}}
        self.assertEqual(plot_flume.quantile_labels(s), ("front (99% mass quantile)", "tail (1% mass quantile)"))
        s = {"diagnostics": {"runout": {"front_quantile": 0.9}}}
        self.assertEqual(plot_flume.quantile_labels(s), ("front (90% mass quantile)", "tail (0.5% mass quantile)"))


class CompareRanksHeaders(unittest.TestCase):
    def test_the_markdown_headers_name_the_first_runs_ranks(self):
        # "vs 1 rank" whatever the first run's rank count
        work = tempfile.mkdtemp(prefix="talus_compare_ranks_")
        try:
            s = scene("inputs/elastic_block_slide.json")
            s["time"]["end"] = 0.01
            s["diagnostics"] = {"runout": {"deposit_cell": 0.04}}
            path, one, two = (os.path.join(work, n) for n in ("block.json", "one", "two"))
            with open(path, "w") as f:
                json.dump(s, f)
            subprocess.run([TALUS, "run", path, "--out", one, "--threads", "1", "--quiet"], check=True, timeout=120)
            shutil.copytree(one, two)
            with open(os.path.join(two, "run.json")) as f:
                record = json.load(f)
            with open(os.path.join(two, "run.json"), "w") as f:  # as a 2-rank run records itself
                json.dump(dict(record, ranks=2), f)
            code, out, err = tool("compare_ranks.py", two, one, "--markdown")
            self.assertEqual(code, 0, err)
            self.assertIn("| front vs 2 ranks | beyond gate vs 2 ranks | tail vs 2 ranks |", out.splitlines()[0])
            code, out, err = tool("compare_ranks.py", one, two, "--markdown")
            self.assertIn("| front vs 1 rank | beyond gate vs 1 rank | tail vs 1 rank |", out.splitlines()[0])
        finally:
            shutil.rmtree(work, ignore_errors=True)


class ColumnCollapseTitle(unittest.TestCase):
    def test_the_title_names_the_runs_material(self):
        # it said "Drucker-Prager phi = 30 deg" for every run, mu(I) ones too
        import plot_column_collapse
        s = scene("inputs/column_collapse_2d.json")
        self.assertEqual(plot_column_collapse.material_text(s), "Drucker-Prager phi = 30 deg")
        s["materials"]["sand"] = {"model": "mu_i", "density": 1600.0, "mu_s": 0.7}
        self.assertEqual(plot_column_collapse.material_text(s), "mu(I) mu_s = 0.7 (35.0 deg)")
        del s["materials"]["sand"]["mu_s"]  # talus's default, tan 20.9 deg
        self.assertEqual(plot_column_collapse.material_text(s), "mu(I) mu_s = 0.382 (20.9 deg)")


class EnergyGuardDemo(unittest.TestCase):
    """tools/energy_guard_demo.py on the shipped inputs/terrain/energy_guard_kink.json (docs/reliability.md,
    "The energy guard on a shipped scene"): the run warns, trips the guard and keeps checkpoint_earlier.h5,
    the resume with a smaller time.courant completes, and the shares the tool computes from energy.csv are
    talus's own (the tool checks them)."""

    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="talus_energy_guard_")

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def test_bad_arguments_are_refused_in_one_line_before_any_run(self):
        runs = os.path.join(self.work, "runs")
        no_checkpoints = os.path.join(self.work, "no_checkpoints.json")
        s = scene("inputs/terrain/energy_guard_kink.json")
        del s["output"]["checkpoint_interval"]
        with open(no_checkpoints, "w") as f:
            json.dump(s, f)
        for args, code, text in ((["--courant", "0"], 2, "--courant 0.0: give a number in (0, 1]"),
                                 (["--courant", "1.5"], 2, "--courant 1.5: give a number in (0, 1]"),
                                 (["--threads", "0"], 2, "--threads 0: give 1 or more"),
                                 (["--scene", os.path.join(self.work, "nope.json")], 1, "nope.json: no such file"),
                                 (["--scene", no_checkpoints], 1, "no output.checkpoint_interval"),
                                 (["--talus", os.path.join(self.work, "talus")], 1, "no executable file there")):
            code_, out, err = tool("energy_guard_demo.py", "--talus", TALUS, "--runs", runs, "--out", self.work, *args)
            self.assertEqual((code_, out), (code, ""), err)
            self.assertEqual(len(err.strip().splitlines()), 1, err)
            self.assertIn(text, err)
        self.assertFalse(os.path.exists(runs))

    def test_the_shipped_scene_warns_trips_the_guard_and_resumes_to_its_end(self):
        runs, out = os.path.join(self.work, "runs"), os.path.join(self.work, "out")
        code, stdout, err = tool("energy_guard_demo.py", "--talus", TALUS, "--runs", runs, "--out", out)
        self.assertEqual(code, 0, err)
        lines = stdout.splitlines()
        # measured (2026-12-07): warned after step 4343 (t = 2.553 s, 16.4%), tripped after step 4424
        # (t = 2.597 s, 42.9%), resumed from the checkpoint of t = 2.0 s with Courant 0.1: -1.93% at 3.5 s
        self.assertTrue(lines[0].startswith("warning: after step "), stdout)
        self.assertIn("(more than energy_warning_factor = 0.1)", lines[0])
        self.assertTrue(lines[1].startswith("trip: after step "), stdout)
        self.assertIn("(energy_growth_factor = 0.4)", lines[1])
        self.assertIn("kept: checkpoint_earlier.h5 of t = 2.0001", lines[2])
        self.assertIn("resumed: no warning, completed at step ", lines[3])
        self.assertIn("t = 3.5 s; energy budget gap -", lines[3])
        self.assertTrue(os.path.isfile(os.path.join(runs, "run", "checkpoint_earlier.h5")))
        with open(os.path.join(runs, "run", "run.json")) as f:
            stopped = json.load(f)
        self.assertEqual(stopped["status"], "unstable")
        # (the warning before the trip: a stopped run's record left it out before 2026-12-07)
        self.assertGreater(stopped["end"]["energy_growth_warning"]["share_of_energy_available"], 0.1)
        self.assertLess(stopped["end"]["energy_growth_warning"]["step"], stopped["end"]["step"])
        with open(os.path.join(runs, "resumed", "run.json")) as f:
            record = json.load(f)
        self.assertEqual(record["status"], "completed")
        self.assertLess(abs(record["end"]["energy_budget_gap"]), 0.05)
        self.assertNotIn("energy_growth_warning", record["end"])
        self.assertEqual(os.listdir(out), ["energy_guard_kink.png"])


class DilationStudy(unittest.TestCase):
    """tools/dilation_study.py on the shipped inputs/column_collapse_2d_unbounded_dilation.json, cut at
    0.16 s (docs/reliability.md, "Unbounded dilation"): without the separation rule the run warns once,
    where the frames' largest V/V0 passes 10, and with the rule it does not (the tool checks both)."""

    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="talus_dilation_")

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def test_bad_arguments_are_refused_in_one_line_before_any_run(self):
        runs = os.path.join(self.work, "runs")
        for args, text in ((["--end", "0.01"], "--end 0.01: give 0.05 or more"),
                           (["--threads", "0"], "--threads 0: give 1 or more")):
            code, out, err = tool("dilation_study.py", "--talus", TALUS, "--runs", runs, "--out", self.work, *args)
            self.assertEqual((code, out), (2, ""), err)
            self.assertEqual(len(err.strip().splitlines()), 1, err)
            self.assertIn(text, err)
        self.assertFalse(os.path.exists(runs))

    def test_the_run_without_the_rule_warns_once_where_it_passes_ten_times_its_volume(self):
        runs, out = os.path.join(self.work, "runs"), os.path.join(self.work, "out")
        code, stdout, err = tool("dilation_study.py", "--talus", TALUS, "--runs", runs, "--out", out, "--end", "0.16")
        self.assertEqual(code, 0, stdout + err)
        # measured (2026-12-07): warned in step 2634, t = 0.125 s, particle 1524
        self.assertIn("separation rule off (0): ", stdout)
        self.assertIn("1 dilation warning(s)", stdout)
        self.assertIn("  warned in step ", stdout)
        self.assertIn("separation rule at 1.5 (default): ", stdout)
        self.assertIn("0 dilation warning(s)", stdout)
        self.assertEqual(sorted(os.listdir(out)), ["unbounded_dilation.csv", "unbounded_dilation.png"])
        with open(os.path.join(out, "unbounded_dilation.csv")) as f:
            rows = list(csv.DictReader(f))
        last_off = [r for r in rows if r["separation_volume_ratio"] == "0.0"][-1]
        last_on = [r for r in rows if r["separation_volume_ratio"] == "1.5"][-1]
        self.assertGreater(float(last_off["largest_V_over_V0"]), 10.0)
        self.assertLess(float(last_on["largest_V_over_V0"]), 10.0)
        self.assertLess(float(last_off["dt"]), float(last_on["dt"]))


class ElementTestPlots(unittest.TestCase):
    def test_the_csvs_go_beside_the_plots_not_into_the_build_tree(self):
        # --csv-dir defaulted to element_tests/ next to --talus: build/element_tests, which a clean
        # rebuild removes and which no one looks for beside docs/verification/*.png
        work = tempfile.mkdtemp(prefix="talus_element_plots_")
        try:
            bin_dir, out = os.path.join(work, "build"), os.path.join(work, "out")
            os.makedirs(bin_dir)
            wrapper = os.path.join(bin_dir, "talus")  # a build tree of its own: the real program, called
            with open(wrapper, "w") as f:
                f.write(f'#!/bin/sh\nexec "{os.path.abspath(TALUS)}" "$@"\n')
            os.chmod(wrapper, 0o755)
            code, stdout, err = tool("plot_element_tests.py", "--talus", wrapper, "--out-dir", out)
            self.assertEqual(code, 0, err)
            self.assertFalse(os.path.exists(os.path.join(bin_dir, "element_tests")), os.listdir(bin_dir))
            csvs = sorted(os.listdir(os.path.join(out, "element_tests")))
            self.assertIn("fig13a_uniaxial_perfect.csv", csvs)
            self.assertIn("fig13b_simple_shear_psi00.csv", csvs)
            self.assertTrue(os.path.isfile(os.path.join(out, "dp_hardening.png")))
            self.assertIn(f"(CSVs in {os.path.join(out, 'element_tests')})", stdout)
        finally:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: plot_tools_test.py TALUS")
    TALUS = sys.argv.pop(1)
    unittest.main()
