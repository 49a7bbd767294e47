"""Ensembles over surface realisations: one run per seed, then statistics over the seeds.

``petsc-contact ensemble`` and :func:`run_ensemble` run the same periodic scene for each
seed, each into its own resumable file ``OUT_seedK.h5`` (:func:`seed_runs`), with the same
pressures for every seed (:func:`ensemble_loads`), then write the mean, standard deviation
and standard error over seeds of every per-step quantity to ``OUT.h5``
(:func:`write_summary`; statistics by
:func:`~petsc_contact.io.results.ensemble_statistics`).

What an earlier ensemble left on the same output is never joined blindly
(:func:`seeds_to_run`): without ``resume`` or ``overwrite`` it is refused; ``overwrite``
clears it first; ``resume`` keeps the seed files and continues the interrupted seed run
only where their ``parameters`` are this ensemble's (:func:`check_kept`), and refuses the
rest.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import warnings
from collections.abc import Sequence
from contextlib import suppress
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.grid import world
from ..conventions.units import pressure_value
from ..io.atomic import atomic_h5, on_root
from ..io.lock import OutputLock
from ..io.names import partial_path
from ..io.partial import check_same_run, read_attributes
from ..io.results import ensemble_statistics, labelled, scale, trusted
from ..io.schema import ENSEMBLE, annotate, ensemble_entry, write_attributes
from ..io.store import tidy
from .description import Run
from .runner import Progress, check_files, locked, run_contact, swept

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
    from .drivers import periodic_substrate
    from .scene import prepare_scene

    scene = prepare_scene(base.with_(seed=first_seed))
    body = periodic_substrate(base, scene)
    problem = PeriodicProblem(
        scene.grid, scene.fft, scene.heights, base.modulus_value, substrate=body
    )
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


def recorded_parameters(run: Run) -> dict[str, Any]:
    """The ``parameters`` a run of a generated surface records, found without making the
    surface: its description with what its defaults become (the sides, their unit, the
    cutoff ratio) and a periodic run's sweep as its pressures."""
    from ..conventions.grid import grid_for
    from ..conventions.units import Lengths
    from ..physics.surface import nyquist_ratio
    from .scene import given_lengths, shape_of

    lengths = given_lengths(run) or Lengths((1.0,), None)
    grid = grid_for(shape_of(run), lengths.pair)
    cutoff = nyquist_ratio(grid) if run.cutoff_ratio is None else run.cutoff_ratio
    out = run.parameters() | {
        "length": list(grid.lengths),
        "length_unit": lengths.unit or "",
        "cutoff_ratio": cutoff,
    }
    if run.geometry == "periodic" and run.sweep is not None:
        out |= {"pressures": ensemble_loads(run, run.seed), "sweep": None}
    return out


def check_kept(path: str, run: Run) -> None:
    """``ValueError`` (one line) unless the file ``path``, a run's output or its ``.partial``
    file, was written by ``run``: its ``parameters`` are the ones ``run`` records
    (:func:`recorded_parameters`, compared by
    :func:`~petsc_contact.io.partial.check_same_run`).  Where the file is kept is not compared
    (it is found by its place), and the loads given with a unit are compared as given (their
    values in the run's units, ``*_resolved``, follow from them)."""
    try:
        theirs = json.loads(read_attributes(path)["parameters"])
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"cannot read the parameters of '{path}' ({exc})") from None
    derived = {k: v for k, v in theirs.items() if k.endswith("_resolved")}
    mine = recorded_parameters(run) | derived | {"output": theirs.get("output")}
    check_same_run(path, theirs, mine)


def seeds_to_run(base: Run, runs: Sequence[Run]) -> list[Run]:
    """The seed runs of ``runs`` still to compute, once what an earlier ensemble on
    ``base.output`` left is dealt with (the caller holds the output's lock).

    With ``base.overwrite`` every file of the earlier ensemble is removed first; with
    ``base.resume`` a complete seed file is kept and an interrupted seed run continues
    where their ``parameters`` are this ensemble's, and any other is refused; with
    neither, an earlier ensemble's summary or seed files are refused.  Refusals are
    ``ValueError`` with one line."""
    if base.overwrite:
        on_root(world(), lambda: clear_ensemble(str(base.output)))
        return list(runs)
    if not base.resume:
        left = [os.path.basename(p) for p in _earlier(base, runs) if os.path.exists(p)]
        if left:
            folder = os.path.dirname(os.path.abspath(str(base.output)))
            raise ValueError(
                f"an earlier ensemble left {_listed(left)} in {folder}: --resume continues it, "
                "--overwrite deletes it and starts afresh"
            )
        return list(runs)
    return [run for run in runs if not _kept(run)]


