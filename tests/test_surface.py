"""Self-affine surfaces (paper Eq. 5): statistics against the prescribed spectrum."""

import numpy as np
import pytest

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft, wavevector_magnitude
from petsc_contact.physics.surface import psd_shape, radial_psd, rms_of, self_affine


def make(n=128, **kw):
    grid = Grid(n, 1.0)
    fft = make_fft(grid)
    args = dict(hurst=0.7, rolloff_ratio=4, cutoff_ratio=n // 4, seed=3, rms_slope=0.1)
    if "rms_height" in kw:
        del args["rms_slope"]
    args.update(kw)
    return grid, fft, self_affine(grid, fft, **args)


def sampling_sigma(grid, fft, hurst, rolloff, cutoff, slope):
    """Relative std of the realised h_rms^2 (or h'_rms^2): each Hermitian pair of modes
    contributes c_q |z_q|^2 twice with |z|^2 ~ Exp(1), so var = sum_all 2 c_q^2."""
    q = (
        np.sqrt(np.add.outer(np.fft.fftfreq(grid.n) ** 2, np.fft.fftfreq(grid.n) ** 2))
        * grid.n
        * 2
        * np.pi
        / grid.length
    )
    q0 = grid.q0
    c = psd_shape(q, q0, q0 * rolloff, q0 * cutoff, hurst) * (q**2 if slope else 1)
    return np.sqrt(2 * np.sum(c**2)) / np.sum(c)


def test_seeded_zero_mean_reproducible():
    grid, fft, h1 = make(seed=11)
    _, _, h2 = make(seed=11)
    _, _, h3 = make(seed=12)
    assert np.array_equal(h1, h2)
    assert not np.allclose(h1, h3)
    assert abs(h1.mean()) < 1e-15 * np.abs(h1).max() * h1.size


@pytest.mark.parametrize("slope", [False, True])
def test_rms_target_within_sampling_error(slope):
    n, hurst, rolloff, cutoff = 128, 0.7, 8, 32
    grid = Grid(n, 1.0)
    fft = make_fft(grid)
    sigma = sampling_sigma(grid, fft, hurst, rolloff, cutoff, slope)
    target = 0.1 if slope else 0.01
    for seed in range(4):
        kw = {"rms_slope": target} if slope else {"rms_height": target}
        h = self_affine(
            grid, fft, hurst=hurst, rolloff_ratio=rolloff, cutoff_ratio=cutoff, seed=seed, **kw
        )
        realised = rms_of(grid, fft, h, slope=slope)
        assert abs(realised**2 / target**2 - 1) < 4 * sigma, (seed, realised, sigma)


def test_exact_rescaling_hits_target():
    grid, fft, h = make(exact=True, rms_slope=0.2)
    assert rms_of(grid, fft, h, slope=True) == pytest.approx(0.2, rel=1e-12)


@pytest.mark.parametrize("hurst", [0.3, 0.7, 0.95])
def test_psd_exponent(hurst):
    n, rolloff, cutoff = 256, 2, 64
    grid, fft, h = make(n, hurst=hurst, rolloff_ratio=rolloff, cutoff_ratio=cutoff, seed=5)
    q, c = radial_psd(grid, fft, h, bins=40)
    q0 = 2 * np.pi
    fit = (q > 3 * rolloff * q0) & (q < 0.8 * cutoff * q0)
    slope = np.polyfit(np.log(q[fit]), np.log(c[fit]), 1)[0]
    assert slope == pytest.approx(-2 - 2 * hurst, abs=0.12)
    assert np.all(c[q > 1.2 * cutoff * q0] < 1e-20 * c.max())


def test_realised_psd_matches_prescribed_level():
    """The radial average of C(q) equals the prescribed C0 (q/qr)^(-2-2H) on average."""
    n, hurst, rolloff, cutoff = 256, 0.7, 2, 64
    grid, fft, h = make(
        n, hurst=hurst, rolloff_ratio=rolloff, cutoff_ratio=cutoff, seed=2, rms_height=1.0
    )
    q, c = radial_psd(grid, fft, h)
    q0 = 2 * np.pi
    qm = wavevector_magnitude(grid, fft)
    shape_q = psd_shape(q, q0, rolloff * q0, cutoff * q0, hurst)
    # C0 from the target: h_rms^2 = C0 sum(shape) dq^2 over the full spectrum
    full = psd_shape(
        np.sqrt(np.add.outer(np.fft.fftfreq(n) ** 2, np.fft.fftfreq(n) ** 2)) * n * q0,
        q0,
        rolloff * q0,
        cutoff * q0,
        hurst,
    )
    c0 = 1.0 / (full.sum() * q0**2)
    band = (q > 4 * q0) & (q < cutoff * q0 * 0.9)
    ratio = c[band] / (c0 * shape_q[band])
    assert np.exp(np.mean(np.log(ratio))) == pytest.approx(1.0, abs=0.15)
    assert qm.shape == fft.spectrum.shape


@pytest.mark.parametrize(
    "bad", [dict(hurst=1.5), dict(rolloff_ratio=0.5), dict(cutoff_ratio=100), dict(rms_slope=-1.0)]
)
def test_bad_parameters(bad):
    with pytest.raises(ValueError):
        make(64, **bad)


def test_a_refined_surface_is_the_same_surface():
    """``scenes.refined``: the heights at the coarse pixels are kept, the spectrum is the
    coarse one (the new wavevectors empty), so h_rms and the rms slope are the same."""
    from petsc_contact.workflows import scenes

    h, _ = scenes.surface(64, 0.7, 1.0, 16, seed=5)
    fine = scenes.refined(h, 4)
    assert fine.shape == (256, 256)
    assert np.allclose(fine[::4, ::4], h, rtol=0, atol=1e-12 * np.abs(h).max())
    assert fine.std() == pytest.approx(h.std(), rel=1e-12)
    spectrum = np.fft.fft2(fine) / 16
    assert np.abs(spectrum[32:-32, :]).max() < 1e-12 * np.abs(spectrum).max()
