"""Periodic contact against analytic solutions and identities."""

import numpy as np
import pytest

from petsc_contact import periodic_contact
from petsc_contact.backend.operator import FourierOperator
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft, wavevector_magnitude
from petsc_contact.physics.greens import periodic_stiffness
from petsc_contact.physics.surface import self_affine
from petsc_contact.reference import westergaard as wave_solution

TIGHT = ["-tao_gatol", "1e-11"]
PK = ["-tao_type", "python", "-tao_python_type", "petsc_contact.backend.cg.PolonskyKeer"]
SOLVERS = {"default": [], "tron": ["-tao_type", "tron"], "bnls": ["-tao_type", "bnls"], "pk": PK}
N_WAVE = 256
DELTA, LENGTH, MODULUS = 0.01, 1.0, 2.0
P_STAR = wave_solution.full_contact_pressure(DELTA, LENGTH, MODULUS)


def wave():
    x = np.arange(N_WAVE) * LENGTH / N_WAVE
    return np.repeat(DELTA * np.cos(2 * np.pi * x / LENGTH)[:, None], N_WAVE, axis=1), x


def westergaard(x, p0):
    """Half-width and pressure of the periodic 1-D wave contact."""
    return (
        wave_solution.half_width(p0, DELTA, LENGTH, MODULUS),
        wave_solution.pressure(x, p0, DELTA, LENGTH, MODULUS),
    )


@pytest.fixture(scope="module")
def rough():
    grid = Grid(128, 1.0)
    return self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=32, seed=7, rms_slope=0.1
    )


@pytest.mark.parametrize("solver", ["default", "tron", "pk"])
def test_westergaard(solver):
    """Contact width within one pixel; pressure within discretisation error.

    The pressure has a square-root edge, so a pixel-centred discretisation converges like
    sqrt(a/L) at the edges and much faster inside: we compare the rms error over the inner
    80% of the contact to 1% of the peak pressure, and the total force to 1e-9.
    """
    h, x = wave()
    fracs = [0.05, 0.3, 0.7]
    steps = periodic_contact(
        h,
        length=LENGTH,
        modulus=MODULUS,
        pressures=[f * P_STAR for f in fracs],
        options=[*SOLVERS[solver], *TIGHT],
        fields=True,
    )
    pix = LENGTH / N_WAVE
    for f, step in zip(fracs, steps, strict=True):
        assert step.converged, step.scalars["verification"]
        half, p_exact = westergaard(x, f * P_STAR)
        contact_px = np.count_nonzero(step.gap[:, 0] == 0)
        assert abs(contact_px * pix - 2 * half) <= pix * (1 + 1e-9)
        p = step.pressure[:, 0]
        inner = np.abs((x + LENGTH / 2) % LENGTH - LENGTH / 2) < 0.8 * half
        err = np.sqrt(np.mean((p[inner] - p_exact[inner]) ** 2))
        assert err < 0.01 * p_exact.max()
        assert step.scalars["area_fraction"] == pytest.approx(contact_px / N_WAVE, abs=1e-12)


def test_identities_rough(rough):
    """Force balance, complementarity and the energy identity on a rough surface."""
    p0s = [1e-3, 3e-3]
    steps = periodic_contact(
        rough, length=1.0, modulus=1.0, pressures=p0s, options=TIGHT, fields=True
    )
    grid = Grid(128, 1.0)
    fft = make_fft(grid)
    k = FourierOperator(grid, fft, periodic_stiffness(wavevector_magnitude(grid, fft), 1.0))
    for p0, step in zip(p0s, steps, strict=True):
        s = step.scalars
        assert step.converged
        # force balance: the mean pressure on the contact set is p0
        assert s["contact_pressure_mean"] == pytest.approx(p0, rel=1e-10)
        # complementarity (Tamaas-style): contact pixels have g = 0, open ones a pressure
        # residual, so Cauchy-Schwarz bounds sum(p+ g) by ||p_res|| ||g|| and the measure by
        # gatol * rms(g) / h_rms (gatol bounds the rms residual in units of p0)
        rms_gap = np.sqrt(np.mean(step.gap**2))
        assert 0 <= s["complementarity"] <= 1e-11 * rms_gap / rough.std()
        assert s["min_gap"] >= 0
        # any pixel's pressure residual is bounded by the projected gradient's 2-norm,
        # which the tolerance bounds by sqrt(n^2) * gatol * p0
        assert s["min_pressure"] >= -128 * 1e-11 * p0
        # energy: 1/2 <u K u> from an independent FFT of the displacement u = g + h
        u = step.gap + rough - rough.mean()
        energy = 0.5 * np.mean(u * k.apply_array(u, np.empty_like(u)))
        assert s["elastic_energy"] == pytest.approx(energy, rel=1e-9)
        # pressure equals the stiffness applied to the displacement, plus p0
        assert np.allclose(step.pressure, k.apply_array(u, np.empty_like(u)) + p0, atol=1e-9 * p0)


