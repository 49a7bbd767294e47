"""The rigid punch on a free half-space: operator, Hertz, flat punches, stiff cases."""

import numpy as np
import pytest

from petsc_contact.backend.operator import PaddedOperator
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.punch import flat_punch_stiffness, interfacial_stiffness
from petsc_contact.physics.greens import hockney_kernel, love_pixel_displacement
from petsc_contact.physics.surface import self_affine
from petsc_contact.reference import flat_punch, hertz
from petsc_contact.workflows.punch_sweep import punch_contact

N = 128  # footprint pixels per side for the analytic comparisons


def centres(n, length=1.0):
    return (np.arange(n) + 0.5) * length / n - length / 2


def test_padded_operator_against_direct_summation():
    """FFT on the 2n x 2n padded grid = dense Love-kernel matrix; symmetric, SPD (n = 12)."""
    n, a, modulus = 12, 0.1, 3.0
    grid = Grid(n, n * a)
    op = PaddedOperator(grid, lambda rows: hockney_kernel(n, a, modulus, rows))
    x = np.repeat(np.arange(n) * a, n)
    y = np.tile(np.arange(n) * a, n)
    # direct summation of the closed form, point by point (no FFT, no padding)
    dense = love_pixel_displacement(x[:, None] - x[None, :], y[:, None] - y[None, :], a, modulus)
    rng = np.random.default_rng(1)
    for _ in range(3):  # repeated applications must not depend on leftover buffer contents
        v = rng.standard_normal((n, n))
        out = op.apply_array(v, np.empty((n, n)))
        assert np.allclose(out.ravel(), dense @ v.ravel(), rtol=0, atol=1e-13 * np.abs(out).max())
        # the quadratic form from the padded spectrum (Parseval), as the CG uses it
        assert op.begin_mult(v) == pytest.approx(v.ravel() @ dense @ v.ravel(), rel=1e-12)
    assert np.allclose(dense, dense.T, rtol=0, atol=1e-15 * dense.max())
    assert np.linalg.eigvalsh(dense).min() > 0
    u, w = rng.standard_normal((2, n, n))
    gu, gw = (op.apply_array(v, np.empty((n, n))) for v in (u, w))
    assert np.vdot(w, gu) == pytest.approx(np.vdot(u, gw), rel=1e-13)  # the FFT operator too
    assert op.diagonal() == pytest.approx(dense[0, 0], rel=1e-14)
    assert dense[0, 0] == pytest.approx(4 * a * np.arcsinh(1) / (np.pi * modulus), rel=1e-14)


def test_hertz():
    """Sphere R = 1 in a 128^2 footprint of side 1, contact radius 0.14-0.3 (18-38 pixels).

    Contact radius from the contact area, force and pressure (rms over r < 0.9 a, relative to
    the peak) within 1% of Hertz.
    """
    x = centres(N)
    r2 = x[:, None] ** 2 + x[None, :] ** 2
    radius, modulus = 1.0, 2.0
    deltas = [0.02, 0.05, 0.09]
    steps = punch_contact(
        -r2 / (2 * radius), length=1.0, modulus=modulus, approaches=deltas, fields=True
    )
    for d, step in zip(deltas, steps, strict=True):
        s = step.scalars
        assert step.converged, s["verification"]
        a = hertz.contact_radius(d, radius)
        assert np.sqrt(s["area_fraction"] / np.pi) == pytest.approx(a, rel=0.01)
        assert s["force"] == pytest.approx(hertz.force(d, radius, modulus), rel=0.01)
        p_hertz = hertz.pressure(np.sqrt(r2), d, radius, modulus)
        inner = r2 < (0.9 * a) ** 2
        err = np.sqrt(np.mean((step.pressure[inner] - p_hertz[inner]) ** 2))
        assert err < 0.01 * p_hertz.max()
        assert s["total_stiffness"] == pytest.approx(hertz.stiffness(d, radius, modulus), rel=0.01)


def test_flat_square_punch():
    """Stiffness within 0.3% of the exact square's pi C E* L on 128^2 (0.27% below it, as
    tests/test_flat_reference.py measures); pressure grows monotonically from the centre to
    the edge (the edge singularity)."""
    (step,) = punch_contact(
        np.zeros((N, N)), length=1.0, modulus=1.0, approaches=[1e-3], fields=True
    )
    s = step.scalars
    assert step.converged and s["area_fraction"] == 1.0
    assert s["force"] / 1e-3 == pytest.approx(flat_punch_stiffness(1.0, 1.0), rel=3e-3)
    assert s["total_stiffness"] == pytest.approx(s["force"] / 1e-3, rel=1e-8)
    assert s["flat_punch_stiffness"] == pytest.approx(s["total_stiffness"], rel=1e-8)
    line = step.pressure[N // 2, N // 2 :]
    assert np.all(np.diff(line) > 0)
    assert s["max_pressure"] == pytest.approx(step.pressure[0, 0], rel=1e-12)  # the corner


def test_flat_circular_punch():
    """Masked disk footprint: stiffness within 1% of 2 E* r (r from the pixel area)."""
    x = centres(N)
    disk = x[:, None] ** 2 + x[None, :] ** 2 < 0.45**2
    modulus = 3.0
    (step,) = punch_contact(
        np.zeros((N, N)),
        length=1.0,
        modulus=modulus,
        approaches=[1e-3],
        fields=True,
        footprint=disk,
        beta=1.0,
    )
    r = np.sqrt(disk.sum() / N**2 / np.pi)
    assert step.converged
    assert step.scalars["total_stiffness"] == pytest.approx(
        flat_punch.circular_stiffness(r, modulus), rel=0.01
    )
    assert np.all(step.pressure[~disk] == 0)
    assert step.scalars["area_fraction"] == 1.0


@pytest.fixture(scope="module")
def rough():
    grid = Grid(64, 1.0)
    return self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=16, seed=3, rms_height=1e-3
    )


