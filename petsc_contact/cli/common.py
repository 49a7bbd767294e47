"""What every command shares: exit codes, input errors, the scene and the run record."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from ..conventions.validation import non_negative, positive

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_UNAVAILABLE = 69  # a package the run needs cannot be loaded (sysexits' EX_UNAVAILABLE)
EXIT_STORAGE = 74  # results cannot be written: disk full, unwritable (sysexits' EX_IOERR)
EXIT_PAUSED = 75  # --stop-after reached: the run continues with --resume
EXIT_INTERRUPTED = 130


class InputError(Exception):
    """Bad user input: reported as one line, exit status 2."""


def check_numbers(args: argparse.Namespace) -> None:
    positive("--modulus", args.modulus)
    if getattr(args, "sweep", None) is not None:
        return
    name = next(
        (
            n
            for n in ("pressures", "approaches", "forces", "pressure")
            if getattr(args, n, None) is not None
        ),
        None,
    )
    if name is None:
        return
    values = getattr(args, name)
    values = values if isinstance(values, list) else [values]
    if not values:
        raise InputError(f"--{name} needs at least one value")
    check = non_negative if name == "approaches" else positive  # an approach may be 0
    for v in values:
        check(f"--{name}", v)


def swept(spec: list[float], low: float, high: float) -> list[float]:
    """The loads of ``--sweep N[,MIN,MAX]``: ``N`` log-spaced, by default from ``low`` to
    ``high``."""
    n, lo, hi = spec if len(spec) == 3 else (spec[0], low, high)
    return [float(v) for v in np.geomspace(lo, hi, int(n))]


FILE_RECORD = (
    "heights_reader",
    "heights_channel",
    "heights_channel_index",
    "file_lengths",
    "file_unit",
    "metadata_overridden",
)
"""What a run records of its ``--heights`` file, beside its path and digest."""


def run_record(
    args: argparse.Namespace,
    argv: Sequence[str],
    petsc: Any,
    realised: dict[str, float],
    resolved: dict[str, Any],
) -> dict[str, Any]:
    """What reproduces the run: every option (defaults resolved), versions, PETSc options."""
    from ..io.provenance import file_digest, petsc_options, versions

    params = {k: v for k, v in vars(args).items() if k not in ("quiet",)} | resolved
    lengths, unit = resolved["length"], resolved["length_unit"]
    attrs: dict[str, Any] = {
        "geometry": "punch" if args.command == "punch" else "periodic",
        "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": params,
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
        "length": lengths[0],
        "lengths": np.array(lengths),
        "length_unit": unit,
        "modulus": args.modulus,
        "units": (
            f"lengths and heights in {unit}"
            if unit
            else "lengths and heights in the unit of --length (none given)"
        )
        + ", pressures and stiffness per area in the unit of --modulus",
        **realised,
    }
    if args.heights is not None:
        attrs["heights_file"] = os.path.abspath(args.heights)
        attrs["heights_sha256"] = file_digest(args.heights)
        attrs.update({k: resolved[k] for k in FILE_RECORD})
    else:
        attrs.update(
            seed=args.seed,
            hurst=args.hurst,
            rolloff_ratio=args.rolloff_ratio,
            cutoff_ratio=params["cutoff_ratio"],
            grid=np.array(args.grid) if isinstance(args.grid, tuple) else args.grid,
        )
    return attrs


@contextmanager
def output_lock(path: str | None) -> Iterator[None]:
    """Hold the exclusive right to write ``path`` (rank 0 takes it; every rank raises the same
    error when another run holds it: :class:`~petsc_contact.io.store.OutputBusy`)."""
    from mpi4py import MPI

    from ..io.store import OutputLock, check_writable

    comm = MPI.COMM_WORLD
    lock = OutputLock(path) if path is not None and comm.rank == 0 else None
    failure: Exception | None = None
    if lock is not None:
        try:
            check_writable(lock.output)
            lock.acquire()
        except (ValueError, OSError) as exc:
            failure = exc
    if comm.size > 1:
        failure = comm.bcast(failure, root=0)
    if failure is not None:
        raise failure
    try:
        yield
    finally:
        if lock is not None:
            lock.release()


def say(message: str, kind: str = "error") -> None:
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print(f"petsc-contact: {kind}: {message}", file=sys.stderr)
