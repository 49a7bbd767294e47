"""Results as tables for analysis: every file the package writes as a pandas ``DataFrame``.

:func:`table_frame` takes rows (a run's table, or the ``scalars`` of the steps that
:func:`~petsc_contact.periodic_contact` returns); :func:`read_frame` reads a results file of
any kind (a run, an ensemble, a theory, a comparison, a squeeze test), finished or
``.partial``, its columns in the schema's order (:data:`~petsc_contact.io.schema.FRAMES`).
Rows of a run, an ensemble or a theory are indexed by ``step``, a squeeze test's by ``row``,
counted from 1 as the printed tables count.  The writers
label every dataset with HDF5 dimension scales (:func:`scale`, :func:`labelled`), so that
``xarray.open_dataset(path, engine="h5netcdf")`` gives arrays on named dimensions (``step``,
``x``, ``y``, ``seed``, ``wavevector``, ``iteration``, ``row``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from .schema import FRAMES


def table_frame(rows: Iterable[Mapping[str, Any]], kind: str | None = None) -> Any:
    """A ``DataFrame`` of the scalars, one row per step (index ``step`` from 1); the per-step
    arrays (histograms) stay in the rows and the file.  With the file ``kind`` (``periodic``,
    ``punch``), the columns :func:`read_frame` gives come first, in its order."""
    import pandas as pd

    rows = [{k: v for k, v in r.items() if np.ndim(v) == 0} for r in rows]
    frame = pd.DataFrame(rows, index=pd.RangeIndex(1, len(rows) + 1, name="step"))
    if kind in FRAMES:
        documented = [c for c in FRAMES[kind].columns if c in frame.columns]
        frame = frame[documented + [c for c in frame.columns if c not in documented]]
    return frame


def trusted(f: Any) -> np.ndarray:
    """Which steps of an open results file ``f`` can be used: converged and, where the file
    records it, accurate (docs/solvers.md)."""
    ok = np.asarray(f["converged"][:], dtype=bool)
    if "accurate" in f:
        ok &= np.asarray(f["accurate"][:], dtype=bool)
    return ok


def scale(group: Any, name: str, values: Any) -> Any:
    """Dataset ``name`` of the h5py ``group`` holding ``values``, made the dimension scale
    ``name`` (xarray's dimension of that name, with ``values`` as its coordinate)."""
    dataset = group.create_dataset(name, data=np.asarray(values))
    dataset.make_scale(name)
    return dataset


def labelled(group: Any, name: str, values: Any, scales: Sequence[Any]) -> Any:
    """Dataset ``name`` of the h5py ``group`` holding ``values``, its axes on the dimension
    ``scales`` in order (from :func:`scale`)."""
    dataset = group.create_dataset(name, data=np.asarray(values))
    for axis, dimension in enumerate(scales):
        dataset.dims[axis].attach_scale(dimension)
    return dataset


def group_name(solver: str) -> str:
    """The HDF5 group of ``solver`` in a comparison's file (a path's ``/`` as ``_``)."""
    return solver.replace("/", "_")


def file_kind(attributes: Mapping[str, Any]) -> str:
    """The kind of a results file from its root ``attributes``: ``compare`` for a file with
    solver groups (root attribute ``solvers``), else its ``geometry`` (a run's ``periodic``
    or ``punch``, ``periodic ensemble``, ``theory``; ``''`` when it has none)."""
    if "solvers" in attributes:
        return "compare"
    return str(attributes.get("geometry", ""))


def read_frame(path: str) -> Any:
    """The table of a results file as a ``DataFrame``: a run's steps, an ensemble's per-step
    statistics, a theory's predictions, a squeeze test's rows, or a comparison's iterations
    (index ``solver`` and ``iteration``); the columns the schema documents for its kind, in
    that order.

    Raises
    ------
    ValueError
        When the file is none of these kinds.
    """
    import h5py

    with h5py.File(path, "r") as f:
        kind = file_kind(f.attrs)
        if kind not in FRAMES:
            raise ValueError(
                f"'{path}' is not a file read_frame reads (kind '{kind}'; it reads "
                f"{', '.join(FRAMES)})"
            )
        if kind == "compare":
            return _compare_frame(f)
        return _step_frame(f, FRAMES[kind].columns, FRAMES[kind].index[0])


def _column(dataset: Any) -> np.ndarray:
    """A dataset's values, strings as ``str``."""
    import h5py

    return dataset.asstr()[...] if h5py.check_string_dtype(dataset.dtype) else dataset[...]


def _step_frame(group: Any, documented: Sequence[str], index: str = "step") -> Any:
    """The ``documented`` columns that ``group`` holds, one row per step (or per ``index``,
    counted from 1)."""
    import pandas as pd

    columns = {name: _column(group[name]) for name in documented if name in group}
    steps = len(next(iter(columns.values()), ()))
    return pd.DataFrame(columns, index=pd.RangeIndex(1, steps + 1, name=index))


def _compare_frame(f: Any) -> Any:
    """A comparison's iterations: each solver's group in order, on ``solver`` and
    ``iteration``."""
    import pandas as pd

    documented = FRAMES["compare"].columns
    parts = {}
    for solver in json.loads(f.attrs["solvers"]):
        group = f[group_name(solver)]
        index = pd.Index(group["iteration"][...], name="iteration")
        parts[solver] = pd.DataFrame(
            {name: group[name][...] for name in documented if name in group}, index=index
        )
    return pd.concat(parts, names=["solver"]) if parts else pd.DataFrame(columns=documented)


def ensemble_statistics(values: np.ndarray) -> dict[str, np.ndarray]:
    """Mean, standard deviation (ddof 1) and standard error over axis 0 (the seeds).

    Non-finite entries (e.g. a step that did not converge) are left out per column.
    """
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    count = ok.sum(axis=0)
    mean = np.where(ok, v, 0.0).sum(axis=0) / np.maximum(count, 1)
    dev = np.where(ok, v - mean, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.sqrt((dev * dev).sum(axis=0) / (count - 1))
        sem = std / np.sqrt(count)
    mean = np.where(count > 0, mean, np.nan)
    return {
        "mean": mean,
        "std": np.where(count > 1, std, np.nan),
        "sem": np.where(count > 1, sem, np.nan),
        "count": count,
    }
