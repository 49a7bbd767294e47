"""A rigid rough square punch on a non-periodic elastic half-space (paper section II, App. A).

The punch face has heights ``h`` on an ``nx x ny`` footprint of sides ``Lx x Ly`` (pixel
area ``a^2``, square or not); it is pressed by the rigid approach ``δ`` (measured from first
touch) into a half-space of contact modulus ``E*``.  The unknown is the pressure ``p >= 0``
on the footprint, zero outside by construction; the dual QP (docs/formulation.md)

    W(p) = a^2 [ 1/2 p^T G p - p^T (δ - s) ],   p >= 0,      s = max(h) - h,

has the gap ``g = G p + s - δ`` as gradient, with ``G`` the free-boundary compliance
(Love's pixel kernel convolved on the ``2nx x 2ny`` zero-padded grid, :class:`PaddedOperator`).

TAO sees ``x = p / p_s`` with ``p_s = E* l / a`` and ``l`` the rms of the recess ``s``
(or the shorter pixel side for a flat punch); the scaled gradient is ``g / (l sqrt(N))``
(``N = nx ny``), so
``-tao_gatol 1e-8`` asks for gaps on the contact set within ``1e-8 l`` rms.

Per step: approach, force ``F = a^2 sum(p)``, nominal pressure ``F / (Lx Ly)``, the mean gap
``u_bar`` over the footprint (whose ``-dp/du_bar`` is the interfacial stiffness without
Eq. 2's flat-punch reference), area fraction
(of footprint pixels; contact when ``p > k g``, ``k = 1/G_00``), exact total stiffness
``dF/dδ`` with the contact set fixed, and the interfacial stiffness per area from springs in
series (paper Eq. 2), ``1/K_int = 1/K_tot - 1/K_flat``, ``K = K_int / (Lx Ly)``.  ``K_flat`` is
the flat punch of the same footprint computed on the same grid (``grid``, the default:
discretisation errors cancel), the analytic ``β 2 E* sqrt(A/π)`` with the footprint's exact
shape factor (``analytic``: ``β = 1.0212`` for the square, 1 for the disk;
:mod:`~petsc_contact.reference.flat_punch`) or King's estimate ``β = 1.012`` for the square, as
Pharr, Oliver & Brotzen quote it (``king``).  Each step records ``K_flat`` and its ``β``.

The problem is written once on the arrays of a :class:`~petsc_contact.devices.device.Device`:
on ``cpu`` TAO minimises it on PETSc Vecs and ``KSPCG`` solves the held sets of the exact
stiffness; on ``gpu`` and ``cpu-array`` the package's constrained CG and held-set CG do
(:mod:`petsc_contact.solver`), with the padded compliance on the device's FFT and no PETSc.
The observables are measured on the host.

The QP is one class composed of parts, :class:`PressureProblem`: the body's compliance
(:class:`Compliance`) and what a step measures (:class:`Measure`), with the interaction, the
device and the backend.  :class:`PunchProblem` is it with the free padded compliance
(:class:`FreeCompliance`) and the punch's measure (:class:`PunchMeasure`); the capped periodic
cell (:mod:`~petsc_contact.geometries.capped_periodic`) with the periodic ones.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..backend.operator import PaddedOperator, SpectralOperator
from ..backend.solve import SolveInfo
from ..backend.stiffness import punch_stiffness_exact
from ..conventions.grid import Grid
from ..conventions.validation import non_negative, positive
from ..devices.device import CPU, Device
from ..interactions.hard_wall import HARD_WALL
from ..interactions.interaction import Interaction
from ..numerics.kernels import compile_kernels
from ..physics.observables import contact_resolved, distributions, patch_sizes
from ..reference import flat_punch
from ..solver.backends import SolverBackend
from ..solver.report import FORCE_ACCURACY, Accuracy, accuracy_limit
from ..substrates.half_space import FreeHalfSpace
from ..substrates.substrate import FreeSubstrate, of_modulus
from .step import (
    MeasuredSolve,
    Step,
    contact_fields,
    default_backend,
    mark_full_contact,
    residual_verdict,
)

FOOTPRINTS = ("square", "disk")
FLAT_REFERENCES = ("grid", "analytic", "king")


def disk_footprint(n: int) -> np.ndarray:
    """The disk inscribed in an ``n x n`` footprint (pixel centres within radius n/2)."""
    x = np.arange(n) + 0.5 - n / 2
    return x[:, None] ** 2 + x[None, :] ** 2 < (n / 2) ** 2


def __getattr__(name: str) -> float:
    """``PHARR_BETA``, deprecated (a ``DeprecationWarning``): King's 1.012, ``KING_BETA`` of
    :mod:`~petsc_contact.reference.flat_punch`, no longer the square's analytic shape factor
    (``SQUARE_BETA`` there, 1.0212)."""
    if name == "PHARR_BETA":
        warnings.warn(
            "geometries.punch.PHARR_BETA is deprecated: it is King's estimate 1.012, "
            "reference.flat_punch.KING_BETA; the square's exact shape factor is "
            "reference.flat_punch.SQUARE_BETA (1.0212)",
            DeprecationWarning,
            stacklevel=2,
        )
        return flat_punch.KING_BETA
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def footprint_mask(
    grid: Grid, footprint: str | np.ndarray | None
) -> tuple[np.ndarray | None, float]:
    """A punch's local footprint mask (``None``: the whole grid) and the shape factor of its
    analytic flat-punch stiffness (paper Eq. 2): ``square`` or ``None`` (the square's exact
    1.0212), ``disk`` (the inscribed disk of a square grid; 1), or a full ``nx x ny`` boolean
    mask (the square's)."""
    if footprint is None or (isinstance(footprint, str) and footprint == "square"):
        return None, flat_punch.SQUARE_BETA
    if isinstance(footprint, str):
        if footprint != "disk":
            raise ValueError(f"the footprint is one of {', '.join(FOOTPRINTS)} or a mask")
        if not grid.square:
            raise ValueError("--footprint disk needs a square grid")
        return grid.scatter(disk_footprint(grid.shape[0]).astype(float)) > 0, 1.0
    return grid.scatter(np.asarray(footprint, dtype=float)) > 0, flat_punch.SQUARE_BETA


def flat_punch_stiffness(
    modulus: float, area: float, beta: float = flat_punch.SQUARE_BETA
) -> float:
    """The analytic flat punch of paper Eq. 2, ``K = β 2 E* sqrt(A/π)``
    (:func:`petsc_contact.reference.flat_punch.stiffness`; default: the square's exact β)."""
    return flat_punch.stiffness(area, modulus, beta)


def reference_beta(flat: str, beta: float, square: bool) -> float:
    """The shape factor of the analytic flat punch that the reference ``flat`` of paper Eq. 2
    takes: the footprint's ``beta`` (``grid``, ``analytic``) or King's 1.012 (``king``).

    Parameters
    ----------
    flat
        ``grid``, ``analytic`` or ``king`` (:data:`FLAT_REFERENCES`).
    beta
        The footprint's exact shape factor (:func:`footprint_mask`).
    square
        Whether the footprint is a square: ``king`` is an estimate for the square only.

    Raises
    ------
    ValueError
        For another ``flat``, or ``king`` on a footprint that is not a square.
    """
    if flat not in FLAT_REFERENCES:
        raise ValueError(
            f"flat-punch stiffness must be one of {', '.join(FLAT_REFERENCES)}, got {flat}"
        )
    if flat != "king":
        return beta
    if not square:
        raise ValueError(
            "--flat-stiffness king is King's estimate for a square footprint; this one is not "
            "square (its analytic value, 1 for the disk, is exact: use analytic)"
        )
    return flat_punch.KING_BETA


def interfacial_stiffness(total: float, flat: float) -> float:
    """Springs in series (paper Eq. 2): ``1/K_int = 1/K_tot - 1/K_flat``.

    ``inf`` when the punch is as stiff as the flat one (full contact: a step there records
    NaN, :func:`~petsc_contact.geometries.step.mark_full_contact`), 0 without contact, NaN
    for the NaN ``total`` of a step that did not converge (never a plausible 0).
    """
    if total == 0:
        return 0.0
    with np.errstate(divide="ignore"):
        return float(1.0 / (np.float64(1.0) / total - np.float64(1.0) / flat))


def face_recess(grid: Grid, heights: np.ndarray, footprint: np.ndarray) -> tuple[np.ndarray, float]:
    """The recess ``s = max(h) - h`` on the ``footprint`` (this rank's mask; 0 off it) of this
    rank's ``heights``, and the scale length ``l``: its rms about its mean, or the shorter
    pixel side for a flat punch."""
    h = np.asarray(heights, dtype=float).reshape(grid.local_shape)
    top = grid.max(float(np.where(footprint, h, -np.inf).max(initial=-np.inf)))
    recess = np.where(footprint, top - h, 0.0)
    pixels = grid.sum(np.count_nonzero(footprint))[0]
    mean = grid.sum(recess.sum())[0] / pixels
    dev = np.where(footprint, recess - mean, 0.0)
    rms = float(np.sqrt(grid.sum(np.vdot(dev, dev))[0] / pixels))
    return recess, rms if rms > 0 else min(grid.spacing)


@dataclass(frozen=True)
class Operators:
    """A problem posed in the pressure's spectral operators: the compliance ``G``, its
    inverse, the scaled Hessian ``H = G / s`` (``s = a sqrt(N) / E*``) and its
    preconditioner ``H^-1``."""

    compliance: SpectralOperator
    inverse: SpectralOperator
    hessian: SpectralOperator
    preconditioner: SpectralOperator


class Compliance(Protocol):
    """The elastic body's part of a problem posed in the pressure: its compliance ``G`` on a
    grid (the free padded one, :class:`FreeCompliance`; the periodic one with a finite mean
    mode, :class:`~petsc_contact.geometries.capped_periodic.PeriodicCompliance`)."""

    def operators(self, grid: Grid, device: Device, scale: float) -> Operators:
        """``G`` and the operators made from it (:class:`Operators`), ``scale`` the Hessian's
        ``s``, on ``device``'s arrays."""
        ...


@dataclass(frozen=True)
class FreeCompliance:
    """The free-boundary compliance of ``substrate``: its pixel kernel convolved on the
    zero-padded ``2nx x 2ny`` grid (:class:`~petsc_contact.backend.operator.PaddedOperator`)."""

    substrate: FreeSubstrate

    def operators(self, grid: Grid, device: Device, scale: float) -> Operators:
        """The padded ``G``, its inverse, ``G / s`` and ``s G^-1`` on ``device``'s FFT."""
        compliance = PaddedOperator(
            grid,
            lambda rows: self.substrate.compliance_kernel(grid.shape, grid.spacing, rows),
            device=device,
        )
        inverse = compliance.with_spectrum(compliance.inverse_spectrum())
        hessian = compliance.with_spectrum(compliance.spectrum / scale)
        return Operators(
            compliance, inverse, hessian, inverse.with_spectrum(inverse.spectrum * scale)
        )


class Measure(Protocol):
    """What a step of a problem posed in the pressure measures beyond the solver's report:
    the punch's (:class:`PunchMeasure`) or the periodic cell's
    (:class:`~petsc_contact.geometries.capped_periodic.CellMeasure`)."""

    def observables(
        self, problem: PressureProblem, pressure: np.ndarray, gap: np.ndarray
    ) -> dict[str, Any]:
        """The step's scalars (the same on every rank) and this rank's masks ``contact`` and
        ``plastic`` (the pixels at the interaction's cap)."""
        ...

    def stiffness_scalars(self, held: dict[str, Any]) -> dict[str, Any]:
        """The step's scalars of :meth:`PressureProblem.held_set_stiffness`'s ``held``."""
        ...

    def stiffness(self, problem: PressureProblem, scalars: dict[str, Any]) -> float:
        """The dataset ``stiffness`` of a step with ``scalars``."""
        ...


class PunchMeasure:
    """The punch's step: :func:`punch_observables`, the total and interfacial stiffness (paper
    Eq. 2), the interfacial one the dataset ``stiffness``."""

    def observables(
        self, problem: PressureProblem, pressure: np.ndarray, gap: np.ndarray
    ) -> dict[str, Any]:
        return punch_observables(problem, pressure, gap)

    def stiffness_scalars(self, held: dict[str, Any]) -> dict[str, Any]:
        return held

    def stiffness(self, problem: PressureProblem, scalars: dict[str, Any]) -> float:
        return float(scalars["interfacial_stiffness"])


class PressureProblem:
    """A rigid face pressed into an elastic body, posed in the pressure: the scaled dual QP
    (module docstring) composed of parts.

    Parameters
    ----------
    grid
        The ``nx x ny`` footprint grid (sides ``Lx x Ly``).
    heights
        This rank's slab of the face's heights (peaks toward the body).
    modulus
        Contact modulus ``E*``.
    elastic
        The body's compliance (:class:`Compliance`): the free half-space's padded one, the
        periodic cell's.
    measured
        What a step measures (:class:`Measure`): the punch's, the periodic cell's.
    footprint
        This rank's slab of a boolean mask of the pixels that belong to the face
        (default: the whole grid); pressure is held at zero elsewhere.
    flat, beta
        The flat-punch stiffness of paper Eq. 2 (:data:`FLAT_REFERENCES`): ``'grid'``, the flat
        punch of the same footprint on the same grid (discretisation errors cancel),
        ``'analytic'``, ``beta 2 E* sqrt(A/pi)`` with ``beta`` the footprint's exact shape
        factor (default: the square's, 1.0212), or ``'king'``, King's ``beta = 1.012`` (a
        square footprint only: :func:`reference_beta`).  Load control's first approach is
        the analytic one's.
    device
        Where the solver's fields live (:class:`~petsc_contact.devices.device.Device`): the
        ``cpu`` device's are TAO's (NumPy, FFTW); ``gpu`` and ``cpu-array`` run the package's
        own CG on their arrays (no PETSc; ``gpu`` on one rank).  Heights, footprint and the fields a
        step measures stay on the host.
    backend
        What solves it (:class:`~petsc_contact.solver.backends.SolverBackend`), the held-set
        solves of the exact stiffness among them (the flat punch's, solved here); default:
        PETSc's, with the options of the block it is made in.
    interaction
        The law at the surface (:class:`~petsc_contact.interactions.interaction.Interaction`);
        default: the hard wall.
    """

    compliance: SpectralOperator  # G, the hessian G / (a sqrt(N) / E*) and their inverses
    inverse: SpectralOperator
    hessian: SpectralOperator
    preconditioner: SpectralOperator

    def __init__(
        self,
        grid: Grid,
        heights: np.ndarray,
        modulus: float,
        elastic: Compliance,
        measured: Measure,
        footprint: np.ndarray | None = None,
        flat: str = "grid",
        beta: float = flat_punch.SQUARE_BETA,
        *,
        device: Device = CPU,
        backend: SolverBackend | None = None,
        interaction: Interaction = HARD_WALL,
    ) -> None:
        positive("modulus", modulus)
        self.elastic, self.measured, self.interaction = elastic, measured, interaction
        compile_kernels(announce=grid.comm.rank == 0)  # before any step's timer
        self.flat = flat
        self.grid = grid
        self.device = device
        self.backend = default_backend() if backend is None else backend
        self.modulus = float(modulus)
        self.filled: np.ndarray | None = None  # this rank's filled pixels (a measured map)
        self.footprint = (
            np.ones(grid.local_shape, dtype=bool)
            if footprint is None
            else np.asarray(footprint, dtype=bool).reshape(grid.local_shape)
        )
        self.footprint_pixels = int(grid.sum(np.count_nonzero(self.footprint))[0])
        if self.footprint_pixels == 0:
            raise ValueError("the punch footprint is empty")
        whole = self.footprint_pixels == grid.shape[0] * grid.shape[1]
        analytic_beta = reference_beta(flat, beta, whole and grid.square)
        self.recess, self.scale_length = self._recess(heights)
        self._operators()
        self.approach = np.nan
        self._device_arrays()
        area = self.footprint_pixels * grid.pixel_area
        self.k_flat_analytic = flat_punch_stiffness(self.modulus, area, beta)  # the footprint's
        self.flat_residual = 0.0  # the recomputed residual of the flat punch's held-set solve
        self.k_flat_grid = self.flat_stiffness_on_grid() if flat == "grid" else np.nan
        self.k_flat = (
            self.k_flat_grid
            if flat == "grid"
            else flat_punch_stiffness(self.modulus, area, analytic_beta)
        )
        # the shape factor of K_flat: the reference's, or the grid's flat punch's
        self.flat_beta = self.k_flat / flat_punch_stiffness(self.modulus, area, 1.0)

    def _device_arrays(self) -> None:
        """The solver's copies of the recess, the footprint and the upper bound (the host
        arrays themselves on the ``cpu`` device), and the objective's buffer."""
        grid, device = self.grid, self.device
        self._u = device.xp.empty(grid.local_shape)  # objective buffer, reused every evaluation
        self._recess_flat = device.asarray(self.recess.reshape(-1))
        self._footprint_flat = device.asarray(self.footprint.reshape(-1).astype(float))
        self._footprint = device.asarray(self.footprint)
        upper = self.interaction.pressure_upper(self.footprint, np) / self.pressure_scale
        self._upper = device.asarray(upper.reshape(-1))

    def _recess(self, heights: np.ndarray) -> tuple[np.ndarray, float]:
        """:func:`face_recess` of this rank's heights on the footprint; the recess's sum over
        the ranks becomes :attr:`recess_sum`."""
        recess, scale = face_recess(self.grid, heights, self.footprint)
        self.recess_sum = self.grid.sum(recess.sum())[0]
        return recess, scale

    def _operators(self) -> None:
        """The body's compliance ``G`` on the device (:attr:`elastic`), its inverse, and the
        scaled Hessian ``H = G / (a sqrt(N) / E*)`` with its preconditioner ``H^-1``."""
        grid = self.grid
        a = np.sqrt(grid.pixel_area)  # the pixel's size for the scaling (its side if square)
        self._scale = a * np.sqrt(grid.size) / self.modulus  # H = G / _scale
        ops = self.elastic.operators(grid, self.device, self._scale)
        self.compliance, self.inverse = ops.compliance, ops.inverse
        self.hessian, self.preconditioner = ops.hessian, ops.preconditioner
        self.pixel_stiffness = 1.0 / self.compliance.diagonal()
        self.pressure_scale = self.modulus * self.scale_length / a

    def held_set_solve(self, grid: Grid, op: Any, pc: Any, mask: Any) -> tuple[Any, int]:
        """The backend's held-set solve on the problem's device."""
        return self.backend.held_set_solve(grid, op, pc, mask, self.device)

    @property
    def upper_bound(self) -> Any:
        """Upper bound of the scaled pressure, the interaction's: for the hard wall ``inf``
        on the footprint, 0 elsewhere (an array of the device; the same array every time)."""
        return self._upper

    @property
    def lower_bound(self) -> float:
        """Lower bound of the scaled pressure: the interaction's."""
        return self.interaction.pressure_lower / self.pressure_scale

    def set_approach(self, delta: float) -> None:
        """Prescribe the rigid approach ``δ`` (beyond first touch; ``δ >= 0``)."""
        non_negative("approach", delta)
        self.approach = float(delta)

    def gap(self, pressure: Any) -> Any:
        """``g = G p + s - δ`` on the footprint (local slab of the device's arrays; zero off
        the footprint)."""
        xp = self.device.xp
        u = self.compliance.apply_array(pressure, xp.empty(self.grid.local_shape))
        return xp.where(
            self._footprint, u + self._recess_flat.reshape(u.shape) - self.approach, 0.0
        )

    def objective_gradient(self, x: Any, grad: Any) -> float:
        """Scaled ``W``; ``grad <- g / (l sqrt(n^2))`` (``g`` zeroed off the footprint)."""
        grid, xp = self.grid, self.device.xp
        c = 1.0 / (self.scale_length * np.sqrt(grid.size))
        u = self._u
        xp.multiply(x.reshape(grid.local_shape), self.pressure_scale, out=u)  # p
        self.compliance.apply_array(u, u)  # u = G p (the FFT works on its own buffers)
        flat = u.reshape(-1)
        flat += self._recess_flat
        flat -= self.approach  # u + s - δ: the gap on the footprint
        # W/a^2 = x.(u_el/2 + s - δ) = (x.g + x.s - δ sum x) / 2 with g = u_el + s - δ
        (w,) = grid.sum(
            0.5 * (xp.vdot(x, flat) + xp.vdot(x, self._recess_flat) - self.approach * x.sum())
        )
        xp.multiply(flat, self._footprint_flat, out=grad)
        grad *= c
        return c * float(w)

    def flat_stiffness_on_grid(self, petsc: object = None) -> float:
        """``dF/dδ`` of the flat punch of the same footprint, on the same grid, on the
        problem's device; the residual of its solve becomes :attr:`flat_residual`.

        ``petsc`` is accepted for compatibility and not used.
        """
        solve = MeasuredSolve(self.held_set_solve, self.device)
        k, _ = punch_stiffness_exact(
            self.grid, self.compliance, self.inverse, self.footprint, solve
        )
        self.flat_residual = solve.residual()
        return k

    def tolerance_floor(self) -> float:
        """No floor: the gap residual is not a difference of large stresses."""
        return 0.0

    def accuracy(self) -> Accuracy:
        """The package's accuracy (:mod:`~petsc_contact.solver.report`): the force of load
        control held to 100 times Newton's tolerance."""
        return Accuracy(accuracy_limit(self.tolerance_floor()), FORCE_ACCURACY)

    def measure(
        self, x: Any, info: SolveInfo, stiffness: bool = False, fields: bool = False
    ) -> Step:
        """The step of a solution ``x`` (TAO's scaled pressure) at the current approach:
        the observables of :attr:`measured`, TAO's report, the verdict, the measured accuracy
        (:meth:`accuracy`) and the exact total stiffness ``dF/dδ`` (always: load control
        needs it) with what :attr:`measured` makes of it (``stiffness`` adds the dataset
        ``stiffness``)."""
        device = self.device
        on_device = x.reshape(self.grid.local_shape) * self.pressure_scale
        gap = device.to_host(self.gap(on_device))
        pressure = device.to_host(on_device)
        obs = self.measured.observables(self, pressure, gap)
        contact, plastic = obs.pop("contact"), obs.pop("plastic")
        verdict = verify_punch(info, obs)
        held = self.held_set_stiffness(contact & ~plastic, verdict == "ok")
        scalars = {
            **obs,
            "force_balance": np.nan,  # under load control: PunchSolver.at_force
            **self.measured.stiffness_scalars(held),
            **info.scalars(verdict),
        }
        if stiffness:
            scalars["stiffness"] = self.measured.stiffness(self, scalars)
        mark_full_contact(scalars)
        self.accuracy().assess(scalars)
        if not fields:
            return Step(scalars)
        extra = self.interaction.fields(gap, plastic)
        return Step(scalars, *contact_fields(gap, pressure, contact), contact=contact, extra=extra)

    def held_set_stiffness(self, contact: np.ndarray, converged: bool) -> dict[str, Any]:
        """The exact total stiffness ``dF/dδ`` with ``contact`` (this rank's host mask of the
        contact pixels below the interaction's cap: a plastic pixel's pressure stays) held
        fixed and the interfacial stiffness per area from it (paper Eq. 2), NaN unless
        ``converged``; the held-set solve's iterations, time, recomputed residual (the
        larger of its and the flat punch's) and the tolerance asked."""
        grid = self.grid
        solve = MeasuredSolve(self.held_set_solve, self.device)
        start = time.perf_counter()
        k_tot, k_its = (
            punch_stiffness_exact(grid, self.compliance, self.inverse, contact, solve)
            if converged
            else (np.nan, 0)
        )
        self.device.synchronize()
        k_time = grid.max(time.perf_counter() - start)
        return {
            "total_stiffness": k_tot,
            "interfacial_stiffness": interfacial_stiffness(k_tot, self.k_flat) / grid.area,
            "flat_punch_stiffness": self.k_flat,
            "flat_punch_beta": self.flat_beta,
            "stiffness_iterations": k_its,
            "stiffness_time": k_time,
            "stiffness_residual": (
                max(solve.residual(), self.flat_residual) if converged else np.nan
            ),
            "stiffness_tolerance": self.backend.stiffness_rtol(),
        }


class PunchProblem(PressureProblem):
    """A rigid rough punch on a free half-space: a :class:`PressureProblem` of the free
    padded compliance (:class:`FreeCompliance`) and the punch's measure
    (:class:`PunchMeasure`).

    Parameters
    ----------
    grid, heights, modulus, footprint, flat, beta, device, backend, interaction
        As for :class:`PressureProblem`.
    substrate
        The elastic body (:class:`~petsc_contact.substrates.substrate.FreeSubstrate`);
        default: the half-space of ``modulus``, whose modulus a given one must have.
    """

    def __init__(
        self,
        grid: Grid,
        heights: np.ndarray,
        modulus: float,
        footprint: np.ndarray | None = None,
        flat: str = "grid",
        beta: float = flat_punch.SQUARE_BETA,
        *,
        device: Device = CPU,
        backend: SolverBackend | None = None,
        substrate: FreeSubstrate | None = None,
        interaction: Interaction = HARD_WALL,
    ) -> None:
        positive("modulus", modulus)
        body: FreeSubstrate = FreeHalfSpace(modulus) if substrate is None else substrate
        self.substrate = of_modulus(body, modulus)
        super().__init__(
            grid, heights, modulus, FreeCompliance(self.substrate), PunchMeasure(), footprint,
            flat, beta, device=device, backend=backend, interaction=interaction,
        )  # fmt: skip


def punch_observables(
    problem: PressureProblem, pressure: np.ndarray, gap: np.ndarray
) -> dict[str, Any]:
    """Scalars of one punch step (same on every rank; see the module docstring), and this
    rank's masks of the pixels in contact and at the interaction's cap (``plastic``, whose
    negative gap is the plastic displacement: ``min_gap`` is over the others)."""
    grid, fp, law = problem.grid, problem.footprint, problem.interaction
    k = problem.pixel_stiffness
    contact = fp & (pressure > k * gap)
    plastic = fp & law.plastic(gap, pressure, k)
    sizes = patch_sizes(grid, contact, periodic=False)
    r = np.where(fp, law.residual(gap, pressure, k), 0.0)
    p_sum, n_contact, pg, r2, g_sum, n_plastic = grid.sum(
        pressure.sum(),
        np.count_nonzero(contact),
        np.vdot(pressure, np.maximum(gap, 0.0)),
        np.vdot(r, r),
        np.where(fp, gap, 0.0).sum(),
        np.count_nonzero(plastic),
    )
    ell, fp_pixels = problem.scale_length, problem.footprint_pixels
    area = grid.area
    force = grid.pixel_area * p_sum
    return {
        "approach": problem.approach,
        "force": force,
        "nominal_pressure": force / area,
        "mean_gap": g_sum / problem.footprint_pixels,
        "area_fraction": n_contact / problem.footprint_pixels,
        "contact_resolved": bool(contact_resolved(n_contact / fp_pixels, fp_pixels)),
        "contact_patches": sizes.size,
        "max_pressure": grid.max(float(pressure.max(initial=0.0))),
        "min_gap": grid.min(float(np.where(fp & ~plastic, gap, np.inf).min(initial=np.inf))),
        "complementarity": pg / (p_sum * ell) if p_sum > 0 else 0.0,
        "kkt_residual": float(np.sqrt(r2 / problem.footprint_pixels)) / ell,
        **distributions(grid, gap, pressure, contact, sizes, fp, problem.filled),
        **law.scalars(int(n_plastic), fp_pixels),
        "contact": contact,
        "plastic": plastic,
    }


def verify_punch(info: SolveInfo, obs: dict[str, Any]) -> str:
    """``'ok'`` or the reason a TAO answer cannot be used (natural residual in units of l)."""
    if info.reason_code <= 0:
        return f"TAO did not converge ({info.reason})"
    return residual_verdict(obs["kkt_residual"], info.effective_tolerance)
