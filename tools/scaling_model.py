#!/usr/bin/env python3
"""The scaling model of talus: replays a work-distribution record under the OpenMP schedules talus
uses and predicts the time per step, the speed-up and the efficiency at T threads.

    build/talus bench --particles 1000000 --threads 1 --steps 3 --record-work block.json
    build/talus run inputs/denlinger_flume.json --threads 1 --record-work flume.json
    tools/scaling_model.py block.json flume.json [--threads 1,2,4,...,128] [--schedule recorded|lpt|static]
                           [--work seconds|particles] [--out docs/performance/scaling_model]

The record (talus-work-record/1, solver/work_recorder.hpp) lists, for each recorded step, every
parallel region in the order the step runs it:
  dynamic  (the colour passes of P2G and G2P, the stress pass: `omp for schedule(dynamic, 1)` over
           blocks) with the measured seconds and particles of every block, in hand-out order;
  static   (loops over particles or grid tiles, `schedule(static)`) with the loop length and time;
  serial   (sort, outflow removal, output) with its time;
and the wall time of the step; what the regions leave of it is serial glue.

The model, per region, for T threads (the record taken at T_rec threads, normally 1):
  dynamic: the greedy list schedule of `dynamic, 1` - each block goes, in hand-out order, to the
           thread that becomes free first - gives the critical path (the largest thread's share);
           the region's own overhead (wall - critical path at T_rec - fork/join at T_rec: the cost
           of handing out the blocks) spread evenly over the blocks as their work when T_rec = 1
           (--loop-overhead per-block, the default; `serial` keeps it serial, the model before
           2026-12-04); plus one fork/join + barrier b(T).
  static:  the loop's work W = (wall - k b(T_rec) - m B(T_rec)) * min(T_rec, n) split in T contiguous
           parts of ceil(n/T) iterations (what `schedule(static)` does): W ceil(n/T)/n, plus k b(T)
           for its k parallel regions and m B(T) for the m barriers between the loops inside them
           (the grid phase: one region of `omp for` loops, grid/tile_stages.hpp).
  serial:  its time.
A dynamic region that runs inside a region opened before it (the colour passes after the first share
one parallel region) adds a barrier B(T) instead: an empty `omp for` in an open region, measured alike
(`barrier_seconds`; b(T) where a record lacks it).
b(T) is the measured cost of an empty `omp parallel for schedule(dynamic, 1)` of T iterations
(the record holds it for 1..nproc threads, `fork_join_seconds`); beyond the measured counts it is
extrapolated as b(T) = b(Tm) + --barrier-per-doubling (default 1 us) * log2(T / Tm), an assumption
to be replaced by the measurement on a many-core node (the recorder measures b up to its nproc).
Optionally a memory-bandwidth floor: --bytes-per-update B --stream "1:14.8,2:29.1" (GB/s per thread
count) bounds a step below by particles * B / STREAM(T).

--contention 2:1.16 multiplies the parallel work at T >= 2 by the per-core slowdown c(T) measured when
T cores work (--measure-contention REC1 REC2: block seconds per particle of a 2-thread record over those
of a 1-thread record of the same scene; two records of different scenes, bench settings or particle
counts are refused); beyond the largest T given c keeps that value (an assumption).
The time at T is split into terms: ideal (parallel work / T), imbalance (critical paths above
work / T), synchronisation (fork/join + barriers), serial (serial parts, glue, region overheads).
The limiting term at T is the largest loss among imbalance, synchronisation, serial (and bandwidth).
--schedule lpt replays the dynamic regions with the blocks handed out largest first (what the
work-sorted colour lists do); static replays them as `schedule(static)`. --work particles uses the
particle counts (scaled to the region's time) instead of the measured block seconds; --work robust
(the default) caps each block's seconds at 4x the region's median seconds per particle times its
particles (+2 us): a block timed across an interruption of its thread (27 ms against 0.03 ms for its
peers, seen in the 8 M record) would otherwise pose as a critical path at 64 threads.
"""
import argparse
import heapq
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import int_list, refuse  # noqa: E402


def parse_counts(text, option="--threads"):
    """Thread counts, each 1 or more (0 divided by zero in the schedules); one line and exit 2 otherwise."""
    return int_list(option, text, 1)


