"""One paper-scale periodic load step with the default solver: iterations, time, memory.

usage: [mpiexec -n P] .venv/bin/python benchmarks/paper_scale.py [--grid 8192] [--pressure 1e-3]
       [--rolloff-ratio 2] [--cutoff-ratio N/4] [--profile]
Surface: H = 0.7, rms slope 0.1, L/lambda_r = 2, L/lambda_1 = n/4 (the paper's own bandwidth:
--rolloff-ratio 1 --cutoff-ratio N/2), seed 1, generated
distributed over the ranks and gathered (``periodic_contact`` takes the whole map on every
rank). The step starts from first touch. Rank 0 prints the surface's time (FFTW planning
included), the load step's wall time (problem set-up and solve) and TAO's solve time, the
iterations and FFT work, the peak resident memory summed over the ranks, and, with
``--profile``, rank 0's 15 most expensive functions by own time (cProfile).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import resource
import time

import numpy as np
from mpi4py import MPI

from petsc_contact import periodic_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=8192)
    ap.add_argument("--pressure", type=float, default=1e-3, help="p0/E*")
    ap.add_argument("--rolloff-ratio", type=float, default=2.0, help="L/lambda_r")
    ap.add_argument("--cutoff-ratio", type=float, default=None, help="L/lambda_1 (default n/4)")
    ap.add_argument("--profile", action="store_true", help="cProfile rank 0's load step")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    n = args.grid
    start = time.perf_counter()
    grid = Grid(n, 1.0, comm)
    fft = make_fft(grid)
    local = self_affine(
        grid,
        fft,
        hurst=0.7,
        rolloff_ratio=args.rolloff_ratio,
        cutoff_ratio=args.cutoff_ratio or n / 4,
        seed=1,
        rms_slope=0.1,
    )
    heights = np.empty((n, n))
    counts = [len(range(n)[s]) * n for s in comm.allgather(grid.rows)]
    comm.Allgatherv(np.ascontiguousarray(local), [heights, counts])
    del local
    surface_time = time.perf_counter() - start
    profile = cProfile.Profile() if args.profile and comm.rank == 0 else None
    start = time.perf_counter()
    if profile is not None:
        profile.enable()
    (step,) = periodic_contact(heights, 1.0, 1.0, [args.pressure], comm=comm)
    if profile is not None:
        profile.disable()
    wall = time.perf_counter() - start
    peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) / 2**20
    if comm.rank:
        return
    s = step.scalars
    print(
        f"n = {n}, ranks = {comm.size}, FFT {type(fft).__name__}, p0/E* = {args.pressure:g}: "
        f"surface {surface_time:.1f} s; load step {wall:.1f} s (solve {s['solve_time']:.1f} s), "
        f"{s['iterations']} iterations, {s['objective_gradient_evaluations']} gradient "
        f"evaluations, {s['hessian_applications']} Hessian and "
        f"{s['preconditioner_applications']} preconditioner applications, "
        f"{s['tao_reason']}; mean gap {s['mean_gap']:.8e}; peak memory {peak:.2f} GiB "
        f"(sum over ranks)",
        flush=True,
    )
    if profile is not None:
        pstats.Stats(profile).sort_stats("tottime").print_stats(15)


if __name__ == "__main__":
    main()