def _listed(paths: Sequence[str], shown: int = 3) -> str:
    """``a, b, c and 5 more``."""
    more = f" and {len(paths) - shown} more" if len(paths) > shown else ""
    return ", ".join(paths[:shown]) + more


def _earlier(base: Run, runs: Sequence[Run]) -> list[str]:
    """The files an earlier ensemble on ``base.output`` with these seeds would have left."""
    seeds = [p for run in runs if run.output for p in (run.output, partial_path(run.output))]
    return [str(base.output), *seeds]


def _kept(run: Run) -> bool:
    """Whether the seed run's file is complete and this ensemble's (then what its writer
    left is tidied); ``ValueError`` when its file or its ``.partial`` is another run's."""
    assert run.output is not None
    for path in (run.output, partial_path(run.output)):
        if os.path.exists(path):
            try:
                check_kept(path, run)
            except ValueError as exc:
                raise ValueError(
                    f"{exc}, not this ensemble's: --overwrite starts the ensemble afresh"
                ) from None
            if path == run.output:
                tidy(path)
                return True
            return False
    return False


def clear_ensemble(output: str) -> None:
    """Remove the summary ``output`` and every seed's files beside it (``OUT_seedK.h5``, its
    table, what an interrupted seed run left), each seed's output locked meanwhile."""
    folder, name = os.path.split(os.path.abspath(output))
    seed = re.compile(rf"({re.escape(name.removesuffix('.h5'))}_seed\d+)\.(h5|csv)\b.*")
    files: dict[str, list[str]] = {}
    for entry in os.listdir(folder):
        found = seed.fullmatch(entry)
        if found:
            files.setdefault(found.group(1), []).append(os.path.join(folder, entry))
    with suppress(FileNotFoundError):
        os.remove(output)
    for stem, paths in sorted(files.items()):
        lock = OutputLock(os.path.join(folder, f"{stem}.h5"))
        with lock:
            for path in paths:
                if path == lock.path:
                    continue
                if os.path.isdir(path):
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    with suppress(FileNotFoundError):
                        os.remove(path)


def summarise(seeds: Sequence[int], files: Sequence[str]) -> dict[str, np.ndarray]:
    """Per-seed tables of every quantity (NaN where a step did not converge) and their
    statistics over seeds, read from the seeds' files."""
    import h5py

    tables: dict[str, list[np.ndarray]] = {}
    pressure = np.empty(0)
    for path in files:
        with h5py.File(path, "r") as f:
            ok = trusted(f)
            pressure = f["nominal_pressure"][:]
            for q in QUANTITIES:
                if q in f:
                    tables.setdefault(q, []).append(np.where(ok, f[q][:], np.nan))
    summary: dict[str, np.ndarray] = {"seeds": np.array(seeds), "nominal_pressure": pressure}
    for q, rows in tables.items():
        summary[q] = np.array(rows)
        summary.update({f"{q}_{name}": v for name, v in ensemble_statistics(summary[q]).items()})
    return summary


def seed_scales(files: Sequence[str]) -> tuple[np.ndarray, dict[str, str]]:
    """Each seed's rms height (its file's ``rms_height``: what a unit-free ensemble's figure
    scales that seed's stiffness by, ``K h_rms/E*``) and the seeds' units (``length``,
    ``pressure``; ``""`` where they have none), as
    :func:`~petsc_contact.io.plot.plot_ensemble` takes them."""
    import h5py

    heights, units = [], {"length": "", "pressure": ""}
    for path in files:
        with h5py.File(path, "r") as f:
            heights.append(float(f.attrs["rms_height"]))
            units = {k: str(f.attrs.get(f"{k}_unit", "")) for k in ("length", "pressure")}
    return np.array(heights), units


def mean_rms_height(files: Sequence[str]) -> float:
    """Deprecated (until 0.3.0): the seeds' mean rms height; :func:`seed_scales` gives each
    seed's, which an ensemble's figure scales that seed by."""
    warnings.warn(
        "workflows.seeds.mean_rms_height is deprecated: use seed_scales",
        DeprecationWarning,
        stacklevel=2,
    )
    return float(np.mean(seed_scales(files)[0]))


