"""The free-boundary punch on the array path (``device="cpu-array"``) against the PETSc path.

The stand-in runs the code ``device="gpu"`` runs, on NumPy: the padded compliance on the
device's FFT, its inverse as the CG's preconditioner, the held-set solves of the exact total
stiffness and of the flat punch on the grid, and the same Newton iteration of load control.
Forces and approaches must agree to 1e-8, mean gaps to 1e-10, stiffnesses to 1e-8 (both
held-set solves stop at the same test, ``rtol`` 1e-6, and differ only in rounding), the CG's
iterations within a few.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import DeviceUnavailable, get_device
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.reference import flat_punch
from petsc_contact.workflows.punch_sweep import punch_contact


def face(n: int, seed: int = 3) -> np.ndarray:
    """A seeded rough punch face, roughness down to four pixels."""
    grid = Grid(n, 1.0)
    fft = make_fft(grid, get_device("cpu-array"))
    return self_affine(
        grid, fft, hurst=0.7, rolloff_ratio=2, cutoff_ratio=n // 4, seed=seed, rms_slope=0.1
    )


def both(heights: np.ndarray, **kwargs: object) -> list[tuple[dict, dict]]:
    """Each step's scalars on the PETSc path and on the stand-in, side by side."""
    return [(a.scalars, b.scalars) for a, b in pairs(heights, "cpu", "cpu-array", **kwargs)]


def pairs(heights: np.ndarray, first: str, second: str, **kwargs: object) -> list[tuple]:
    """Each step on the devices ``first`` and ``second``, side by side."""
    one = punch_contact(heights, length=1.0, modulus=1.0, device=first, **kwargs)
    two = punch_contact(heights, length=1.0, modulus=1.0, device=second, **kwargs)
    return list(zip(one, two, strict=True))


def agree(sa: dict, sb: dict, pixels: int, iterations: int = 3) -> None:
    """The stand-in's step ``sb`` is the PETSc path's ``sa`` (module docstring)."""
    assert sb["converged"] and sb["verification"] == "ok"
    assert sb["tao_reason"] == sa["tao_reason"]
    assert abs(sb["iterations"] - sa["iterations"]) <= iterations
    for key in ("force", "approach"):
        assert sb[key] == pytest.approx(sa[key], rel=1e-8, abs=1e-300)
    if np.isfinite(sa["mean_gap"]) and sa["mean_gap"] != 0:
        assert sb["mean_gap"] == pytest.approx(sa["mean_gap"], rel=1e-10)
    for key in ("total_stiffness", "flat_punch_stiffness", "interfacial_stiffness"):
        assert sb[key] == pytest.approx(sa[key], rel=1e-8, nan_ok=True)  # NaN: full contact
    assert sb["area_fraction"] == pytest.approx(sa["area_fraction"], abs=2 / pixels)


@pytest.mark.parametrize("n", [48, 64])
def test_the_stand_in_presses_the_punch_as_the_petsc_path_does(petsc, n):
    """Load control: the same Newton steps on the approach around the same solves."""
    for sa, sb in both(face(n), forces=[1e-4, 1e-3, 5e-3, 2e-2], stiffness=True):
        agree(sa, sb, n * n)
        assert sb["newton_iterations"] == sa["newton_iterations"]
        assert sb["stiffness"] == pytest.approx(sa["stiffness"], rel=1e-8)
        assert sb["force_balance"] < 1e-6


def test_the_stand_in_follows_approaches_with_a_disk_footprint(petsc):
    """Displacement control on a footprint that is not the grid (the pressure's upper bound
    holds it at zero outside), with the analytic flat punch as the reference."""
    steps = both(
        face(40, seed=5), approaches=[2e-3, 1e-2, 3e-2], footprint="disk", flat_stiffness="analytic"
    )
    for sa, sb in steps:
        agree(sa, sb, 40 * 40)


def test_a_flat_punch_on_the_stand_in_is_the_flat_punch_of_the_grid(petsc):
    """A flat face in full contact: its total stiffness is the grid's flat punch, the same on
    both paths, within 2% of the continuum's ``1.0212 2 E* sqrt(A/pi)`` (at 32 pixels the
    grid's is 1.1% below it)."""
    flat = np.zeros((32, 32))
    for sa, sb in both(flat, approaches=[1e-3], stiffness=True):
        agree(sa, sb, 32 * 32)
        assert sb["area_fraction"] == 1.0 and sb["full_contact"]
        assert np.isnan(sb["interfacial_stiffness"]) and np.isnan(sa["interfacial_stiffness"])
        assert sb["total_stiffness"] == pytest.approx(sb["flat_punch_stiffness"], rel=1e-6)
        exact = 2 * flat_punch.SQUARE_BETA / np.sqrt(np.pi)  # 1.1523 E* L
        assert sb["flat_punch_stiffness"] == pytest.approx(exact, rel=2e-2)


def test_the_array_punch_runs_without_petsc4py_pyfftw_or_mpi4py():
    """The stand-in's punch imports none of them: a GPU machine may have none."""
    code = (
        "import sys\n"
        "for m in ('petsc4py', 'pyfftw', 'mpi4py', 'mpi4py_fft', 'SurfaceTopography'):\n"
        "    sys.modules[m] = None\n"
        "import numpy as np\n"
        "from petsc_contact.workflows.punch_sweep import punch_contact\n"
        "x = np.linspace(0, 2 * np.pi, 32, endpoint=False)\n"
        "h = 0.01 * np.cos(x)[:, None] * np.cos(2 * x)[None, :]\n"
        "steps = punch_contact(h, length=1.0, modulus=1.0, forces=[1e-4, 1e-3], "
        "stiffness=True, device='cpu-array', options=['-stiffness_ksp_rtol', '1e-7'])\n"
        "s = steps[-1].scalars\n"
        "print(all(t.converged for t in steps), s['total_stiffness'] > 0,\n"
        "      s['flat_punch_stiffness'] > s['total_stiffness'], s['stiffness_tolerance'])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True", "True", "1e-07"]


def test_the_array_punch_refuses_options_it_does_not_read():
    with pytest.raises(ValueError, match="needs --device cpu"):
        punch_contact(
            np.zeros((8, 8)),
            length=1.0,
            approaches=[1e-3],
            device="cpu-array",
            options=["-tao_type", "bncg"],
        )


@pytest.mark.gpu
@pytest.mark.parametrize("n", [128, 256])
def test_the_gpu_presses_the_punch_as_its_stand_in_does(n):
    """``pytest -m gpu``: the GPU's punch against the stand-in (only rounding differs)."""
    try:
        get_device("gpu")
    except DeviceUnavailable as why:
        pytest.skip(str(why))
    steps = pairs(
        face(n), "cpu-array", "gpu", forces=[1e-4, 1e-3, 1e-2], stiffness=True, fields=True
    )
    for a, b in steps:
        agree(a.scalars, b.scalars, n * n)
        assert b.scalars["newton_iterations"] == a.scalars["newton_iterations"]
        assert isinstance(b.pressure, np.ndarray)
        assert b.scalars["force"] == pytest.approx(a.scalars["force"], rel=1e-8)
    assert isinstance(steps[-1][1].state, np.ndarray)