def test_stiffness_matches_force_difference(rough):
    """Exact dF/dδ (contact set fixed) against a central difference of F(δ) (2%: the contact
    set changes inside the difference step) and springs in series (Eq. 2)."""
    d, eps = 3e-3, 2e-5
    steps = punch_contact(rough, length=1.0, modulus=1.0, approaches=[d - eps, d, d + eps])
    assert all(s.converged for s in steps)
    lo, mid, hi = (s.scalars for s in steps)
    assert mid["total_stiffness"] == pytest.approx(
        (hi["force"] - lo["force"]) / (2 * eps), rel=0.02
    )
    k_int = interfacial_stiffness(mid["total_stiffness"], mid["flat_punch_stiffness"])
    assert mid["interfacial_stiffness"] == pytest.approx(k_int, rel=1e-12)
    assert 1 / k_int == pytest.approx(
        1 / mid["total_stiffness"] - 1 / mid["flat_punch_stiffness"], rel=1e-12
    )


def test_load_control_reaches_force(rough):
    forces = [1e-5, 1e-4, 1e-3]
    steps = punch_contact(rough, length=1.0, modulus=1.0, forces=forces)
    for f, step in zip(forces, steps, strict=True):
        s = step.scalars
        assert step.converged, s["verification"]
        assert s["force"] == pytest.approx(f, rel=1e-6)
    (check,) = punch_contact(
        rough, length=1.0, modulus=1.0, approaches=[steps[1].scalars["approach"]]
    )
    assert check.scalars["force"] == pytest.approx(1e-4, rel=1e-6)


def test_load_control_on_a_few_pixels():
    """At forces that touch 4-6 pixels of a 256^2 punch, Newton stops within the solve's
    resolution (TAO accepting its warm start) instead of running out of steps: converged,
    the force within 1e-4 of the target, in a handful of Newton steps."""
    grid = Grid(256, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=128, seed=1, rms_slope=0.1
    )
    steps = punch_contact(h, length=1.0, modulus=1.0, forces=[1e-6, 3e-6])
    for f, step in zip([1e-6, 3e-6], steps, strict=True):
        s = step.scalars
        assert step.converged, s["verification"]
        assert s["force"] == pytest.approx(f, rel=1e-4)
        assert s["newton_iterations"] <= 10 and s["area_fraction"] * 256**2 <= 8


def test_load_control_continues_from_the_last_step(rough):
    """Each force starts Newton from the last step's tangent: a few Newton steps, and the
    same approach as a solver that starts afresh (to the force tolerance over K)."""
    steps = punch_contact(rough, length=1.0, modulus=1.0, forces=[1e-4, 2e-4, 4e-4])
    for f, step in zip([2e-4, 4e-4], steps[1:], strict=True):
        (fresh,) = punch_contact(rough, length=1.0, modulus=1.0, forces=[f])
        assert step.scalars["newton_iterations"] <= 4 < fresh.scalars["newton_iterations"]
        assert step.scalars["approach"] == pytest.approx(fresh.scalars["approach"], rel=1e-5)


@pytest.mark.parametrize("solver", [[], ["-tao_type", "tron"]])
def test_edge_singularity_at_high_load(rough, solver):
    """Pressed 200 h_rms beyond first touch: full contact, the corner carries the peak
    pressure, and the solve converges (default: ~20 iterations, tron: ~10)."""
    (step,) = punch_contact(
        rough, length=1.0, modulus=1.0, approaches=[0.2], options=solver, fields=True
    )
    s = step.scalars
    assert step.converged, s["verification"]
    assert s["area_fraction"] == 1.0
    assert s["iterations"] < 200
    corners = step.pressure[[0, 0, -1, -1], [0, -1, 0, -1]]
    assert s["max_pressure"] == pytest.approx(corners.max(), rel=1e-12)
    assert s["max_pressure"] > 5 * s["nominal_pressure"]


def test_mean_gap_over_the_face(rough):
    """``u_bar``: the mean recess at first touch (no deformation yet), zero under a flat punch
    in full contact, and its ``-dp/du_bar`` the interfacial stiffness of Eq. 2 within 10%
    from 1% to 30% contact area (both measure the interface's compliance alone: Eq. 2 takes
    the flat punch's out of the total, ``u_bar`` never holds it)."""
    (first,) = punch_contact(rough, length=1.0, modulus=1.0, approaches=[0.0])
    assert first.scalars["mean_gap"] == pytest.approx(np.mean(rough.max() - rough), rel=1e-12)
    (flat,) = punch_contact(np.zeros((32, 32)), length=1.0, modulus=1.0, approaches=[1e-3])
    assert flat.scalars["area_fraction"] == 1.0 and abs(flat.scalars["mean_gap"]) < 1e-9
    eps = 2e-5
    for d in (1e-3, 3e-3, 6e-3):
        lo, mid, hi = (
            s.scalars
            for s in punch_contact(rough, length=1.0, modulus=1.0, approaches=[d - eps, d, d + eps])
        )
        assert 0.01 < mid["area_fraction"] < 0.31
        dp_du = -(hi["nominal_pressure"] - lo["nominal_pressure"]) / (
            hi["mean_gap"] - lo["mean_gap"]
        )
        assert dp_du == pytest.approx(mid["interfacial_stiffness"], rel=0.1)
