"""Peak memory per grid point of one load step or of a sweep, per geometry and solver; and
peak memory per rank of a run on several ranks.

usage: .venv/bin/python benchmarks/memory.py [--grids 1024 2048 4096] [--punch-grids 512 1024]
       [--loads N]  (N > 1: a sweep of N loads with the exact stiffness at each, as the study's)
       [--stiffness]  (the exact stiffness also of a single load)
       .venv/bin/python benchmarks/memory.py --ranks 1 2 4 8 [--grids 4096] [--loads 2]
Each case runs in a fresh process; peak resident memory (ru_maxrss) minus the resident memory
of the same process before the grid is allocated, divided by n^2, is bytes per grid point.
Between consecutive grids of a geometry and solver, the difference of the peaks over the points
added is the marginal cost per point, free of every per-process constant (the compiled kernels,
PETSc, the FFT's plans): the figure a large grid's memory is estimated from.

With ``--ranks``, each grid runs as ``petsc-contact periodic --fields --stiffness`` would,
written to a file (``--loads`` loads from 1e-3 to 1e-2 of the modulus), under
``mpiexec --oversubscribe -n P`` for each ``P`` (as root, set OMPI_ALLOW_RUN_AS_ROOT=1 and
OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1); every rank reports its peak resident memory and its
resident memory before the run (the per-process constant: Python, PETSc, MPI, the
package), and the per-process constant: the largest rank's peak of the same run on a
``--constant-grid`` grid (128^2) on as many ranks, which has loaded and touched everything a
process does but the grid (MPI's buffers, the compiled kernels, the FFT libraries).  The
target of ``P`` ranks is the serial run's memory above its constant divided by ``P``, plus
the constant of ``P`` ranks' processes: the largest rank should be within 15% of it, and
rank 0 within 15% of the others' largest.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys, time
import numpy as np
import petsc_contact
from petsc_contact import periodic_contact, punch_contact
from petsc_contact.backend import _petsc
from petsc_contact.paper import figures as scenes
_petsc.init([])
geometry, n, solver, loads = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
stiffness = loads > 1 or sys.argv[5] == "1"
opts = [] if solver == "cg" else ["-tao_type", solver]
h, _ = scenes.surface(n, 0.7, 2.0, n / 4, 1)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t = time.perf_counter()
scale = np.geomspace(1e-3, 1.0, loads) if loads > 1 else np.ones(1)
if geometry == "periodic":
    steps = periodic_contact(h, 1.0, 1.0, 1e-2 * scale, options=opts, stiffness=stiffness)
else:
    approaches = 3 * h.std() * scale
    steps = punch_contact(h, 1.0, 1.0, approaches=approaches, options=opts)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"geometry": geometry, "n": n, "solver": solver, "peak_GiB": peak / 2**30,
                  "bytes_per_point": (peak - base + h.nbytes) / n**2,
                  "iterations": sum(s.scalars["iterations"] for s in steps),
                  "time": time.perf_counter() - t, "converged": all(s.converged for s in steps)}))
"""


RANK_CHILD = r"""
import json, os, resource, sys, time
from mpi4py import MPI
from petsc_contact import Run, run_contact
from petsc_contact.backend import _petsc
_petsc.init([])
n, loads, folder = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
comm = MPI.COMM_WORLD
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
run = Run(grid=n, hurst=0.7, rms_slope=0.1, seed=1, sweep=(loads, 1e-3, 1e-2), stiffness=True,
          fields=True, output=os.path.join(folder, f"memory-{n}-{comm.size}.h5"))
comm.Barrier()
t = time.perf_counter()
result = run_contact(run)
took = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
said = comm.gather({"rank": comm.rank, "base": base, "peak": peak}, root=0)
if comm.rank == 0:
    print(json.dumps({"n": n, "size": comm.size, "time": took, "ranks": said,
                      "converged": all(bool(s["converged"]) for s in result.table)}))
"""


def per_rank(n: int, size: int, loads: int, folder: str) -> dict | None:
    """Every rank's base and peak resident memory for a run of ``n^2`` on ``size`` ranks."""
    command = [sys.executable, "-c", RANK_CHILD, str(n), str(loads), folder]
    if size > 1:
        command = ["mpiexec", "--oversubscribe", "-n", str(size), *command]
    out = subprocess.run(command, capture_output=True, text=True)
    line = [text for text in out.stdout.splitlines() if text.startswith("{")]
    if not line:
        print(f"{n} on {size} ranks: failed: {out.stderr.strip().splitlines()[-3:]}")
        return None
    return json.loads(line[0])


