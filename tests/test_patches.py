"""Contact patches: clusters of contact pixels, 4-connected, across periodic edges."""

import numpy as np
import pytest
from conftest import python
from mpi4py import MPI

from petsc_contact import periodic_contact, punch_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.physics.observables import contact_patches, patch_sizes


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
    low, high = periodic_contact(h, length=1.0, modulus=1.0, pressures=[1e-5, 5e-3])
    assert low.converged and high.converged
    assert low.scalars["contact_patches"] == 4
    assert 0 < low.scalars["area_fraction"] < 0.1
    assert high.scalars["area_fraction"] > 0.5
    assert high.scalars["contact_patches"] == 1  # joined over the saddles: one net


def test_punch_counts_without_wrapping():
    """A flat punch in full contact is one patch; its footprint does not wrap."""
    (step,) = punch_contact(np.zeros((32, 32)), length=1.0, modulus=1.0, approaches=[1e-3])
    assert step.scalars["area_fraction"] == 1.0
    assert step.scalars["contact_patches"] == 1


SCRIPT = r"""
import numpy as np
from mpi4py import MPI
from petsc_contact.conventions.grid import Grid
from petsc_contact.physics.observables import contact_patches, patch_sizes
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


def test_patch_sizes_and_distributions_add_up(petsc):
    """Patch sizes add up to the contact pixels on 1 rank and are the same set on 3; the
    histograms count every contact and every open pixel; the filled statistics see the
    filled pixels."""
    from petsc_contact import periodic_contact
    from petsc_contact.paper.figures import surface

    h, _ = surface(64, 0.7, 1.0, 32.0, 2)
    (step,) = periodic_contact(h, length=1.0, modulus=1.0, pressures=[1e-2], fields=True)
    s, contact = step.scalars, step.contact
    n = int(contact.sum())
    assert s["pressure_histogram"].sum() == n and s["gap_histogram"].sum() == h.size - n
    assert s["pressure_bins"][-1] == pytest.approx(s["max_pressure"])
    grid = Grid(64, 1.0)
    sizes = patch_sizes(grid, contact)
    assert sizes.sum() == n and sizes.size == s["contact_patches"]
    assert s["largest_patch"] == sizes.max() and s["patch_size_histogram"].sum() == sizes.size
    r = python("-c", SIZES_ON_RANKS.format(seed=2), mpi=3)
    assert r.returncode == 0, r.stderr
    assert sorted(int(v) for v in r.stdout.split()) == sorted(sizes.tolist())


SIZES_ON_RANKS = """
import numpy as np
from mpi4py import MPI
from petsc_contact import periodic_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.physics.observables import patch_sizes
from petsc_contact.paper.figures import surface
h, _ = surface(64, 0.7, 1.0, 32.0, {seed})
(step,) = periodic_contact(
    h, length=1.0, modulus=1.0, pressures=[1e-2], fields=True, comm=MPI.COMM_SELF
)
grid = Grid(64, 1.0)
sizes = patch_sizes(grid, step.contact[grid.rows])
if grid.comm.rank == 0:
    print(" ".join(map(str, sizes)))
"""


def test_observables_of_row_blocks_are_the_fields(monkeypatch):
    """The observables reduced a few rows at a time (blocks of 200 points: 3 rows of 64,
    the last block shorter) are those of the whole field at once: the same counts and
    histograms, sums within their rounding."""
    from petsc_contact.paper.figures import surface
    from petsc_contact.physics import observables

    h, _ = surface(64, 0.7, 1.0, 32.0, 2)
    (step,) = periodic_contact(h, length=1.0, modulus=1.0, pressures=[1e-2], fields=True)
    gap, pressure = step.gap, step.pressure
    heights = h - h.mean()
    args = (Grid(64, 1.0), gap, pressure, heights, 1e-2, 2.0 * 64)
    whole = observables.step_observables(*args)
    monkeypatch.setattr(observables, "BLOCK_POINTS", 200)
    assert len(observables.row_blocks(gap.shape)) == 22
    blocked = observables.step_observables(*args)
    assert whole.keys() == blocked.keys()
    for key, value in whole.items():
        if isinstance(value, float):
            assert blocked[key] == pytest.approx(value, rel=1e-13, abs=1e-300), key
        else:
            assert np.array_equal(blocked[key], value), key
    assert whole["contact"].sum() == whole["pressure_histogram"].sum() > 0
