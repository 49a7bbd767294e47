"""Ensembles over surface realisations: one run per seed, then statistics over the seeds.

``petsc-contact ensemble`` and :func:`run_ensemble` run the same periodic scene for each
seed, each into its own resumable file ``OUT_seedK.h5`` (:func:`seed_runs`), with the same
pressures for every seed (:func:`ensemble_loads`), then write the mean, standard deviation
and standard error over seeds of every per-step quantity to ``OUT.h5``
(:func:`write_summary`; statistics by
:func:`~petsc_contact.workflows.ensemble.ensemble_statistics`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.grid import world
from ..conventions.units import pressure_value
from ..io.schema import ENSEMBLE, annotate, ensemble_entry, write_attributes
from ..io.store import atomic_h5
from .description import Run
from .ensemble import ensemble_statistics
from .runner import Progress, locked, run_contact, swept

QUANTITIES = tuple(k for k in ENSEMBLE if k not in ("seeds", "nominal_pressure"))


@dataclass
class EnsembleResult:
    """The statistics over seeds (``seeds x steps`` tables, and ``_mean``, ``_std``, ``_sem``,
    ``_count`` per step) and the files of the seeds."""

    summary: dict[str, np.ndarray]
    files: list[str]

    def to_dataframe(self) -> Any:
        """The per-step statistics as a pandas ``DataFrame`` (one row per load)."""
        import pandas as pd

        columns = {k: v for k, v in self.summary.items() if np.ndim(v) == 1 and k != "seeds"}
        return pd.DataFrame(columns)


def ensemble_loads(base: Run, first_seed: int) -> list[float]:
    """The pressures every seed gets: ``base.pressures``, or its sweep, whose default range is
    ``1e-4`` to ``0.9`` times the full-contact pressure of the first seed's surface."""
    if base.pressures is not None:
        return [pressure_value(p, base.pressure_unit, "--pressures") for p in base.pressures]
    if base.sweep is None:
        raise ValueError("give the nominal pressures (--pressures) or a --sweep")
    if len(base.sweep) == 3:  # the bounds given (with their units, if any)
        unit = base.pressure_unit
        return swept(base.sweep, 0.0, 0.0, lambda v: pressure_value(v, unit, "--sweep"))
    from ..geometries.periodic import PeriodicProblem
    from .scene import prepare_scene

    scene = prepare_scene(base.with_(seed=first_seed))
    problem = PeriodicProblem(scene.grid, scene.fft, scene.heights, base.modulus_value)
    p_full = problem.full_contact_pressure()
    return swept(base.sweep, 1e-4 * p_full, 0.9 * p_full)


def seed_runs(base: Run, seeds: Sequence[int]) -> list[Run]:
    """One periodic run per seed, into ``OUT_seedK.h5`` beside ``base.output`` (if any), all
    at the same pressures."""
    if base.measured:
        raise ValueError("ensemble needs a generated surface (--grid, --hurst, ...), not --heights")
    if base.geometry != "periodic":
        raise ValueError("an ensemble is of periodic runs")
    pressures = ensemble_loads(base, seeds[0])
    stem = None if base.output is None else base.output.removesuffix(".h5")
    return [
        base.with_(
            seed=k,
            pressures=pressures,
            sweep=None,
            output=None if stem is None else f"{stem}_seed{k}.h5",
        )
        for k in seeds
    ]


def summarise(seeds: Sequence[int], files: Sequence[str]) -> dict[str, np.ndarray]:
    """Per-seed tables of every quantity (NaN where a step did not converge) and their
    statistics over seeds, read from the seeds' files."""
    import h5py

    tables: dict[str, list[np.ndarray]] = {}
    pressure = np.empty(0)
    for path in files:
        with h5py.File(path, "r") as f:
            ok = f["converged"][:]
            pressure = f["nominal_pressure"][:]
            for q in QUANTITIES:
                if q in f:
                    tables.setdefault(q, []).append(np.where(ok, f[q][:], np.nan))
    summary: dict[str, np.ndarray] = {"seeds": np.array(seeds), "nominal_pressure": pressure}
    for q, rows in tables.items():
        summary[q] = np.array(rows)
        summary.update({f"{q}_{name}": v for name, v in ensemble_statistics(summary[q]).items()})
    return summary


def write_summary(
    path: str, summary: dict[str, np.ndarray], files: Sequence[str], record: dict[str, Any]
) -> None:
    """The ensemble's ``OUT.h5``: the summary, the seeds' files and the record (atomically)."""
    with atomic_h5(path) as out:
        write_attributes(out, {"geometry": "periodic ensemble", **record})
        out.attrs["seed_files"] = json.dumps([os.path.abspath(p) for p in files])
        for name, values in summary.items():
            out[name] = values
        out.attrs["complete"] = True
        annotate(out, ensemble_entry)


def ensemble_record(
    base: Run, seeds: Sequence[int], pressures: list[float], command_line: str
) -> dict[str, Any]:
    """What reproduces an ensemble: its command, description, versions and PETSc options."""
    from ..backend import _petsc
    from ..io.provenance import petsc_options, versions

    petsc = _petsc.init()
    return {
        "command_line": command_line,
        "parameters": base.parameters()
        | {"command": "ensemble", "seeds": list(seeds), "pressures": pressures, "sweep": None},
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
    }


def run_ensemble(
    base: Run, seeds: Sequence[int], progress: Progress | None = None
) -> EnsembleResult:
    """Run ``base`` for every seed (each resumable; with ``base.resume`` the seeds whose files
    are complete are not run again), then the statistics, written to ``base.output`` if any."""
    if base.output is None:
        raise ValueError("an ensemble keeps its seeds in files: give it an output")
    runs = seed_runs(base, seeds)
    with locked(base.output):
        for run in runs:
            if base.resume and run.output is not None and os.path.exists(run.output):
                continue
            run_contact(run, progress)
        files = [r.output for r in runs if r.output is not None]
        pressures = [float(p) for p in runs[0].pressures or []]
        line = " ".join(["petsc-contact", "ensemble", *base.arguments()[1:]])
        record = ensemble_record(base, seeds, pressures, line)
        summary = summarise(seeds, files)
        if world().rank == 0:
            write_summary(base.output, summary, files, record)
    return EnsembleResult(summary, files)
