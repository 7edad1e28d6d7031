#!/usr/bin/env python3
"""A model of talus's weak scaling over nodes (MPI ranks, one per node, OpenMP inside), 1 to 64 nodes.

docs/performance.md, "Distributed runs (MPI)", states the model and its assumptions; in short:

  t_step(P) = imbalance x N / R                                  compute of a node's slab
            + sum over the two exchanges (7 fields after P2G, 3 after the MUSL remap) of
                n_nb x (alpha + m_f / beta)                       messages, one to each slab neighbour
                + pack_add x m_f x n_nb                           packing the tiles and adding the sums
            + alpha_coll x ceil(log2 P)                           the step's allgather (24 bytes a rank)
            + (alpha_coll x ceil(log2 P) + P x C x 8 / beta) / sort_interval   the sort's column counts
  m_f = S x f x 64 nodes x 8 bytes, S = tiles a rank sends a neighbour (measured), n_nb = 2 (1 at P = 2).
  Efficiency E(P) = t_step(1) / t_step(P) with t_step(1) = N / R (one node: no exchange at all).

Weak scaling: N particles per node fixed, the flume grows in length with P; the y-z cross-section is that
of the bench block (0.5 m x 0.5 m at h = 0.01 m, 8 particles a cell), whose measured exchange gives S
(exchange_bytes_per_step of the 2-rank bench / (2 ranks x 10 fields x 512 bytes); the flag bytes of the
tiles not sent are left out, < 0.2%).

Inputs: --bench (tools/mpi_bench.py's JSON: the measured S, imbalance, the 2-core rate, the MPI message
costs and the tile-exchange microbenchmark on this machine). Inter-node figures are assumptions (InfiniBand
HDR: alpha 1.5 us, beta 22 GB/s), as is the rate of a 64-core node (from the OpenMP model of "Scaling").

  /usr/bin/python3 tools/mpi_weak_scaling_model.py --bench docs/performance/mpi_bench.json \
      --out docs/performance/mpi_weak_scaling
writes mpi_weak_scaling.json and mpi_weak_scaling.png and prints the table.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import require_inputs  # noqa: E402

TILE_BYTES = 64 * 8  # one field of one 4x4x4-node tile
FIELDS = (7, 3)      # after P2G (mass, momentum, force) and after the MUSL remap (momentum)
SORT_INTERVAL = 20   # solver.sort_interval default: the column counts are summed at every sort
COLUMN_CELLS = 4     # colour-block columns along x (block_cells of the bench)


def median(v):
    v = sorted(v)
    return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])


def intra_node_costs(bench):
    """alpha, beta and the allgather latency from the session's ping-pong (medians of the runs)."""
    runs = bench["message_costs"]
    alpha = median([next(p["seconds"] for p in r["pingpong"] if p["bytes"] == 8) for r in runs])
    big = 8388608
    t_big = median([next(p["seconds"] for p in r["pingpong"] if p["bytes"] == big) for r in runs])
    beta = big / (t_big - alpha)
    coll = median([r["allgather_24_bytes_seconds"] for r in runs])
    return alpha, beta, coll


def pack_add_seconds_per_byte(bench, alpha, beta):
    """The tile-exchange microbenchmark's time beyond its messages: packing and adding, per byte sent.
    With buffers kept across calls ("tiles_reused"): talus's own exchange does not pay the fresh-page
    cost the microbenchmark shows with new buffers on this VM (docs/performance.md: the "+keep" A/B)."""
    per_byte = []
    for r in bench["message_costs"]:
        for t in r.get("tiles_reused", []):
            if t["tiles"] in (420, 1000):
                per_byte.append(max(0.0, t["seconds"] - (alpha + t["bytes"] / beta)) / t["bytes"])
    return median(per_byte)


