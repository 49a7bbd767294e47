"""``--device`` at every door of the periodic geometry: the command line (``periodic``,
``ensemble``, resume) and ``Run(device=...)`` through ``run_contact``.

``--device cpu-array`` runs the code ``--device gpu`` runs, on NumPy: its sweeps must give what
the PETSc path gives (mean gaps to 1e-10 relative, stiffnesses to 1e-8, iterations within 2),
its files must read as a cpu run's do and record the device, and it must run without
petsc4py, pyFFTW and SurfaceTopography.  A GPU asked for where there is none is exit status 69,
a TAO type on an array device one line with exit status 2.
"""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from conftest import cli, python

from petsc_contact.cli.arguments import build_parser
from petsc_contact.solver.driver import SolveSettings
from petsc_contact.solver.report import DEFAULT_MAX_IT
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.drivers import on_device

SCENE = "--grid 96 --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 2 --cutoff-ratio 32 --seed 3"
LOADS = "1e-4,1e-3,5e-3,2e-2"  # first contact to about a third of the area
HIDDEN = ("petsc4py", "pyfftw", "mpi4py", "mpi4py_fft", "SurfaceTopography", "cupy")
NEVER = {"petsc4py", "pyfftw", "mpi4py_fft", "SurfaceTopography"}  # mpi4py: tried, optional

HIDE = f"""
import sys
tried = []


class Hide:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {HIDDEN!r}:
            tried.append(name.split(".")[0])
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


sys.meta_path.insert(0, Hide())
from petsc_contact.cli.main import main

code = main(sys.argv[1:])
print("tried:" + ",".join(sorted(set(tried))), file=sys.stderr)
sys.exit(code)
"""
"""``python -c HIDE ARGS`` runs the command line where ``HIDDEN`` cannot be imported, and says
on its last line of standard error which of them the run tried to import."""


def _sweep(path, *extra: str):
    return cli("periodic", *SCENE.split(), "--pressures", LOADS, "--output", str(path), *extra)


def _one_error(done) -> str:
    """The one line a refused command prints (no traceback)."""
    lines = [line for line in done.stderr.splitlines() if not line.startswith("tried:")]
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    return lines[0]


def test_the_cli_sweep_on_the_stand_in_is_the_petsc_path_s(tmp_path):
    """``periodic --device cpu-array --stiffness --fields`` against ``--device cpu``: the same
    steps, fields and file layout; the file records the device."""
    runs = {}
    for device in ("cpu", "cpu-array"):
        out = tmp_path / f"{device}.h5"
        done = _sweep(out, "--stiffness", "--fields", "--quiet", "--device", device)
        assert done.returncode == 0, done.stderr
        runs[device] = out
    with h5py.File(runs["cpu"]) as a, h5py.File(runs["cpu-array"]) as b:
        assert b["converged"][:].all() and b["accurate"][:].all()
        assert np.isfinite(b["stiffness"][:]).all() and b["area_fraction"][-1] > 0.1
        np.testing.assert_allclose(b["mean_gap"][:], a["mean_gap"][:], rtol=1e-10)
        np.testing.assert_allclose(b["stiffness"][:], a["stiffness"][:], rtol=1e-8)
        assert np.abs(b["iterations"][:] - a["iterations"][:]).max() <= 2
        assert list(b["tao_reason"][:]) == list(a["tao_reason"][:])
        scale = np.abs(a["gap"][:]).max()
        np.testing.assert_allclose(b["gap"][:], a["gap"][:], rtol=0, atol=1e-8 * scale)
        assert b["solve_time"].shape == (4,) and (b["solve_time"][:] > 0).all()
        assert set(a) == set(b)
        assert (a.attrs["device"], b.attrs["device"]) == ("cpu", "cpu-array")
        assert json.loads(b.attrs["parameters"])["device"] == "cpu-array"
        assert "device_name" not in b.attrs  # a GPU's model and memory only
    from petsc_contact import read_frame

    cpu, array = read_frame(str(runs["cpu"])), read_frame(str(runs["cpu-array"]))
    assert list(array.columns) == list(cpu.columns) and len(array) == 4
    np.testing.assert_allclose(array["mean_gap"], cpu["mean_gap"], rtol=1e-10)


