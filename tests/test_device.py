"""The array path (``--device cpu-array``, the GPU's code on NumPy) against the PETSc path.

The stand-in runs the very code ``--device gpu`` runs, on NumPy: the same constrained CG, the
same preconditioner (held compliance, exact Schur form, two-level form) and the held-set
stiffness solve.  On the stability matrix's scenes it must take the same iterations as TAO's
Python type (within 2) and give the same mean gaps (1e-10) and stiffnesses (1e-8 relative:
KSPCG and the array CG stop at the same test, ``rtol`` 1e-6 on ``K``'s solve, and differ only
in rounding).
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
from petsc_contact.solver.driver import SolveSettings
from petsc_contact.workflows.periodic_sweep import periodic_contact

LOADS = [1e-5, 1e-4, 1e-3, 1e-2, 5e-2]  # first contact to about half the area


def assert_same_steps(reference, steps, iterations: int, gaps: float, stiffnesses: float) -> None:
    """Each of ``steps`` converged as its ``reference`` step did: iterations within
    ``iterations``, mean gaps and stiffnesses to the relative tolerances given."""
    for a, b in zip(reference, steps, strict=True):
        sa, sb = a.scalars, b.scalars
        assert sb["converged"], sb["verification"]
        assert abs(sb["iterations"] - sa["iterations"]) <= iterations
        assert sb["mean_gap"] == pytest.approx(sa["mean_gap"], rel=gaps)
        assert sb["stiffness"] == pytest.approx(sa["stiffness"], rel=stiffnesses)


def surface(n: int, hurst: float, cutoff: float, seed: int = 1) -> np.ndarray:
    grid = Grid(n, 1.0)
    return self_affine(
        grid,
        make_fft(grid, get_device("cpu-array")),
        hurst=hurst,
        rolloff_ratio=2,
        cutoff_ratio=cutoff,
        seed=seed,
        rms_slope=0.1,
    )


@pytest.mark.parametrize(
    ("n", "hurst", "cutoff"),
    [(128, 0.7, 32), (256, 0.3, 128), (256, 0.8, 64)],  # down to 2 pixels per wavelength
)
def test_the_stand_in_solves_as_the_petsc_path_does(petsc, n, hurst, cutoff):
    h = surface(n, hurst, cutoff)
    cpu = periodic_contact(h, length=1.0, modulus=1.0, pressures=LOADS, stiffness=True)
    array = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=LOADS, stiffness=True, device="cpu-array"
    )
    for a, b in zip(cpu, array, strict=True):
        sa, sb = a.scalars, b.scalars
        assert sb["converged"] and sb["verification"] == "ok"
        assert sb["tao_reason"] == sa["tao_reason"]
        assert abs(sb["iterations"] - sa["iterations"]) <= 2
        assert sb["mean_gap"] == pytest.approx(sa["mean_gap"], rel=1e-10, abs=1e-12)
        assert sb["area_fraction"] == pytest.approx(sa["area_fraction"], abs=2 / n**2)
        assert sb["stiffness"] == pytest.approx(sa["stiffness"], rel=1e-8)


def test_the_stand_in_uses_every_form_of_the_preconditioner(petsc):
    """A 256^2 sweep that goes through the Schur form (few contact pixels) and the two-level
    form (up to 10% contact): the same iterations as TAO's type, with and without it."""
    h = surface(256, 0.7, 128)
    loads = list(np.logspace(-4.5, -2, 6))
    for options in ([], ["-petsc_contact_two_level", "0"]):
        cpu = periodic_contact(h, length=1.0, modulus=1.0, pressures=loads, options=options)
        array = periodic_contact(
            h, length=1.0, modulus=1.0, pressures=loads, options=options, device="cpu-array"
        )
        its = [
            (a.scalars["iterations"], b.scalars["iterations"])
            for a, b in zip(cpu, array, strict=True)
        ]
        assert all(abs(i - j) <= 2 for i, j in its), its


def test_the_array_path_runs_without_petsc4py_pyfftw_or_mpi4py():
    """A GPU machine often has CuPy and NumPy but none of these: the stand-in still runs."""
    code = (
        "import sys\n"
        "for m in ('petsc4py', 'pyfftw', 'mpi4py', 'mpi4py_fft', 'SurfaceTopography'):\n"
        "    sys.modules[m] = None\n"
        "import numpy as np\n"
        "from petsc_contact.workflows.periodic_sweep import periodic_contact\n"
        "x = np.linspace(0, 2 * np.pi, 64, endpoint=False)\n"
        "h = 0.01 * np.cos(x)[:, None] * np.cos(2 * x)[None, :]\n"
        "steps = periodic_contact(h, length=1.0, modulus=1.0, pressures=[1e-4, 1e-3], "
        "stiffness=True, device='cpu-array')\n"
        "print(all(s.converged for s in steps), steps[-1].scalars['stiffness'] > 0)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]


def test_options_the_array_path_does_not_read_are_refused_in_one_line():
    with pytest.raises(ValueError, match="needs --device cpu"):
        SolveSettings.from_options(["-tao_type", "bncg"], "gpu")
    with pytest.raises(ValueError, match="does not read -ksp_rtol"):
        SolveSettings.from_options(["-ksp_rtol", "1e-3"], "cpu-array")
    settings = SolveSettings.from_options(
        ["-tao_gatol", "1e-10", "-tao_monitor", "-petsc_contact_two_level", "0"], "gpu"
    )
    assert (settings.gatol, settings.monitor, settings.two_level) == (1e-10, True, False)


def test_a_gpu_without_cupy_or_a_device_is_one_line():
    try:
        import cupy  # noqa: F401
    except ImportError:
        with pytest.raises(DeviceUnavailable, match="needs CuPy"):
            get_device("gpu")
    with pytest.raises(ValueError, match="unknown device 'tpu'"):
        get_device("tpu")
