"""The periodic contact's preconditioner: the inverse Hessian held by the interfacial
stiffness, with the exact Schur form on a few contact pixels and the two-level form on many
(docs/solvers.md).  Used by :class:`~petsc_contact.geometries.periodic.PeriodicProblem`."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.grid import Grid
from ..devices.fft import FFT, ArrayFFT
from ..numerics.schur import ContactSchur, response_quarter
from .coarse import CoarseSpace, TwoLevelOptions, add_correction, input_sum
from .operator import FourierOperator

SCHUR_MAX = 4096  # the most bound variables for the Schur form (dense matrix: 134 MB)
SETTLE_FRACTION = 0.1  # a contact count changing more than this per iteration is still moving
REBUILD_FRACTION = 0.01  # the coarse space is rebuilt when this much of the set has changed


class MeanModePreconditioner(FourierOperator):
    """The inverse of the Hessian held by the contact's interfacial stiffness, with its
    ``q = 0`` entry adapted to the contact set.

    On the open pixels the contact spots hold the surface like a layer of springs of the
    interfacial stiffness ``K_i`` (:func:`~petsc_contact.physics.greens.held_compliance`), so the
    multiplier is ``1/(E*|q|/2 + K_i)`` (scaled like the Hessian), with ``K_i`` an estimate
    for the current load.  The free compliance ``2/(E*|q|)`` misses exactly that support:
    at long wavelengths it over-predicts the response of the open surface, most of all for
    the mean mode, which ``K`` alone does not hold at all.

    With ``m`` isolated pixels at the bound a uniform gap change meets a stiffness of at
    most ``m k / n^2`` (``k`` the Hessian's diagonal), so the ``q = 0`` entry used is the
    larger of the two compliances, ``max(1/K_i, 1/(m k))``: a few contact pixels are softer
    than any estimate of ``K_i`` from the continuum.

    With at most :attr:`schur_max` variables at the bound it is instead the exact inverse of
    the Hessian on the free set, built on the unsupported inverse ``1/K``
    (:class:`~petsc_contact.numerics.schur.ContactSchur`: two FFT round trips and a dense solve of
    the contact pixels' bordered system per application), which
    makes each CG step exact on the current contact set; :func:`schur_limit` keeps its
    factorisation, once per contact set, within about ten FFT round trips.

    Above that, up to the fraction ``options.max_fraction`` of the grid in contact, it is the
    two-level form (:class:`~petsc_contact.backend.coarse.CoarseSpace`): the same inverse with
    the reactions piecewise constant on the contact pixels of ``b x b`` blocks (``b`` grown
    until the aggregates are at most :func:`coarse_limit`).  It is first built once the
    contact count changes by at most :data:`SETTLE_FRACTION` per iteration (until then the
    held compliance serves), and rebuilt when the count has settled again and more than
    :data:`REBUILD_FRACTION` of the contact set has changed since the last build; in between
    the coarse space of an older set is kept (it stays symmetric positive semi-definite) and
    the recurrence goes on.
    Called by :class:`~petsc_contact.backend.cg.PolonskyKeer` through :meth:`adapt`.

    With :meth:`use_single` the Fourier form's round trip, alone and within the two-level
    form, is made in ``float32`` (``-petsc_contact_pc_float32``): the field, its spectrum
    and the multiplier, the answer written back into the CG's ``float64`` field.  The CG's
    residual, the Hessian and the exact Schur form stay ``float64`` (the Schur form's image
    ``H z = r + lambda`` stands in for a Hessian application, which needs ``z`` exact).
    """

    def __init__(self, grid: Grid, fft: FFT, hessian: FourierOperator, schur_max: int) -> None:
        zeros = fft.device.xp.zeros(fft.spectrum.shape)
        super().__init__(grid, fft, zeros)  # filled by invert
        self._hessian = hessian
        self.schur_max = schur_max  # the Schur form's largest bound set
        self.options = TwoLevelOptions()  # the two-level form's: the solve's settings
        self.device = fft.device
        self.hessian_diagonal = 1.0
        self.base_mean_mode = self.mean_mode = 0.0
        self.expected_bound_count = 0  # contact pixels Persson's theory expects at this load
        self.support = 0.0  # the interfacial stiffness held by (normalised), set by invert
        self._filled = 0.0  # the support the multiplier holds now (0 in the Schur form)
        self.correction: ContactSchur | CoarseSpace | None = None  # the set-dependent form
        self.builds = 0  # coarse spaces built since the last invert
        self._last_count = 0  # the bound count of the last adapt
        self._built_free: np.ndarray | None = None  # the free set the coarse space was built on
        self._quarter: Any = None  # G's quarter (of the device), made by a set-dependent form
        self._reactions: np.ndarray | None = None  # the Schur form's, of the last application
        self._fft32: ArrayFFT | None = None  # the float32 round trip's FFT (use_single)
        self._multiplier32: Any = None  # the multiplier in float32, made when first used

    @property
    def schur(self) -> ContactSchur | None:
        """The exact Schur form, when it is in use."""
        return self.correction if isinstance(self.correction, ContactSchur) else None

    @property
    def coarse(self) -> CoarseSpace | None:
        """The two-level form's coarse space, when it is in use."""
        return self.correction if isinstance(self.correction, CoarseSpace) else None

    @property
    def two_level(self) -> bool:
        """Whether the two-level form is in use (the CG then limits the set's growth more)."""
        return self.coarse is not None

    def invert(
        self, support: float, hessian_diagonal: float, mean_mode: float, expected_bound_count: int
    ) -> None:
        """Become the inverse of the Hessian plus ``support`` (the Hessian's diagonal entry
        is ``hessian_diagonal``), with ``mean_mode`` as its ``q = 0`` entry; ``support >= 0``
        is the interfacial stiffness in the Hessian's normalised units, and
        ``expected_bound_count`` the contact the load is expected to bring (a scale for the
        CG's growth limit).  The two-level form's options are :attr:`options` (the solve's
        settings: :class:`~petsc_contact.backend.coarse.TwoLevelOptions`).

        Computed in place, with no copy of the kernel kept: with ``N = n^2`` the normalised
        multipliers are ``c K/N`` for the Hessian, ``s = c K_i/N`` for the support and
        ``N^-2/(c K/N + s)`` for the inverse, whose ``q = 0`` entry is ``1/(N c K_i)``.
        Between loads the Hessian changes only by its scale ``c`` (the periodic problem
        rescales it in place), so a column of ``1/K`` already computed is rescaled by the
        ratio of the diagonals instead of computed again (one FFT round trip saved per load).
        """
        self.support = support
        self.expected_bound_count = int(expected_bound_count)
        self._fill(support)
        self.base_mean_mode = mean_mode
        self._set_mean_mode(self.base_mean_mode)
        if self._quarter is not None:  # the Hessian was rescaled: so is its inverse's column
            self._quarter *= self.hessian_diagonal / hessian_diagonal
        self.hessian_diagonal = hessian_diagonal
        self.correction = self._built_free = None
        self._last_count = self.builds = 0

    def use_single(self, single: bool) -> None:
        """Make the Fourier form's round trip in ``float32`` (``single``) or ``float64``
        (class docstring); ``ValueError`` in one line where the FFT is not the array module's
        (``--device cpu``, or several MPI ranks)."""
        if not single:
            self._fft32 = self._multiplier32 = None
        elif self._fft32 is None:
            if not isinstance(self.fft, ArrayFFT):
                raise ValueError(
                    "-petsc_contact_pc_float32 needs the array module's FFT: --device gpu or "
                    "cpu-array, on one MPI rank"
                )
            self._fft32 = ArrayFFT(self.grid, self.device, np.float32)

    def _fill(self, support: float) -> None:
        """The multiplier ``N^-2/(c K/N + support)`` in place (``q = 0``: set separately)."""
        self.set_inverse(self._hessian, support)
        self._filled = support
        self._multiplier32 = None

    def adapt(self, bound_count: int, free: np.ndarray) -> bool:
        """Adapt to ``bound_count`` variables at their bound (``free``: this rank's free mask).

        Returns whether the operator changed with the set (the same on every rank): always
        in the Schur form, on every build of the two-level form and when leaving it;
        otherwise only its ``q = 0`` entry followed the count (or an older coarse space is
        kept).  Leaving the Schur form for the Fourier one is not reported: the CG's
        recurrence goes on across it (``beta = r.z/r_old.z_old``), which takes fewer
        iterations than a restart there (docs/performance.md, "The lost iterations").  The
        Schur form needs a free pixel (``G_BB`` is singular on the whole grid).
        """
        last, self._last_count = self._last_count, bound_count
        if 0 < bound_count <= min(self.schur_max, self.grid.size - 1):
            bound = (~free).reshape(self.grid.local_shape)  # on the device: made there
            schur = ContactSchur(self.grid, self._exact_compliance(), bound, self.device)
            if schur.factorised:
                self.correction = schur
                return True
        settled = last > 0 and abs(bound_count - last) <= SETTLE_FRACTION * last
        if self.options.covers(bound_count, self.grid.size):
            if self.coarse is not None and not (settled and self._stale(free, bound_count)):
                return False  # an older coarse space is kept until the set has settled
            if settled and self._build(free):
                return True
        # a restart on leaving the Schur form too took 1749 iterations against 1684 over 64
        # cold 512^2 steps and 2102 against 1996 over 64 at 1024^2 (a Polak-Ribiere beta
        # there, with one more array: 1694 at 512^2; at 1024^2 and p0 = 1e-3 809, the
        # restart 807, this 797; docs/performance.md, "The lost iterations")
        leaving = self.coarse is not None
        self.correction = self._built_free = None
        if self._filled != self.support:
            self._fill(self.support)
        self._set_mean_mode(
            max(self.base_mean_mode, 1.0 / (max(bound_count, 1) * self.hessian_diagonal))
        )
        return leaving

    def release(self) -> None:
        """Drop the set-dependent form once the solve is over (the two-level form's factor
        is ``k x k``, on every rank); the next :meth:`invert` starts without it anyway.  The
        quarter of ``G`` is kept."""
        self.correction = self._built_free = self._reactions = None
        self._multiplier32 = None  # the stiffness solve may write the shared multiplier

    def _exact_compliance(self) -> Any:
        """Become ``G = 1/K`` with a zero ``q = 0`` entry (the set-dependent forms); returns
        its quarter (:func:`~petsc_contact.numerics.schur.quarter`)."""
        if self._filled != 0.0:
            self._fill(0.0)
        self._set_mean_mode(0.0)
        if self._quarter is None:
            self._quarter = response_quarter(
                self.grid, super().apply_array, self.work_fields(), self.device
            )
        return self._quarter

    def compliance_quarter(self, scale: float) -> Any:
        """The quarter of ``G = 1/K`` (zero ``q = 0`` entry) for the Hessian ``scale K`` this
        preconditioner inverts, from the column of ``1/(scale K)`` it keeps (rescaled with the
        Hessian at every :meth:`invert`); ``None`` before a set-dependent form made it."""
        return None if self._quarter is None else self._quarter * scale

    def work_fields(self) -> tuple[Any, Any]:
        """Two flat field-sized arrays for the set-dependent forms to compute in
        (:func:`~petsc_contact.backend.coarse.add_correction`): the FFT's input buffer
        twice, which a round trip uses only while it runs (for a caller's array it cannot
        transform in place), so that no field is kept for them: an application to it reads
        it into the spectrum before the transform back writes it; lent to the held-set
        stiffness solve."""
        real = self.fft.real.reshape(-1)
        return real, real

    def _stale(self, free: np.ndarray, bound_count: int) -> bool:
        """Whether more than :data:`REBUILD_FRACTION` of the set changed since the build."""
        assert self._built_free is not None
        (changed,) = self.grid.sum(self.device.passes.changed_count(self._built_free, free))
        return bool(changed > REBUILD_FRACTION * bound_count)

    def _build(self, free: np.ndarray) -> bool:
        """The two-level form on the bound set of ``free``; ``False`` if it cannot be had."""
        coarse = CoarseSpace(
            self.grid,
            self._exact_compliance(),
            (~free).reshape(self.grid.local_shape),  # on the device: built there
            self.options.block,
            coarse_limit(self.grid.size),
            self.device,
        )
        if not coarse.factorised:
            return False
        self.correction, self._built_free = coarse, free.copy()
        self.builds += 1
        return True

    def _set_mean_mode(self, value: float) -> None:
        self.mean_mode = value
        set_mean_mode(self, value)
        self._multiplier32 = None

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out <- M x``, ``out`` may be ``x`` (the constrained CG preconditions in place);
        in the Schur form ``x`` must vanish on the bound set."""
        exact = self._fft32 is None or self.schur is not None
        round_trip = super().apply_array if exact else self._single_round_trip
        total = None if self.correction is None else input_sum(self.grid, x)
        round_trip(x, out)
        self._reactions = None
        if total is not None:
            assert self.correction is not None
            work = self.work_fields()
            reactions = add_correction(round_trip, self.correction, total, out, work)
            if self.schur is not None:
                self._reactions = reactions
        return out

    def _single_round_trip(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out <- G x``, the Fourier form's round trip in ``float32`` (:meth:`use_single`)."""
        fft = self._fft32
        assert fft is not None
        if self._multiplier32 is None:  # laid out as the spectrum's float view
            entries = self.device.xp.repeat(self.multiplier * self.factor, 2, axis=-1)
            self._multiplier32 = entries.astype(np.float32).reshape(-1)
        self.applications += 1
        fft.forward_from(x)
        values = fft.spectrum.view(np.float32).reshape(-1)
        self.device.xp.multiply(values, self._multiplier32, out=values)
        fft.backward_into(out)
        return out

    def hessian_image(self, g: np.ndarray, out: np.ndarray, beta: float) -> bool:
        """``out <- beta out + H z`` without a transform, for ``z`` the last application, to
        ``r = P_F g``, when the form gives ``H z`` exactly; ``False`` (``out`` untouched)
        otherwise.

        In the exact Schur form ``z = G (r + lambda) + c`` vanishes on the bound set and
        ``r + lambda`` sums to zero, so ``H z = r + lambda``: the restricted residual plus
        the reactions on the bound pixels (to rounding).  The bound set is the one the form
        was built on (:meth:`adapt` is told every new set before an application), so ``r``
        is ``g`` off its pixels and the reactions on them.  The other forms are restricted
        to the free set after they are applied, and their image needs the Hessian.
        """
        schur = self.schur
        if self._reactions is None or schur is None:
            return False
        flat, bound = out.reshape(-1), schur.local
        kept = beta * flat[bound] if beta != 0.0 else 0.0  # r vanishes there
        if beta == 0.0:
            flat[...] = g.reshape(-1)
        else:
            flat *= beta
            flat += g.reshape(-1)
        flat[bound] = kept + self._reactions
        return True


def set_mean_mode(op: FourierOperator, value: float) -> None:
    """Set the normalised ``q = 0`` entry of ``op``'s multiplier (on the rank that holds it:
    FFTW-MPI may give a rank no spectrum columns at all, its empty range starting at 0)."""
    rows, cols = op.fft.spectral_index
    holds = rows.start == 0 and cols.start == 0 and rows.stop > 0 and cols.stop > 0
    if holds:
        op.set_entry(0, 0, value)


def schur_limit(size: int) -> int:
    """Largest bound set for the Schur preconditioner on a grid of ``size = n^2`` points.

    Its dense factorisation (measured as an LU, ``~1.8e-11 m^3`` s here; the Cholesky factor
    used now has half its flops) should cost at most about ten FFT round trips
    (``~2.7e-10 n^2 log2(n^2)`` s): ``m <= (150 n^2 log2 n^2)^(1/3)``, 880 at 512^2 and
    2400 at 2048^2, and never more than :data:`SCHUR_MAX`.
    """
    return int(min(SCHUR_MAX, (150 * size * np.log2(max(size, 2))) ** (1 / 3)))


def coarse_limit(size: int) -> int:
    """Most aggregates for the two-level form on a grid of ``size = n^2`` points.

    Its Cholesky factorisation (``~2.2e-11 k^3`` s here) should cost at most about ten FFT
    round trips (``~2.7e-10 n^2 log2(n^2)`` s): ``k <= (120 n^2 log2 n^2)^(1/3)``, 2200 at
    2048^2, 3600 at 4096^2 and 5900 at 8192^2.
    """
    return int((120 * size * np.log2(max(size, 2))) ** (1 / 3))
