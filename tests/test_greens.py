"""The periodic elastic operator: exact on single sine waves, symmetric, constants annihilated."""

import numpy as np
import pytest

from petsc_contact.backend.operator import FourierOperator
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft, wavevector_magnitude
from petsc_contact.physics.greens import periodic_compliance, periodic_stiffness


@pytest.fixture(scope="module")
def op():
    grid = Grid(64, 2.5)
    fft = make_fft(grid)
    return FourierOperator(grid, fft, periodic_stiffness(wavevector_magnitude(grid, fft), 3.0))


@pytest.mark.parametrize("k", [(1, 0), (0, 3), (5, 7), (32, 0), (-4, 9)])
def test_single_wave_exact(op, k):
    grid = op.grid
    x = np.arange(grid.n) * grid.pixel
    X, Y = np.meshgrid(x, x, indexing="ij")
    qx, qy = 2 * np.pi * np.array(k) / grid.length
    u = np.cos(qx * X + qy * Y + 0.3)
    p = op.apply_array(u, np.empty_like(u))
    if k == (32, 0):  # Nyquist: only the cosine part survives sampling
        u = np.cos(qx * X) * np.cos(0.3)
    assert np.allclose(p, 3.0 * np.hypot(qx, qy) / 2 * u, atol=1e-11)


def test_constant_annihilated_and_symmetric(op):
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((2, 64, 64))
    assert np.abs(op.apply_array(np.ones((64, 64)), np.empty((64, 64)))).max() < 1e-12
    ka, kb = (op.apply_array(v, np.empty_like(v)) for v in (a, b))
    assert np.vdot(b, ka) == pytest.approx(np.vdot(a, kb), rel=1e-12)
    assert np.vdot(a, ka) > 0


def test_compliance_inverts_stiffness(op):
    grid, fft = op.grid, op.fft
    q = wavevector_magnitude(grid, fft)
    comp = FourierOperator(grid, fft, periodic_compliance(q, 3.0, grid.q0))
    u = np.random.default_rng(1).standard_normal((64, 64))
    u -= u.mean()
    back = comp.apply_array(op.apply_array(u, np.empty_like(u)), np.empty_like(u))
    assert np.allclose(back, u, atol=1e-12)


@pytest.mark.parametrize("n", [64, 15])
def test_quadratic_form_from_spectrum(n):
    """``begin_mult`` returns ``x.Kx`` from the half spectrum (multiplicities 1 on the
    ``qy = 0`` and, for even n, ``qy = n/2`` columns, 2 elsewhere); ``end_mult`` gives ``Kx``."""
    grid = Grid(n, 2.5)
    fft = make_fft(grid)
    op = FourierOperator(grid, fft, periodic_stiffness(wavevector_magnitude(grid, fft), 3.0))
    x = np.random.default_rng(n).standard_normal((n, n))
    quadratic = op.begin_mult(x)
    kx = op.end_mult(np.empty_like(x))
    assert quadratic == pytest.approx(np.vdot(x, kx), rel=1e-12)
    assert np.allclose(kx, op.apply_array(x, np.empty_like(x)), rtol=0, atol=1e-12)


def test_reference_solutions_are_consistent():
    """The analytic references agree with their own identities: Westergaard's pressure
    averages to p0 and its stiffness is -dp0/du_bar; Hertz's stiffness is dF/d delta and its
    pressure integrates to the force."""
    from petsc_contact.reference import flat_punch, hertz, westergaard

    amp, lam, modulus, p0 = 0.01, 1.0, 2.0, 0.02
    x = (np.arange(200000) + 0.5) / 200000 * lam
    assert westergaard.pressure(x, p0, amp, lam, modulus).mean() == pytest.approx(p0, rel=1e-6)
    dp = 1e-6 * p0
    du = westergaard.mean_gap(p0 + dp, amp, lam, modulus) - westergaard.mean_gap(
        p0 - dp, amp, lam, modulus
    )
    assert -2 * dp / du == pytest.approx(westergaard.stiffness(p0, amp, lam, modulus), rel=1e-8)
    with pytest.raises(ValueError, match="full-contact"):
        westergaard.half_width(
            2 * westergaard.full_contact_pressure(amp, lam, modulus), amp, lam, modulus
        )

    radius, d = 2.0, 0.01
    dd = 1e-6 * d
    dfdd = (hertz.force(d + dd, radius, modulus) - hertz.force(d - dd, radius, modulus)) / (2 * dd)
    assert dfdd == pytest.approx(hertz.stiffness(d, radius, modulus), rel=1e-8)
    a = hertz.contact_radius(d, radius)
    r = (np.arange(100000) + 0.5) / 100000 * a
    integral = np.sum(hertz.pressure(r, d, radius, modulus) * 2 * np.pi * r) * (a / 100000)
    assert integral == pytest.approx(hertz.force(d, radius, modulus), rel=1e-6)
    assert hertz.radius_at_force(hertz.force(d, radius, modulus), radius, modulus) == pytest.approx(
        a
    )
    assert flat_punch.stiffness(np.pi, 1.0, beta=1.0) == pytest.approx(2.0)
