#!/usr/bin/env python3
"""Tests of tools/scaling_model.py (docs/performance.md, "The model"): its schedules, its b(T), its
per-core slowdown and its replay of a record, on records small enough to predict by hand; and its
refusal of bad arguments in one line (they were tracebacks, or a silent exit 0).

    python3 tests/tools/scaling_model_test.py      (ctest: ScalingModel.PredictsRecordsByHand)
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
import scaling_model as sm  # noqa: E402

MS = 1e-3
B = [0.0, 1e-6, 2e-6, 3e-6, 4e-6]  # b(T) for T = 1..4 (index 0 unused), as a record holds it


def dynamic(blocks, particles=100):
    """A colour pass recorded on 1 thread: its blocks and one fork/join, nothing else."""
    return {"name": "p2g", "schedule": "dynamic", "parallel_regions": 1, "block_seconds": list(blocks),
            "block_particles": [particles] * len(blocks), "seconds": sum(blocks) + B[1]}


def record(regions, glue=0.0, **extra):
    step = {"step": 0, "particles": 800, "blocks": 8, "regions": regions,
            "seconds": sum(r["seconds"] for r in regions) + glue}
    return {"format": "talus-work-record/1", "threads": 1, "fork_join_seconds": B, "steps": [step], **extra}


def seconds_at(rec, threads, contention=None):
    return sum(sm.predict(rec, threads, sm.Barrier(rec["fork_join_seconds"], 1e-6), "recorded", "seconds",
                          contention=contention).values())


class Schedules(unittest.TestCase):
    def test_dynamic_one_hands_each_block_to_the_first_free_thread(self):
        # [3, 1, 1, 1] on 2 threads: 3 | 1+1+1 -> 3; the heavy block last: 1+1 | 1+3 -> 4
        self.assertEqual(sm.greedy_makespan([3, 1, 1, 1], 2), 3)
        self.assertEqual(sm.greedy_makespan([1, 1, 1, 3], 2), 4)
        self.assertEqual(sm.greedy_makespan([1, 2, 3], 1), 6)
        self.assertEqual(sm.greedy_makespan([1, 2, 3], 8), 3)  # more threads than blocks: the largest

    def test_static_gives_contiguous_parts_the_first_ones_larger(self):
        # 5 items on 2 threads: [1, 2, 3] and [4, 5] (libgomp: the first n % T threads one more)
        self.assertEqual(sm.static_makespan([1, 2, 3, 4, 5], 2), 9)
        self.assertEqual(sm.static_makespan([5, 4, 3, 2, 1], 2), 12)

    def test_barrier_is_measured_up_to_the_record_then_one_step_per_doubling(self):
        b = sm.Barrier(B, 1e-6)
        self.assertEqual(b(3), 3e-6)
        self.assertAlmostEqual(b(16), 4e-6 + 1e-6 * math.log2(16 / 4), delta=1e-18)

    def test_contention_holds_the_largest_measured_count_below(self):
        c = {2: 1.2, 16: 1.5}
        self.assertEqual(sm.contention_factor(c, 1), 1.0)
        self.assertEqual(sm.contention_factor(c, 8), 1.2)
        self.assertEqual(sm.contention_factor(c, 64), 1.5)
        self.assertEqual(sm.contention_factor(None, 64), 1.0)


class Replay(unittest.TestCase):
    def test_a_step_of_a_colour_pass_a_static_loop_and_a_serial_part(self):
        static = {"name": "grid update", "schedule": "static", "items": 4, "parallel_regions": 1,
                  "seconds": 2 * MS + B[1]}
        serial = {"name": "sort bookkeeping", "schedule": "serial", "parallel_regions": 0, "seconds": 1 * MS}
        rec = record([dynamic([1 * MS] * 8), static, serial])
        # 1 thread: the record itself, 8 + 2 + 1 ms and two fork/joins of 1 us
        self.assertAlmostEqual(seconds_at(rec, 1), 11 * MS + 2e-6, delta=1e-12)
        # 4 threads: 8 ms / 4 and 2 ms / 4 with no imbalance, two fork/joins of b(4) = 4 us, 1 ms serial
        self.assertAlmostEqual(seconds_at(rec, 4), 2 * MS + 0.5 * MS + 1 * MS + 8e-6, delta=1e-12)
        rows = sm.model(rec, [1, 4], sm.Barrier(B, 1e-6), "recorded", "seconds")
        self.assertAlmostEqual(rows[1]["speedup"], (11 * MS + 2e-6) / (3.5 * MS + 8e-6), places=12)
        self.assertEqual(rows[1]["limit"], "serial")  # 1 ms of 3.508: the largest loss

    def test_a_static_region_of_several_loops_pays_one_fork_join_and_a_barrier_between_loops(self):
        # the grid phase as TileStages runs it: 4 loops in one region, 3 barriers of B(T)
        inner = [0.0, 0.5e-6, 1e-6, 1.5e-6, 2e-6]
        static = {"name": "grid update", "schedule": "static", "items": 4, "parallel_regions": 1, "barriers": 3,
                  "seconds": 2 * MS + B[1] + 3 * inner[1]}
        rec = record([static], barrier_seconds=inner)
        terms = sm.predict(rec, 4, sm.Barrier(B, 1e-6), "recorded", "seconds")
        self.assertAlmostEqual(terms["ideal"], 0.5 * MS, delta=1e-12)  # the loops' work, the barriers' time out
        self.assertAlmostEqual(terms["sync"], B[4] + 3 * inner[4], delta=1e-15)

    def test_imbalance_is_the_critical_path_above_the_mean(self):
        rec = record([dynamic([1 * MS] * 5)])
        terms = sm.predict(rec, 4, sm.Barrier(B, 1e-6), "recorded", "seconds")
        self.assertAlmostEqual(terms["ideal"], 5 * MS / 4, delta=1e-12)
        self.assertAlmostEqual(terms["imbalance"], 2 * MS - 5 * MS / 4, delta=1e-12)  # one thread takes two
        self.assertAlmostEqual(terms["sync"], B[4], delta=1e-15)

    def test_heaviest_first_shortens_the_critical_path(self):
        rec = record([dynamic([1 * MS, 1 * MS, 1 * MS, 3 * MS])])
        recorded = sm.predict(rec, 2, sm.Barrier(B, 1e-6), "recorded", "seconds")
        lpt = sm.predict(rec, 2, sm.Barrier(B, 1e-6), "lpt", "seconds")
        self.assertAlmostEqual(recorded["ideal"] + recorded["imbalance"], 4 * MS, delta=1e-12)
        self.assertAlmostEqual(lpt["ideal"] + lpt["imbalance"], 3 * MS, delta=1e-12)

    def test_contention_slows_the_parallel_work_only(self):
        serial = {"name": "sort bookkeeping", "schedule": "serial", "parallel_regions": 0, "seconds": 1 * MS}
        rec = record([dynamic([1 * MS] * 8), serial])
        self.assertAlmostEqual(seconds_at(rec, 4, {4: 1.5}), 1.5 * 2 * MS + B[4] + 1 * MS, delta=1e-12)
        self.assertAlmostEqual(seconds_at(rec, 1, {4: 1.5}), seconds_at(rec, 1), delta=1e-15)

    def test_a_loop_s_hand_out_cost_is_spread_over_its_blocks(self):
        # 0.4 ms beyond the blocks and the fork/join: per block, so it parallelises with them
        region = dynamic([1 * MS] * 4)
        region["seconds"] += 0.4 * MS
        rec = record([region])
        barrier = sm.Barrier(B, 1e-6)
        per_block = sm.predict(rec, 4, barrier, "recorded", "seconds", loop_overhead="per-block")
        serial = sm.predict(rec, 4, barrier, "recorded", "seconds", loop_overhead="serial")
        self.assertAlmostEqual(per_block["ideal"] + per_block["imbalance"], 1.1 * MS, delta=1e-12)
        self.assertAlmostEqual(serial["serial"], 0.4 * MS, delta=1e-12)
        self.assertAlmostEqual(serial["ideal"] + serial["imbalance"], 1 * MS, delta=1e-12)

    def test_glue_between_the_regions_stays_serial(self):
        rec = record([dynamic([1 * MS] * 4)], glue=0.25 * MS)
        terms = sm.predict(rec, 4, sm.Barrier(B, 1e-6), "recorded", "seconds")
        self.assertAlmostEqual(terms["serial"], 0.25 * MS, delta=1e-12)


class Records(unittest.TestCase):
    def test_the_per_core_slowdown_is_the_ratio_of_block_seconds_per_particle(self):
        one = record([dynamic([1 * MS] * 8)])
        many = record([dynamic([1.25 * MS] * 8)])
        self.assertAlmostEqual(sm.block_seconds_per_particle(many) / sm.block_seconds_per_particle(one), 1.25)

    def test_the_run_loop_s_work_enters_as_its_run_mean(self):
        output = {"name": "output and guards", "schedule": "serial", "parallel_regions": 0, "seconds": 30 * MS}
        rec = record([dynamic([1 * MS] * 8), output], run_steps=100, run_other_seconds=50 * MS)
        mean = sm.with_run_mean_output(rec)
        names = [r["name"] for r in mean["steps"][0]["regions"]]
        self.assertNotIn("output and guards", names)  # the sampled frame: 30 ms in this step
        kept = [r for r in mean["steps"][0]["regions"] if r["name"] == "output and guards (run mean)"]
        self.assertAlmostEqual(kept[0]["seconds"], 0.5 * MS, delta=1e-15)  # 50 ms over 100 steps
        self.assertAlmostEqual(mean["steps"][0]["seconds"], rec["steps"][0]["seconds"] - 29.5 * MS, delta=1e-12)

    def test_the_history_rows_enter_as_a_parallel_part(self):
        output = {"name": "output and guards", "schedule": "serial", "parallel_regions": 0, "seconds": 2 * MS}
        history = {"name": "history row", "schedule": "static", "items": 800, "parallel_regions": 5,
                   "seconds": 4 * MS}
        rec = record([dynamic([1 * MS] * 8), history, output], run_steps=100, run_other_seconds=60 * MS,
                     run_history_seconds=40 * MS, run_history_regions=500)
        mean = sm.with_run_mean_output(rec)
        by_name = {r["name"]: r for r in mean["steps"][0]["regions"]}
        self.assertNotIn("history row", by_name)  # the sampled row: 4 ms in this step
        self.assertAlmostEqual(by_name["output and guards (run mean)"]["seconds"], 0.2 * MS, delta=1e-15)
        rows = by_name["history rows (run mean)"]
        self.assertEqual(rows["schedule"], "static")
        self.assertAlmostEqual(rows["seconds"], 0.4 * MS, delta=1e-15)  # 40 ms over 100 steps
        self.assertAlmostEqual(rows["parallel_regions"], 5.0)
        # on 4 threads the rows' 0.4 ms a step (less the 5 fork/joins recorded on 1 thread) take a quarter,
        # plus 5 fork/joins at b(4); serial, they would stay 0.4 ms
        serial = dict(rows, schedule="serial", parallel_regions=0)
        as_serial = dict(mean, steps=[dict(mean["steps"][0], regions=[serial if r is rows else r
                                                                        for r in mean["steps"][0]["regions"]])])
        self.assertAlmostEqual(seconds_at(as_serial, 4) - seconds_at(mean, 4), 0.4 * MS - (0.4 * MS - 5 * B[1]) / 4 - 5 * B[4], delta=1e-12)


class Refusals(unittest.TestCase):
    """Bad arguments: exit 2 and one line naming the option, never a traceback."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.rec = os.path.join(cls.tmp.name, "rec.json")
        with open(cls.rec, "w") as f:
            json.dump(record([dynamic([1 * MS, 1 * MS])]), f)
        cls.bench = os.path.join(cls.tmp.name, "bench.json")  # what talus bench --json writes: no work record
        with open(cls.bench, "w") as f:
            json.dump({"threads": 1, "particles": 1000, "cpu": "x"}, f)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def refused(self, *args, naming):
        tool = os.path.join(os.path.dirname(sm.__file__), "scaling_model.py")
        out = os.path.join(self.tmp.name, "out")
        r = subprocess.run([sys.executable, tool, *args], capture_output=True, text=True, timeout=30, cwd=self.tmp.name)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn(naming, r.stderr)
        self.assertFalse(os.path.exists(out + ".json"), "a refused run wrote its output")

    def test_thread_counts_below_1_or_not_numbers(self):
        self.refused(self.rec, "--threads", "0", naming="--threads 0")
        self.refused(self.rec, "--threads", "1,x", naming="--threads 1,x")

    def test_contention_without_a_thread_count_or_not_above_0(self):
        self.refused(self.rec, "--contention", "2", naming="--contention 2")
        self.refused(self.rec, "--contention", "2:0", naming="--contention 2:0")

    def test_a_bench_json_file_is_not_a_work_record(self):
        self.refused(self.rec, self.bench, naming="not a work record")
        self.refused("--measure-contention", self.rec, self.bench, naming="--record-work")

    def test_contention_from_records_of_different_scenes_or_sizes(self):
        # c(T) from a 1-thread record of one scene and a T-thread record of another was printed without a word
        def write(name, **changes):
            rec = record([dynamic([1 * MS, 1 * MS])], scene="flume", threads=2)
            rec.update(changes.pop("top", {}))
            rec["steps"][0].update(changes)
            path = os.path.join(self.tmp.name, name)
            with open(path, "w") as f:
                json.dump(rec, f)
            return path
        one = write("flume_1.json", top={"threads": 1})
        self.refused("--measure-contention", one, write("other.json", top={"scene": "column"}),
                     naming="scene flume against column")
        self.refused("--measure-contention", one, write("bigger.json", particles=1600),
                     naming="particles 800 against 1600")
        tool = os.path.join(os.path.dirname(sm.__file__), "scaling_model.py")
        r = subprocess.run([sys.executable, tool, "--measure-contention", one, write("same.json")],
                           capture_output=True, text=True, timeout=30)
        self.assertEqual((r.returncode, r.stdout.strip()), (0, "c(2) = 1.0000"), r.stderr)

    def test_no_records_writes_nothing(self):
        self.refused("--out", "out", naming="give one or more work records")

    def test_a_good_record_still_runs(self):
        tool = os.path.join(os.path.dirname(sm.__file__), "scaling_model.py")
        r = subprocess.run([sys.executable, tool, self.rec, "--threads", "1,2", "--contention", "2:1.1"],
                           capture_output=True, text=True, timeout=30)
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main()
