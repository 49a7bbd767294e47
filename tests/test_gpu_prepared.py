"""The array path's work kept on its device, checked on the CPU stand-in (``cpu-array``).

- The coarse matrix of the two-level form summed with array operations (as on a GPU) equals
  the numba build of the ``cpu`` device to rounding, and is factorised on the device.
- A step's observables are taken where its fields live: with ``fields=False`` no field
  crosses to the host, and a sweep's resume state crosses only when it is read.
- The held-set stiffness's preconditioner takes ``G``'s column from the contact solve's
  preconditioner instead of transforming an impulse again, with the same stiffness.
- The preconditioner's round trips in float32 (``-petsc_contact_pc_float32``) give the
  float64 answers and iterations; the option is refused where the FFT is FFTW's.
- :class:`~petsc_contact.devices.fft.ArrayFFT` transforms in its kept buffers as NumPy does,
  in float64 and in float32 (the stand-in of the GPU's cuFFT plans).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
from test_device import assert_same_steps, surface

from petsc_contact.backend.coarse import array_coarse_matrix, host_coarse_matrix
from petsc_contact.backend.operator import FourierOperator
from petsc_contact.backend.preconditioner import MeanModePreconditioner
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.device import CPU, Device, get_device
from petsc_contact.devices.fft import ArrayFFT, make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.solver.backends import ArrayBackend
from petsc_contact.solver.driver import ArraySolver, SolveSettings
from petsc_contact.workflows.periodic_sweep import periodic_contact, sweep


@dataclass(frozen=True)
class RecordingDevice(Device):
    """The stand-in, recording the size of every array it brings to the host."""

    moved: list[int] = field(default_factory=list)

    def to_host(self, values):
        self.moved.append(int(np.size(values)))
        return super().to_host(values)


@dataclass(frozen=True)
class FieldRecordingDevice(Device):
    """The stand-in, recording the size of every floating-point array it brings to the host
    (not the Schur form's contact masks, which are boolean)."""

    fields: list[int] = field(default_factory=list)

    def to_host(self, values):
        if np.asarray(values).dtype.kind == "f":
            self.fields.append(int(np.size(values)))
        return super().to_host(values)


def compliance_quarter(n: int) -> np.ndarray:
    """``G``'s quarter of a ``n^2`` periodic problem on the stand-in."""
    grid = Grid(n, 1.0)
    device = get_device("cpu-array")
    fft = make_fft(grid, device)
    problem = PeriodicProblem(grid, fft, surface(n, 0.7, n // 2), 1.0, ArrayBackend())
    problem.set_pressure(1e-3)
    return problem.preconditioner._exact_compliance()


@pytest.mark.parametrize(
    ("n", "fraction", "block"),
    [(128, 0.03, 16), (128, 0.08, 4), (256, 0.02, 16), (256, 0.08, 8), (256, 0.2, 4)],
)
def test_the_device_build_of_the_coarse_matrix_is_the_numba_one(n, fraction, block):
    """The same aggregates and ``E`` to 1e-12 relative on clustered contact sets (the highest
    pixels of a rough surface), whichever way the numba build takes its near sums."""
    heights = surface(n, 0.3, n // 2, seed=2)
    bound = heights > np.quantile(heights, 1.0 - fraction)
    grid, quarter = Grid(n, 1.0), compliance_quarter(n)
    host = host_coarse_matrix(grid, quarter, bound, block, 10**6, CPU)
    array = array_coarse_matrix(grid, quarter, bound, block, 10**6, get_device("cpu-array"))
    assert array.block == host.block and host.matrix.shape[0] > 20
    np.testing.assert_array_equal(array.local, host.local)
    np.testing.assert_array_equal(array.labels, host.labels)
    np.testing.assert_array_equal(array.sizes, host.sizes)
    np.testing.assert_array_equal(array.matrix, array.matrix.T)
    scale = np.abs(host.matrix).max()
    assert np.abs(np.triu(array.matrix) - host.matrix).max() <= 1e-12 * scale


def test_the_block_grows_alike_on_the_device():
    heights = surface(128, 0.7, 64, seed=2)
    bound = heights > np.quantile(heights, 0.9)
    grid, quarter = Grid(128, 1.0), compliance_quarter(128)
    host = host_coarse_matrix(grid, quarter, bound, 2, 40, CPU)
    array = array_coarse_matrix(grid, quarter, bound, 2, 40, get_device("cpu-array"))
    assert host.block > 2 and array.block == host.block
    assert array.matrix.shape == (host.sizes.size,) * 2 and host.sizes.size <= 40


def test_the_device_factorises_or_says_it_cannot():
    device = get_device("cpu-array")
    rng = np.random.default_rng(0)
    a = rng.standard_normal((30, 30))
    e = a @ a.T + 30 * np.eye(30)
    b = rng.standard_normal(30)
    factor = device.cho_factor(e.copy())
    assert factor is not None
    np.testing.assert_allclose(device.cho_solve(factor, b), np.linalg.solve(e, b), rtol=1e-12)
    assert device.cho_factor(e - 100 * np.eye(30)) is None


def test_a_step_measured_on_the_array_path_brings_no_field_to_the_host():
    """Scalars, histograms and the patches' sizes and edge rows cross; the gap, pressure and
    contact mask only with ``fields=True``."""
    n = 128
    grid = Grid(n, 1.0)
    device = RecordingDevice("cpu-array", np)
    settings = SolveSettings()
    problem = PeriodicProblem(
        grid, make_fft(grid, device), surface(n, 0.7, 32), 1.0, ArrayBackend(settings)
    )
    problem.set_pressure(3e-3)
    x0 = problem.initial_gap().reshape(-1) / problem.scale_length
    problem.start(x0)
    solver = ArraySolver(problem.hessian, problem.preconditioner, device, settings)
    x, info = solver.solve(problem.objective_gradient, x0)
    for stiffness in (False, True):
        device.moved.clear()
        step = problem.measure(x, info, stiffness=stiffness, fields=False)
        assert step.scalars["verification"] == "ok" and step.gap is None
        assert device.moved and max(device.moved) <= n, device.moved
    device.moved.clear()
    with_fields = problem.measure(x, info, fields=True)
    assert device.moved.count(n * n) == 3  # the gap, the pressure and the contact mask
    assert with_fields.scalars["mean_gap"] == step.scalars["mean_gap"]
    assert with_fields.gap is not None and with_fields.gap.shape == (n, n)


def test_a_sweep_brings_its_resume_state_to_the_host_only_when_read():
    """No field crosses while a sweep runs without ``fields``; reading the last step's
    ``state`` and ``held`` brings its gap and the load path's older gap, the gaps the sweep
    ended with (the state's mean is the step's mean gap); a dropped step has none."""
    n = 128
    grid = Grid(n, 1.0)
    device = FieldRecordingDevice("cpu-array", np)
    fft = make_fft(grid, device)
    problem = PeriodicProblem(grid, fft, surface(n, 0.7, 32), 1.0, ArrayBackend())
    steps = list(sweep(problem, [1e-3, 3e-3, 1e-2]))
    assert all(s.converged for s in steps) and n * n not in device.fields, device.fields
    state, held = steps[-1].state, steps[-1].held
    assert device.fields.count(n * n) == 2 and state.shape == (n, n)
    assert state.mean() == pytest.approx(steps[-1].scalars["mean_gap"], rel=1e-12)
    assert held.scalars[:, 0].tolist() == [3e-3, 1e-2] and len(held.fields) == 1
    assert held.fields[0].mean() == pytest.approx(steps[1].scalars["mean_gap"], rel=1e-12)
    assert steps[-1].state is state and steps[-1].resume is None  # taken once, let go
    steps[1].forget_resume()
    assert steps[1].state is None and steps[1].held is None
    kept = periodic_contact(
        surface(n, 0.7, 32), length=1.0, modulus=1.0, pressures=[1e-3], device="cpu-array"
    )[-1]  # the last step of a returned list holds its state on the host, no device array
    assert kept.resume is None and kept.state.shape == (n, n)


@pytest.mark.parametrize("device", ["cpu-array", "cpu"])
def test_the_stiffness_takes_the_contact_solves_column(device, request, monkeypatch):
    """The held-set solve's coarse spaces built on the preconditioner's column of ``G``
    give the stiffnesses of a column transformed afresh, to 1e-12 (the Schur form at the
    first load, the two-level form at the others)."""
    if device == "cpu":
        request.getfixturevalue("petsc")
    heights = surface(128, 0.7, 32)
    loads = [1e-4, 1e-3, 3.2e-3]
    kept = MeanModePreconditioner.compliance_quarter
    given: list[bool] = []

    def spied(self, scale):
        column = kept(self, scale)
        given.append(column is not None)
        return column

    def run():
        steps = periodic_contact(
            heights, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device=device
        )
        return np.array([s.scalars["stiffness"] for s in steps])

    monkeypatch.setattr(MeanModePreconditioner, "compliance_quarter", spied)
    reused = run()
    assert given == [True] * len(loads)
    monkeypatch.setattr(MeanModePreconditioner, "compliance_quarter", lambda self, scale: None)
    afresh = run()
    np.testing.assert_allclose(reused, afresh, rtol=1e-12)


def test_a_sweep_keeps_its_forms_and_checks_on_the_device(monkeypatch):
    """From the map's checks through the Schur and two-level forms to the stiffness, a
    sweep without fields brings no array longer than a row to the host: the map is checked
    where it lives, the Schur form's ``G_BB`` is made, factorised and solved on the device
    (no contact mask, no right-hand side crosses) and ``G``'s quarter stays there."""
    from petsc_contact.backend import preconditioner
    from petsc_contact.geometries.periodic import PeriodicProblem
    from petsc_contact.numerics.schur import ContactSchur
    from petsc_contact.workflows.periodic_sweep import periodic_scene

    n = 128
    made: list[int] = []  # the sizes of the Schur forms made, minus those of coarse spaces

    class Counted(ContactSchur):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self.size)

    class Built(preconditioner.CoarseSpace):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(-self.size)

    monkeypatch.setattr(preconditioner, "ContactSchur", Counted)
    monkeypatch.setattr(preconditioner, "CoarseSpace", Built)
    device = RecordingDevice("cpu-array", np)
    comm, backend = Grid(n, 1.0).comm, ArrayBackend()
    scene = periodic_scene(surface(n, 0.7, 32), (1.0, 1.0), comm, device)
    problem = PeriodicProblem(scene.grid, scene.fft, scene.heights, 1.0, backend)
    steps = list(sweep(problem, [1e-4, 1e-3, 1e-2], stiffness=True))
    assert all(s.converged for s in steps)
    assert max(made) > 0 > min(made), made  # both forms were used (coarse: negative)
    assert device.moved and max(device.moved) <= n, sorted(device.moved)[-5:]


FLOAT32_LOADS = [1e-4, 1e-3, 1e-2, 1e-1]  # the Schur form, the two-level one, the Fourier one


@pytest.mark.parametrize(("hurst", "cutoff"), [(0.7, 32), (0.3, 64)])
def test_the_preconditioner_in_float32_gives_the_float64_answers(monkeypatch, hurst, cutoff):
    """``-petsc_contact_pc_float32`` makes most of the preconditioner's round trips in float32
    (all but the exact Schur form's), and the sweep keeps its answers and its iterations: the
    residual, the Hessian and the stopping test stay float64, so the preconditioner steers the
    CG's path, never where it stops.  Any path that passes the stopping test lands within
    1e-10 of the answer (the stand-in against the PETSc path, tests/test_device.py); measured
    over 32 surfaces (8 seeds x H 0.3/0.7 x 256^2/512^2, 6 loads from 1e-4 to 1e-1): the same
    iterations at all 192 steps, mean gaps to 8.5e-15, stiffnesses equal (docs/gpu.md)."""
    h = surface(128, hurst, cutoff)
    run = {"length": 1.0, "modulus": 1.0, "pressures": FLOAT32_LOADS, "stiffness": True}
    double = periodic_contact(h, device="cpu-array", **run)
    spectra: list[np.dtype] = []
    original = MeanModePreconditioner._single_round_trip

    def counted(self, x, out):
        spectra.append(self._fft32.spectrum.dtype)
        return original(self, x, out)

    monkeypatch.setattr(MeanModePreconditioner, "_single_round_trip", counted)
    single = periodic_contact(h, device="cpu-array", options=["-petsc_contact_pc_float32"], **run)
    trips = sum(int(s.scalars["preconditioner_applications"]) for s in single)
    assert 2 * len(spectra) > trips and set(spectra) == {np.dtype(np.complex64)}
    assert_same_steps(double, single, iterations=1, gaps=1e-10, stiffnesses=1e-10)


def test_the_float32_preconditioner_is_read_and_refused_off_the_array_fft():
    """The option reads as PETSc's flags do, and a problem whose FFT is FFTW's (the ``cpu``
    device, or several ranks) refuses it in one line rather than ignoring it."""
    assert SolveSettings.from_options(["-petsc_contact_pc_float32"], "cpu-array").pc_float32
    off = SolveSettings.from_options(["-petsc_contact_pc_float32", "0"], "cpu-array")
    assert not off.pc_float32 and not SolveSettings().pc_float32
    grid = Grid(32, 1.0)
    h = np.random.default_rng(1).standard_normal(grid.shape)
    backend = ArrayBackend(SolveSettings(pc_float32=True))
    with pytest.raises(ValueError, match="^-petsc_contact_pc_float32 needs the array module's"):
        PeriodicProblem(grid, make_fft(grid, CPU), h, 1.0, backend)


def test_the_array_fft_transforms_in_its_buffers_as_numpy_does():
    """:class:`ArrayFFT`'s transforms (the stand-in of the GPU's kept-buffer plans): the
    spectrum is NumPy's ``rfft2`` bit for bit, the inverse unnormalised (the ``1/N`` is the
    operators' multipliers': an operator's answer is NumPy's normalised round trip to
    rounding), ``real`` is never written by :meth:`forward_from`, and a field of another
    dtype or layout goes through the staging buffer both ways."""
    grid = Grid(48, 1.0)
    fft = make_fft(grid, get_device("cpu-array"))
    x = np.random.default_rng(2).standard_normal(grid.shape)
    fft.forward_from(x)
    np.testing.assert_array_equal(fft.spectrum, np.fft.rfft2(x))
    assert not fft.real.any()
    fft.forward_from(np.asfortranarray(x))
    np.testing.assert_array_equal(fft.spectrum, np.fft.rfft2(x))
    out = np.zeros((48, 96))[:, ::2]  # not contiguous: through the staging buffer
    fft.backward_into(out)
    np.testing.assert_allclose(out, grid.size * x, rtol=1e-12, atol=1e-12 * grid.size)
    kernel = np.random.default_rng(3).random(fft.spectrum.shape)
    op = FourierOperator(grid, fft, kernel)
    expected = np.fft.irfft2(kernel * np.fft.rfft2(x), s=grid.shape)
    scale = 1e-13 * np.abs(expected).max()  # rounding, of the largest entry
    np.testing.assert_allclose(op.apply_array(x, np.empty(grid.shape)), expected, atol=scale)


def test_the_array_fft_in_float32_computes_in_float32():
    """With ``dtype=float32`` the transforms run in single precision (NumPy 2, as cuFFT's
    C2R/R2C): a round trip is good to float32's rounding, not float64's, and writes into a
    float64 field through the staging buffer, the one field it makes (not ``real`` nor
    ``result``: the preconditioner's float32 transforms cost a spectrum and one field)."""
    grid = Grid(64, 1.0)
    fft = ArrayFFT(grid, get_device("cpu-array"), np.float32)
    x = np.random.default_rng(4).standard_normal(grid.shape)
    fft.forward_from(x)
    assert fft.spectrum.dtype == np.complex64
    out = np.empty(grid.shape)
    fft.backward_into(out)
    error = np.abs(out / grid.size - x).max() / np.abs(x).max()
    assert 1e-12 < error < 1e-5, error
    assert set(fft._fields) == {"staging"}
