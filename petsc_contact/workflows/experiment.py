"""A measured squeeze test: the interfacial stiffness of a measured ``p(s)`` table (paper
Eq. C3), written as one HDF5 file (``petsc-contact experiment``)."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np

from ..conventions.validation import positive
from ..conventions.warnings import DoubtfulTable, user_level
from ..io.atomic import atomic_h5
from ..io.lock import check_writable
from ..io.results import labelled, scale
from ..io.schema import EXPERIMENT, FRAMES, annotate
from ..io.tables import load_table
from ..physics.theory import block_corrected_stiffness

FORMULA = "K* = dp/ds (2nd-order differences), K = K*/(1 - K* d/E')"


@dataclass
class Experiment:
    """A squeeze test's table and the stiffness found from it, one value per row."""

    pressure: np.ndarray
    displacement: np.ndarray
    measured_stiffness: np.ndarray  # K* = dp/ds
    stiffness: np.ndarray  # K, the block's own compliance taken out


def squeeze_test(
    table: str, modulus: float, thickness: float, output: str, plot: str | None = None
) -> Experiment:
    """Paper Eq. C3 on the measured ``p(s)`` ``table`` (two columns) of a block of
    ``modulus`` E' and ``thickness`` d: written whole to ``output`` (HDF5) and, if given,
    drawn as ``plot`` (PNG).

    Raises
    ------
    ValueError
        A modulus or thickness that is not positive, or a table that is not two columns of
        numbers.
    StorageError
        ``output`` cannot be written.
    """
    for name, value in (("modulus", modulus), ("thickness", thickness)):
        positive(f"--{name}", value)
    rows = load_table(table, 2)
    check_writable(output)
    p, disp = rows[:, 0], rows[:, 1]
    found = Experiment(p, disp, *block_corrected_stiffness(p, disp, modulus, thickness))
    falling = int(np.count_nonzero(found.measured_stiffness <= 0))
    compressed = int(np.count_nonzero(np.isnan(found.stiffness))) - falling
    for count, why in (
        (falling, "the pressure does not rise with the displacement (K* <= 0)"),
        (compressed, "the block's own compression dominates (K* d/E' >= 1, Eq. C3)"),
    ):
        if count:
            warnings.warn(
                f"K is NaN at {count} of {len(p)} rows of '{table}': {why}",
                DoubtfulTable,
                stacklevel=user_level(),
            )
    with atomic_h5(output) as f:
        row = scale(f, "row", np.arange(1, len(p) + 1))
        for name in FRAMES["experiment"].columns:
            labelled(f, name, getattr(found, name), [row])
        f.attrs.update(
            geometry="experiment",
            block_modulus=modulus,
            thickness=thickness,
            table=os.path.abspath(table),
            formula=FORMULA,
        )
        annotate(f, EXPERIMENT.__getitem__)
    if plot:
        from ..io.plot import plot_experiment

        plot_experiment(plot, p, found.measured_stiffness, found.stiffness)
    return found
