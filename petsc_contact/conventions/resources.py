"""What a run will need of the machine, checked before it allocates: memory per grid point.

The figures (:data:`BYTES_PER_POINT`) are a whole command's peak over a tiny run's (the
process with its imports), rounded up: ``petsc-contact periodic`` with a generated surface,
the default solver, the exact stiffness and an output file (its resume state), and the punch
per footprint point (its padded FFT has four times the points); TAO's quasi-Newton and Newton
types keep about twice the default's fields (``benchmarks/memory.py``, docs/performance.md,
"Memory", where the solver alone is measured).  Fields kept for the output (``--fields``,
gathered on rank 0) add three 8-byte fields.  tests/test_resources.py checks the figures
against such runs.
"""

from __future__ import annotations

import ctypes
import gc
import os
from typing import Any

BYTES_PER_POINT = {"periodic": 180.0, "punch": 380.0}
"""Peak bytes per grid point (footprint point for the punch) of the default solver: a 512^2
periodic sweep with the stiffness and its resume state took 246, and 181 since the contact
solve keeps no bound Vecs, no FFT output buffer, no scaled copy of the stiffness's multiplier
and no copy of its answer, and its preconditioner no work fields of its own; 163 since the CG
keeps no residual, every multiplier is kept once per entry and no FFT plan holds its last
output; the punch's two approaches at 512^2, 396, then 335 (tests/test_resources.py;
docs/performance.md, "Memory")."""
OTHER_TAO_FACTOR = 2.0  # TAO's own types keep about twice the default's fields
FIELD_BYTES = 24.0  # gap, pressure and contact of one step on rank 0, with the state


def estimated_bytes(
    points: int, geometry: str, default_solver: bool = True, fields: bool = False
) -> float:
    """The peak memory of a run on ``points`` grid points, all ranks together."""
    per_point = BYTES_PER_POINT["punch" if geometry == "punch" else "periodic"]
    if not default_solver:
        per_point *= OTHER_TAO_FACTOR
    return points * (per_point + (FIELD_BYTES if fields else 0.0))


def release_freed() -> None:
    """Give back what this process has finished with before the memory available is read:
    collect cyclic garbage (whatever a finished run left in reference cycles) and return the
    C heap's free pages to the system (glibc's ``malloc_trim``; nothing where the C library
    has none).  After a 1024^2 run its process held on to all of the 0.29 GB the run had
    taken, and 0.005 GB once given back (tests/test_resources.py); after a 4096^2 run 4.51
    and 0.013 GB; a study's second 8192^2 piece, in the process of the first, saw 3 GiB
    available beside the 19 GiB the first had held."""
    gc.collect()
    try:
        trim = ctypes.CDLL(None).malloc_trim  # the process's own C library
    except (OSError, AttributeError):
        return
    trim(0)


def available_bytes() -> float:
    """The memory this machine can give now (``MemAvailable``), else all of it."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


FEWEST_ROWS = 512
"""Rows a rank's slab should have for more ranks to pay: two ranks gained 1.2-1.3x at 2048^2
and 4096^2 (1024 rows or more a rank, docs/parallel.md, "Strong scaling"), and a smaller slab
has less work to set against each transform's exchange of the whole spectrum."""


def rank_excess(comm: Any, rows: int) -> str:
    """Why the ``comm.size`` ranks of a grid of ``rows`` rows are more than help, in words
    (``""`` when they are not): slabs of fewer than :data:`FEWEST_ROWS` rows, or more ranks
    on one node than the cores they may run on (the union of their affinity masks).
    Collective."""
    if comm.size == 1:
        return ""
    from mpi4py import MPI

    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    cores = len(set().union(*node.allgather(os.sched_getaffinity(0))))
    ranks, cores = max(comm.allgather((node.size, cores)), key=lambda rc: rc[0] - rc[1])
    node.Free()
    said = []
    if rows < FEWEST_ROWS * comm.size:
        said.append(
            f"its {rows} rows give each rank {rows // comm.size} or so, fewer than the "
            f"{FEWEST_ROWS} from which more ranks pay"
        )
    if ranks > cores:
        said.append(f"{ranks} ranks share {cores} core{'s' * (cores > 1)} on one node")
    return "; ".join(said)


def check_memory(points: int, geometry: str, default_solver: bool, fields: bool) -> None:
    """``MemoryError`` with one line when the run would need more memory than is available
    (what this process has finished with given back first, :func:`release_freed`)."""
    release_freed()
    need, have = estimated_bytes(points, geometry, default_solver, fields), available_bytes()
    if need > have:
        raise MemoryError(
            f"this run needs about {need / 2**30:.3g} GiB ({points:,} grid points), more than "
            f"the {have / 2**30:.3g} GiB available: choose a smaller grid, or "
            "--skip-memory-check to try anyway"
        )
