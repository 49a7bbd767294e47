"""The constrained CG's passes as fused CuPy kernels: the GPU's :class:`ArrayPasses`.

:class:`~petsc_contact.devices.passes.ArrayPasses` writes each pass with the array module's
operators, which on a GPU makes one kernel and one full-size temporary per operator: ``y += a
x`` reads and writes twice the memory it needs, the free set's test makes seven masks.  Here
the passes that touch whole fields every iteration are one ``ElementwiseKernel`` each.  The
sums and counts stay CuPy's own reductions (``dot``, ``count_nonzero``: cuBLAS and CUB), read
on the host in one transfer per pass: a ``ReductionKernel`` of CuPy's to one scalar does not
use CUB, and took the CG's iterations at 8192^2 from 44 to 209 ms on one H100 (docs/gpu.md).
The contracts are :class:`ArrayPasses`'s, which the stand-in (``cpu-array``) runs on NumPy:
``pytest -m gpu`` checks the two against each other.

Only the ``gpu`` device uses these passes (:attr:`~petsc_contact.devices.device.Device.passes`);
CuPy is imported when they are first compiled.
"""

from __future__ import annotations

from functools import cache
from types import ModuleType
from typing import Any

from .passes import ArrayPasses


@cache
def _kernels() -> dict[str, Any]:
    """The kernels, compiled by CuPy on first use (and cached by it on disk)."""
    import cupy

    return {
        "free_set": cupy.ElementwiseKernel(
            "float64 x, float64 g, float64 lower, float64 upper",
            "bool mask, float64 r, int8 code",
            """
            const bool pull = g < 0.0;
            const bool now = (x > lower || pull) && !(x >= upper && pull);
            code = (now != mask ? 1 : 0) + (now && !mask ? 2 : 0);
            mask = now;
            r = now ? g : 0.0;
            """,
            "petsc_contact_free_set",
        ),
        "axpy": cupy.ElementwiseKernel(
            "float64 a, float64 x", "float64 y", "y += a * x", "petsc_contact_axpy"
        ),
        "extend": cupy.ElementwiseKernel(
            "float64 d, bool mask, float64 beta",
            "float64 z",
            "if (mask) z += beta * d;",
            "petsc_contact_extend",
        ),
    }


class FusedPasses(ArrayPasses):
    """:class:`ArrayPasses` on CuPy with the per-iteration passes fused (module docstring)."""

    def __init__(self, xp: ModuleType) -> None:
        super().__init__(xp)
        self._code: Any = None  # the free set's per-entry change codes, kept between calls

    def free_set(
        self, x: Any, g: Any, lower: Any, upper: Any, free: Any, r: Any
    ) -> tuple[float, int, int, int]:
        xp, k = self.xp, _kernels()
        if self._code is None or self._code.shape != free.shape:
            self._code = xp.empty(free.shape, dtype=xp.int8)
        code = self._code  # each entry written by the kernel
        k["free_set"](x, g, self._bound(lower), self._bound(upper), free, r, code)
        values = xp.stack(  # CuPy's reductions (CUB's), one transfer; code is 0, 1 or 3
            [
                xp.dot(r, r),
                xp.count_nonzero(code).astype(float),
                xp.count_nonzero(code > 1).astype(float),
                xp.count_nonzero(free).astype(float),
            ]
        ).get()
        return float(values[0]), int(values[1]), int(values[2]), int(values[3])

    def extend_direction(self, z: Any, d: Any, free: Any, beta: float, r: Any) -> float:
        _kernels()["extend"](d, free, float(beta), z)
        return float(self.xp.dot(r, z))

    def advance(self, x: Any, d: Any, alpha: float, lower: Any, upper: Any) -> tuple[int, int]:
        xp = self.xp
        self.axpy(alpha, d, x)
        counts = xp.stack([xp.count_nonzero(x < lower), xp.count_nonzero(x > upper)]).get()
        return int(counts[0]), int(counts[1])

    def axpy(self, a: float, x: Any, y: Any) -> None:
        _kernels()["axpy"](float(a), x, y)

    def _bound(self, value: Any) -> Any:
        """A bound as a kernel takes it: an array of the device, or a float."""
        return value if isinstance(value, self.xp.ndarray) else float(value)