def step_seconds(P, N, rate, S, imbalance, net, pack_add, slab_columns):
    alpha, beta, alpha_coll = net
    compute = N / rate * (imbalance if P > 1 else 1.0)
    if P == 1:
        return {"compute": compute, "messages": 0.0, "pack_add": 0.0, "collectives": 0.0, "total": compute}
    n_nb = 1 if P == 2 else 2  # the interior ranks have two neighbours; they set the pace
    messages = sum(n_nb * (alpha + S * f * TILE_BYTES / beta) for f in FIELDS)
    packing = sum(n_nb * S * f * TILE_BYTES * pack_add for f in FIELDS)
    hops = math.ceil(math.log2(P))
    columns = P * slab_columns
    collectives = alpha_coll * hops + (alpha_coll * hops + P * columns * 8 / beta) / SORT_INTERVAL
    total = compute + messages + packing + collectives
    return {"compute": compute, "messages": messages, "pack_add": packing, "collectives": collectives, "total": total}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", required=True, help="tools/mpi_bench.py JSON")
    ap.add_argument("--alpha-ib", type=float, default=1.5e-6, help="inter-node latency [s] (assumption: InfiniBand HDR)")
    ap.add_argument("--beta-ib", type=float, default=22e9, help="inter-node bandwidth [B/s] (assumption: InfiniBand HDR)")
    ap.add_argument("--node-rate-64", type=float, default=None,
                    help="particle-updates/s of a 64-core node (default: 64 x 4.8 M/s x the OpenMP model's efficiency)")
    ap.add_argument("--out", help="prefix of the .json and .png written")
    a = ap.parse_args()
    if a.out and not os.path.isdir(os.path.dirname(os.path.abspath(a.out))):  # found before the model, not after
        sys.exit(f"mpi_weak_scaling_model.py: --out {a.out}: the folder {os.path.dirname(os.path.abspath(a.out))} does not exist")
    require_inputs(bench=a.bench)
    with open(a.bench) as f:
        bench = json.load(f)
    if "summary" not in bench or "runs" not in bench:
        sys.exit(f"mpi_weak_scaling_model.py: --bench {a.bench}: not a tools/mpi_bench.py report (no summary and runs)")
    s = bench["summary"]
    # S: tiles a rank sends its neighbour a step, from the 2-rank bench
    ex = s["2x1-bound"]["exchange_bytes_per_step"]
    S = ex / (2 * sum(FIELDS) * TILE_BYTES)
    imbalance = max(r["bench"]["imbalance"] for r in bench["runs"] if r["bench"].get("ranks", 1) > 1)
    alpha, beta, coll = intra_node_costs(bench)
    pack_add = pack_add_seconds_per_byte(bench, alpha, beta)
    vm_rate = s["1x2"]["median_m_per_s"] * 1e6
    # The OpenMP model ("Scaling"): 1-thread 4.8 M/s; 64 threads at 63.6% (1 M) and 84.8% (8 M)
    # efficiency; 4 M between them, interpolated in log N (an assumption).
    eff = {1e6: 0.636, 4e6: 0.636 + (0.848 - 0.636) * math.log(4) / math.log(8)}
    node64 = {N: (a.node_rate_64 or 64 * 4.8e6 * eff[N]) for N in eff}
    ib = (a.alpha_ib, a.beta_ib, a.alpha_ib)
    # label, node rate, network, particles per node, imbalance (largest slab / mean)
    cases = [
        ("this VM (2 cores), intra-node MPI measured", vm_rate, (alpha, beta, coll), 1e6, imbalance),
        ("this VM (2 cores), InfiniBand HDR assumed", vm_rate, ib, 1e6, imbalance),
        ("64-core node, InfiniBand HDR assumed", node64[1e6], ib, 1e6, imbalance),
        ("64-core node, InfiniBand HDR assumed", node64[4e6], ib, 4e6, imbalance),
        ("64-core node, IB HDR, slabs 10% out of balance (the rebalance threshold)", node64[4e6], ib, 4e6, 1.10),
    ]
    nodes = [1, 2, 4, 8, 16, 32, 64]
    slab_cell_length = {1e6: 50, 4e6: 200}  # cells along x of a node's slab (50 x 50 cross-section, 8 per cell)
    out = {"inputs": {"sent_tiles_per_neighbour": S, "exchange_bytes_per_step_2_ranks": ex, "imbalance": imbalance,
                      "intra_node_alpha_s": alpha, "intra_node_beta_B_per_s": beta, "intra_node_allgather_s": coll,
                      "pack_add_s_per_byte": pack_add, "vm_rate_per_s": vm_rate, "node64_rate_per_s": node64,
                      "alpha_ib_s": a.alpha_ib, "beta_ib_B_per_s": a.beta_ib}, "cases": []}
    print(f"S = {S:.0f} tiles sent a neighbour a step ({ex / 2e6:.2f} MB a rank a step at 2 ranks); imbalance {imbalance:.3f}")
    print(f"intra-node: alpha {alpha * 1e6:.2f} us, beta {beta / 1e9:.1f} GB/s (8 MiB), allgather {coll * 1e6:.2f} us; "
          f"pack + add {pack_add * 1e9:.3f} ns/B ({1 / pack_add / 1e9 if pack_add else float('inf'):.2f} GB/s)")
    print("| node, network | particles per node | " + " | ".join(f"{P}" for P in nodes) + " |")
    print("|---|---|" + "---|" * len(nodes))
    for label, rate, net, N, imb in cases:
        rows = [step_seconds(P, N, rate, S, imb, net, pack_add, slab_cell_length[N] / COLUMN_CELLS) for P in nodes]
        e = [rows[0]["total"] / r["total"] for r in rows]
        out["cases"].append({"label": label, "particles_per_node": N, "rate_per_s": rate, "imbalance": imb,
                             "network": {"alpha_s": net[0], "beta_B_per_s": net[1], "collective_alpha_s": net[2]},
                             "nodes": nodes, "steps": rows, "efficiency": e})
        print(f"| {label} | {N / 1e6:.0f} M | " + " | ".join(f"{x * 100:.1f}%" for x in e) + " |")
    for c in out["cases"]:
        r = c["steps"][-1]
        print(f"  {c['label']}, {c['particles_per_node'] / 1e6:.0f} M: at 64 nodes a step is {r['total'] * 1e3:.2f} ms = "
              f"compute {r['compute'] * 1e3:.2f} + messages {r['messages'] * 1e3:.3f} + pack/add {r['pack_add'] * 1e3:.3f} "
              f"+ collectives {r['collectives'] * 1e6:.1f} us")
    if a.out:
        with open(a.out + ".json", "w") as f:
            json.dump(out, f, indent=1)
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
        for c in out["cases"]:
            lab = f"{c['label']}, {c['particles_per_node'] / 1e6:.0f} M/node"
            ax1.plot(c["nodes"], [100 * x for x in c["efficiency"]], "o-", label=lab)
            ax2.plot(c["nodes"][1:], [1e3 * (r["messages"] + r["pack_add"] + r["collectives"]) for r in c["steps"][1:]], "o-",
                     label=lab)
        ax1.set(xscale="log", xlabel="nodes (1 rank each)", ylabel="weak-scaling efficiency [%]", ylim=(0, 105),
                title="talus weak scaling model (flume 0.5 m x 0.5 m, h = 0.01 m)")
        ax2.set(xscale="log", xlabel="nodes", ylabel="[ms] per step", ylim=(0, None),
                title="exchange (messages, pack, add) + collectives per step")
        for ax in (ax1, ax2):
            ax.set_xticks(nodes)
            ax.minorticks_off()
            ax.set_xticklabels([str(n) for n in nodes])
            ax.grid(True, alpha=0.3)
        ax1.legend(fontsize=7, loc="lower left")
        fig.tight_layout()
        fig.savefig(a.out + ".png", dpi=110)
        print(f"wrote {a.out}.json, {a.out}.png")


if __name__ == "__main__":
    sys.exit(main())
