"""The element-wise passes of the package's solver, written once with the array module's
operators (NumPy or CuPy): the ``cpu-array`` device's, and the base of the GPU's fused
kernels (:mod:`~petsc_contact.devices.fused`)."""

from __future__ import annotations

from types import ModuleType
from typing import Any


class ArrayPasses:
    """The element-wise passes of the constrained CG and the spectral operators, written
    once for any array module ``xp`` with NumPy's interface (NumPy or CuPy).

    The same contracts as the numba passes of :mod:`~petsc_contact.devices.compiled`
    (which the PETSc path uses): bounds are a float or an array of the vector's length;
    every reduction is returned as a Python number (one host synchronisation on a GPU).
    """

    def __init__(self, xp: ModuleType) -> None:
        self.xp = xp

    def free_set(
        self, x: Any, g: Any, lower: Any, upper: Any, free: Any, r: Any
    ) -> tuple[float, int, int, int]:
        """``free <- (x > lower | g < 0) & ~(x >= upper & g < 0)``, ``r <- g`` on it;
        returns ``(r.r, changed, joined, free count)``."""
        xp = self.xp
        pull = g < 0.0
        now = ((x > lower) | pull) & ~((x >= upper) & pull)
        changed = int(xp.count_nonzero(now != free))
        joined = int(xp.count_nonzero(now & ~free))
        free[...] = now
        xp.multiply(g, now, out=r)
        return float(xp.dot(r, r)), changed, joined, int(xp.count_nonzero(now))

    def restrict_dot(self, z: Any, free: Any, r: Any) -> float:
        """``z <- z`` on the free set, ``0`` elsewhere; returns ``r.z``."""
        self.xp.multiply(z, free, out=z)
        return float(self.xp.dot(r, z))

    def restrict(self, out: Any, x: Any, free: Any) -> None:
        """``out <- x`` on the free set, ``0`` elsewhere (``out`` may be ``x``)."""
        self.xp.multiply(x, free, out=out)

    def fill_outside(self, out: Any, x: Any, inside: Any) -> None:
        """``out <- x`` off ``inside`` (``out`` kept on it)."""
        self.xp.copyto(out, x, where=~inside)

    def extend_direction(self, z: Any, d: Any, free: Any, beta: float, r: Any) -> float:
        """``z <- z + beta d`` with ``d`` restricted to the free set; returns ``r.z``."""
        z += beta * (d * free)
        return float(self.xp.dot(r, z))

    def advance(self, x: Any, d: Any, alpha: float, lower: Any, upper: Any) -> tuple[int, int]:
        """``x <- x + alpha d``; how many entries fell below ``lower`` and rose above ``upper``."""
        xp = self.xp
        self.axpy(alpha, d, x)
        return int(xp.count_nonzero(x < lower)), int(xp.count_nonzero(x > upper))

    def clip(self, x: Any, lower: Any, upper: Any) -> None:
        """``x <- min(max(x, lower), upper)``."""
        xp = self.xp
        xp.maximum(x, lower, out=x)
        xp.minimum(x, upper, out=x)

    def axpy(self, a: float, x: Any, y: Any) -> None:
        """``y <- y + a x``."""
        y += a * x

    def scale_entries(self, values: Any, multiplier: Any, single: Any, factor: float) -> float:
        """Multiply a spectrum's float view by a real multiplier (one entry per complex
        value) times ``factor``; return ``sum(w k |s|^2)`` before it (``w = 1`` on
        ``single``, 2 elsewhere; Parseval)."""
        xp = self.xp
        if factor != 1.0:
            multiplier = multiplier * factor  # a temporary of the pass
        pairs = values.reshape(-1, 2)
        power = pairs[:, 0] * pairs[:, 0]  # |s|^2, half a field
        power += pairs[:, 1] * pairs[:, 1]
        once = xp.dot(multiplier[single], power[single])
        total = xp.dot(multiplier, power)
        pairs *= multiplier[:, None]
        return float(2.0 * total - once)

    def add_dot(self, y: Any, base: Any, d: Any) -> float:
        """``y <- y + base``; returns ``d.base``."""
        y += base
        return float(self.xp.dot(d, base))

    def changed_count(self, before: Any, now: Any) -> int:
        """How many entries of two boolean masks differ."""
        return int(self.xp.count_nonzero(before != now))
