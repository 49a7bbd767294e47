"""``ensemble``: one periodic run per seed, then statistics over seeds."""

from __future__ import annotations

import argparse
import json
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..io.output import ENSEMBLE, annotate, ensemble_entry, write_attributes
from ..io.store import atomic_h5
from .common import EXIT_INTERRUPTED, EXIT_PAUSED, InputError, swept
from .runs import run
from .scene import prepare_scene


def run_ensemble(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """One periodic run per seed (each resumable), then statistics over seeds in OUT.h5."""
    import h5py

    from ..io.store import check_writable
    from ..workflows.ensemble import ensemble_statistics

    if args.heights is not None:
        raise InputError("ensemble needs a generated surface (--grid, --hurst, ...), not --heights")
    check_writable(args.output)
    if args.plot:
        check_writable(args.plot)
    pressures = args.pressures if args.pressures is not None else _ensemble_loads(args, petsc_args)
    stem = args.output[:-3] if args.output.endswith(".h5") else args.output
    files, status = [], 0
    for seed in args.seeds:
        path = f"{stem}_seed{seed}.h5"
        files.append(path)
        if args.resume and os.path.exists(path):
            continue  # finished earlier: nothing recomputed
        one = argparse.Namespace(
            **{
                **vars(args),
                **{"seed": seed, "output": path, "command": "periodic", "plot": None},
                **{"pressures": pressures, "sweep": None},
            }
        )
        del one.seeds
        code = run(one, argv, petsc_args)
        if code in (EXIT_INTERRUPTED, EXIT_PAUSED):
            return code  # the next --resume continues with this seed
        status = max(status, code)
    from mpi4py import MPI

    record = _ensemble_record(args, argv, pressures)  # collective: every rank joins
    if MPI.COMM_WORLD.rank == 0:
        summary = _write_ensemble(args, files, ensemble_statistics, h5py, record)
        if args.plot:
            from ..io.plot import plot_ensemble

            plot_ensemble(args.plot, summary, args.modulus)
        if not args.quiet:
            plotted = f" and {args.plot}" if args.plot else ""
            print(f"# wrote {args.output}{plotted} ({len(files)} seeds)")
    return status


def _ensemble_loads(args: argparse.Namespace, petsc_args: list[str]) -> list[float]:
    """``--sweep N[,PMIN,PMAX]``'s pressures, the same for every seed: the default range is
    ``1e-4`` to ``0.9`` times the full-contact pressure of the first seed's surface."""
    if len(args.sweep) == 3:
        return swept(args.sweep, args.sweep[1], args.sweep[2])
    from ..geometries.periodic import PeriodicProblem

    first = argparse.Namespace(**{**vars(args), "seed": args.seeds[0]})
    _, grid, fft, heights, _ = prepare_scene(first, petsc_args)
    p_full = PeriodicProblem(grid, fft, heights, args.modulus).full_contact_pressure()
    return swept(args.sweep, 1e-4 * p_full, 0.9 * p_full)


def _ensemble_record(
    args: argparse.Namespace, argv: Sequence[str], pressures: list[float]
) -> dict[str, Any]:
    """What reproduces an ensemble: its command, options, versions and PETSc options."""
    from ..backend import _petsc
    from ..io.provenance import petsc_options, versions

    petsc = _petsc.petsc()
    return {
        "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": {k: v for k, v in vars(args).items() if k != "quiet"}
        | {"pressures": pressures, "sweep": None},
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
    }


ENSEMBLE_QUANTITIES = tuple(k for k in ENSEMBLE if k not in ("seeds", "nominal_pressure"))


def _write_ensemble(
    args: argparse.Namespace, files: list[str], stats: Any, h5py: Any, record: dict[str, Any]
) -> dict[str, np.ndarray]:
    """The summary over seeds, written to ``OUT.h5`` with the run record; returned too."""
    tables: dict[str, list[np.ndarray]] = {}
    for path in files:
        with h5py.File(path, "r") as f:
            ok = f["converged"][:]
            pressure = f["nominal_pressure"][:]
            for q in ENSEMBLE_QUANTITIES:
                if q in f:
                    tables.setdefault(q, []).append(np.where(ok, f[q][:], np.nan))
    summary: dict[str, np.ndarray] = {"seeds": np.array(args.seeds), "nominal_pressure": pressure}
    for q, rows in tables.items():
        summary[q] = np.array(rows)
        summary.update({f"{q}_{name}": v for name, v in stats(summary[q]).items()})
    with atomic_h5(args.output) as out:
        write_attributes(out, {"geometry": "periodic ensemble", **record})
        out.attrs["seed_files"] = json.dumps([os.path.abspath(p) for p in files])
        for name, values in summary.items():
            out[name] = values
        out.attrs["complete"] = True
        annotate(out, ensemble_entry)
    return summary
