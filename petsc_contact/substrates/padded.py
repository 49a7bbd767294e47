"""A free substrate seen as a periodic one on its zero-padded cell (docs/formulation.md).

The free surface's compliance on an ``nx x ny`` footprint is the circulant convolution with
the pixel influence function on the ``2nx x 2ny`` zero-padded grid, read back on the
footprint (Hockney 1970; :class:`~petsc_contact.substrates.substrate.FreeSubstrate`).  That
circulant ``G`` is positive definite, and so is its inverse ``C``: the stiffness of the
padded cell.  Posed in the displacement of the whole padded cell, with no traction off the
footprint (the natural condition of an unknown with no bound and no interaction there), the
energy ``1/2 u^T C u`` is the free surface's: minimising over the padded pixels leaves the
Schur complement ``(G_FF)^-1``, the inverse of the footprint's compliance.

:class:`PaddedCell` gives ``C`` with its mean mode taken out, a
:class:`~petsc_contact.substrates.substrate.PeriodicSubstrate` on the padded grid: the mean
mode is the punch's rigid approach, held by the force (``p0 = F / A_pad``) or by the approach
(a spring of stiffness :attr:`PaddedCell.mean_stiffness`, ``c0 = 1/G(q = 0)``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.grid import Grid
from ..devices.fft import FFT
from .substrate import FreeSubstrate


class PaddedCell:
    """The stiffness of ``body``'s zero-padded cell without its mean mode (module docstring).

    Parameters
    ----------
    body
        The free substrate.
    footprint
        The ``nx x ny`` footprint grid.
    fft
        The FFT of the padded ``2nx x 2ny`` grid (``footprint.padded()``), whose spectrum
        block :meth:`stiffness` is laid out on.
    """

    def __init__(self, body: FreeSubstrate, footprint: Grid, fft: FFT) -> None:
        self.body = body
        padded = footprint.padded()
        kernel = body.compliance_kernel(footprint.shape, footprint.spacing, padded.rows)
        (self.mean_compliance,) = padded.sum(float(np.sum(kernel)))  # G(q = 0)
        fft.real[...] = fft.device.asarray(kernel)
        fft.forward()
        self._compliance = fft.spectrum.real.copy()  # G on the padded spectrum block
        fft.real[...] = 0.0

    @property
    def modulus(self) -> float:
        """The body's ``E*``."""
        return self.body.modulus

    @property
    def name(self) -> str:
        """The body's name."""
        return self.body.name

    @property
    def mean_stiffness(self) -> float:
        """``c0 = 1/G(q = 0)``: the pressure of a uniform displacement of the padded cell."""
        return 1.0 / self.mean_compliance

    def stiffness(self, q: Any) -> Any:
        """``C = 1/G`` on the padded spectrum block, 0 at ``q = 0`` (``q`` only gives the
        block's shape: ``C`` is not a function of ``|q|`` alone)."""
        if q.shape != self._compliance.shape:
            raise ValueError("the padded cell's stiffness is laid out on its own FFT's block")
        return (q != 0) / self._compliance

    def mean_mode_compliance(self, q0: float, interfacial_stiffness: float) -> float:
        """``1/K`` held by ``interfacial_stiffness`` ``K > 0``, else ``G(q = 0)``."""
        if interfacial_stiffness > 0:
            return 1.0 / interfacial_stiffness
        return self.mean_compliance
