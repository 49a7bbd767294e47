"""The two-level form of the preconditioner: contact reactions constant on aggregates."""

import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import cli, python

from petsc_contact import periodic_contact
from petsc_contact.backend import _petsc, coarse
from petsc_contact.backend.coarse import DIAGONAL_INFLATION, CoarseSpace, TwoLevelOptions
from petsc_contact.backend.tao import PetscBackend
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.numerics import aggregates
from petsc_contact.numerics.schur import _fold
from petsc_contact.physics.surface import self_affine


def problem(n=64, p0=1e-3):
    grid = Grid(n, 1.3)
    fft = make_fft(grid)
    h = self_affine(
        grid, fft, hurst=0.7, rolloff_ratio=1, cutoff_ratio=n / 2, seed=3, rms_slope=0.1
    )
    pb = PeriodicProblem(grid, make_fft(grid), h, 2.0)
    pb.set_pressure(p0)
    return grid, pb


def dense(pre, free):
    """``P_F M P_F`` as a dense matrix, column by column."""
    n = free.size
    out = np.zeros((n, n))
    e = np.zeros(n)
    for j in np.flatnonzero(free):
        e[j] = 1.0
        out[:, j] = pre.apply_array(e, np.empty(n)) * free
        e[j] = 0.0
    return out


def exact_coarse(pre, space):
    """``W^T G_BB W`` pixel pair by pixel pair."""
    q = pre._quarter
    n = pre.grid.shape[0]
    rows, cols = np.divmod(space.local, pre.grid.shape[1])
    g_bb = q[_fold(rows[:, None] - rows[None, :], n), _fold(cols[:, None] - cols[None, :], n)]
    w = np.zeros((len(space.local), space.size))
    w[np.arange(len(space.local)), space.labels] = 1.0
    return w.T @ g_bb @ w


def test_symmetric_positive_semidefinite_for_any_aggregates(petsc):
    """``P_F M P_F`` is symmetric and positive semi-definite for a random bound set, and for a
    coarse space built on another (older) set: a stale coarse space never breaks the CG."""
    grid, pb = problem(24)
    pre = pb.preconditioner
    pre.options = TwoLevelOptions(block=3)
    rng = np.random.default_rng(1)
    for trial in range(2):
        built = rng.random(grid.size) < 0.15
        pre._exact_compliance()
        pre._build(~built)
        assert pre.coarse is not None and pre.coarse.size > 20
        free = ~built if trial == 0 else rng.random(grid.size) > 0.15  # then a newer set
        m = dense(pre, free)
        scale = np.abs(m).max()
        assert np.abs(m - m.T).max() <= 1e-12 * scale
        sub = m[np.ix_(free, free)]
        eig = np.linalg.eigvalsh(0.5 * (sub + sub.T))
        assert eig.min() > 1e-6 * eig.max()  # definite on the free set


def test_coarse_matrix_is_above_the_exact_one(petsc):
    """The assembled ``E`` (exact near blocks, monopoles beyond, diagonal raised) minus the
    exact ``W^T G_BB W`` is positive definite on a rough surface's contact (the highest 3%
    of a paper-bandwidth surface): the preconditioner stays semi-definite."""
    grid, pb = problem(256)
    pre = pb.preconditioner
    pre._exact_compliance()
    bound = pb.heights > np.quantile(pb.heights, 0.97)
    space = CoarseSpace(grid, pre._quarter, bound, 8, grid.size)
    exact = exact_coarse(pre, space)
    factor, lower = space.system.factor
    triangle = np.tril(factor) if lower else np.triu(factor).T
    assembled = triangle @ triangle.T
    assert space.size > 50
    assert np.linalg.eigvalsh(assembled - exact).min() > 0
    # and close to it: within the inflation
    d = np.sqrt(np.diag(exact))
    rel = np.linalg.eigvalsh(assembled / np.outer(d, d) - exact / np.outer(d, d))
    assert rel.max() <= 2 * DIAGONAL_INFLATION


