"""A contact model put together from parts: a substrate, an interaction, a solver backend and
a device, each given to the geometries, which use what they are given."""

from dataclasses import dataclass

import numpy as np
import pytest

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import get_device
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.capped_periodic import (
    CappedPeriodicProblem,
    CellMeasure,
    PeriodicCompliance,
)
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.geometries.punch import PressureProblem, PunchProblem
from petsc_contact.interactions.hard_wall import HARD_WALL, HardWall
from petsc_contact.interactions.hardness import HardnessCap
from petsc_contact.physics.greens import mean_mode_compliance
from petsc_contact.physics.surface import self_affine
from petsc_contact.solver.backends import ArrayBackend
from petsc_contact.substrates.half_space import FreeHalfSpace, PeriodicHalfSpace
from petsc_contact.workflows.periodic_sweep import sweep
from petsc_contact.workflows.punch_sweep import PunchSolver


@dataclass(frozen=True)
class TwiceAsStiff:
    """A substrate of modulus ``E`` whose stiffness is the half-space's of ``2 E``."""

    modulus: float
    name = "twice as stiff"

    def stiffness(self, q):
        return self.modulus * q

    def mean_mode_compliance(self, q0, interfacial_stiffness):
        return mean_mode_compliance(2 * self.modulus, q0, interfacial_stiffness)


def heights(n=64, seed=3):
    grid = Grid(n, 1.0)
    h = self_affine(
        grid,
        make_fft(grid),
        hurst=0.7,
        rolloff_ratio=2,
        cutoff_ratio=n // 4,
        seed=seed,
        rms_slope=0.1,
    )
    return grid, h


def test_the_periodic_geometry_uses_the_substrate_it_is_given(petsc):
    """The contact of a substrate whose Green's function is the half-space's of ``2 E*`` is
    that half-space's contact (same mean gap and area to the solver's tolerance, ``1e-8`` of
    the pressures), and not the half-space of its own modulus's (the gaps differ by tens of
    percent at ``p0 = 10^-3 E*``)."""
    grid, h = heights()
    p0 = 1e-3
    given = PeriodicProblem(grid, make_fft(grid), h, 1.0, substrate=TwiceAsStiff(1.0))
    stiffer = PeriodicProblem(grid, make_fft(grid), h, 2.0)
    plain = PeriodicProblem(grid, make_fft(grid), h, 1.0)
    (a,), (b,), (c,) = (list(sweep(p, [p0])) for p in (given, stiffer, plain))
    assert a.converged and b.converged and c.converged
    gap_a, gap_b = a.scalars["mean_gap"], b.scalars["mean_gap"]
    assert gap_a == pytest.approx(gap_b, rel=1e-6)
    assert a.scalars["area_fraction"] == pytest.approx(b.scalars["area_fraction"], abs=2e-4)
    assert abs(c.scalars["mean_gap"] / gap_a - 1) > 0.1


def test_the_default_parts_are_the_papers_model(petsc):
    """The half-space and the hard wall given explicitly are the defaults, bit for bit."""
    grid, h = heights(48)
    explicit = PeriodicProblem(
        grid, make_fft(grid), h, 1.0, substrate=PeriodicHalfSpace(1.0), interaction=HardWall()
    )
    default = PeriodicProblem(grid, make_fft(grid), h, 1.0)
    (a,), (b,) = (list(sweep(p, [2e-3])) for p in (explicit, default))
    assert a.scalars["mean_gap"] == b.scalars["mean_gap"]
    assert a.scalars["iterations"] == b.scalars["iterations"]


def test_a_substrate_of_another_modulus_is_refused(petsc):
    grid, h = heights(16)
    with pytest.raises(ValueError, match="substrate's modulus is 2.0, not 1.0"):
        PeriodicProblem(grid, make_fft(grid), h, 1.0, substrate=PeriodicHalfSpace(2.0))
    with pytest.raises(ValueError, match="substrate's modulus"):
        PunchProblem(grid, h, 1.0, substrate=FreeHalfSpace(3.0))
    with pytest.raises(ValueError, match="modulus"):
        PeriodicHalfSpace(-1.0)


def test_the_hard_wall_s_bounds_and_its_check():
    """``g >= 0``, ``p >= 0``, no pressure off a footprint; a gap below zero by more than
    rounding (``1e-12`` of the scale length) breaks it."""
    footprint = np.array([[True, False], [False, True]])
    upper = HARD_WALL.pressure_upper(footprint, np)
    assert np.array_equal(upper, [[np.inf, 0.0], [0.0, np.inf]])
    assert HARD_WALL.gap_lower == 0.0 and HARD_WALL.pressure_lower == 0.0
    assert HARD_WALL.violation(-1e-13, 1.0) is None
    assert HARD_WALL.violation(-1e-6, 1.0) == "bound violated: min gap -1.000e-06"


def test_the_punch_uses_the_backend_and_substrate_it_is_given(petsc):
    """The punch with the array backend on the stand-in device and an explicit free
    half-space gives the PETSc default's answer: the same force to ``1e-6`` (the solves'
    tolerance is ``1e-8`` of the gap) and the same grid flat punch to the held-set solves'
    tolerance (``1e-6``)."""
    grid, h = heights(32)
    args = (grid, h * 1e-2, 1.0)
    array = PunchProblem(
        *args, device=get_device("cpu-array"), backend=ArrayBackend(), substrate=FreeHalfSpace(1.0)
    )
    default = PunchProblem(*args)
    steps = []
    for problem in (array, default):
        with PunchSolver(problem) as solver:
            steps.append(solver.at_approach(5e-3))
    mine, theirs = steps
    assert mine.converged and theirs.converged
    assert mine.scalars["tao_type"] == "cg" and array.backend.name == "array"
    assert default.backend.name == "petsc"
    assert mine.scalars["force"] == pytest.approx(theirs.scalars["force"], rel=1e-6)
    assert array.k_flat == pytest.approx(default.k_flat, rel=1e-6)


def test_the_capped_cell_is_the_problem_in_the_pressure_composed_of_its_parts(petsc):
    """The capped periodic cell is no punch: it is the one problem posed in the pressure
    (:class:`PressureProblem`) with the periodic compliance and the cell's measure, and that
    class composed by hand of those parts gives its step bit for bit (the same arithmetic),
    Newton's iterations and all; the punch is the same class with its own parts."""
    grid, h = heights(32)
    fft, cap = make_fft(grid), HardnessCap(0.02)
    named = CappedPeriodicProblem(grid, fft, h, 1.0, cap)
    assert isinstance(named, PressureProblem) and not isinstance(named, PunchProblem)
    assert isinstance(PunchProblem(grid, h, 1.0, flat="analytic"), PressureProblem)
    c = PeriodicHalfSpace(1.0).mean_mode_compliance(grid.q0, 0.0)
    body = PeriodicCompliance(PeriodicHalfSpace(1.0), fft, c)
    composed = PressureProblem(grid, h, 1.0, body, CellMeasure(c), flat="analytic", interaction=cap)
    steps = []
    for problem in (named, composed):
        with PunchSolver(problem) as solver:
            steps.append(solver.at_force(5e-3 * grid.area, stiffness=True))
    assert steps[0].converged and steps[0].scalars["plastic_area_fraction"] > 0  # at the cap
    mine, theirs = ({k: v for k, v in s.scalars.items() if not k.endswith("_time")} for s in steps)
    assert repr(mine) == repr(theirs)  # every scalar, NaNs alike