def test_work_equals_energy(rough):
    """dU = -p0 du_bar: the elastic energy gained equals the work of the load (trapezoid
    rule on a fine sweep; its error is O(dp^2), below 1e-3 here)."""
    p0s = np.linspace(2e-3, 4e-3, 21)
    steps = periodic_contact(rough, length=1.0, modulus=1.0, pressures=p0s, options=TIGHT)
    u = np.array([s.scalars["mean_gap"] for s in steps])
    energy = np.array([s.scalars["elastic_energy"] for s in steps])
    work = -np.trapezoid(p0s, u)
    assert energy[-1] - energy[0] == pytest.approx(work, rel=1e-3)


def test_full_contact_limit(rough):
    grid = Grid(128, 1.0)
    fft = make_fft(grid)
    k = FourierOperator(grid, fft, periodic_stiffness(wavevector_magnitude(grid, fft), 1.0))
    h = rough - rough.mean()
    kh = k.apply_array(h, np.empty_like(h))
    p_full = -kh.min()
    steps = periodic_contact(
        rough,
        length=1.0,
        modulus=1.0,
        pressures=[0.98 * p_full, 1.5 * p_full],
        options=TIGHT,
        fields=True,
    )
    below, above = steps
    assert below.scalars["area_fraction"] < 1.0
    assert above.converged
    assert above.scalars["area_fraction"] == 1.0
    assert np.abs(above.gap).max() == 0.0
    assert np.allclose(above.pressure, 1.5 * p_full + kh, rtol=0, atol=1e-12 * p_full)
    assert above.scalars["elastic_energy"] == pytest.approx(0.5 * np.mean(h * kh), rel=1e-12)


def test_cross_solver_agreement(rough):
    """Different TAO types reach the same solution (mean gap to 1e-6, area to two pixels)
    at their default tolerance (BQNLS at its options file's 1e-7, see options/bqnls.opts)."""
    results = {}
    types = {t: ["-tao_type", t] for t in ("tron", "bqnls", "blmvm", "bncg", "bnls")}
    types["bqnls"] += ["-tao_gatol", "1e-7"]
    for t, opts in {"default": [], "pk": PK, **types}.items():
        (step,) = periodic_contact(rough, length=1.0, modulus=1.0, pressures=[2e-3], options=opts)
        assert step.converged, (t, step.scalars["verification"])
        results[t] = step.scalars
    ref = results["default"]
    for t, s in results.items():
        assert s["mean_gap"] == pytest.approx(ref["mean_gap"], rel=1e-6), t
        assert abs(s["area_fraction"] - ref["area_fraction"]) * 128**2 <= 2, t


@pytest.mark.parametrize("tao_type", ["tron", "bnls"])
def test_fourier_ksp_preconditioner(rough, tao_type):
    """The Newton types' KSP preconditioned by the restricted Fourier compliance (PCMAT)
    reaches the unpreconditioned solution with far fewer Hessian applications (measured at
    128^2: about 5x fewer; asserted: 2x)."""
    steps = {}
    for name, extra in (("fourier", []), ("none", ["-petsc_contact_no_ksp_pc"])):
        (steps[name],) = periodic_contact(
            rough,
            length=1.0,
            modulus=1.0,
            pressures=[2e-3],
            options=["-tao_type", tao_type, *extra],
        )
        assert steps[name].converged, steps[name].scalars["verification"]
    fourier, none = steps["fourier"].scalars, steps["none"].scalars
    assert fourier["preconditioner_applications"] > 0 == none["preconditioner_applications"]
    assert 2 * fourier["hessian_applications"] < none["hessian_applications"]
    assert fourier["mean_gap"] == pytest.approx(none["mean_gap"], rel=1e-6)


