"""Extreme and degenerate scenes for the default solver (the cheap part of the stability
matrix; the whole matrix is benchmarks/stability.py -> docs/stability.md)."""

from pathlib import Path

import numpy as np
import pytest

from petsc_contact import periodic_contact
from petsc_contact.backend._petsc import init
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine

N = 64


def rough(hurst=0.7, slope=0.1, seed=1):
    grid = Grid(N, 1.0)
    return self_affine(
        grid,
        make_fft(grid),
        hurst=hurst,
        rolloff_ratio=2,
        cutoff_ratio=16,
        seed=seed,
        rms_slope=slope,
    )


def solve(h, p0, length=1.0, modulus=1.0, options=()):
    (step,) = periodic_contact(
        h, length=length, modulus=modulus, pressures=[p0], options=list(options)
    )
    assert step.converged, step.scalars["verification"]
    return step.scalars


def test_offset_heights_change_nothing():
    h = rough()
    a, b = solve(h, 1e-2), solve(h + 1e6 * h.std(), 1e-2)
    assert b["mean_gap"] == pytest.approx(a["mean_gap"], rel=1e-8)
    assert b["area_fraction"] == a["area_fraction"]


@pytest.mark.parametrize("length, modulus", [(1e-6, 1.0), (1e3, 1.0), (1.0, 1e-6), (1.0, 1e9)])
def test_scaling_invariance(length, modulus):
    """Heights scaled with L and pressures with E*: u_bar/L and the area are unchanged."""
    h = rough()
    ref = solve(h, 1e-2)
    s = solve(h * length, 1e-2 * modulus, length, modulus)
    assert s["mean_gap"] / length == pytest.approx(ref["mean_gap"], rel=1e-7)
    assert s["area_fraction"] == ref["area_fraction"]
    assert s["elastic_energy"] / (modulus * length) == pytest.approx(
        ref["elastic_energy"], rel=1e-6
    )


def test_flat_surface_is_full_contact():
    s = solve(np.zeros((N, N)), 1e-3)
    assert s["area_fraction"] == 1.0 and s["mean_gap"] == 0.0
    assert s["max_pressure"] == pytest.approx(1e-3, rel=1e-12)


@pytest.mark.parametrize("hurst, slope", [(0.1, 0.1), (0.95, 0.1), (0.7, 0.01), (0.7, 1.0)])
@pytest.mark.parametrize("solver", [[], ["-tao_type", "tron"]])
def test_extreme_spectra(hurst, slope, solver):
    """H near 0 and 1, slopes 0.01 and 1, from a single-asperity load to half contact."""
    h = rough(hurst, slope)
    steps = periodic_contact(
        h,
        length=1.0,
        modulus=1.0,
        pressures=[slope * 1e-6, slope * 1e-2, slope * 0.3],
        options=solver,
    )
    assert all(s.converged for s in steps), [s.scalars["verification"] for s in steps]
    area = [s.scalars["area_fraction"] for s in steps]
    assert area[0] < area[1] < area[2]


OPTIONS = Path(__file__).parent.parent / "options"


@pytest.mark.parametrize(
    "tao_type, extra",
    [("blmvm", []), ("bncg", []), ("blmvm", ["-options_file", str(OPTIONS / "blmvm.opts")])],
)
def test_first_order_tao_types_with_fourier_h0(tao_type, extra):
    """BLMVM and BNCG with the Fourier compliance restricted to their free set as ``H0``
    converge from a single asperity's load to beyond half contact, where without it they
    stall at ``p0/E* = 1e-7`` (measured at 64^2: 5000 iterations, the limit), and reach the
    default solver's mean gap within their shared tolerance (1e-8 p0 rms: 1e-6 relative);
    BLMVM also with its options file (a history of two pairs)."""
    h = rough()
    loads = [1e-7, 1e-5, 1e-3, 1e-2, 0.1]
    default = periodic_contact(h, length=1.0, modulus=1.0, pressures=loads)
    steps = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, options=["-tao_type", tao_type, *extra]
    )
    assert all(s.converged for s in steps), [s.scalars["verification"] for s in steps]
    for s, ref in zip(steps, default, strict=True):
        assert s.scalars["preconditioner_applications"] > 0  # H0 is applied
        assert s.scalars["iterations"] <= 60  # measured: at most 41
        assert s.scalars["mean_gap"] == pytest.approx(ref.scalars["mean_gap"], rel=1e-6)
    (without,) = periodic_contact(
        h,
        length=1.0,
        modulus=1.0,
        pressures=[1e-7],
        options=["-tao_type", tao_type, "-petsc_contact_no_j0"],
    )
    said = {k: without.scalars[k] for k in ("iterations", "tao_reason", "tolerance")}
    assert not without.converged, (said, init().Options().getAll())  # the database: no leak