def rank_table(grids: list[int], sizes: list[int], loads: int, small: int) -> None:
    """Peak memory per rank on each of ``sizes`` ranks, against serial/P plus the constant:
    the peak of the same run on a ``small`` grid on as many ranks (Python, PETSc, MPI's
    buffers, the compiled kernels, the FFT libraries: all but the grid)."""
    import tempfile

    def run(n: int, size: int) -> dict | None:
        with tempfile.TemporaryDirectory() as folder:
            return per_rank(n, size, loads, folder)

    gib = 2.0**30
    print(
        "| grid | ranks | rank 0 (GiB) | largest rank (GiB) | smallest rank (GiB) | before the "
        f"run (GiB) | constant: {small}^2 (GiB) | target (GiB) | largest / target | "
        "rank 0 / others' largest | time (s) |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    constants = {}
    for size in sizes:
        r = run(small, size)
        constants[size] = max(p["peak"] for p in r["ranks"]) if r else float("nan")
    for n in grids:
        serial = None
        for size in sizes:
            r = run(n, size)
            if r is None:
                continue
            peaks = [p["peak"] for p in r["ranks"]]
            before = sorted(p["base"] for p in r["ranks"])[len(peaks) // 2]
            if serial is None:
                serial = peaks[0] - constants[size]  # the first size given is the reference
            target = constants[size] + serial / size
            others = max(peaks[1:], default=peaks[0])
            print(f"| {n} | {size} | {peaks[0] / gib:.3f} | {max(peaks) / gib:.3f} | "
                  f"{min(peaks) / gib:.3f} | {before / gib:.3f} | {constants[size] / gib:.3f} | "
                  f"{target / gib:.3f} | {max(peaks) / target:.3f} | {peaks[0] / others:.3f} | "
                  f"{r['time']:.0f} |", flush=True)  # fmt: skip


def case(geometry: str, n: int, solver: str, loads: int, stiffness: bool) -> dict | None:
    """One case in a fresh process: its peak, bytes per point, iterations, time."""
    command = [sys.executable, "-c", CHILD, geometry, str(n), solver, str(loads)]
    out = subprocess.run([*command, str(int(stiffness))], capture_output=True, text=True)
    line = [text for text in out.stdout.splitlines() if text.startswith("{")]
    if not line:
        print(f"{geometry} {n} {solver}: failed: {out.stderr.strip().splitlines()[-1:]}")
        return None
    r = json.loads(line[0])
    print(
        f"{geometry:>8} {n:>5} {solver:>6}: {r['bytes_per_point']:6.0f} B/point, "
        f"peak {r['peak_GiB']:.3f} GiB, {r['iterations']} its, {r['time']:.1f} s, "
        f"converged {r['converged']}",
        flush=True,
    )
    return r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--punch-grids", type=int, nargs="*", default=[512, 1024, 2048])
    ap.add_argument("--solvers", nargs="+", default=["cg", "tron", "bqnls"])
    ap.add_argument("--loads", type=int, default=1, help="loads per run (default: one step)")
    ap.add_argument("--stiffness", action="store_true", help="the exact stiffness of one load too")
    ap.add_argument("--ranks", type=int, nargs="*", help="peak memory per rank on these ranks")
    ap.add_argument("--constant-grid", type=int, default=128, help="the per-process constant's")
    args = ap.parse_args()
    if args.ranks:
        rank_table(args.grids, args.ranks, args.loads, args.constant_grid)
        return
    cases = [("periodic", n, s) for n in args.grids for s in args.solvers]
    cases += [("punch", n, "cg") for n in args.punch_grids]
    peaks: dict[tuple[str, str], list[tuple[int, float]]] = {}
    for geometry, n, solver in cases:
        r = case(geometry, n, solver, args.loads, args.stiffness)
        if r is not None:
            peaks.setdefault((geometry, solver), []).append((n, r["peak_GiB"] * 2.0**30))
    for (geometry, solver), runs in peaks.items():  # the marginal cost: free of constants
        for (m, low), (n, high) in zip(runs, runs[1:], strict=False):
            added = (high - low) / (n * n - m * m)
            print(f"{geometry} {solver}, {m}^2 -> {n}^2: {added:.0f} B per point added")


if __name__ == "__main__":
    main()
