"""Projection of a periodic sweep to 16384^2-65536^2 on N nodes: memory and time per step.

usage: .venv/bin/python benchmarks/projection.py [--inputs benchmarks/projection.json]
       [--grids 16384 32768 65536] [--nodes 1 2 4 8 16 32 64 128] [--ranks-per-node 64]
       [--node-memory 256] [--bandwidth 1.0] [--latency 2e-6] [--allreduces 3]
       [--loads 12] [--disk-bandwidth 1.0] [--json]

Nothing is run: the projection is computed from this machine's measured figures, read from
``--inputs`` (each with the date, commit and page it comes from), and from assumptions about
the cluster, given as options.  Printed as two markdown tables (``--json``: the rows).

Memory per rank (a sweep with ``--fields --stiffness``, as measured by
``benchmarks/memory.py --ranks``): ``c + b n^2 / P + x n^2 (P - 1) / P``, with ``c`` the
per-process constant measured on as many ranks (the largest measured count's beyond it),
``b`` the serial run's peak less its constant over ``n^2`` (bytes per point), and ``x`` the
least-squares fit of the measured excess of the largest rank over ``c + b n^2 / P`` on
``P > 1`` ranks, in bytes per point of the whole grid (as an array of the whole grid less
the rank's own rows would be).  On one rank it is the measured serial peak.

Time per step: iterations per step (the 12-step sweeps' mean at the two measured grids,
grown as the power of ``n`` they fit), times FFT round trips per iteration (counted), times
one round trip's time from :func:`project`: local work scaled from the FFTW-MPI measurement
as ``n^2 log n / P``, over the FFT's share of a profiled solve (the solver's other passes),
and the transposes' bytes ``2 x 16 n (n/2+1) (P-1)/P^2`` per rank sent at ``--bandwidth``
with ``--latency`` per message.  The contact solve only: ``--stiffness`` adds a solve about
as long again.  Slab decomposition: at most ``n`` ranks.

The output file: the heights (8 B a point) and ``--loads`` steps of gap, pressure (8 B) and
contact (1 B), uncompressed (gzip makes it smaller, by how much depends on the contact), and
the time rank 0 takes to assemble it from the parts, reading each and writing the file once
at ``--disk-bandwidth``.
"""

from __future__ import annotations

import argparse
import json
import os
from dataclasses import dataclass

import numpy as np

GiB = 2**30
FIELD_CHUNK = 256  # rows of the fields' chunks (io.store): slabs of whole chunks are copied
HEIGHT_BYTES, FIELD_BYTES = 8, 8 + 8 + 1  # a point of the heights; of gap, pressure, contact


@dataclass(frozen=True)
class MemoryModel:
    """Peak memory per rank, fitted to a measured table (:func:`fit_memory`).

    Attributes
    ----------
    constants
        The per-process constant (bytes), by rank count measured.
    per_point
        ``b``: the serial run's bytes per grid point above its constant.
    excess
        ``x``: the excess of the largest rank on ``P > 1``, per point of the whole grid, at
        ``(P - 1) / P`` of it.
    """

    constants: dict[int, float]
    per_point: float
    excess: float

    def per_rank(self, n: int, p: int) -> tuple[float, float]:
        """Peak bytes of the largest of ``p`` ranks at ``n^2``, and the excess in it."""
        constant = self.constants.get(p, self.constants[max(self.constants)])
        excess = self.excess * n**2 * (p - 1) / p
        return constant + self.per_point * n**2 / p + excess, excess


def fit_memory(table: dict) -> MemoryModel:
    """:class:`MemoryModel` of a measured table (``memory_per_rank`` of the inputs)."""
    n2 = table["grid"] ** 2
    ranks = table["ranks"]
    largest = np.array(table["largest_GiB"]) * GiB
    constants = np.array(table["constant_GiB"]) * GiB
    serial = largest[ranks.index(1)] - constants[ranks.index(1)]
    p = np.array(ranks, dtype=float)
    measured = largest - constants - serial / p  # over the target, 0 on one rank
    share = n2 * (p - 1) / p
    excess = float(share @ measured / (share @ share))
    return MemoryModel(dict(zip(ranks, constants.tolist(), strict=True)), serial / n2, excess)