def test_a_paused_stand_in_sweep_resumes_as_if_never_stopped(tmp_path):
    """``--stop-after 0`` pauses after the first step (exit status 75); ``--resume`` goes on
    from the state file to the uninterrupted sweep's steps."""
    whole, parted = tmp_path / "whole.h5", tmp_path / "parted.h5"
    args = ("--stiffness", "--quiet", "--device", "cpu-array")
    assert _sweep(whole, *args).returncode == 0
    paused = _sweep(parted, *args, "--stop-after", "0")
    assert paused.returncode == 75, paused.stderr
    resumed = _sweep(parted, *args, "--resume")
    assert resumed.returncode == 0, resumed.stderr
    with h5py.File(whole) as a, h5py.File(parted) as b:
        np.testing.assert_allclose(b["mean_gap"][:], a["mean_gap"][:], rtol=1e-12)
        np.testing.assert_allclose(b["stiffness"][:], a["stiffness"][:], rtol=1e-10)
        assert list(b["iterations"][:]) == list(a["iterations"][:])
        (segment,) = json.loads(b.attrs["resumed"])
        assert segment["after_step"] == 1 and segment["from_saved_state"]
        assert segment["device"] == b.attrs["device"] == "cpu-array"


def test_a_sweep_paused_on_one_device_goes_on_on_another(tmp_path):
    """A run paused on the stand-in resumes on the cpu (the device is how, not what): the
    uninterrupted sweep's steps to the devices' agreement; each part's device recorded."""
    whole, parted = tmp_path / "whole.h5", tmp_path / "parted.h5"
    assert _sweep(whole, "--stiffness", "--quiet").returncode == 0
    paused = _sweep(parted, "--stiffness", "--quiet", "--device", "cpu-array", "--stop-after", "0")
    assert paused.returncode == 75, paused.stderr
    resumed = _sweep(parted, "--stiffness", "--quiet", "--device", "cpu", "--resume")
    assert resumed.returncode == 0, resumed.stderr
    with h5py.File(whole) as a, h5py.File(parted) as b:
        np.testing.assert_allclose(b["mean_gap"][:], a["mean_gap"][:], rtol=1e-10)
        np.testing.assert_allclose(b["stiffness"][:], a["stiffness"][:], rtol=1e-8)
        assert b.attrs["device"] == "cpu-array"
        assert [s["device"] for s in json.loads(b.attrs["resumed"])] == ["cpu"]


def test_run_takes_the_device_through_run_contact(tmp_path, petsc):
    """``Run(device="cpu-array")`` through ``run_contact`` gives the cpu run's steps, records
    its device, and reads the array path's options (``-tao_type`` refused in one line)."""
    from petsc_contact import run_contact

    run = Run(
        grid=64,
        hurst=0.7,
        rms_slope=0.1,
        rolloff_ratio=2,
        cutoff_ratio=16,
        seed=2,
        pressures=[1e-3, 1e-2],
        stiffness=True,
    )
    cpu = run_contact(run)
    array = run_contact(run.with_(device="cpu-array", output=str(tmp_path / "a.h5")))
    assert array.converged and array.record["device"] == "cpu-array"
    assert array.record["petsc_options"] == "" and array.record["mpi_size"] == 1
    for a, b in zip(cpu.table, array.table, strict=True):
        assert b["mean_gap"] == pytest.approx(a["mean_gap"], rel=1e-10)
        assert b["stiffness"] == pytest.approx(a["stiffness"], rel=1e-8)
        assert abs(b["iterations"] - a["iterations"]) <= 2
    assert array.to_dataframe()["mean_gap"].tolist() == [s["mean_gap"] for s in array.table]
    with pytest.raises(ValueError, match="-tao_type needs --device cpu"):
        run_contact(run.with_(device="cpu-array", options=("-tao_type", "bncg")))
    with pytest.raises(ValueError, match="--device must be one of cpu, gpu, cpu-array, not 'tpu'"):
        Run(grid=64, device="tpu")
    with pytest.raises(ValueError, match="--flat-stiffness must be one of grid, analytic, king"):
        Run(grid=64, geometry="punch", flat_stiffness="pharr")


