"""``--device gpu`` against its CPU stand-in (``pytest -m gpu``; skipped without CuPy or a GPU).

The GPU runs the code the stand-in runs (:mod:`petsc_contact.solver`), with CuPy's arrays,
cuFFT and its reductions: only rounding differs.  At 256^2-1024^2 (paper bandwidth, a sweep
from first contact to about half the area) both must take the same iterations (within 2) and
give the same mean gaps (1e-9 relative) and exact stiffnesses (1e-8).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_device import assert_same_steps

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import DeviceUnavailable, get_device
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import periodic_contact

pytestmark = pytest.mark.gpu


@pytest.fixture(scope="module")
def gpu():
    try:
        return get_device("gpu")
    except DeviceUnavailable as why:
        pytest.skip(str(why))


def surface(n: int) -> np.ndarray:
    grid = Grid(n, 1.0)
    return self_affine(
        grid,
        make_fft(grid, get_device("cpu-array")),
        hurst=0.7,
        rolloff_ratio=1,
        cutoff_ratio=n / 2,
        seed=1,
        rms_slope=0.1,
    )


@pytest.mark.parametrize("n", [256, 512, 1024])
def test_the_gpu_solves_as_its_stand_in_does(gpu, n):
    h = surface(n)
    loads = list(np.logspace(-6, -1, 6))
    host = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device="cpu-array"
    )
    device = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device="gpu"
    )
    assert_same_steps(host, device, iterations=2, gaps=1e-9, stiffnesses=1e-8)


def test_fields_and_state_come_back_to_the_host(gpu):
    h = surface(256)
    steps = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=[1e-3], fields=True, device="gpu"
    )
    step = steps[-1]
    for field in (step.gap, step.pressure, step.state):
        assert isinstance(field, np.ndarray) and field.shape == (256, 256)
    assert step.pressure.sum() / 256**2 == pytest.approx(1e-3, rel=1e-6)  # force balance


def test_each_fused_pass_is_the_array_pass(gpu):
    """The GPU's fused kernels (:mod:`~petsc_contact.devices.fused`) against the array
    module's operators on the same CuPy arrays: masks, counts and updates exactly, sums to
    rounding (1e-12), with bounds given as floats and as arrays."""
    from petsc_contact.devices.fused import FusedPasses
    from petsc_contact.devices.passes import ArrayPasses

    xp = gpu.xp
    fused, plain = FusedPasses(xp), ArrayPasses(xp)
    rng = np.random.default_rng(5)
    n = 100_003  # not a multiple of a block
    x = xp.asarray(np.maximum(rng.normal(size=n), 0.0))
    g = xp.asarray(rng.normal(size=n))
    d = xp.asarray(rng.normal(size=n))
    upper = x + xp.asarray(np.where(rng.random(n) < 0.1, 0.0, 1.0))  # x >= upper on 10%
    old = xp.asarray(rng.random(n) < 0.5)
    for lo, up in ((0.0, np.inf), (0.0, upper)):
        outs = []
        for passes in (fused, plain):
            free, r = old.copy(), xp.empty(n)
            outs.append((passes.free_set(x, g, lo, up, free, r), free, r))
        (sf, ff, rf), (sp, fp, rp) = outs
        assert sf[1:] == sp[1:] and sf[0] == pytest.approx(sp[0], rel=1e-12)
        assert bool((ff == fp).all()) and bool((rf == rp).all())
        ya, yb = x.copy(), x.copy()
        assert fused.advance(ya, d, 0.3, lo, up) == plain.advance(yb, d, 0.3, lo, up)
        assert float(xp.abs(ya - yb).max()) <= 1e-15
    za, zb = g.copy(), g.copy()
    ra = fused.extend_direction(za, d, old, 0.7, x)
    assert ra == pytest.approx(plain.extend_direction(zb, d, old, 0.7, x), rel=1e-12)
    assert float(xp.abs(za - zb).max()) <= 1e-15


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_the_cufft_plans_transform_as_cupy_s_functions(gpu, monkeypatch, dtype):
    """:class:`~petsc_contact.devices.fft.CuFFTPlans` (``PETSC_CONTACT_CUFFT_PLANS=on``: cuFFT's
    plans on the kept buffers) against CuPy's ``rfft2`` and ``irfft2`` on the same field: the
    spectrum and the unnormalised round trip to rounding (1e-12 in float64, 1e-5 in float32),
    through the buffers in place and through the staging buffer."""
    from petsc_contact.devices.fft import CUFFT_PLANS_VARIABLE, ArrayFFT, CuFFTPlans

    xp = gpu.xp
    monkeypatch.setenv(CUFFT_PLANS_VARIABLE, "on")
    grid = Grid(96, 1.0)
    fft = ArrayFFT(grid, gpu, dtype)
    assert isinstance(fft.transforms, CuFFTPlans)
    tol = 1e-12 if dtype == np.float64 else 1e-5
    x = xp.asarray(np.random.default_rng(6).standard_normal(grid.shape))
    fft.forward_from(x)
    expected = xp.fft.rfft2(x.astype(dtype))
    assert float(xp.abs(fft.spectrum - expected).max()) <= tol * float(xp.abs(expected).max())
    for out in (xp.empty(grid.shape, dtype=dtype), xp.empty(grid.shape)[:, ::-1]):
        fft.forward_from(x)
        fft.backward_into(out)
        assert float(xp.abs(out / grid.size - x).max()) <= 10 * tol * float(xp.abs(x).max())


def test_the_gpu_with_its_plans_and_float32_solves_as_its_stand_in_does(gpu, monkeypatch):
    """A 512^2 sweep on the GPU with its cuFFT plans and the preconditioner in float32
    against the stand-in in float64: what :func:`test_the_gpu_solves_as_its_stand_in_does`
    asks (the float32 preconditioner steers the path only: tests/test_gpu_prepared.py)."""
    from petsc_contact.devices.fft import CUFFT_PLANS_VARIABLE

    h = surface(512)
    loads = list(np.logspace(-6, -1, 6))
    run = {"length": 1.0, "modulus": 1.0, "pressures": loads, "stiffness": True}
    host = periodic_contact(h, device="cpu-array", **run)
    monkeypatch.setenv(CUFFT_PLANS_VARIABLE, "on")
    device = periodic_contact(h, device="gpu", options=["-petsc_contact_pc_float32"], **run)
    assert_same_steps(host, device, iterations=2, gaps=1e-9, stiffnesses=1e-8)
