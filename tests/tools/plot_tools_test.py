#!/usr/bin/env python3
"""Tests of what the plotting tools and the scene generators show and write, from user reviews: the
Bagnold plot's axis, the flume's deposit profile, the terrain tool's rigid answers, the flume scene
generator's refusals and the column collapse's initial half-width.

    python3 tests/tools/plot_tools_test.py TALUS      (ctest: Tools.PlotsShowWhatTheRunsDid)
"""
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


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: plot_tools_test.py TALUS")
    TALUS = sys.argv.pop(1)
    unittest.main()
