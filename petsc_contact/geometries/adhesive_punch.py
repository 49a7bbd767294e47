"""The punch with adhesion: the free substrate and the adhesive law, posed in the
displacement of the zero-padded cell (docs/formulation.md).

The punch's face (heights ``h``, recess ``s = max(h) - h`` on the footprint ``F``) meets a
free half-space through an adhesive law ``phi``
(:class:`~petsc_contact.interactions.adhesion.Adhesion`).  The unknown lives on the
``2nx x 2ny`` padded cell of the free substrate (:class:`~petsc_contact.substrates.padded.
PaddedCell`): the gap ``g >= 0`` on ``F`` and the surface's displacement ``w``, with no bound,
off it.  With the displacement ``u = g - s + δ`` on ``F`` and ``u = w + δ`` off it (``δ``
the approach beyond first touch),

    Pi = a^2 [ 1/2 u^T C u + sum_F phi(g) ] - F δ,

``C = 1/G`` the padded cell's stiffness.  Its gradient is ``a^2 (p + phi'(g))`` on ``F`` and
``a^2 p`` off it, ``p = C u``: off the footprint the surface is free.  The mean mode of ``u``
is the approach: under load control (force ``F``) minimising over ``δ`` leaves the periodic
adhesive energy on the padded cell with ``C`` less its mean mode and the nominal pressure
``p0 = F / A_pad`` (:class:`~petsc_contact.geometries.adhesive_periodic.
AdhesivePeriodicProblem`, whose law, scaling, TAO set-up and pull-off detection serve as
they are); under displacement control the approach holds the mean mode by the spring
``c0 = 1/G(q = 0)`` (its loading machine, exact here: :meth:`AdhesivePunchProblem.
set_approach`).  The approach of a solution is ``mean(p)/c0 - mean(u - δ)``.  A gradient
solver (TAO's ``blmvm``, ``bncg``) solves it; the package's CG refuses it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..backend.operator import RowExchange
from ..backend.solve import SolveInfo
from ..conventions.grid import Grid
from ..devices.device import CPU, Device
from ..devices.fft import make_fft
from ..interactions.adhesion import Adhesion
from ..solver.backends import SolverBackend
from ..substrates.half_space import FreeHalfSpace
from ..substrates.padded import PaddedCell
from ..substrates.substrate import FreeSubstrate, of_modulus
from .adhesive_periodic import AdhesivePeriodicProblem
from .punch import face_recess
from .step import Step


class AdhesivePunchProblem(AdhesivePeriodicProblem):
    """A rigid punch with face ``heights`` on a free half-space through ``adhesion`` (module
    docstring).

    Parameters
    ----------
    grid
        The ``nx x ny`` footprint grid; the problem's :attr:`grid` is its padded cell.
    heights
        This rank's slab of the face's heights.
    modulus, adhesion, backend
        As for :class:`~petsc_contact.geometries.adhesive_periodic.AdhesivePeriodicProblem`.
    footprint
        This rank's slab of the punch's pixels (default: the whole grid).
    device
        Where the solver's fields live.
    substrate
        The free elastic body (default: the half-space of ``modulus``).
    """

    def __init__(
        self,
        grid: Grid,
        heights: np.ndarray,
        modulus: float,
        adhesion: Adhesion,
        footprint: np.ndarray | None = None,
        backend: SolverBackend | None = None,
        *,
        device: Device = CPU,
        substrate: FreeSubstrate | None = None,
    ) -> None:
        body = of_modulus(FreeHalfSpace(modulus) if substrate is None else substrate, modulus)
        padded = grid.padded()
        fft = make_fft(padded, device)
        self.cell = PaddedCell(body, grid, fft)
        self.face_grid, self._cell_shape = grid, padded.local_shape
        self.exchange = RowExchange(grid.comm, grid.shape, padded.shape[0])
        face = np.ones(grid.local_shape, dtype=bool) if footprint is None else footprint
        self.footprint = np.asarray(face, dtype=bool).reshape(grid.local_shape)
        self.footprint_pixels = int(grid.sum(np.count_nonzero(self.footprint))[0])
        if self.footprint_pixels == 0:
            raise ValueError("the punch footprint is empty")
        recess, self.face_scale = face_recess(grid, heights, self.footprint)
        lifted = -self.to_padded(recess)  # u - δ = g - s on F, w off it
        self.mean_lift = padded.mean(lifted)
        super().__init__(padded, fft, lifted, modulus, adhesion, backend, substrate=self.cell)
        self.face_mask = self.to_padded(self.footprint) > 0  # the footprint in the cell (host)
        self._on_face = device.asarray(self.face_mask.reshape(-1))
        self._lower = device.asarray(np.where(self.face_mask, 0.0, -np.inf).reshape(-1))
        self.approach = np.nan
        self.face_pressure = np.nan  # the prescribed nominal pressure (load control)

    def to_padded(self, field: np.ndarray) -> np.ndarray:
        """This rank's rows of the padded cell with ``field`` (a footprint slab) in its
        first block, 0 elsewhere (host arrays)."""
        out = np.zeros(self._cell_shape)
        self.exchange.to_padded(np.asarray(field, dtype=float), out[:, : self.face_grid.shape[1]])
        return out

    def to_face(self, field: Any) -> np.ndarray:
        """The footprint slab of a padded field (on the host)."""
        out = np.empty(self.face_grid.local_shape)
        block = self.device.to_host(field).reshape(self.grid.local_shape)
        self.exchange.to_footprint(block[:, : self.face_grid.shape[1]], out)
        return out

    @property
    def lower_bound(self) -> Any:
        """The scaled unknown's lower bounds: the gap's 0 on the footprint, none off it."""
        return self._lower

    def law_gap(self, x: Any) -> Any:
        """The gap the law sees: ``l x`` on the footprint, infinite (no attraction) off it."""
        on_face = self._on_face.reshape(x.shape)
        return self.device.xp.where(on_face, x * self.scale_length, np.inf)

    @property
    def face_area(self) -> float:
        """The footprint's area ``Lx Ly`` (the nominal pressure's)."""
        return self.face_grid.area

    def set_pressure(self, p0: float, interfacial_stiffness: float | None = None) -> None:
        """Load control: the force ``F = p0 Lx Ly`` (``p0`` the nominal pressure over the face,
        any sign), the padded cell's ``p0 Lx Ly / A_pad``."""
        self.adhesion.check_nominal(p0, "nominal pressure")
        super().set_pressure(p0 * self.face_area / self.grid.area, interfacial_stiffness)
        self.approach, self.face_pressure = np.nan, float(p0)

    def set_approach(self, delta: float) -> None:
        """Displacement control: the approach ``δ`` (any sign: negative pulls the punch back
        beyond first touch), held by the spring ``c0`` on the mean mode at the anchor
        ``-(mean(u - δ - l x) + δ)``."""
        if not np.isfinite(delta):
            raise ValueError(f"the approach {delta} is not a finite number")
        c0 = self.cell.mean_stiffness
        scale = max(self.adhesion.strength, c0 * abs(float(delta)))
        self.set_machine(-(self.mean_lift + float(delta)), scale, c0)
        self.approach, self.face_pressure = float(delta), np.nan

    def measure(
        self, x: Any, info: SolveInfo, stiffness: bool = False, fields: bool = False
    ) -> Step:
        """The step of a solution ``x`` (the scaled unknown on the padded cell):
        :func:`adhesive_punch_observables`, the solver's report and the verdict."""
        if self.machine is not None:  # the padded cell's nominal pressure the machine holds
            self.nominal_pressure = self._spring(x)[1]
        ell = self.scale_length
        gap = x.reshape(self.grid.local_shape) * ell
        pressure = self.device.to_host(self.pressure(gap))
        obs = adhesive_punch_observables(self, self.device.to_host(gap), pressure)
        return self.judged(info, obs, fields, self.to_face(gap), self.to_face(pressure))