def parse_pairs(text, option):
    """T:value pairs, e.g. 2:1.16,4:1.3: T a thread count (1 or more), the value above 0 (a slowdown
    factor or GB/s: 0 or less scales the work to nothing or divides by zero); one line and exit 2 otherwise."""
    out = {}
    for item in text.split(","):
        if item:
            try:
                k, v = item.split(":")
                k, v = int(k), float(v)
            except ValueError:
                k = v = None
            if k is None or k < 1 or not v > 0 or math.isinf(v):
                where = "" if item == text else f"{item}: "
                refuse(option, text, f"{where}give T:value pairs separated by commas (e.g. 2:1.16), T 1 or more "
                                     "and the value above 0")
            out[k] = v
    return out


def load_record(path, option="record"):
    """A work record (talus-work-record/1), or one line and exit 2 naming what the file is instead (a
    bench --json file gave KeyError 'fork_join_seconds')."""
    if not os.path.isfile(path):
        refuse(option, path, "is a folder, not a file" if os.path.isdir(path) else "no such file")
    try:
        with open(path) as f:
            record = json.load(f)
    except (ValueError, UnicodeDecodeError) as e:
        refuse(option, path, f"not JSON ({e}); give a work record: talus bench/run ... --record-work FILE")
    if not (isinstance(record, dict) and str(record.get("format", "")).startswith("talus-work-record")
            and "fork_join_seconds" in record and record.get("steps")):
        refuse(option, path, "not a work record (talus-work-record/1; a bench --json file is not one): "
                             "make one with talus bench ... --record-work FILE or talus run ... --record-work FILE")
    return record


class Barrier:
    """b(T): measured where the record has it, extrapolated (log2) beyond."""

    def __init__(self, measured, per_doubling):
        self.measured = [m for m in measured]  # index = threads
        self.tm = len(self.measured) - 1
        self.per_doubling = per_doubling

    def __call__(self, threads):
        if threads <= self.tm:
            return self.measured[threads]
        return self.measured[self.tm] + self.per_doubling * math.log2(threads / self.tm)


def greedy_makespan(times, threads):
    """dynamic, 1: each item, in order, goes to the thread that is free first."""
    if threads == 1 or len(times) <= 1:
        return sum(times) if threads == 1 else (max(times) if times else 0.0)
    if len(times) <= threads:
        return max(times)
    free = [0.0] * threads
    for t in times:
        heapq.heapreplace(free, free[0] + t)
    return max(free)


def static_makespan(times, threads):
    """schedule(static): contiguous parts, the first n % T threads one item more (libgomp)."""
    n = len(times)
    if n == 0:
        return 0.0
    q, r = divmod(n, threads)
    best, start = 0.0, 0
    for t in range(threads):
        size = q + (1 if t < r else 0)
        best = max(best, sum(times[start:start + size]))
        start += size
    return best