def write_summary(
    path: str, summary: dict[str, np.ndarray], files: Sequence[str], record: dict[str, Any]
) -> None:
    """The ensemble's ``OUT.h5``: the summary, the seeds' files (relative to its folder, with
    each one's ``created`` stamp) and the record (atomically), every dataset on the
    dimensions ``seed`` (the seeds) and ``step`` (from 1)."""
    folder = os.path.dirname(os.path.abspath(path))
    with atomic_h5(path) as out:
        write_attributes(out, {"geometry": "periodic ensemble", **record})
        out.attrs["seed_files"] = json.dumps([os.path.relpath(p, folder) for p in files])
        out.attrs["seed_created"] = json.dumps([_identity(p)[0] for p in files])
        seed = scale(out, "seed", summary["seeds"])
        step = scale(out, "step", np.arange(1, len(summary["nominal_pressure"]) + 1))
        for name, values in summary.items():
            labelled(out, name, values, [seed] if name == "seeds" else [seed, step][-values.ndim :])
        out.attrs["complete"] = True
        annotate(out, ensemble_entry)


def seed_files(path: str, ensemble: Any) -> list[str]:
    """The seeds' files of the open ensemble file ``ensemble`` at ``path``, found from its
    folder: its ``seed_files`` are relative to it (those of an earlier version, absolute: the
    file of that name beside it, else that path).  ``ValueError`` (one line) when one is
    missing, or is not the run the ensemble summarised: not of its seed, or not with the
    ``created`` stamp the ensemble recorded (``seed_created``; an earlier version's file
    records none)."""
    folder = os.path.dirname(os.path.abspath(path))
    names = json.loads(ensemble.attrs["seed_files"])
    found = []
    for name in names:
        beside = os.path.join(folder, os.path.basename(name) if os.path.isabs(name) else name)
        seed = beside if os.path.exists(beside) or not os.path.isabs(name) else name
        if not os.path.exists(seed):
            raise ValueError(f"'{path}': its seeds' files are needed, and {seed} is missing")
        found.append(seed)
    stamps = json.loads(ensemble.attrs.get("seed_created", "null"))
    for seed, stamp, k in zip(found, stamps or (), ensemble["seeds"][...], strict=False):
        created, theirs = _identity(seed)
        if (created, theirs) != (stamp, int(k)):
            raise ValueError(
                f"'{path}': {seed} is not the run of seed {k} it summarises (seed {theirs}, "
                f"created {created or '?'}; the ensemble's was created {stamp}): the "
                "ensemble's --resume summarises the seed files there again"
            )
    return found


def _identity(path: str) -> tuple[str, int | None]:
    """The ``created`` stamp and the seed of run file ``path`` (``""`` and ``None`` where it
    records none or cannot be read)."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            seed = json.loads(f.attrs.get("parameters", "{}")).get("seed")
            return str(f.attrs.get("created", "")), seed
    except (OSError, ValueError):
        return "", None


def ensemble_record(
    base: Run, seeds: Sequence[int], pressures: list[float], command_line: str
) -> dict[str, Any]:
    """What reproduces an ensemble: its command, description, versions, PETSc options and
    device (:func:`~petsc_contact.workflows.runner.provenance`)."""
    from .runner import provenance

    return {
        "command_line": command_line,
        "parameters": base.parameters()
        | {"command": "ensemble", "seeds": list(seeds), "pressures": pressures, "sweep": None},
        **provenance(base),
    }


def run_ensemble(
    base: Run, seeds: Sequence[int], progress: Progress | bool | None = True
) -> EnsembleResult:
    """Run ``base`` for every seed (each resumable; with ``base.resume`` the seeds whose files
    are complete are not run again; what an earlier ensemble left: :func:`seeds_to_run`),
    then the statistics, written to ``base.output``."""
    if base.output is None:
        raise ValueError("an ensemble keeps its seeds in files: give it an output")
    check_files(base)  # before anything is computed
    runs = seed_runs(base, seeds)
    for run in runs:  # before any lock is taken
        check_files(run)
    with locked(base.output):
        for run in seeds_to_run(base, runs):
            run_contact(run, progress)
        files = [r.output for r in runs if r.output is not None]
        pressures = [float(p) for p in runs[0].pressures or []]
        line = " ".join(["petsc-contact", "ensemble", *base.arguments()[1:]])
        record = ensemble_record(base, seeds, pressures, line)
        summary = summarise(seeds, files)
        if world().rank == 0:
            write_summary(base.output, summary, files, record)
    return EnsembleResult(summary, files)
