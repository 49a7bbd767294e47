"""Rectangular grids (nx x ny, sides Lx x Ly, pixels not square) in both geometries."""

import numpy as np
import pytest
from conftest import in_process, python

from petsc_contact import periodic_contact, punch_contact
from petsc_contact.backend.operator import PaddedOperator
from petsc_contact.conventions.grid import Grid, grid_for
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.greens import hockney_kernel, love_pixel_displacement
from petsc_contact.physics.surface import rms_of, self_affine
from petsc_contact.reference import westergaard

TIGHT = ["-tao_gatol", "1e-11"]


def test_grid_of_a_rectangle():
    """Sides, pixels, spectrum spacings; one length means square pixels; ``n`` and ``length``
    are for squares only."""
    grid = Grid((64, 16), (2.0, 0.25))
    assert grid.shape == (64, 16) and grid.spacing == (2.0 / 64, 0.25 / 16)
    assert grid.area == 0.5 and grid.pixel_area == pytest.approx(0.5 / 1024, rel=1e-15)
    assert grid.q0 == pytest.approx(np.pi) and grid.dq == pytest.approx((np.pi, 8 * np.pi))
    assert grid_for((64, 16), 2.0).lengths == (2.0, 0.5)
    for name in ("n", "length", "pixel"):
        with pytest.raises(ValueError):
            getattr(grid, name)
    assert Grid(8, 1.0) == Grid((8, 8), (1.0, 1.0)) and Grid(8, 1.0).n == 8


def test_westergaard_on_a_rectangle_with_oblong_pixels():
    """The 1-D wave along x on a 128 x 8 grid of sides 1 x 0.5 (pixels 1/128 x 1/16): mean gap
    and contact width as on the square grid, the width within one pixel of Westergaard's."""
    nx, ny, length, amplitude, modulus = 128, 8, 1.0, 0.01, 2.0
    x = np.arange(nx) * length / nx
    h = np.repeat(amplitude * np.cos(2 * np.pi * x / length)[:, None], ny, axis=1)
    p_star = westergaard.full_contact_pressure(amplitude, length, modulus)
    loads = [0.1 * p_star, 0.5 * p_star]
    rect = periodic_contact(
        h, length=(length, 0.5), modulus=modulus, pressures=loads, options=TIGHT, fields=True
    )
    square = periodic_contact(
        np.repeat(h[:, :1], nx, axis=1),
        length=length,
        modulus=modulus,
        pressures=loads,
        options=TIGHT,
    )
    for p0, a, b in zip(loads, rect, square, strict=True):
        assert a.converged and b.converged
        assert a.scalars["mean_gap"] == pytest.approx(b.scalars["mean_gap"], rel=1e-9)
        assert a.scalars["area_fraction"] == b.scalars["area_fraction"]
        half = westergaard.half_width(p0, amplitude, length, modulus)
        width = np.count_nonzero(a.contact[:, 0]) * length / nx
        assert abs(width - 2 * half) <= length / nx
        assert np.all(a.contact == a.contact[:, :1])  # uniform along y


def test_tiled_square_is_the_square():
    """A square surface repeated twice along x, on a 2n x n cell of sides 2L x L: the same
    mean gap, area and stiffness as the square (the periodic problem is the same)."""
    grid = Grid(32, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=8, seed=4, rms_slope=0.1
    )
    loads = [1e-3, 1e-2]
    one = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, options=TIGHT, stiffness=True
    )
    two = periodic_contact(
        np.vstack([h, h]),
        length=(2.0, 1.0),
        modulus=1.0,
        pressures=loads,
        options=TIGHT,
        stiffness=True,
    )
    for a, b in zip(one, two, strict=True):
        assert a.converged and b.converged
        for key in ("mean_gap", "area_fraction", "stiffness", "elastic_energy"):
            assert b.scalars[key] == pytest.approx(a.scalars[key], rel=1e-7), key


def test_surface_statistics_on_a_rectangle():
    """A generated surface on a rectangle with oblong pixels hits its rms slope exactly
    (``--exact-rms``) and its rms height as expected within sampling error."""
    grid = Grid((128, 48), (2.0, 1.0))
    fft = make_fft(grid)
    h = self_affine(
        grid, fft, hurst=0.5, rolloff_ratio=2, cutoff_ratio=24, seed=1, rms_slope=0.1, exact=True
    )
    assert rms_of(grid, fft, h, slope=True) == pytest.approx(0.1, rel=1e-12)
    slopes = np.diff(h, axis=0) / grid.spacing[0], np.diff(h, axis=1) / grid.spacing[1]
    assert np.sqrt(sum(np.mean(s**2) for s in slopes)) == pytest.approx(0.1, rel=0.2)