def adhesive_punch_observables(
    problem: AdhesivePunchProblem, padded_gap: np.ndarray, pressure: np.ndarray
) -> dict[str, Any]:
    """Scalars of one adhesive punch step (same on every rank) and the footprint's contact
    mask ``contact`` (where the wall pushes, ``p + phi'(g) > k g``), from the padded cell's
    host fields ``l x`` and ``p``.

    ``force`` is ``a^2 sum_F p`` and ``nominal_pressure`` the prescribed one (load control:
    a step that pulled off keeps its load) or the force over ``Lx Ly``; ``approach``
    ``mean(p)/c0 - mean(u - δ)`` over the padded cell; ``adhesive_pressure`` the attraction
    over the face, ``a^2 sum_F phi'(g) / (Lx Ly)``; ``force_balance`` the traction left off
    the footprint, ``|a^2 sum p - F| / (P Lx Ly)``; ``kkt_residual``
    ``sqrt((sum_F min(k g, p + phi'(g))^2 + sum_off p^2) / N_F) / P``;
    ``interaction_energy`` ``a^2 sum_F phi(g) / (Lx Ly)``."""
    face, cell, law = problem.face_grid, problem.grid, problem.adhesion
    fp, k, scale = problem.footprint, problem.pixel_stiffness, problem.pressure_scale
    gap, p = problem.to_face(padded_gap), problem.to_face(pressure)
    seen = np.where(fp, gap, np.inf)  # the gap the law sees: none off the footprint
    total = p + law.derivative(seen)
    contact = fp & (total > k * gap)
    r = np.where(fp, np.minimum(k * gap, total), 0.0)
    off = np.where(problem.face_mask, 0.0, pressure)
    lifted = padded_gap + problem.device.to_host(problem.heights)  # u - δ less its mean lift
    p_f, a_f, n_contact, g_f, r2, phi_f = face.sum(
        np.where(fp, p, 0.0).sum(), law.derivative(seen).sum(), np.count_nonzero(contact),
        np.where(fp, gap, 0.0).sum(), np.vdot(r, r), law.energy(seen).sum(),
    )  # fmt: skip
    p_all, p2_off, u_sum = cell.sum(pressure.sum(), np.vdot(off, off), lifted.sum())
    a2, n_f, area = face.pixel_area, problem.footprint_pixels, problem.face_area
    lift, load = problem.mean_lift, problem.face_pressure
    approach = p_all / cell.size / problem.cell.mean_stiffness - (u_sum / cell.size + lift)
    force = a2 * p_f
    return {
        "approach": approach,
        "force": force,
        "nominal_pressure": force / area if np.isnan(load) else load,
        "mean_gap": g_f / n_f,
        "area_fraction": n_contact / n_f,
        "adhesive_pressure": a2 * a_f / area,
        "force_balance": abs(a2 * p_all - force) / (scale * area),
        "pressure_scale": scale,
        "max_pressure": face.max(float(np.where(fp, p, -np.inf).max(initial=-np.inf))),
        "min_pressure": face.min(float(np.where(fp, p, np.inf).min(initial=np.inf))),
        "min_gap": face.min(float(seen.min(initial=np.inf))),
        "kkt_residual": float(np.sqrt((r2 + p2_off) / n_f)) / scale,
        "interaction_energy": a2 * phi_f / area,
        "contact": contact,
    }
