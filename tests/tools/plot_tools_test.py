#!/usr/bin/env python3
"""Tests of what the plotting tools and the scene generators show and write, from user reviews: the
Bagnold plot's axis, the flume's deposit profile, the terrain tool's rigid answers, the flume scene
generator's refusals and the column collapse's initial half-width.

    python3 tests/tools/plot_tools_test.py TALUS      (ctest: Tools.PlotsShowWhatTheRunsDid)
"""
import json
import os
import sys
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


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: plot_tools_test.py TALUS")
    TALUS = sys.argv.pop(1)
    unittest.main()