def test_oblong_pixel_kernel():
    """Love's solution is additive: one a x b pixel is its two a x b/2 halves; and the padded
    FFT convolution of a 9 x 5 footprint of 0.1 x 0.07 pixels is the dense sum."""
    x, y = np.meshgrid(np.linspace(-1, 1, 7), np.linspace(-0.8, 0.9, 5), indexing="ij")
    a, b = 0.3, 0.2
    whole = love_pixel_displacement(x, y, (a, b), 1.0)
    halves = sum(love_pixel_displacement(x, y - s * b / 4, (a, b / 2), 1.0) for s in (-1, 1))
    assert np.allclose(whole, halves, rtol=1e-13, atol=0)
    (nx, ny), (ax, ay) = (9, 5), (0.1, 0.07)
    grid = Grid((nx, ny), (nx * ax, ny * ay))
    op = PaddedOperator(grid, lambda rows: hockney_kernel((nx, ny), (ax, ay), 2.0, rows))
    px, py = (np.indices((nx, ny)) * np.array([ax, ay])[:, None, None]).reshape(2, -1)
    dense = love_pixel_displacement(px[:, None] - px, py[:, None] - py, (ax, ay), 2.0)
    v = np.random.default_rng(2).standard_normal((nx, ny))
    out = op.apply_array(v, np.empty((nx, ny)))
    assert np.allclose(out.ravel(), dense @ v.ravel(), rtol=0, atol=1e-13 * np.abs(out).max())


def test_rectangular_flat_punch_two_pixel_shapes():
    """A flat 2:1 rectangular punch, drawn with square pixels (64 x 32) and with oblong ones
    (64 x 64, pixels 1/64 x 1/128): the same stiffness within the grid's discretisation
    error (the square punch's grid stiffness changes by 0.5% from 64 to 128 pixels)."""
    stiffness = [
        punch_contact(np.zeros(shape), length=(1.0, 0.5), modulus=1.0, approaches=[1e-3])[
            0
        ].scalars["total_stiffness"]
        for shape in ((64, 32), (64, 64))
    ]
    assert stiffness[1] == pytest.approx(stiffness[0], rel=5e-3)


SCRIPT = r"""
import numpy as np
from mpi4py import MPI
from petsc_contact import periodic_contact, punch_contact

x, y = np.meshgrid(np.arange(48) / 48, np.arange(20) / 20, indexing="ij")
h = 0.01 * np.cos(2 * np.pi * x) + 0.005 * np.sin(2 * np.pi * (2 * x + y))
h += 0.003 * np.cos(6 * np.pi * y)
periodic = periodic_contact(
    h, length=(1.2, 0.5), modulus=1.0, pressures=[1e-3, 3e-3], stiffness=True
)
punch = punch_contact(h, length=(1.2, 0.5), modulus=1.0, forces=[1e-4])
values = [s.scalars["mean_gap"] for s in periodic] + [s.scalars["stiffness"] for s in periodic]
values.append(punch[0].scalars["approach"])
if MPI.COMM_WORLD.rank == 0:
    print(" ".join(repr(float(v)) for v in values))
"""


def test_rectangles_under_mpi():
    """Both geometries on a 48 x 20 rectangle: 2 and 3 ranks (FFTW-MPI, and mpi4py-fft where
    FFTW's row split differs) give the serial answer within the solver tolerance. The
    serial answer is computed in this process."""
    code = compile(SCRIPT, "serial", "exec")
    results = []
    for ranks in (0, 2, 3):
        if ranks:
            r = python("-c", SCRIPT, mpi=ranks, timeout=180)
        else:
            r = in_process(["python", "-c", SCRIPT], lambda: exec(code, {"__name__": "__main__"}))
        assert r.returncode == 0, r.stdout + r.stderr
        results.append([float(v) for v in r.stdout.split()])
    for other in results[1:]:
        assert np.allclose(other, results[0], rtol=1e-6)