def scaled_local(local: float, ranks: int, measured: int, n: int) -> float:
    """A round trip's local work on one rank at ``n^2``, from ``local`` seconds per rank
    measured on ``ranks`` ranks at ``measured^2``: scaled as ``n^2 log n``."""
    return local * ranks * (n / measured) ** 2 * np.log2(n) / np.log2(measured)


def project(
    n: int, local_1: float, ranks: list[int], bandwidth: float, latency: float, allreduces: int
) -> list[tuple[int, float, float, float]]:
    """(P, local time, communication time, efficiency) per round trip at grid ``n``.

    ``local_1`` is the measured local time of one round trip on one rank of the
    measured grid, already rescaled to ``n`` (:func:`scaled_local`).  The transposes send
    ``2 x 16 n (n/2+1) (P-1)/P^2`` bytes per rank at ``bandwidth`` GB/s, ``P - 1`` messages
    each at ``latency`` s, and ``allreduces`` reductions of ``log2 P`` latencies.
    """
    rows = []
    for p in ranks:
        local = local_1 / p
        volume = 2 * 16 * n * (n // 2 + 1) * (p - 1) / p**2
        comm = (
            volume / (bandwidth * 1e9) + 2 * (p - 1) * latency + allreduces * latency * np.log2(p)
        )
        rows.append((p, local, comm, local / (local + comm)))
    return rows


def iterations(sweep: dict, n: int) -> tuple[float, float]:
    """Iterations per step at ``n^2`` and the power of ``n`` they grow with: the sweeps'
    means per step at the two measured grids, extrapolated as that power."""
    (g1, g2), (i1, i2) = sweep["grids"], np.array(sweep["iterations"]) / sweep["steps"]
    power = float(np.log(i2 / i1) / np.log(g2 / g1))
    return float(i2 * (n / g2) ** power), power


def step_rows(args: argparse.Namespace, inputs: dict) -> list[dict]:
    """Per grid and node count: memory per rank and node, and time per step."""
    model = fit_memory(inputs["memory_per_rank"])
    measured = inputs["local_round_trip"]
    share = inputs["fft_share"]["fftw_s"] / inputs["fft_share"]["solve_s"]
    trips = inputs["round_trips_per_iteration"]["value"]
    local = np.mean(measured["ms"]) * 1e-3
    rows = []
    for n in args.grids:
        local_1 = scaled_local(local, measured["ranks"], measured["grid"], n) / share
        its, _ = iterations(inputs["sweep_iterations"], n)
        counts = [nodes * args.ranks_per_node for nodes in args.nodes]
        timed = project(n, local_1, counts, args.bandwidth, args.latency, args.allreduces)
        for nodes, (p, loc, comm, efficiency) in zip(args.nodes, timed, strict=True):
            rank, excess = model.per_rank(n, p)
            rows.append(
                {
                    "grid": n,
                    "nodes": nodes,
                    "ranks": p,
                    "rows_per_rank": n / p,
                    "rank_GiB": rank / GiB,
                    "excess_GiB": excess / GiB,
                    "node_GiB": args.ranks_per_node * rank / GiB,
                    "node_without_excess_GiB": args.ranks_per_node * (rank - excess) / GiB,
                    "slabs": p <= n,
                    "iterations": its,
                    "local_ms": loc * 1e3,
                    "network_ms": comm * 1e3,
                    "step_s": its * trips * (loc + comm),
                    "efficiency": efficiency,
                }
            )
    return rows


def output_rows(args: argparse.Namespace) -> list[dict]:
    """Per grid: the output file's size and the time rank 0 takes to assemble it."""
    rows = []
    for n in args.grids:
        size = n**2 * (HEIGHT_BYTES + args.loads * FIELD_BYTES)
        largest = max(args.nodes) * args.ranks_per_node
        whole = min(n // FIELD_CHUNK, largest)  # up to this many ranks, slabs of whole chunks
        assembly = 2 * size / (args.disk_bandwidth * 1e9)
        rows.append({"grid": n, "GB": size / 1e9, "assembly_min": assembly / 60, "whole": whole})
    return rows


def fits(row: dict, memory: float) -> str:
    """Whether a row's ranks fit a node of ``memory`` GiB, as measured and without the
    excess."""
    if not row["slabs"]:
        return "P > n"
    said = ["yes" if row[k] <= memory else "no" for k in ("node_GiB", "node_without_excess_GiB")]
    return " / ".join(said)


def print_tables(steps: list[dict], outputs: list[dict], args: argparse.Namespace) -> None:
    """The two tables, in markdown."""
    print(
        f"| grid | nodes | ranks | rows per rank | per rank (GiB) | of it the excess (GiB) | "
        f"per node (GiB) | fits {args.node_memory:g} GiB (measured / without the excess) | "
        f"iterations per step | local (ms) | network (ms) | per step (s) | efficiency |"
    )
    print("| --- " * 13 + "|")
    for r in steps:
        print(
            f"| {r['grid']} | {r['nodes']} | {r['ranks']} | {r['rows_per_rank']:g} | "
            f"{r['rank_GiB']:.3f} | {r['excess_GiB']:.3f} | {r['node_GiB']:.0f} | "
            f"{fits(r, args.node_memory)} | {r['iterations']:.0f} | {r['local_ms']:.2f} | "
            f"{r['network_ms']:.2f} | {r['step_s']:.1f} | {r['efficiency']:.2f} |"
        )
    print()
    print(
        f"| grid | output, {args.loads} loads, uncompressed (GB) | assembled on rank 0 at "
        f"{args.disk_bandwidth:g} GB/s (min) | ranks up to which slabs are whole chunks |"
    )
    print("| --- " * 4 + "|")
    for r in outputs:
        print(f"| {r['grid']} | {r['GB']:.0f} | {r['assembly_min']:.1f} | {r['whole']} |")


def arguments() -> argparse.Namespace:
    """The command line."""
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs", default=os.path.join(here, "projection.json"))
    ap.add_argument("--grids", type=int, nargs="+", default=[16384, 32768, 65536])
    ap.add_argument("--nodes", type=int, nargs="+", default=[1, 2, 4, 8, 16, 32, 64, 128])
    ap.add_argument("--ranks-per-node", type=int, default=64)
    ap.add_argument("--node-memory", type=float, default=256, help="GiB per node")
    ap.add_argument("--bandwidth", type=float, default=1.0, help="network GB/s per rank")
    ap.add_argument("--latency", type=float, default=2e-6, help="s per message")
    ap.add_argument(
        "--allreduces", type=int, default=3, help="latency-bound reductions per round trip"
    )
    ap.add_argument("--loads", type=int, default=12, help="steps stored in the output")
    ap.add_argument(
        "--disk-bandwidth", type=float, default=1.0, help="GB/s of rank 0's reads and writes"
    )
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    return ap.parse_args()


def main() -> None:
    args = arguments()
    with open(args.inputs) as f:
        inputs = json.load(f)
    steps, outputs = step_rows(args, inputs), output_rows(args)
    if args.json:
        model = fit_memory(inputs["memory_per_rank"])
        its = iterations(inputs["sweep_iterations"], args.grids[0])
        print(
            json.dumps(
                {
                    "per_point": model.per_point,
                    "excess_per_point": model.excess,
                    "iteration_power": its[1],
                    "steps": steps,
                    "outputs": outputs,
                }
            )
        )
    else:
        print_tables(steps, outputs, args)


if __name__ == "__main__":
    main()
