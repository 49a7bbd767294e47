"""Results as tables for analysis: the scalars of every step as a pandas ``DataFrame``.

:func:`table_frame` takes rows (a run's table, or the ``scalars`` of the steps that
:func:`~petsc_contact.periodic_contact` returns); :func:`read_frame` reads a results file,
finished or ``.partial``.  Rows are indexed by ``step``, counted from 1 as the printed table
counts.  (For the maps, ``xarray.open_dataset(path, engine="h5netcdf")`` gives labelled
arrays: ``step``, ``x`` and ``y`` are dimension scales of the file.)
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np


def table_frame(rows: Iterable[Mapping[str, Any]]) -> Any:
    """A ``DataFrame`` of the scalars, one row per step (index ``step`` from 1); the per-step
    arrays (histograms) stay in the rows and the file."""
    import pandas as pd

    rows = [{k: v for k, v in r.items() if np.ndim(v) == 0} for r in rows]
    return pd.DataFrame(rows, index=pd.RangeIndex(1, len(rows) + 1, name="step"))


def trusted(f: Any) -> np.ndarray:
    """Which steps of an open results file ``f`` can be used: converged and, where the file
    records it, accurate (docs/solvers.md)."""
    ok = np.asarray(f["converged"][:], dtype=bool)
    if "accurate" in f:
        ok &= np.asarray(f["accurate"][:], dtype=bool)
    return ok


def read_frame(path: str) -> Any:
    """The step table of a results file (its one-entry-per-step datasets) as a ``DataFrame``."""
    import h5py

    with h5py.File(path, "r") as f:
        columns = {
            name: [v.decode() if isinstance(v, bytes) else v for v in f[name][...]]
            for name in f
            if name != "step"
            and getattr(f[name], "ndim", 0) == 1
            and f[name].shape[0] == f["converged"].shape[0]
        }
    steps = len(next(iter(columns.values()), []))
    return table_frame({k: v[i] for k, v in columns.items()} for i in range(steps))