def test_the_stand_in_runs_the_cli_without_petsc4py_pyfftw_or_surfacetopography(tmp_path):
    """The command line's array path, ``ensemble`` included, imports none of them."""
    out = tmp_path / "e.h5"
    scene = "--grid 32 --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 2 --cutoff-ratio 8"
    line = ["ensemble", *scene.split(), "--seeds", "1-2", "--sweep", "3", "--stiffness"]
    done = python("-c", HIDE, *line, "--output", str(out), "--quiet", "--device", "cpu-array")
    assert done.returncode == 0, done.stderr
    tried = done.stderr.splitlines()[-1].removeprefix("tried:").split(",")
    assert not NEVER & set(tried), done.stderr
    with h5py.File(out) as f:
        assert f.attrs["device"] == "cpu-array" and f.attrs["complete"]
    with h5py.File(tmp_path / "e_seed2.h5") as f:
        assert f.attrs["device"] == "cpu-array" and f["converged"][:].all()


def test_the_stand_in_reads_a_map_without_them(tmp_path):
    """A map given as ``.npy`` (read by numpy; the package only asks whether SurfaceTopography
    is installed), with the modules absent as where they are not installed."""
    x = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    np.save(tmp_path / "h.npy", 0.01 * np.cos(x)[:, None] * np.cos(2 * x)[None, :])
    absent = "".join(f"sys.modules[{name!r}] = None; " for name in HIDDEN)
    code = f"import sys; {absent}from petsc_contact.cli import main; sys.exit(main(sys.argv[1:]))"
    line = ["periodic", "--heights", str(tmp_path / "h.npy"), "--length", "1"]
    line += ["--pressures", "1e-4,1e-3", "--stiffness", "--fields", "--device", "cpu-array"]
    done = python("-c", code, *line, "--output", str(tmp_path / "m.h5"), "--quiet")
    assert done.returncode == 0, done.stderr
    with h5py.File(tmp_path / "m.h5") as f:
        assert f["converged"][:].all() and f.attrs["device"] == "cpu-array"
        assert f["gap"].shape == (2, 64, 64)


def test_a_gpu_without_cupy_is_exit_status_69_in_one_line(tmp_path):
    """``--device gpu`` where CuPy cannot be imported: one line, exit status 69, no output."""
    out = tmp_path / "g.h5"
    done = python("-c", HIDE, "periodic", *SCENE.split(), "--pressures", "1e-3",
                  "--output", str(out), "--device", "gpu")  # fmt: skip
    assert done.returncode == 69, done.stderr
    assert "--device gpu needs CuPy" in _one_error(done)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_tao_type_on_the_array_path_is_refused_in_one_line(tmp_path):
    """A TAO type on an array device: exit status 2, one line, before anything is written."""
    out = tmp_path / "r.h5"
    tao = _sweep(out, "--device", "cpu-array", "-tao_type", "bncg")
    assert tao.returncode == 2
    assert "-tao_type needs --device cpu" in _one_error(tao)
    assert list(tmp_path.iterdir()) == []


