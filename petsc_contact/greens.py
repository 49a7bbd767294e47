"""Surface Green's functions of the elastic half-space (pure numpy).

Periodic (paper Appendix A): in Fourier space the pressure that holds a surface displacement
``u(q)`` is ``p(q) = E* |q| / 2 u(q)`` for ``q != 0``; the ``q = 0`` mode carries the mean
load and no displacement, so the stiffness kernel is 0 there.  Evaluated on the DFT
wavevectors this is exact for a single sine wave.
"""

from __future__ import annotations

import numpy as np


def periodic_stiffness(q: np.ndarray, modulus: float) -> np.ndarray:
    """Stiffness kernel ``E* |q| / 2`` (pressure per displacement), 0 at ``q = 0``."""
    return 0.5 * modulus * np.asarray(q, dtype=float)


def periodic_compliance(q: np.ndarray, modulus: float, q_zero: float) -> np.ndarray:
    """Compliance kernel ``2 / (E* |q|)``, with ``|q| = q_zero`` used at ``q = 0``.

    The ``q = 0`` value is a convention (the stiffness is singular there); it is only used
    to precondition, where any positive value keeps the preconditioner positive definite.
    """
    q = np.asarray(q, dtype=float)
    return 2.0 / (modulus * np.where(q > 0, q, q_zero))
