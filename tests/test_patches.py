"""Contact patches: clusters of contact pixels, 4-connected, across periodic edges."""

import numpy as np
import pytest
from conftest import python
from mpi4py import MPI

from petsc_contact import periodic_contact, punch_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.physics.observables import contact_patches


def count(mask, periodic=True):
    grid = Grid(mask.shape, (1.0, 1.0), MPI.COMM_SELF)
    return contact_patches(grid, mask, periodic)


def test_edges_corners_and_wrapping():
    """Pixels touching at a corner are two patches; a patch cut by the cell's edges is one
    patch when periodic and one per piece when not."""
    m = np.zeros((8, 8), bool)
    m[2, 2] = m[3, 3] = True  # corner to corner
    assert count(m) == 2
    m = np.zeros((8, 8), bool)
    m[[0, 0, 7, 7], [0, 7, 0, 7]] = True  # one square cut in four by both edges
    assert count(m) == 1
    assert count(m, periodic=False) == 4
    assert count(np.indices((6, 6)).sum(0) % 2 == 0) == 18  # checkerboard: every pixel alone
    assert count(np.ones((5, 3), bool)) == 1
    assert count(np.zeros((5, 3), bool)) == 0


def test_egg_crate_touches_at_each_summit():
    """``h = cos(4 pi x) + cos(4 pi y)`` has four summits per cell: at a small load each
    carries its own Hertz-like contact, and the patches merge as the load grows."""
    n = 64
    x = np.arange(n) / n
    h = 1e-3 * (np.cos(4 * np.pi * x)[:, None] + np.cos(4 * np.pi * x)[None, :])
    low, high = periodic_contact(h, 1.0, 1.0, [1e-5, 5e-3])
    assert low.converged and high.converged
    assert low.scalars["contact_patches"] == 4
    assert 0 < low.scalars["area_fraction"] < 0.1
    assert high.scalars["area_fraction"] > 0.5
    assert high.scalars["contact_patches"] == 1  # joined over the saddles: one net


def test_punch_counts_without_wrapping():
    """A flat punch in full contact is one patch; its footprint does not wrap."""
    (step,) = punch_contact(np.zeros((32, 32)), 1.0, 1.0, approaches=[1e-3])
    assert step.scalars["area_fraction"] == 1.0
    assert step.scalars["contact_patches"] == 1


SCRIPT = r"""
import numpy as np
from mpi4py import MPI
from petsc_contact.conventions.grid import Grid
from petsc_contact.physics.observables import contact_patches
rng = np.random.default_rng(3)
for shape in [(16, 16), (30, 47), (7, 5)]:
    for fraction in (0.3, 0.5, 0.6):
        mask = rng.random(shape) < fraction
        grid = Grid(shape, (1.0, 1.0), MPI.COMM_WORLD)
        serial = Grid(shape, (1.0, 1.0), MPI.COMM_SELF)
        for periodic in (True, False):
            got = contact_patches(grid, mask[grid.rows], periodic)
            assert got == contact_patches(serial, mask, periodic), (shape, fraction, periodic)
print("ok")
"""


@pytest.mark.parametrize("ranks", [2, 3])
def test_ranks_agree_with_one(ranks):
    """Slabs on 2 and 3 ranks give the serial count, with and without wrapping, on random
    masks near the percolation threshold (where patches cross every slab boundary)."""
    run = python("-c", SCRIPT, mpi=ranks)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.count("ok") == ranks
