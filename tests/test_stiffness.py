"""Exact incremental stiffness (contact set held fixed) against analytic and sweep values."""

import numpy as np
import pytest

from petsc_contact import periodic_contact
from petsc_contact.backend.stiffness import sweep_stiffness
from petsc_contact.conventions.grid import Grid
from petsc_contact.conventions.warnings import FullContact
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.reference import westergaard

N, DELTA, LENGTH, MODULUS = 256, 0.01, 1.0, 2.0
P_STAR = np.pi * MODULUS * DELTA / LENGTH


def test_westergaard_mean_gap_and_stiffness():
    """1-D wave: u_bar/Delta = 1 - x + x ln x, K = p*/(Delta ln(1/x)), x = p0/p*.

    The mean gap converges fast (to 1e-4 here); the fixed-set stiffness depends on the
    pixel-quantised contact edges, whose half-pixel error gives up to ~1.5% on 256 pixels.
    """
    x = np.arange(N) * LENGTH / N
    h = np.repeat(DELTA * np.cos(2 * np.pi * x / LENGTH)[:, None], N, axis=1)
    fracs = np.array([0.05, 0.2, 0.5, 0.8])
    steps = periodic_contact(
        h,
        length=LENGTH,
        modulus=MODULUS,
        pressures=fracs * P_STAR,
        options=["-tao_gatol", "1e-11"],
        stiffness=True,
    )
    for f, step in zip(fracs, steps, strict=True):
        s = step.scalars
        assert step.converged
        p0 = f * P_STAR
        exact_gap = westergaard.mean_gap(p0, DELTA, LENGTH, MODULUS)
        assert s["mean_gap"] / DELTA == pytest.approx(exact_gap / DELTA, abs=1e-4)
        assert s["stiffness"] == pytest.approx(
            westergaard.stiffness(p0, DELTA, LENGTH, MODULUS), rel=0.02
        )


def test_exact_stiffness_matches_sweep_derivative():
    """Rough 128^2 surface, 1% pressure steps: the fixed-set stiffness and -p d(ln p)/du agree
    to 3% (the contact set changes by a few pixels per step; the difference scheme is
    second order)."""
    grid = Grid(128, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=32, seed=5, rms_slope=0.1
    )
    p0 = np.geomspace(3e-3, 3.3e-3, 11)
    steps = periodic_contact(h, length=1.0, modulus=1.0, pressures=p0, stiffness=True)
    assert all(s.converged for s in steps)
    u = np.array([s.scalars["mean_gap"] for s in steps])
    exact = np.array([s.scalars["stiffness"] for s in steps])
    diff = sweep_stiffness(p0, u)
    assert np.allclose(diff[2:-2], exact[2:-2], rtol=0.03)
    assert np.all(exact > 0)


def test_stiffness_limits():
    """Full contact: no open pixel to soften, the stiffness unbounded, recorded NaN and the
    step flagged; too short a sweep is refused."""
    x = np.arange(32) / 32
    h = np.repeat(DELTA * np.cos(2 * np.pi * x)[:, None], 32, axis=1)
    with pytest.warns(FullContact, match="at or beyond full contact"):
        steps = periodic_contact(
            h, length=1.0, modulus=MODULUS, pressures=[2 * P_STAR], stiffness=True
        )
    assert steps[0].scalars["area_fraction"] == 1.0
    assert steps[0].scalars["full_contact"] and np.isnan(steps[0].scalars["stiffness"])
    with pytest.raises(ValueError):
        sweep_stiffness([1.0, 2.0], [0.1, 0.05])


def test_stiffness_solves_release_their_operators():
    """Each stiffness solve holds two field-sized arrays in its restricted operator and
    preconditioner; PETSc must give both back, or a long sweep grows by two fields a step."""
    import gc

    from petsc_contact.backend.stiffness import Restricted

    x = np.arange(32) / 32
    h = np.repeat(DELTA * np.cos(2 * np.pi * x)[:, None], 32, axis=1)
    steps = periodic_contact(
        h, length=1.0, modulus=MODULUS, pressures=[0.2 * P_STAR, 0.4 * P_STAR], stiffness=True
    )
    assert all(s.converged and s.scalars["stiffness"] > 0 for s in steps)
    gc.collect()
    assert not [o for o in gc.get_objects() if isinstance(o, Restricted)]


def test_the_iteration_limit_fits_petsc_s_integer(petsc):
    """Ten iterations per unknown, capped where PETSc's integer ends: a 15360^2 grid (235.9
    million points) asks for more than a 32-bit ``PetscInt`` holds, and the KSP takes the
    cap, not an ``OverflowError`` after the contact solve."""
    from petsc_contact.backend.stiffness import iteration_cap

    most = int(np.iinfo(petsc.IntType).max)
    assert iteration_cap(512**2, petsc.IntType) == 10 * 512**2
    assert iteration_cap(15360**2, petsc.IntType) == min(10 * 15360**2, most)
    ksp = petsc.KSP().create()
    try:
        ksp.setTolerances(max_it=iteration_cap(15360**2, petsc.IntType))
        assert ksp.getTolerances()[3] == min(10 * 15360**2, most)
    finally:
        ksp.destroy()