@pytest.mark.parametrize("solver", ["default", "tron"])
def test_single_asperity_and_huge_load(rough, solver):
    steps = periodic_contact(
        rough, length=1.0, modulus=1.0, pressures=[1e-7, 1e-6, 10.0], options=SOLVERS[solver]
    )
    assert all(s.converged for s in steps), [s.scalars["verification"] for s in steps]
    assert 0 < steps[0].scalars["area_fraction"] < 1e-3
    assert steps[-1].scalars["area_fraction"] == 1.0


@pytest.mark.parametrize("solver", ["default", "blmvm"])
def test_not_converged_is_flagged(rough, solver):
    opts = [] if solver == "default" else ["-tao_type", solver]
    (step,) = periodic_contact(
        rough, length=1.0, modulus=1.0, pressures=[1e-2], options=[*opts, "-tao_max_it", "3"]
    )
    assert not step.converged
    assert step.scalars["tao_reason"] == "DIVERGED_MAXITS"
    assert "did not converge" in step.scalars["verification"]


def test_options_do_not_leak(rough):
    periodic_contact(
        rough, length=1.0, modulus=1.0, pressures=[1e-2], options=["-tao_type", "bncg"]
    )
    (step,) = periodic_contact(rough, length=1.0, modulus=1.0, pressures=[1e-2])
    assert step.scalars["tao_type"] == "cg"


def test_contact_fields_are_projected(rough):
    """Stored fields follow the contact rule exactly: zero pressure off contact, zero gap in
    it, the mask's fraction is the area fraction; force balance survives the projection to
    the step's own tolerance (the projected pressures are the KKT residual's share)."""
    (step,) = periodic_contact(rough, length=1.0, modulus=1.0, pressures=[1e-2], fields=True)
    contact = step.field("contact")
    assert contact is not None and contact.dtype == bool
    assert np.all(step.pressure[~contact] == 0.0) and np.all(step.gap[contact] == 0.0)
    assert contact.mean() == pytest.approx(step.scalars["area_fraction"], abs=1e-12)
    assert step.pressure.mean() == pytest.approx(1e-2, rel=1e-6)
    with pytest.raises(KeyError, match="no field"):
        step.field("heights")


def test_list_keeps_the_last_state_only(rough):
    """A returned sweep holds one field per step only when asked (``fields``); the last step
    keeps the gap to go on from, whose mean is its mean gap."""
    steps = periodic_contact(rough, length=1.0, modulus=1.0, pressures=[3e-3, 1e-2, 3e-2])
    assert [s.state is None for s in steps] == [True, True, False]
    assert steps[-1].state.min() >= 0.0
    assert steps[-1].state.mean() == pytest.approx(steps[-1].scalars["mean_gap"], rel=1e-12)


def test_a_bad_pressure_is_refused_in_one_line(rough):
    """periodic_contact refuses a pressure that is not positive (checked once, where it is
    given) and one the surface does not resolve, before solving."""
    solved: list[object] = []
    for pressure, says in (
        (-1e-3, "must be positive"),
        (np.nan, "must be positive"),
        (1e7, "no elastic contact"),
        (1e-300, "below what double precision"),
    ):
        with pytest.raises(ValueError, match=says) as refused:
            periodic_contact(
                rough,
                length=1.0,
                modulus=1.0,
                pressures=[1e-3, pressure],
                progress=lambda *step: solved.append(step),
            )
        assert "\n" not in str(refused.value)
    assert solved == []


def test_options_forms_and_unused(rough):
    """A list, a string and a dict select the same solver; a misspelt option is reported;
    anything else is refused with the reason."""
    for options in (["-tao_type", "bnls"], "-tao_type bnls", {"tao_type": "bnls"}):
        (step,) = periodic_contact(
            rough, length=1.0, modulus=1.0, pressures=[1e-3], options=options
        )
        assert step.scalars["tao_type"] == "bnls"
    with pytest.warns(UserWarning, match="never used: -tao_typo"):
        periodic_contact(rough, length=1.0, modulus=1.0, pressures=[1e-3], options="-tao_typo bncg")
    with pytest.raises(TypeError, match="options must be"):
        periodic_contact(rough, length=1.0, modulus=1.0, pressures=[1e-3], options=3)
    with pytest.raises(ValueError, match="start with a dash"):
        periodic_contact(
            rough, length=1.0, modulus=1.0, pressures=[1e-3], options=["tao_type", "bnls"]
        )