@pytest.mark.parametrize(
    "shape, block, fraction",
    [((48, 40), 7, 0.3), ((20, 20), 8, 0.5), ((16, 16), 8, 0.9), ((30, 18), 16, 0.4)],
)
def test_fft_pair_sums_are_the_pixel_pair_sums(shape, block, fraction):
    """The near sums by FFTs on ``2b x 2b`` cells equal the pixel-pair sums to rounding
    (1e-12 relative) for any kernel: partial last blocks, rectangles, and small grids whose
    blocks wrap onto the same neighbour."""
    rng = np.random.default_rng(4)
    nx, ny = shape
    quarter = rng.random((nx // 2 + 1, ny // 2 + 1))
    rows, cols = np.nonzero(rng.random(shape) < fraction)
    bx, by = -(-nx // block), -(-ny // block)
    ids, labels = np.unique((rows // block) * by + cols // block, return_inverse=True)
    order = np.argsort(labels, kind="stable")
    starts = np.concatenate([[0], np.cumsum(np.bincount(labels))]).astype(np.int64)
    block_rc = np.stack(np.divmod(ids, by), axis=1)
    lookup = np.full((bx, by), -1, dtype=np.int64)
    lookup[block_rc[:, 0], block_rc[:, 1]] = np.arange(len(ids))
    rows, cols = rows[order].copy(), cols[order].copy()
    pairs = aggregates.near_pairs(block_rc, lookup, coarse.NEAR_REACH)
    direct = aggregates.pair_sums_direct(rows, cols, starts, pairs, quarter, nx, ny)
    fft = coarse._pair_sums_fft(rows, cols, starts, block_rc * block, pairs, quarter, shape, block)
    assert np.abs(fft - direct).max() <= 1e-12 * np.abs(direct).max()


def test_block_grows_to_the_limit(petsc):
    """At most ``max_size`` aggregates: the block side grows until they fit."""
    grid, pb = problem(64)
    pre = pb.preconditioner
    pre._exact_compliance()
    bound = np.random.default_rng(2).random(grid.local_shape) < 0.2
    space = CoarseSpace(grid, pre._quarter, bound, 4, 30)
    assert space.size <= 30 and space.block > 4
    assert np.bincount(space.labels).sum() == bound.sum()


@pytest.mark.parametrize("hurst, p0", [(0.7, 1e-3), (0.3, 1e-3), (0.7, 1e-2)])
def test_two_level_solves_the_same_contact(hurst, p0):
    """At 2-3% and about 20% contact (with ``-petsc_contact_two_level_max_fraction 0.3``: its
    near sums by FFTs) on a paper-bandwidth 256^2 surface the two-level form is built, takes
    fewer iterations, and reaches the same mean gap and KKT as the held compliance alone
    (both to 1e-8 p0: the mean gaps agree to 1e-7 relative, measured 2e-10)."""
    n = 256
    grid = Grid(n, 1.0)
    h = self_affine(
        grid,
        make_fft(grid),
        hurst=hurst,
        rolloff_ratio=1,
        cutoff_ratio=n / 2,
        seed=1,
        rms_slope=0.1,
    )
    steps = {
        on: periodic_contact(
            h,
            length=1.0,
            modulus=1.0,
            pressures=[p0],
            options=f"-petsc_contact_two_level {on} -petsc_contact_two_level_max_fraction 0.3",
        )[0]
        for on in (0, 1)
    }
    for s in steps.values():
        assert s.scalars["converged"] and s.scalars["kkt_residual"] <= 1e-8
    off, on = steps[0].scalars, steps[1].scalars
    assert on["iterations"] < off["iterations"]
    assert abs(on["mean_gap"] / off["mean_gap"] - 1) <= 1e-7


def test_iterations_at_1024_do_not_grow_with_the_spots():
    """A cold step at 1024^2, ``p0 = 1e-3 E*``, H = 0.7, roughness down to two pixels (2.3%
    contact, about 24 000 pixels): at most 30 iterations (25 measured; 68 with the held
    compliance alone, docs/performance.md)."""
    n = 1024
    grid = Grid(n, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=n / 2, seed=1, rms_slope=0.1
    )
    (step,) = periodic_contact(h, length=1.0, modulus=1.0, pressures=[1e-3])
    assert step.scalars["converged"]
    assert step.scalars["iterations"] <= 30


def test_options_switch_it(petsc):
    """``-petsc_contact_two_level*`` name its choices; a non-positive block is refused."""
    with _petsc.scoped_options("-petsc_contact_two_level 0 -petsc_contact_two_level_block 8"):
        opts = TwoLevelOptions.from_settings(PetscBackend().settings)
    assert not opts.enabled and opts.block == 8 and not opts.covers(1, 100)
    assert TwoLevelOptions().covers(10, 100) and not TwoLevelOptions().covers(11, 100)
    with _petsc.scoped_options("-petsc_contact_two_level_block 0"), pytest.raises(ValueError):
        PetscBackend()


SERIAL = [
    "periodic", "--grid", "256", "--hurst", "0.7", "--rms-slope", "0.1",
    "--rolloff-ratio", "1", "--cutoff-ratio", "128", "--seed", "1",
    "--pressures", "1e-3,2.3e-3", "--stiffness",
]  # fmt: skip


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The serial run of :data:`SERIAL` that every rank count's is held against."""
    out = tmp_path_factory.mktemp("serial") / "s.h5"
    r = cli(*SERIAL, "--output", str(out))
    assert r.returncode == 0, r.stderr
    return out


@pytest.mark.parametrize("ranks", [2, 3])
def test_mpi_matches_serial(tmp_path, serial, ranks):
    """On 2 and 3 ranks (the coarse system gathered on every rank) the two-level form takes
    the serial run's path: the same iterations within two, mean gaps to 1e-8 and exact
    stiffnesses to 1e-6 relative (the tolerances' reach) at 2-5% contact on 256^2."""
    par = tmp_path / "p.h5"
    r = cli(*SERIAL, "--output", str(par), mpi=ranks, timeout=240)
    assert r.returncode == 0, r.stdout + r.stderr
    with h5py.File(serial) as s, h5py.File(par) as p:
        assert p.attrs["mpi_size"] == ranks
        assert np.allclose(p["mean_gap"][:], s["mean_gap"][:], rtol=1e-8, atol=0)
        assert np.allclose(p["stiffness"][:], s["stiffness"][:], rtol=1e-6, atol=0)
        assert np.abs(p["iterations"][:] - s["iterations"][:]).max() <= 2


EVEN_COLUMN = r"""
nx, ny = (int(v) for v in sys.argv[1].split(","))
comm = MPI.COMM_WORLD
grid, whole = (Grid((nx, ny), (1.0, ny / nx), c) for c in (comm, MPI.COMM_SELF))
rng = np.random.default_rng(2)  # a random positive even spectrum, q = 0 entry zero
spectrum = 1.0 + rng.random((nx, ny // 2 + 1))
spectrum = spectrum + spectrum[-np.arange(nx) % nx]
spectrum[0, 0] = 0.0
table = np.fft.irfft2(spectrum, s=(nx, ny))[: nx // 2 + 1, : ny // 2 + 1]
i, j = np.meshgrid(_fold(np.arange(nx), nx), _fold(np.arange(ny), ny), indexing="ij")
column = table[i, j]  # an even periodic G e_0, positive semi-definite (constants: zero)
mine, full = quarter(grid, column[grid.rows]), quarter(whole, column)
"""  # the scripts' grid on the run's ranks and on one, and G's column: its quarter on each


HELD_QUARTER = r"""
import sys
import numpy as np
from mpi4py import MPI
from petsc_contact.backend import coarse
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import CPU
from petsc_contact.numerics import schur as sums
from petsc_contact.numerics.schur import ContactSchur, _fold, held_rows, quarter

sums.SUM_CHUNK = 37  # the matrices summed over the ranks in many pieces, the last one short
{even_column}
held = held_rows(grid)
rows = len(held) + (len(held) > 0 and held.stop < nx // 2 + 1)  # and the next row
assert mine.shape == (rows, ny // 2 + 1) and rows < nx // 2 + 1, mine.shape
assert np.array_equal(mine, table[held.start : held.start + rows])
rng = np.random.default_rng(5)
sparse = rng.random((nx, ny)) < 0.08  # single pixels: the near pairs summed pair by pair
dense = rng.random((nx, ny)) < 0.9  # filled blocks: the near pairs summed by FFTs
for bound, block in ((sparse, 1), (sparse, 3), (dense, 4)):
    parts = [
        (ContactSchur(g, q, bound[g.rows]).system.factor[0], coarse.host_coarse_matrix(
            g, q, bound[g.rows], block, 10**6, CPU).matrix)
        for g, q in ((grid, mine), (whole, full))
    ]
    (schur, e_mat), (schur_1, e_mat_1) = parts
    assert np.array_equal(schur, schur_1), np.abs(schur - schur_1).max()
    assert np.array_equal(e_mat, e_mat_1), np.abs(e_mat - e_mat_1).max()
""".replace("{even_column}\n", EVEN_COLUMN.lstrip("\n"))


@pytest.mark.parametrize("ranks, shape", [(3, "30,26"), (4, "32,20")])
def test_no_rank_holds_the_quarter(launched, ranks, shape):
    """On 3 and 4 ranks each rank holds only its slab's rows of ``G``'s quarter (and the next
    row; the last ranks none), and the Schur system's factor and the coarse matrix (single
    pixels, monopoles and near pairs pair by pair and by FFTs), summed over the ranks in
    pieces, are the serial ones exactly. Launched with :data:`HALO`'s grid
    (:func:`launched`)."""
    r = launched[ranks]
    assert f"passed quarter {shape}\n" in r.stdout, r.stdout + r.stderr


HALO = r"""
import sys
import numpy as np
from mpi4py import MPI
from petsc_contact.backend import coarse
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import CPU
from petsc_contact.numerics.schur import _fold, quarter

{even_column}
held = []  # the bound pixels each exchange leaves this rank with
exchange = coarse._halo


def counted(*args):
    near = exchange(*args)
    held.append(len(near))
    return near


coarse._halo = counted
rng = np.random.default_rng(7)
sparse = rng.random((nx, ny)) < 0.05  # near pairs pixel pair by pair
dense = rng.random((nx, ny)) < 0.9  # near pairs by FFTs
cases = [(sparse, 3, 10**6), (sparse, 2, 80), (dense, 4, 10**6), (dense, 2, 60)]
cases.append((dense, 2, 9))  # blocks of about nx/3: slabs beside their block rows, or none
for case, (bound, block, cap) in enumerate(cases):
    held.clear()
    par = coarse.host_coarse_matrix(grid, mine, bound[grid.rows], block, cap, CPU)
    ser = coarse.host_coarse_matrix(whole, full, bound, block, cap, CPU)
    assert par.block == ser.block and (par.block > block) == (cap < 10**6), (par.block, block)
    assert np.array_equal(par.matrix, ser.matrix), np.abs(par.matrix - ser.matrix).max()
    assert np.array_equal(par.sizes, ser.sizes)
    slab = (ser.local >= grid.rows.start * ny) & (ser.local < grid.rows.stop * ny)
    assert np.array_equal(par.local + grid.rows.start * ny, ser.local[slab])
    assert np.array_equal(par.labels, ser.labels[slab])
    # at most the pixels of the rows the near block rows of this slab's can reach
    b, reach = par.block, coarse.NEAR_REACH
    near = np.arange(grid.rows.start - reach * b, grid.rows.stop + (reach + 1) * b) % nx
    halo, own, total = bound[np.unique(near)].sum(), bound[grid.rows].sum(), bound.sum()
    assert max(held) <= halo and (halo < total or case == len(cases) - 1), (held, halo, total)
    counts = comm.gather((int(own), max(held), int(halo)), root=0)
    if comm.rank == 0:
        print(f"case {case} b {b} k {par.sizes.size} total {total} (own, held, bound):", counts)
""".replace("{even_column}\n", EVEN_COLUMN.lstrip("\n"))


LAUNCH = r"""
import sys
from mpi4py import MPI
from petsc_contact.backend import coarse

halo = coarse._halo
for name, code, shape in zip(sys.argv[1::3], sys.argv[2::3], sys.argv[3::3]):
    sys.argv[1:] = [shape]
    exec(compile(code, name, "exec"), {"__name__": "__main__"})
    coarse._halo = halo  # as it was before the script counted its exchanges
    MPI.COMM_WORLD.Barrier()
    if MPI.COMM_WORLD.rank == 0:
        print("passed", name, shape, flush=True)
"""
LAUNCHED = {3: ("128,96", "30,26"), 4: ("128,128", "32,20")}  # (HALO's, HELD_QUARTER's)


@pytest.fixture(scope="module")
def launched() -> dict[int, subprocess.CompletedProcess]:
    """One launch per rank count of :data:`LAUNCHED`: :data:`HALO` on its grid, then
    :data:`HELD_QUARTER` (which sums in pieces of 37 from then on) on its own; a failed check
    ends the launch, so that the quarter's test fails with the halo's."""
    return {
        ranks: python(
            "-c",
            LAUNCH,
            "halo",
            HALO,
            halo,
            "quarter",
            HELD_QUARTER,
            quarter,
            mpi=ranks,
            timeout=300,
        )  # fmt: skip
        for ranks, (halo, quarter) in LAUNCHED.items()
    }


@pytest.mark.parametrize("ranks, shape", [(3, "128,96"), (4, "128,128")])
def test_no_rank_holds_the_contact_set(launched, ranks, shape):
    """On 3 and 4 ranks the cpu device's coarse matrix, the local pixels' aggregates and their
    sizes equal the serial ones exactly (near pairs pixel pair by pixel pair and by FFTs, the
    block kept and grown, up to a block row wider than a slab), and no rank receives more of
    the contact set (random, on every slab) than the pixels of the rows within reach of its
    slab's near block rows: less than the whole set where the blocks are narrower than the
    grid's share. Launched with :data:`HELD_QUARTER`'s grid (:func:`launched`)."""
    r = launched[ranks]
    assert f"passed halo {shape}\n" in r.stdout, r.stdout + r.stderr
