"""The file of ``petsc-contact theory``: Persson's predictions from a map's spectrum, as HDF5.

The spectrum (``wavevector``, ``psd``) is on the dimension ``wavevector``, the predictions
(``nominal_pressure``, ``mean_gap``, ``stiffness``, ``area_fraction``) on ``step`` (1, 2, ...
as the printed table counts); the single numbers (:meth:`Prediction.scalars`) and the run
record are root attributes, beside ``geometry = 'theory'``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.atomic import atomic_h5
from ..io.results import labelled, scale
from ..io.schema import COORDINATES, THEORY, Entry, annotate, write_attributes
from .predictions import Prediction


def write_theory(
    path: str,
    result: Prediction,
    record: dict[str, Any],
    length_unit: str = "",
    pressure_unit: str = "",
) -> None:
    """Write ``result`` and the run ``record`` to ``path`` (atomically), its units those of
    the map (``length_unit``) and the modulus (``pressure_unit``)."""
    with atomic_h5(path) as f:
        step = scale(f, "step", np.arange(1, len(result.nominal_pressure) + 1))
        wavevector = scale(f, "wavevector", result.wavevector)
        for name in THEORY:
            if name != "wavevector":
                labelled(f, name, getattr(result, name), [wavevector if name == "psd" else step])
        write_attributes(f, {**record, "geometry": "theory", **result.scalars()})
        annotate(f, _entry, length_unit, pressure_unit)


def _entry(name: str) -> Entry:
    """The schema entry of a theory file's dataset."""
    return THEORY[name] if name in THEORY else COORDINATES[name]
