"""``--device cpu-array`` on several MPI ranks: the array solver's sums and minima go over the
grid's communicator, its transforms are FFTW's MPI ones and the two-level form is summed by
the host build, so 2 and 3 ranks give what one rank and the ``cpu`` device give (mean gaps to
1e-9 relative, stiffnesses to 1e-8, iterations within 2).  A GPU on several ranks is refused in
one line."""

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
    "periodic": {"mean_gap": 1e-9, "stiffness": 1e-8, "area_fraction": 1e-12},
    "punch": {"approach": 1e-9, "mean_gap": 1e-9, "total_stiffness": 1e-8},
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


@pytest.mark.parametrize("ranks", [2, 3])
@pytest.mark.parametrize("args", [PERIODIC, PUNCH], ids=["periodic", "punch"])
def test_the_stand_in_on_several_ranks_is_one_rank_s(tmp_path, one_rank, args, ranks):
    """A periodic sweep with ``--stiffness`` (through the two-level form) and a punch on 2 and
    3 ranks: what one rank gives on ``cpu-array`` and on ``cpu``."""
    geometry = args[0]
    mine = _run(args, tmp_path / "p.h5", "cpu-array", ranks)
    for device in ("cpu-array", "cpu"):
        ref = one_rank[geometry, device]
        for name, rtol in COMPARED[geometry].items():
            np.testing.assert_allclose(mine[name], ref[name], rtol=rtol, atol=0, err_msg=name)
        assert np.abs(mine["iterations"] - ref["iterations"]).max() <= 2


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
