"""``--device cpu-array`` on several MPI ranks: the array solver's sums and minima go over the
grid's communicator, its transforms are FFTW's MPI ones and the two-level form is summed by
the host build, so 2-4 ranks give what one rank on ``cpu-array`` and on ``cpu`` gives: the
same iterations, and answers to 1e-12 relative.  The runs make the same iterations of the same
algorithm on the same numbers; only the order of the sums differs (each rank's partial sums,
then the reduction over ranks; FFTW's MPI transforms against ``numpy.fft``), which moves the
answers by a few units of rounding: 5.6e-16 at most on 2, 3 and 4 ranks against either
one-rank run (mean gaps, stiffnesses, approaches, both scenes; 2026-12-02), so 1e-12 leaves
three orders of magnitude for other machines' sums.  A GPU on several ranks is refused in one
line."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from conftest import cli, python

PERIODIC = (
    "periodic --grid 64 --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 1 --cutoff-ratio 16 "
    "--seed 1 --pressures 1e-3,2e-3,4e-3 --stiffness --quiet"
).split()  # 3-10% contact: the Schur form, then the two-level one
PUNCH = (
    "punch --grid 32 --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 2 --cutoff-ratio 16 --seed 3 "
    "--forces 1e-4,5e-4,2e-3 --stiffness --quiet"
).split()
COMPARED = {
    "periodic": ("mean_gap", "stiffness", "area_fraction"),
    "punch": ("approach", "mean_gap", "total_stiffness"),
}


def _run(args: list[str], path, device: str, ranks: int = 0) -> dict[str, np.ndarray]:
    done = cli(*args, "--device", device, "--output", str(path), mpi=ranks, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    with h5py.File(path) as f:
        assert f.attrs["mpi_size"] == max(ranks, 1) and f["converged"][:].all()
        return {name: f[name][:] for name in f if isinstance(f[name], h5py.Dataset)}


@pytest.fixture(scope="module")
def one_rank(tmp_path_factory):
    """Each geometry's run on one rank, on ``cpu-array`` and on ``cpu``."""
    where = tmp_path_factory.mktemp("one")
    return {
        (args[0], device): _run(args, where / f"{args[0]}-{device}.h5", device)
        for args in (PERIODIC, PUNCH)
        for device in ("cpu-array", "cpu")
    }


@pytest.mark.parametrize(
    ("args", "ranks"),
    [(PERIODIC, 2), (PERIODIC, 4), (PUNCH, 3)],
    ids=["periodic-2", "periodic-4", "punch-3"],
)  # the punch's 64 padded rows on 3 ranks: uneven slabs, the last one all padding
def test_the_stand_in_on_several_ranks_is_one_rank_s(tmp_path, one_rank, args, ranks):
    """A periodic sweep with ``--stiffness`` (through the two-level form) and a punch on 2-4
    ranks: what one rank gives on ``cpu-array`` and on ``cpu``, to 1e-12."""
    geometry = args[0]
    mine = _run(args, tmp_path / "p.h5", "cpu-array", ranks)
    for device in ("cpu-array", "cpu"):
        ref = one_rank[geometry, device]
        for name in COMPARED[geometry]:
            np.testing.assert_allclose(mine[name], ref[name], rtol=1e-12, atol=0, err_msg=name)
        np.testing.assert_array_equal(mine["iterations"], ref["iterations"])


GPU_ON_RANKS = """
from types import ModuleType
from mpi4py import MPI
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import Device
from petsc_contact.devices.fft import make_fft

try:  # an array module that is not NumPy: a GPU's, as CuPy is
    make_fft(Grid(32, 1.0, MPI.COMM_WORLD), Device("gpu", ModuleType("cupy")))
except ValueError as error:
    print(error)
"""


def test_a_gpu_on_several_ranks_is_refused():
    """The GPU's transforms are one rank's: on two its FFT is refused in one line, never run."""
    done = python("-c", GPU_ON_RANKS, mpi=2, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["the gpu device runs on one MPI rank, not 2"] * 2