def test_the_cli_punch_on_the_stand_in_is_the_petsc_path_s(tmp_path):
    """``punch --device cpu-array --forces ... --stiffness --fields`` against ``--device cpu``:
    the same forces, approaches, stiffnesses and fields; a paused run resumes there."""
    runs = {}
    for device in ("cpu", "cpu-array"):
        runs[device] = tmp_path / f"{device}.h5"
        loads = ("--forces", "1e-4,5e-4,2e-3", "--stiffness", "--fields", "--quiet")
        done = cli("punch", *SCENE.split(), *loads, "--device", device,
                   "--output", str(runs[device]))  # fmt: skip
        assert done.returncode == 0, done.stderr
    with h5py.File(runs["cpu"]) as a, h5py.File(runs["cpu-array"]) as b:
        assert b["converged"][:].all() and b.attrs["device"] == "cpu-array"
        for name in ("force", "approach", "mean_gap"):
            np.testing.assert_allclose(b[name][:], a[name][:], rtol=1e-8)
        for name in ("total_stiffness", "interfacial_stiffness"):
            np.testing.assert_allclose(b[name][:], a[name][:], rtol=1e-8)
        scale = np.abs(a["pressure"][:]).max()
        np.testing.assert_allclose(b["pressure"][:], a["pressure"][:], rtol=0, atol=1e-7 * scale)
        assert set(a) == set(b)
    parted = tmp_path / "parted.h5"
    loads = ("--forces", "1e-4,5e-4,2e-3", "--stiffness", "--quiet", "--device", "cpu-array")
    paused = cli("punch", *SCENE.split(), *loads, "--output", str(parted), "--stop-after", "0")
    assert paused.returncode == 75, paused.stderr
    resumed = cli("punch", *SCENE.split(), *loads, "--output", str(parted), "--resume")
    assert resumed.returncode == 0, resumed.stderr
    with h5py.File(runs["cpu-array"]) as a, h5py.File(parted) as b:
        np.testing.assert_allclose(b["approach"][:], a["approach"][:], rtol=1e-10)
        np.testing.assert_allclose(b["total_stiffness"][:], a["total_stiffness"][:], rtol=1e-8)


def test_the_array_path_reads_the_run_s_prefixed_options():
    """With ``--options-prefix a_`` the array path reads ``-a_tao_gatol`` and leaves the
    unprefixed options to others, as PETSc's solvers with that prefix do."""
    options = ["-a_tao_gatol", "1e-9", "-tao_max_it", "3", "-a_tao_monitor"]
    settings = SolveSettings.from_options(options, "cpu-array", "a_")
    assert (settings.gatol, settings.max_it, settings.monitor) == (1e-9, DEFAULT_MAX_IT, True)
    with pytest.raises(ValueError, match="needs --device cpu"):
        SolveSettings.from_options(["-a_tao_type", "bncg"], "gpu", "a_")


def test_a_study_runs_its_pieces_on_the_device():
    """``study --device``: the periodic and punch pieces on the device with the command
    line's PETSc options."""
    periodic = Run(grid=64, hurst=0.7, rms_slope=0.1, pressures=[1e-3])
    punch = periodic.with_(geometry="punch", pressures=None, approaches=[1e-3])
    moved = on_device(periodic, "gpu", ["-tao_gatol", "1e-9"])
    assert (moved.device, moved.options) == ("gpu", ("-tao_gatol", "1e-9"))
    assert on_device(punch, "gpu", ["-tao_gatol", "1e-9"]).device == "gpu"
    assert on_device(periodic, "cpu") is periodic
    assert build_parser().parse_args(["study", "--device", "cpu-array"]).device == "cpu-array"


def test_periodic_reads_cut_from_1_with_a_warning(capsys):
    """``periodic --cut-from 1`` (an option periodic runs once listed) is read and ignored with
    a warning; another value is the unknown argument it is."""
    parser = build_parser()
    line = ["periodic", "--grid", "8", "--hurst", "0.7", "--rms-slope", "0.1"]
    line += ["--pressures", "1e-3", "--output", "x.h5"]
    args = parser.parse_args([*line, "--cut-from", "1"])
    assert not hasattr(args, "cut_from")
    assert "--cut-from is for punch runs; ignored" in capsys.readouterr().err
    with pytest.raises(SystemExit) as refused:
        parser.parse_args([*line, "--cut-from", "2"])
    assert refused.value.code == 2
    assert "unrecognized arguments: --cut-from 2" in capsys.readouterr().err