def region_items(region, work):
    secs = region["block_seconds"]
    if work == "robust":
        # A block timed while its thread was interrupted (a timer tick, a page fault, another process)
        # shows up as 10-1000x its peers; such a delay is not the block's work and does not recur with
        # it. Each block's seconds are capped at 4x the region's median seconds per particle times its
        # particles (plus 2 us).
        rates = sorted(t / p for t, p in zip(secs, region["block_particles"]) if p > 0)
        if not rates:
            return secs
        rate = rates[len(rates) // 2]
        return [min(t, 4.0 * rate * p + 2e-6) for t, p in zip(secs, region["block_particles"])]
    if work == "particles":
        parts = region["block_particles"]
        total_p = sum(parts)
        total_s = sum(secs)
        return [total_s * p / total_p for p in parts] if total_p else secs
    return secs


def record_case(record):
    """What a work record measured, for comparing two: the scene (a run's name; a bench's scene, shape,
    scheme, material and MLS), the scatter and block edge, and the particles of its first recorded step."""
    bench = record.get("bench") if isinstance(record.get("bench"), dict) else {}
    scene = record.get("scene") or bench.get("scene") or "?"
    if bench:
        scene = f"bench {scene} " + " ".join(str(bench.get(k, "?")) for k in ("shape", "scheme", "material", "mls"))
    return {"scene": scene, "scatter": record.get("scatter"), "block_cells": record.get("block_cells"),
            "particles": record["steps"][0].get("particles")}


def block_seconds_per_particle(record):
    """Seconds per particle in the recorded block loops: the speed of one core at the record's thread count."""
    secs = parts = 0.0
    for step in record["steps"]:
        for r in step["regions"]:
            if r["schedule"] == "dynamic":
                secs += sum(r["block_seconds"])
                parts += sum(r["block_particles"])
    return secs / parts


def contention_factor(contention, threads):
    """c(T): how much slower a core works when T cores work (1 at T = 1; beyond the largest given T, its value)."""
    if threads == 1 or not contention:
        return 1.0
    known = sorted(contention)
    below = [t for t in known if t <= threads]
    return contention[below[-1]] if below else 1.0


def predict_step(step, threads, barrier, t_rec, schedule, work, contention=1.0, inner=None, loop_overhead="per-block"):
    """Terms of the predicted step time at `threads`: ideal, imbalance, sync, serial (seconds).
    `contention` multiplies the parallel work (the per-core slowdown when `threads` cores work);
    `inner` is the cost of a barrier inside an open region (the fused colour passes), b(T) if not given.
    `loop_overhead`: what a dynamic loop's time beyond its blocks and its fork/join is, in a record
    taken on 1 thread: "per-block" (the default) - the cost of handing out each block (the loop's
    shared counter, the block's clock reads, the loop's own bookkeeping), paid by the thread that
    takes the block, so spread evenly over the blocks as their work; "serial" - kept serial, as
    before 2026-12-04 (an upper bound)."""
    inner = inner or barrier
    terms = {"ideal": 0.0, "imbalance": 0.0, "sync": 0.0, "serial": 0.0}
    listed = 0.0
    for r in step["regions"]:
        listed += r["seconds"]
        kind = r["schedule"]
        k = r.get("parallel_regions", 0)
        m = r.get("barriers", 0)  # barriers inside a region opened by an earlier one (fused colour passes)
        if kind == "serial":
            terms["serial"] += r["seconds"]
        elif kind == "dynamic":
            items = region_items(r, work)
            critical_rec = greedy_makespan(r["block_seconds"], t_rec)
            overhead = max(r["seconds"] - critical_rec - k * barrier(t_rec) - m * inner(t_rec), 0.0)
            if loop_overhead == "per-block" and t_rec == 1 and items:
                items = [x + overhead / len(items) for x in items]
                overhead = 0.0
            if schedule == "lpt":
                items = sorted(items, reverse=True)
            span = (static_makespan(items, threads) if schedule == "static" else greedy_makespan(items, threads)) * contention
            total = sum(items) * contention
            terms["ideal"] += total / threads
            terms["imbalance"] += max(span - total / threads, 0.0)
            terms["sync"] += k * barrier(threads) + m * inner(threads)
            terms["serial"] += overhead
        else:  # static; m: barriers between the loops of one region (the grid phase's TileStages)
            n = max(int(r["items"]), 1)
            w = max(r["seconds"] - k * barrier(t_rec) - m * inner(t_rec), 0.0) * min(t_rec, n) * contention
            span = w * math.ceil(n / threads) / n
            terms["ideal"] += w / threads
            terms["imbalance"] += span - w / threads
            terms["sync"] += k * barrier(threads) + m * inner(threads)
    # glue between the listed regions, less the recorder's own bookkeeping (not in an unrecorded step)
    terms["serial"] += max(step["seconds"] - listed - step.get("recorder_seconds", 0.0), 0.0)
    return terms


def inner_barrier(record, per_doubling):
    """The cost of a barrier inside an open parallel region, where the record measured it."""
    return Barrier(record["barrier_seconds"], per_doubling) if record.get("barrier_seconds") else None


def predict(record, threads, barrier, schedule, work, bandwidth=None, contention=None, loop_overhead="per-block"):
    t_rec = int(record["threads"])
    inner = inner_barrier(record, barrier.per_doubling)
    total = {"ideal": 0.0, "imbalance": 0.0, "sync": 0.0, "serial": 0.0, "bandwidth": 0.0}
    c = contention_factor(contention, threads) / contention_factor(contention, t_rec)
    for step in record["steps"]:
        terms = predict_step(step, threads, barrier, t_rec, schedule, work, c, inner, loop_overhead)
        compute = sum(terms.values())
        floor = bandwidth(step["particles"], threads) if bandwidth else 0.0
        for k, v in terms.items():
            total[k] += v
        total["bandwidth"] += max(floor - compute, 0.0)
    return total


LOOP_REGIONS = ("output and guards", "snapshot", "history row")


def with_run_mean_output(record):
    """A `talus run` record with the run loop's work after each step (output, guards, snapshot) replaced by
    its mean over the whole run. That work is spiky - a frame (30 ms for the default flume) every few
    hundred steps, a snapshot every 10 - so the recorded sample of steps (every 37th) holds a frame or
    none by chance: the flume's 176 recorded steps of 6504 held 3 frames where 0.3 were due, 475 us of
    output per step against the run's 200. The run's totals are exact: run_other_seconds (the loop
    outside the steps, start and finish included) and, of it, run_snapshot_seconds (the field checks
    and copies of the snapshots, parallel, in run_snapshot_regions regions) and run_history_seconds
    (the history rows: the energies' parallel sum, the runout's parallel loops and sort, and the
    rows' file writes, which are serial but small; in run_history_regions regions, counted as on many
    threads; records before 2026-12-05 hold the rows in the serial rest), and beside them
    run_background_seconds: the frames' compression and writes on the writer's thread, which overlap
    the steps. The model shares that work among the cores, as a parallel part without a region of its
    own (a background write on a core slows the steps' work on that core). Records without totals
    come back unchanged."""
    steps_total = record.get("run_steps", 0)
    if not steps_total:
        return record
    other = record["run_other_seconds"]
    snapshot = record.get("run_snapshot_seconds", 0.0)
    regions_per_step = record.get("run_snapshot_regions", 0) / steps_total
    history = record.get("run_history_seconds", 0.0)
    history_regions_per_step = record.get("run_history_regions", 0) / steps_total
    background = record.get("run_background_seconds", 0.0)
    out = dict(record)
    out["steps"] = []
    for step in record["steps"]:
        kept = [r for r in step["regions"] if r["name"] not in LOOP_REGIONS]
        removed = sum(r["seconds"] for r in step["regions"] if r["name"] in LOOP_REGIONS)
        kept.append({"name": "output and guards (run mean)", "schedule": "serial", "parallel_regions": 0,
                     "seconds": (other - snapshot - history) / steps_total})
        added = (other - snapshot - history) / steps_total
        if snapshot > 0.0:
            kept.append({"name": "snapshot (run mean)", "schedule": "static", "items": step["particles"],
                         "parallel_regions": regions_per_step, "seconds": snapshot / steps_total})
            added += snapshot / steps_total
        if history > 0.0:
            kept.append({"name": "history rows (run mean)", "schedule": "static", "items": step["particles"],
                         "parallel_regions": history_regions_per_step, "seconds": history / steps_total})
            added += history / steps_total
        if background > 0.0:
            # one thread's work; a static region's seconds are wall time on the recording's threads
            wall = background / steps_total / max(int(record.get("threads", 1)), 1)
            kept.append({"name": "frames in the background (run mean)", "schedule": "static",
                         "items": step["particles"], "parallel_regions": 0, "seconds": wall})
            added += wall
        out["steps"].append(dict(step, regions=kept, seconds=step["seconds"] - removed + added))
    return out


def model(record, counts, barrier, schedule, work, bandwidth=None, contention=None, loop_overhead="per-block"):
    """Per thread count: predicted seconds (over the recorded steps), speed-up, efficiency, terms."""
    base = sum(predict(record, 1, barrier, schedule, work, bandwidth, contention, loop_overhead).values())
    rows = []
    for t in counts:
        terms = predict(record, t, barrier, schedule, work, bandwidth, contention, loop_overhead)
        seconds = sum(terms.values())
        losses = {k: terms[k] for k in ("imbalance", "sync", "serial", "bandwidth")}
        if contention:  # the contention's share of the parallel work
            c = contention_factor(contention, t)
            losses["contention"] = (terms["ideal"] + terms["imbalance"]) * (1.0 - 1.0 / c)
        rows.append({"threads": t, "seconds": seconds, "speedup": base / seconds, "efficiency": base / seconds / t,
                     "terms": {k: v / seconds for k, v in terms.items()},
                     "limit": max(losses, key=losses.get) if t > 1 else "none"})
    return rows


def summary(record):
    steps = record["steps"]
    blocks = [s["blocks"] for s in steps]
    parts = [s["particles"] for s in steps]
    per_colour = []
    for s in steps:
        for r in s["regions"]:
            if r["schedule"] == "dynamic" and "colour" in r["name"] and r["block_seconds"]:
                per_colour.append(len(r["block_seconds"]))
    return {"recorded_steps": len(steps), "particles": [min(parts), max(parts)], "blocks": [min(blocks), max(blocks)],
            "blocks_per_colour_pass_mean": sum(per_colour) / len(per_colour) if per_colour else 0,
            "blocks_per_colour_pass_min": min(per_colour) if per_colour else 0,
            "seconds_per_step_recorded": sum(s["seconds"] for s in steps) / len(steps)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("records", nargs="*", help="work records (talus bench/run --record-work)")
    ap.add_argument("--threads", default="1,2,4,8,16,32,64,128")
    ap.add_argument("--schedule", default="recorded", choices=["recorded", "lpt", "static"],
                    help="how the dynamic regions hand out blocks (recorded: dynamic,1 in the recorded order)")
    ap.add_argument("--work", default="robust", choices=["robust", "seconds", "particles"],
                    help="block work: measured seconds with interruptions capped (robust), as measured, or particles")
    ap.add_argument("--barrier-per-doubling", type=float, default=1e-6,
                    help="seconds b(T) grows per doubling of T beyond the measured thread counts")
    ap.add_argument("--bytes-per-update", type=float, default=0.0, help="DRAM bytes per particle-update (bandwidth floor)")
    ap.add_argument("--stream", default="", help="STREAM triad GB/s per thread count, e.g. 1:14.8,2:29.1")
    ap.add_argument("--contention", default="",
                    help="per-core slowdown c(T) when T cores work, e.g. 2:1.16 (kept at the largest given T beyond it)")
    ap.add_argument("--measure-contention", nargs=2, metavar=("REC1", "RECT"),
                    help="print c(T) = block seconds per particle of a T-thread record / of a 1-thread record, and exit")
    ap.add_argument("--loop-overhead", default="per-block", choices=["per-block", "serial"],
                    help="a dynamic loop's time beyond its blocks (1-thread records): the blocks' hand-out cost, "
                         "spread over the blocks (default), or kept serial (the model before 2026-12-04)")
    ap.add_argument("--output", default="run-mean",
                    help="the run loop's output, guards and snapshot per step: run-mean (the run's mean, talus run "
                         "records) or sampled (as in the recorded steps: for a record of a run's first steps, whose "
                         "start and end frames would weigh on the mean); one value, or one per record, comma-separated")
    ap.add_argument("--labels", default="", help="comma-separated labels for the records")
    ap.add_argument("--out", default="", help="write OUT.json and OUT.png")
    a = ap.parse_args()
    if a.measure_contention:
        r1, rt = (load_record(p, "--measure-contention") for p in a.measure_contention)
        for path, rec in zip(a.measure_contention, (r1, rt)):
            if not any(r["schedule"] == "dynamic" and r["block_particles"] for s in rec["steps"] for r in s["regions"]):
                refuse("--measure-contention", path, "has no block loops (dynamic regions with particles) to "
                                                     "measure c(T) from")
        # c(T) compares one scene's speed per core at two thread counts: records of another scene or size
        # gave a c without a word (a smaller scene's blocks fit the cache, a larger one's do not)
        case1, caset = record_case(r1), record_case(rt)
        if case1 != caset:
            differ = ", ".join(f"{k} {case1[k]} against {caset[k]}" for k in case1 if case1[k] != caset[k])
            refuse("--measure-contention", " ".join(a.measure_contention),
                   f"the records are of different cases ({differ}): record one scene at two thread counts")
        c = block_seconds_per_particle(rt) / block_seconds_per_particle(r1)
        print(f"c({rt['threads']}) = {c:.4f}")
        return
    if not a.records:  # it printed nothing and exited 0 (with --out: an empty JSON and plot)
        refuse("records", "(none)", "give one or more work records (talus bench/run ... --record-work FILE)")
    counts = parse_counts(a.threads)
    contention = parse_pairs(a.contention, "--contention") if a.contention else None
    labels = a.labels.split(",") if a.labels else [os.path.basename(r) for r in a.records]
    if len(labels) != len(a.records):  # zip() below dropped the records past the shorter list
        refuse("--labels", a.labels, f"{len(labels)} labels for {len(a.records)} records: give one per record")
    stream = parse_pairs(a.stream, "--stream") if a.stream else {}
    bandwidth = None
    if a.bytes_per_update > 0 and stream:
        def bandwidth(particles, threads):
            return particles * a.bytes_per_update / (stream[threads] * 1e9) if threads in stream else 0.0
    results = []
    outputs = a.output.split(",")
    if len(outputs) == 1:
        outputs = outputs * len(a.records)
    if len(outputs) != len(a.records):
        refuse("--output", a.output, f"{len(outputs)} values for {len(a.records)} records: give one, or one per record")
    if any(output not in ("run-mean", "sampled") for output in outputs):
        refuse("--output", a.output, "give run-mean or sampled, once or once per record")
    # every record checked before the first is modelled: a wrong one later stopped the tool halfway
    records = [load_record(path) for path in a.records]
    for path, record, label, output in zip(a.records, records, labels, outputs):
        if record.get("omp_wait_policy", "").upper() == "PASSIVE":
            print(f"note: {path} was recorded with OMP_WAIT_POLICY=PASSIVE: its fork/join costs are those of waking "
                  "sleeping threads, and the model predicts runs under that policy", file=sys.stderr)
        if output == "run-mean":
            record = with_run_mean_output(record)
        barrier = Barrier(record["fork_join_seconds"], a.barrier_per_doubling)
        rows = model(record, counts, barrier, a.schedule, a.work, bandwidth, contention, a.loop_overhead)
        info = summary(record)
        results.append({"label": label, "record": path, "source": record.get("source"), "threads_recorded": record["threads"],
                        "output": output,
                        "contention": contention,
                        "block_cells": record.get("block_cells"), "schedule": a.schedule, "work": a.work,
                        "fork_join_seconds": record["fork_join_seconds"], **info, "prediction": rows})
        print(f"{label}: {info['recorded_steps']} steps recorded at {record['threads']} thread(s), "
              f"{info['particles'][1]} particles, {info['blocks'][1]} blocks, "
              + (f"{info['blocks_per_colour_pass_mean']:.1f} blocks per colour pass (min {info['blocks_per_colour_pass_min']}); "
                 if info['blocks_per_colour_pass_mean'] else "no colour passes (solver.scatter = block_buffers); ")
              + f"schedule {a.schedule}, work {a.work}")
        print(f"  {'T':>4} {'speed-up':>9} {'eff.':>6} {'ideal':>6} {'imbal.':>6} {'sync':>6} {'serial':>6} {'bw':>6}  limit"
              + ("  (ideal and imbalance include the contention)" if contention else ""))
        for r in rows:
            t = r["terms"]
            print(f"  {r['threads']:4} {r['speedup']:9.2f} {100 * r['efficiency']:5.1f}% {100 * t['ideal']:5.1f}% "
                  f"{100 * t['imbalance']:5.1f}% {100 * t['sync']:5.1f}% {100 * t['serial']:5.1f}% "
                  f"{100 * t['bandwidth']:5.1f}%  {r['limit']}")
    if not a.out:
        return
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    with open(a.out + ".json", "w") as f:
        json.dump({"model": "tools/scaling_model.py", "barrier_per_doubling": a.barrier_per_doubling,
                   "bytes_per_update": a.bytes_per_update, "stream": stream, "results": results}, f, indent=1)
    print("wrote", a.out + ".json")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for res in results:
        ts = [r["threads"] for r in res["prediction"]]
        axes[0].plot(ts, [r["speedup"] for r in res["prediction"]], "o-", label=res["label"])
        axes[1].plot(ts, [r["efficiency"] for r in res["prediction"]], "o-", label=res["label"])
    axes[0].plot(counts, counts, "k--", lw=0.8, label="ideal")
    axes[0].set(xscale="log", yscale="log", xlabel="threads", ylabel="predicted speed-up", title="scaling model")
    axes[1].set(xscale="log", xlabel="threads", ylabel="predicted efficiency", ylim=(0, 1.05))
    for ax in axes:
        ax.set_xticks(counts)
        ax.set_xticklabels([str(c) for c in counts])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"talus scaling model (schedule {a.schedule}; b(T) extrapolated +{a.barrier_per_doubling * 1e6:.1f} us per "
                 "doubling beyond the measured threads)", fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=110)
    print("wrote", a.out + ".png")


if __name__ == "__main__":
    main()
