"""The periodic hard-wall contact as a bound-constrained QP in the gap (docs/formulation.md).

A rigid surface with heights ``h`` (peaks toward the elastic body) is pressed with nominal
pressure ``p0`` onto an elastic half-space.  With the gap ``g >= 0`` as unknown,

    Pi(g) = a^2 [ 1/2 (g + h)^T K (g + h) + p0 sum(g) ],     g >= 0,

where ``K`` is the periodic stiffness (``E*|q|/2``, annihilating constants).  Its gradient is
``a^2 p`` with the contact pressure ``p = K(g + h) + p0``, so the bound-constrained optimum is
exactly the hard-wall KKT system ``g >= 0, p >= 0, p g = 0``.

TAO sees the scaled problem in ``x = g / l`` (``l = h_rms``):

    f(x) = s / l * Pi(l x) / a^2,     s = 1 / (sqrt(n^2) p0),

whose gradient is ``s p``, so TAO's 2-norm of the projected gradient is the rms pressure
residual in units of ``p0`` and ``-tao_gatol 1e-8`` means "pressures to 1e-8 p0".
The Hessian is ``s l K``.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from scipy.special import erfinv

from ..backend.coarse import CoarseCorrected, CoarseSpace, TwoLevelOptions
from ..backend.operator import FourierOperator, ShellInterface
from ..backend.preconditioner import (
    MeanModePreconditioner,
    coarse_limit,
    schur_limit,
    set_mean_mode,
)
from ..backend.solve import SolveInfo
from ..backend.stiffness import periodic_stiffness_exact
from ..conventions.grid import Grid
from ..conventions.validation import non_negative, positive
from ..devices.fft import FFT, wavevector_magnitude
from ..interactions.hard_wall import HARD_WALL
from ..interactions.interaction import Interaction
from ..numerics.kernels import compile_kernels
from ..numerics.schur import response_quarter
from ..physics.observables import step_observables
from ..physics.theory import area_fraction, linear_stiffness
from ..solver.backends import SolverBackend
from ..solver.report import Accuracy, accuracy_limit
from ..substrates.half_space import PeriodicHalfSpace
from ..substrates.substrate import PeriodicSubstrate, of_modulus
from .step import (
    MeasuredSolve,
    Step,
    contact_fields,
    default_backend,
    mark_full_contact,
    residual_verdict,
)

IQR_PER_SIGMA = 1.349  # a Gaussian's interquartile range in units of its rms
ROUNDING_FACTOR = 1000.0  # see PeriodicProblem.rounding_floor
RESOLVED = 1e-4  # a load is solved only where rounding leaves its residual this far below p0
LARGEST_LOAD = 1e6  # p0/E* beyond this is no elastic contact (strains of a million)


def verify(
    info: SolveInfo,
    obs: dict[str, float],
    scale_length: float,
    interaction: Interaction = HARD_WALL,
) -> str:
    """``'ok'`` or the reason a TAO answer cannot be used (one that breaks ``interaction``'s
    law among them)."""
    if info.reason_code <= 0:
        return f"TAO did not converge ({info.reason})"
    broken = interaction.violation(obs["min_gap"], scale_length)
    if broken is not None:
        return broken
    return residual_verdict(obs["kkt_residual"], info.effective_tolerance)


def _quantile(grid: Grid, values: Any, fraction: float, halvings: int = 60) -> float:
    """The ``fraction`` quantile of a distributed field (of any device's array module), by
    bisection on the global count at or below it: ``halvings`` reductions of one count."""
    low = grid.min(float(values.min()) if values.size else np.inf)
    high = grid.max(float(values.max()) if values.size else -np.inf)
    for _ in range(halvings):
        middle = 0.5 * (low + high)
        below = grid.sum(int(values.size and (values <= middle).sum()))[0]
        low, high = (middle, high) if below < fraction * grid.size else (low, middle)
    return high


class PeriodicProblem:
    """Operators and scaled objective of the periodic contact of one surface.

    Parameters
    ----------
    grid, fft
        Layout and FFT backend.
    heights
        This rank's slab of the rigid surface heights (the mean is removed), on the host or
        on ``fft``'s device.  It is kept, not copied, and must not change while the problem
        is in use: :attr:`heights`, less the mean, is made from it when asked for, and
        dropped while a solve runs (a field less at 8192^2 is 512 MB).
    modulus
        Contact modulus ``E*``.
    backend
        What solves it (:class:`~petsc_contact.solver.backends.SolverBackend`); default:
        PETSc's, with the options of the block it is first used in.
    substrate
        The elastic body (:class:`~petsc_contact.substrates.substrate.PeriodicSubstrate`);
        default: the half-space of ``modulus``, whose modulus a given one must have.
    interaction
        The law at the surface (:class:`~petsc_contact.interactions.interaction.Interaction`);
        default: the hard wall.
    """

    def __init__(
        self,
        grid: Grid,
        fft: FFT,
        heights: np.ndarray,
        modulus: float,
        backend: SolverBackend | None = None,
        *,
        substrate: PeriodicSubstrate | None = None,
        interaction: Interaction = HARD_WALL,
    ) -> None:
        positive("modulus", modulus)
        body: PeriodicSubstrate = PeriodicHalfSpace(modulus) if substrate is None else substrate
        self.substrate = of_modulus(body, modulus)
        self.interaction = interaction
        compile_kernels(announce=grid.comm.rank == 0)  # before any step's timer
        self.grid = grid
        self.device = fft.device
        self.modulus = float(modulus)
        self.filled: np.ndarray | None = None  # this rank's filled pixels (a measured map)
        self._given = heights  # as given: the zero-mean heights are made from it
        self._mean = grid.mean(self.device.asarray(heights, dtype=float))
        self._heights: Any = None  # made when asked for (heights)
        self.h_rms = grid.rms(self.heights)
        self.scale_length = self.h_rms if self.h_rms > 0 else max(grid.lengths)
        q = wavevector_magnitude(grid, fft, self.device.xp)  # on the device
        self.stiffness = FourierOperator(grid, fft, self.substrate.stiffness(q))
        self.hessian = self.stiffness.times(1.0)  # its scale set by each load
        limit = schur_limit(grid.size)
        self.preconditioner = MeanModePreconditioner(grid, fft, self.hessian, limit)
        self.pixel_stiffness = self.stiffness.diagonal()
        kh = self.stiffness.apply_array(self.heights, self.device.xp.empty(grid.local_shape))
        self.elastic_pressure_rms = grid.rms(kh)  # rms(K h) ~ E* h'_rms / 2
        self._min_kh = grid.min(float(kh.min()))
        self.nominal_pressure = np.nan
        self.interfacial_stiffness = np.nan
        self._s = np.nan
        self._held: FourierOperator | None = None
        self._x_ref: Any = None  # the reference point and the scaled gradient at it (start)
        self._sp_ref: Any = None
        self._backend: SolverBackend | None = None
        if backend is not None:
            self.use(backend)

    @property
    def heights(self) -> Any:
        """This rank's slab of the heights less their mean, on the device: made from the
        heights given when first asked for after :meth:`drop_heights` (the same numbers)."""
        if self._heights is None:
            given = self.device.asarray(self._given, dtype=float)  # a GPU's copy
            self._heights = self.device.xp.ascontiguousarray(given - self._mean)
        return self._heights

    def drop_heights(self) -> None:
        """Let go of :attr:`heights` until it is asked for again: the contact solve and the
        stiffness solve do not read it."""
        self._heights = None

    @property
    def backend(self) -> SolverBackend:
        """What solves the problem (made when first asked for where none was given)."""
        if self._backend is None:
            self._backend = default_backend()
        return self._backend

    def use(self, backend: SolverBackend) -> None:
        """Be solved by ``backend`` from now on (its settings: the two-level form's, the
        preconditioner's precision, the stiffness solve's; ``ValueError`` in one line for a
        precision this problem's FFT cannot make)."""
        self.preconditioner.use_single(backend.settings.pc_float32)
        self._backend = backend

    def held_set_solve(self, grid: Grid, op: Any, pc: Any, mask: Any) -> tuple[Any, int]:
        """The backend's held-set solve on the problem's device."""
        return self.backend.held_set_solve(grid, op, pc, mask, self.device)

    def set_pressure(self, p0: float, interfacial_stiffness: float | None = None) -> None:
        """Set the nominal pressure ``p0`` (one :meth:`check_pressure` accepts) and rescale
        the TAO-facing operators.

        ``interfacial_stiffness`` is an estimate of ``K = -dp0/du_bar`` at ``p0`` (per area)
        that the preconditioner is held by (:class:`MeanModePreconditioner`); it changes
        the path of the solver, never its answer.  Default: :meth:`stiffness_estimate`;
        ``0``: no support, the free compliance ``2/(E* q)`` with ``2/(E* q0)`` at ``q = 0``.
        """
        k_i = (
            self.stiffness_estimate(p0)
            if interfacial_stiffness is None
            else float(interfacial_stiffness)
        )
        non_negative("interfacial stiffness", k_i)
        self.nominal_pressure = float(p0)
        self.interfacial_stiffness = k_i
        self._s = 1.0 / (np.sqrt(self.grid.size) * p0)
        c = self._s * self.scale_length
        self.hessian.factor = c  # the stiffness's multiplier times c
        mean_compliance = self.substrate.mean_mode_compliance(self.grid.q0, k_i)
        self.preconditioner.options = TwoLevelOptions.from_settings(self.backend.settings)
        self.preconditioner.invert(
            self.hessian.normalised(c * k_i),
            self.pixel_stiffness * c,
            self.hessian.normalised(mean_compliance / c),
            self.expected_contact_count(p0),
        )

    upper_bound = None  # the gap has no upper bound

    @property
    def lower_bound(self) -> float:
        """The lower bound of the scaled gap: the interaction's."""
        return self.interaction.gap_lower / self.scale_length

    def tolerance_floor(self) -> float:
        """The tolerance double precision can resolve at the current load."""
        return self.rounding_floor(self.nominal_pressure)

    def accuracy(self) -> Accuracy:
        """The package's accuracy at the current load (:mod:`~petsc_contact.solver.report`):
        the force balance held to the natural residual's limit, which bounds it."""
        limit = accuracy_limit(self.tolerance_floor())
        return Accuracy(limit, limit)

    def measure(
        self, x: np.ndarray, info: SolveInfo, stiffness: bool = False, fields: bool = False
    ) -> Step:
        """The step of a solution ``x`` (TAO's scaled gap) at the current nominal pressure:
        observables, TAO's report, the package's verdict, the measured accuracy
        (:meth:`accuracy`) and, if asked, the exact stiffness ``-dp0/du_bar`` with the
        contact set held fixed.

        The observables are taken where the solution lives (:func:`~petsc_contact.physics.
        observables.step_observables` on the device's arrays): only scalars, histograms and
        the patches' sizes come to the host, and the fields only when ``fields`` asks."""
        grid, ell, p0, device = self.grid, self.scale_length, self.nominal_pressure, self.device
        self.preconditioner.release()  # the solve is over (the stiffness solve builds its own)
        self._sp_ref = None  # and so is its objective's (made again if it is asked for)
        gap = x.reshape(grid.local_shape) * ell
        pressure = self.pressure(gap)
        filled = None if self.filled is None else device.asarray(self.filled)
        obs = step_observables(
            grid, gap, pressure, self.heights, p0, self.pixel_stiffness, filled, device
        )
        contact = obs.pop("contact")
        verdict = verify(info, obs, ell, self.interaction)
        scalars = {
            "nominal_pressure": p0,
            **obs,
            "force_balance": abs(obs["contact_pressure_mean"] - p0) / p0,
            **info.scalars(verdict),
            "preconditioner_stiffness": self.interfacial_stiffness,
        }
        kept = (gap, pressure) if fields else ()
        del gap, pressure  # the stiffness solve's fields take their place unless kept
        self.drop_heights()  # and so do the heights
        if stiffness:
            scalars.update(self.held_set_stiffness(contact, verdict == "ok"))
        mark_full_contact(scalars)
        self.accuracy().assess(scalars)
        if not fields:
            return Step(scalars)
        gap, pressure, contact = (device.to_host(a) for a in (*kept, contact))
        return Step(scalars, *contact_fields(gap, pressure, contact), contact=contact)

    def held_set_stiffness(self, contact: np.ndarray, converged: bool) -> dict[str, Any]:
        """The exact stiffness ``-dp0/du_bar`` with ``contact`` (this rank's mask, on the
        device) held fixed (NaN unless ``converged``), its solve's iterations and time, the
        residual of its answer recomputed
        (:func:`~petsc_contact.geometries.step.held_set_residual`) and the tolerance asked."""
        grid = self.grid
        solve = MeasuredSolve(self.held_set_solve, self.device)
        start = time.perf_counter()
        k, its = (
            periodic_stiffness_exact(
                grid, self.stiffness, self.stiffness_preconditioner(contact), contact, solve
            )
            if converged
            else (np.nan, 0)
        )
        elapsed = grid.max(time.perf_counter() - start)
        return {
            "stiffness": k,
            "stiffness_iterations": its,
            "stiffness_time": elapsed,
            "stiffness_residual": solve.residual() if converged else np.nan,
            "stiffness_tolerance": self.backend.stiffness_rtol(),
        }

    def stiffness_estimate(self, p0: float) -> float:
        """Persson's interfacial stiffness ``K = p0/u0``, ``u0 = gamma h_rms`` (paper Eq. 1).

        The estimate the preconditioner uses when nothing better is known; from half to twice
        it the iterations stay within 20% of the best (measured, ``docs/performance.md``).
        """
        if self.h_rms <= 0:  # a flat surface: contact is complete at any load
            return self.pixel_stiffness
        return float(linear_stiffness(p0, self.h_rms))

    def stiffness_preconditioner(self, contact: np.ndarray) -> ShellInterface:
        """The preconditioner of the held-set stiffness solve on the open pixels of ``contact``
        (this rank's mask): the exact Schur form while at most ``schur_max`` pixels are in
        contact (the solve then takes one iteration), the two-level form up to the
        preconditioner's ``options.max_fraction``, and the held compliance above or when
        ``-petsc_contact_two_level 0`` switches both off (:meth:`held_compliance`), all on
        one operator recomputed in place.
        """
        pre = self.preconditioner
        (m,) = self.grid.sum(self.device.xp.count_nonzero(contact))
        exact = pre.options.enabled and 0 < m <= min(pre.schur_max, self.grid.size - 1)
        if not (exact or (m > 0 and pre.options.covers(int(m), self.grid.size))):
            return self.held_compliance(self.interfacial_stiffness)
        compliance = self._compliance(0.0)
        set_mean_mode(compliance, 0.0)
        work = pre.work_fields()  # the contact solve is over: its work fields are free
        # G's column: the contact solve's preconditioner keeps it (times the Hessian's scale)
        column = pre.compliance_quarter(self._s * self.scale_length)
        space = CoarseSpace(
            self.grid,
            (
                response_quarter(self.grid, compliance.apply_array, work, self.device)
                if column is None
                else column
            ),
            contact.reshape(self.grid.local_shape),
            1 if exact else pre.options.block,
            self.grid.size if exact else coarse_limit(self.grid.size),
            self.device,
        )
        if not space.factorised:
            return self.held_compliance(self.interfacial_stiffness)
        return CoarseCorrected(compliance, space, work)

    def _compliance(self, support: float) -> FourierOperator:
        """``1/(K + support)`` (normalised ``support``) in the one operator kept for it, whose
        multiplier is the contact preconditioner's: the contact solve is over, and the next
        :meth:`set_pressure` fills it again (no field more for the stiffness solve)."""
        if self._held is None:
            self._held = self.stiffness.sharing(self.preconditioner.multiplier)
        self._held.set_inverse(self.stiffness, support)
        return self._held

    def held_compliance(self, interfacial_stiffness: float) -> FourierOperator:
        """The compliance held by ``interfacial_stiffness``, ``1/(E* q/2 + K_i)``
        (:func:`~petsc_contact.physics.greens.held_compliance`): the preconditioner of the exact
        stiffness solve.  One operator, recomputed in place (no field-sized temporaries).
        """
        positive("interfacial stiffness", interfacial_stiffness)
        return self._compliance(self.stiffness.normalised(interfacial_stiffness))

    def expected_contact_count(self, p0: float) -> int:
        """Contact pixels at ``p0`` in Persson's theory, ``n^2 erf(p0 / (sqrt(2) sigma))``
        (:func:`~petsc_contact.physics.theory.area_fraction`).

        ``sigma = rms(K h)`` is the rms pressure of full contact (``E* h'_rms / 2``); for small
        ``p0`` this is the linear law ``A/A0 = sqrt(8/pi) p0 / (E* h'_rms)``.  Simulations find
        1-2.5 times more contact at low load; the solver only uses it as a scale.
        """
        if self.elastic_pressure_rms <= 0:
            return self.grid.size
        return int(self.grid.size * area_fraction(p0, self.elastic_pressure_rms))

    def area_pressure(self, fraction: float) -> float:
        """The nominal pressure at which Persson's law (:meth:`expected_contact_count`) puts
        ``fraction`` of the pixels in contact, ``sqrt(2) sigma erfinv(fraction)``, with
        ``sigma`` estimated from the interquartile range of ``K h`` (``IQR / 1.349``, its rms
        for a Gaussian field): a few outlier pixels of a measured map (a dropout, a spike),
        which set ``rms(K h)`` and the full-contact pressure, do not move it.  Collective."""
        kh = self.stiffness.apply_array(self.heights, self.device.xp.empty(self.grid.local_shape))
        spread = _quantile(self.grid, kh, 0.75) - _quantile(self.grid, kh, 0.25)
        return float(np.sqrt(2) * spread / IQR_PER_SIGMA * erfinv(fraction))

    def pressure(self, gap: np.ndarray) -> np.ndarray:
        """Contact pressure ``p = K(g + h) + p0`` of a gap field (local slab)."""
        p = self.stiffness.apply_array(gap + self.heights, self.device.xp.empty_like(gap))
        p += self.nominal_pressure
        return p

    def start(self, x0: np.ndarray) -> None:
        """Take ``x0`` as the reference point of :meth:`objective_gradient` (one FFT) and
        as :attr:`start_point`.  ``x0`` is kept, not copied: it must not change until the
        next :meth:`start` (a field less at 8192^2 is 512 MB)."""
        self._x_ref = self.device.asarray(x0, dtype=float).reshape(-1)
        self._sp_ref = self._reference_gradient()
        self.drop_heights()  # the solve reads x_ref and the gradient there only

    def _reference_gradient(self) -> Any:
        """The scaled gradient at the reference point, ``s p(x_ref)`` (flat): made by
        :meth:`start`, dropped when a solve is measured (a field less for the stiffness
        solve), and made again, the same numbers, for another solve from the same start."""
        sp = self._x_ref.reshape(self.grid.local_shape) * self.scale_length  # the one field
        sp += self.heights  # p = K(g + h) + p0 (:meth:`pressure`), computed in place
        self.stiffness.apply_array(sp, sp)
        sp += self.nominal_pressure
        sp *= self._s
        return sp.reshape(-1)

    @property
    def start_point(self) -> np.ndarray:
        """The point given to :meth:`start` (flat local array, scaled gap)."""
        return self._x_ref

    def objective_gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        """Scaled objective relative to the reference, ``f(x) - f(x_ref)``; ``grad <- s p``.

        With ``d = x - x_ref``: ``f(x) - f(x_ref) = s d.p_ref + s l / 2 d.K d`` and
        ``p = p_ref + l K d``.  Evaluating the *difference* keeps its rounding error
        proportional to the decrease itself, so line searches still see progress when the
        pressure residual is ``1e-10 p0``; the absolute energy would drown it.
        ``d`` is formed in the FFT's input buffer, which the real-to-complex transform keeps;
        ``d.K d`` comes from its spectrum (Parseval), in the pass that multiplies it.
        """
        if self._sp_ref is None:
            self._sp_ref = self._reference_gradient()
        d = self.stiffness.fft.real.reshape(-1)
        np.subtract(x, self._x_ref, out=d)
        d_skd = self.hessian.transform(d)  # the Hessian is s l K
        self.hessian.end_mult(grad)  # s l K d
        d_sp = self.device.passes.add_dot(grad, self._sp_ref, d)
        d_sp, d_skd = self.grid.sum(d_sp, d_skd)
        return float(d_sp + 0.5 * d_skd)

    def initial_gap(self) -> np.ndarray:
        """Gap at first touch of the undeformed surfaces, ``max(h) - h``."""
        return self.largest_mean_gap() - self.heights

    def largest_mean_gap(self) -> float:
        """The mean gap at first touch, ``max(h) - mean(h)`` (the heights' mean is zero): no
        load has a larger one (collective)."""
        return self.grid.max(float(self.heights.max()))

    def full_contact_pressure(self) -> float:
        """Nominal pressure at which contact becomes complete, ``-min(K h)``."""
        return -self._min_kh

    def check_pressure(self, p0: float) -> None:
        """``ValueError`` in one line for a nominal pressure this grid cannot resolve: so
        small that rounding alone exceeds :data:`RESOLVED` of it (:meth:`rounding_floor`), or
        above :data:`LARGEST_LOAD` ``E*``.  Each load is checked once, before it is solved, by
        what solves it, after it was checked positive where it was given (a run's
        description, the periodic contact's or the comparison's arguments)."""
        smallest = self.smallest_pressure()
        if not np.isfinite(p0):
            raise ValueError(f"nominal pressure {p0} is not a finite number")
        if p0 < smallest:
            rms = self.elastic_pressure_rms
            raise ValueError(
                f"nominal pressure {p0:.3g} is below what double precision resolves on this "
                f"surface, {smallest:.2g}: its elastic stresses (rms {rms:.3g}) are rounded at "
                f"{self.rounding_floor(p0):.1e} of it"
            )
        if p0 > LARGEST_LOAD * self.modulus:
            raise ValueError(
                f"nominal pressure {p0:.3g} is more than {LARGEST_LOAD:g} E* (E* = "
                f"{self.modulus:g}): no elastic contact; full contact is reached at "
                f"{self.full_contact_pressure():.3g}"
            )

    def smallest_pressure(self) -> float:
        """The smallest nominal pressure this grid resolves (:meth:`check_pressure`): where
        rounding alone is :data:`RESOLVED` of it (:meth:`rounding_floor`)."""
        return float(ROUNDING_FACTOR * np.finfo(float).eps * self.elastic_pressure_rms / RESOLVED)

    def check_mean_gap(self, mean_gap: float) -> None:
        """``ValueError`` in one line for a prescribed mean gap no load reaches: not below
        the mean gap at first touch (:meth:`largest_mean_gap`, where ``p0 = 0``), or not
        above zero (full contact, from ``p0 = -min(K h)`` on).  Checked by what solves it,
        before the output is touched."""
        largest = self.largest_mean_gap()
        if not 0 < mean_gap < largest:  # NaN too
            raise ValueError(
                f"mean gap {mean_gap:.6g} is not between 0 (full contact) and {largest:.6g}, "
                "the mean gap at first touch max(h) - mean(h) (p0 = 0): no load reaches it"
            )

    def stiffness_rounding_floor(self, p0: float) -> float:
        """The rms pressure residual (units of ``p0``) below which a tight solve stagnates.

        The largest stiffness entries (``E* |q|/2``, so ``~ k``, the pixel stiffness, which
        grows like ``n``) act on gaps of size ``h_rms``: the pressure is rounded at
        ``~ eps k h_rms``.  Measured at ``p0 = 1e-3 E*`` on the stability surface
        (``L/lambda_1 = n/4``): after 250 iterations the residual stood at 5e-13, 9e-13,
        2e-12 and 5e-12 for n = 256 ... 2048, which is 3 to 7.5 times ``eps k h_rms / p0``;
        this returns 30 times that.  Used for the reference solves of
        :func:`~petsc_contact.workflows.compare.compare`, which at ``1e-12`` ran to the iteration
        limit from 2048^2 on.
        """
        return float(30 * np.finfo(float).eps * self.pixel_stiffness * self.h_rms / p0)

    def rounding_floor(self, p0: float) -> float:
        """The smallest rms pressure residual (in units of ``p0``) double precision resolves.

        Pressures are differences of elastic stresses of size ``rms(K h) ~ E* h'_rms/2``;
        an FFT convolution rounds them at ``~eps`` of that, and more on larger grids.
        Measured at ``p0 = 1e-7 E*`` (H = 0.7, ``L = lambda_r``, roughness down to two
        pixels, ``h'_rms = 0.1``), the exactly evaluated residual stops falling at 7.4e-9,
        1.2e-8, 1.3e-8 and 1.6e-8 for n = 1024 ... 8192, that is 70 to 150 times
        ``eps rms(K h)/p0``; this returns :data:`ROUNDING_FACTOR` = 1000 times it.  It
        matters only at small loads: above ``1e-8`` for ``p0 < 1.1e-6 E*``.
        """
        return float(ROUNDING_FACTOR * np.finfo(float).eps * self.elastic_pressure_rms / p0)
