"""Strong scaling of a periodic load step, and a projection to many ranks.

usage: mpiexec -n P .venv/bin/python benchmarks/scaling.py [--grid 2048] [--pressure 1e-3]
       [--bandwidth 1.0] [--latency 2e-6] [--project 8192]
Run it with P = 1 and P = 2 (as root: OMPI_ALLOW_RUN_AS_ROOT=1
OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1), one ``--grid`` per ``mpiexec`` for P > 1: once
mpi4py-fft has planned in a process, FFTW-MPI fails to plan and the package falls back to
mpi4py-fft (the printed backend shows it).  ``mpiexec`` binds each rank to one core, so P = 1 runs
FFTW with one thread: the comparison is one core against two.  Rank 0 prints, per grid: the
FFT backend, the load step's iterations, wall time and time per operator application
(gradient evaluations, Hessian and preconditioner applications: each one FFT round trip,
except a Hessian application of the CG's projected steps, which skips the inverse); for P > 1
also mpi4py-fft's round trip, its two global transposes timed alone (the same volume FFTW-MPI
sends), and the bytes each rank sends per round trip, read from the MPI datatypes
mpi4py-fft hands to Alltoallw, and the time of a serial one-thread round trip of the whole
grid when every rank runs one at the same time (compare with the P = 1 round trip alone:
how the cores scale on FFTs when no distributed transform is involved).

The projection scales the measured per-rank work: local FFT time ~ n^2 log n / P, transpose
volume per rank ``V(P) = 2 * 16 n (n/2+1) (P-1) / P^2`` bytes (both transposes of the half
spectrum), sent at ``--bandwidth`` GB/s per rank with ``--latency`` s per message
(``P - 1`` messages per transpose), plus ``--allreduces`` latency-bound reductions per round
trip.  Those two network numbers are assumptions about the cluster, not measurements here.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI
from projection import project, scaled_local

from petsc_contact import periodic_contact
from petsc_contact.backend.operator import FourierOperator
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import SerialFFT, SlabFFT, make_fft
from petsc_contact.physics.surface import self_affine


def median_time(fn, repeats: int = 5, batch: int = 10) -> float:
    """Median over ``repeats`` batches of the time of one call (ranks synchronised)."""
    times = []
    for _ in range(repeats):
        MPI.COMM_WORLD.Barrier()
        start = time.perf_counter()
        for _ in range(batch):
            fn()
        MPI.COMM_WORLD.Barrier()
        times.append((time.perf_counter() - start) / batch)
    return float(np.median(times))


def transpose_bytes(fft) -> int:
    """Bytes this rank sends to other ranks in one forward transpose (from the MPI datatypes)."""
    transfer = fft._pfft.transfer[0]
    me = MPI.COMM_WORLD.rank
    return sum(t.Get_size() for q, t in enumerate(transfer._subtypesA) if q != me)


def measure(n: int, p0: float) -> dict[str, float]:
    comm = MPI.COMM_WORLD
    grid = Grid(n, 1.0, comm)
    fft = make_fft(grid)
    h = self_affine(grid, fft, hurst=0.7, rolloff_ratio=2, cutoff_ratio=64, seed=1, rms_slope=0.1)
    x = np.random.default_rng(comm.rank).standard_normal(grid.local_shape)
    out = np.empty_like(x)
    op = FourierOperator(grid, fft, np.ones(fft.spectrum.shape))
    result = {
        "round_trip": median_time(lambda: op.apply_array(x, out)),
        "backend": type(fft).__name__,
        "threads": fft.threads if isinstance(fft, SerialFFT) else 1,
    }
    heights = np.concatenate(comm.allgather(h))  # periodic_contact takes the whole map
    (step,) = periodic_contact(heights, 1.0, 1.0, [p0], comm=comm)
    if comm.size > 1:  # after the solve: FFTW-MPI cannot plan once mpi4py-fft has planned
        # every rank transforms the whole grid on its own core, all at once: how the cores
        # scale on independent FFTs, with no distributed transform in between
        whole = Grid(n, 1.0, MPI.COMM_SELF)
        solo = FourierOperator(whole, SerialFFT(whole, threads=1), np.ones((n, n // 2 + 1)))
        xs = np.random.default_rng(comm.rank).standard_normal((n, n))
        result["concurrent_round_trip"] = median_time(lambda: solo.apply_array(xs, xs))
        del solo, xs
        slab = SlabFFT(grid)  # mpi4py-fft: its round trip, and its transposes timed alone
        slab_op = FourierOperator(grid, slab, np.ones(slab.spectrum.shape))
        result["slab_round_trip"] = median_time(lambda: slab_op.apply_array(x, out))
        transfer = slab._pfft.transfer[0]
        a = np.zeros(transfer.subshapeA, dtype=transfer.dtype)
        b = np.zeros(transfer.subshapeB, dtype=transfer.dtype)
        result["transposes"] = 2 * median_time(lambda: transfer.forward(a, b))
        result["bytes"] = 2 * comm.allreduce(transpose_bytes(slab), op=MPI.MAX)
    s = step.scalars
    ffts = (
        s["objective_gradient_evaluations"]
        + s["hessian_applications"]
        + s["preconditioner_applications"]
    )
    result.update(
        iterations=s["iterations"],
        time=s["solve_time"],
        ffts=ffts,
        per_fft=s["solve_time"] / ffts,
        converged=float(step.converged),
    )
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, nargs="+", default=[2048])
    ap.add_argument("--pressure", type=float, default=1e-3)
    ap.add_argument(
        "--bandwidth",
        type=float,
        default=1.0,
        help="assumed network bandwidth per rank, GB/s (projection only)",
    )
    ap.add_argument(
        "--latency",
        type=float,
        default=2e-6,
        help="assumed latency per message, s (projection only)",
    )
    ap.add_argument(
        "--allreduces",
        type=int,
        default=3,
        help="latency-bound reductions per FFT round trip (the CG does 5-8 "
        "per iteration of ~2.8 round trips)",
    )
    ap.add_argument("--project", type=int, default=8192, help="grid of the projection")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    for n in args.grid:
        r = measure(n, args.pressure)
        if comm.rank:
            continue
        print(
            f"n = {n}, ranks = {comm.size}, FFT {r['backend']} ({r['threads']} thread(s) "
            f"per rank): {r['iterations']} iterations, "
            f"{r['time']:.2f} s, {r['ffts']} operator applications, {r['per_fft'] * 1e3:.1f} ms "
            f"per application in the solve, FFT round trip alone {r['round_trip'] * 1e3:.1f} ms"
            + ("" if r["converged"] else "  NOT CONVERGED")
        )
        if comm.size > 1:
            print(
                f"  whole-grid serial round trips, one per rank, all at once: "
                f"{r['concurrent_round_trip'] * 1e3:.1f} ms each"
            )
            local = r["round_trip"] - r["transposes"]
            print(
                f"  mpi4py-fft round trip {r['slab_round_trip'] * 1e3:.1f} ms; its transposes "
                f"alone {r['transposes'] * 1e3:.1f} ms ({r['bytes'] / 1e6:.1f} MB sent "
                f"per rank per round trip, {r['bytes'] / r['transposes'] / 1e9:.2f} GB/s); "
                f"the {r['backend']} round trip less those: {local * 1e3:.1f} ms"
            )
            m = args.project
            local_1 = scaled_local(local, comm.size, n, m)
            print(
                f"  projection to {m}^2 (bandwidth {args.bandwidth} GB/s per rank, "
                f"latency {args.latency:g} s), per round trip:"
            )
            print("      P   local_ms    comm_ms  efficiency")
            for p, loc, com, eff in project(
                m, local_1, [16, 32, 64, 128, 256], args.bandwidth, args.latency, args.allreduces
            ):
                print(f"  {p:5d} {loc * 1e3:10.2f} {com * 1e3:10.2f} {eff:11.2f}")


if __name__ == "__main__":
    main()
