"""A punch face cut from a larger surface (``--cut-from M``): the central patch of the periodic
surface of ``M`` times the sides with the same pixel size and spectrum (paper Eq. 5)."""

import numpy as np
import pytest

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.preparation import edge_mismatch, rms_slope
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.scene import prepare_scene

N, M = 64, 4
FACE = dict(geometry="punch", grid=N, hurst=0.7, rms_slope=0.1, cutoff_ratio=N / 4, seed=3)


def test_cut_face_is_the_centre_of_the_larger_surface():
    """Same seed, pixel size and wavelengths: the face is the parent's central N x N patch,
    and ``--cut-from 1`` is the periodic face itself."""
    parent_grid = Grid((M * N, M * N), (M, M))
    parent = self_affine(
        parent_grid,
        make_fft(parent_grid),
        hurst=0.7,
        rolloff_ratio=M,
        cutoff_ratio=M * N / 4,
        seed=3,
        rms_slope=0.1,
    )
    start = (M - 1) * N // 2
    cut = prepare_scene(Run(**FACE, cut_from=M))
    assert np.array_equal(cut.heights, parent[start : start + N, start : start + N])
    grid = Grid((N, N), (1.0, 1.0))
    own = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=N / 4, seed=3, rms_slope=0.1
    )
    assert np.array_equal(prepare_scene(Run(**FACE)).heights, own)
    assert cut.realised["parent_rms_slope"] == pytest.approx(0.1, rel=0.1)


def test_cut_face_keeps_the_roughness_and_loses_periodicity():
    """Cut or periodic, the face has the prescribed rms slope inside (within sampling); only
    the cut face has a step at its periodic seam (its edges do not match)."""
    periodic = prepare_scene(Run(**FACE)).heights
    cut = prepare_scene(Run(**FACE, cut_from=M)).heights
    spacing = (1 / N, 1 / N)
    assert rms_slope(cut, spacing) == pytest.approx(rms_slope(periodic, spacing), rel=0.25)
    assert edge_mismatch(periodic) < 2 < edge_mismatch(cut)


def test_cut_from_is_a_punch_option_recorded_in_the_run():
    with pytest.raises(ValueError, match="cut-from"):
        prepare_scene(Run(**{**FACE, "geometry": "periodic"}, cut_from=2))
    with pytest.raises(ValueError, match="cut-from"):
        Run(**FACE, cut_from=0)
    run = Run(**FACE, cut_from=M)
    assert run.parameters()["cut_from"] == M
    assert run.arguments()[run.arguments().index("--cut-from") + 1] == str(M)


def test_cut_face_records_and_shows_its_slope_inside(tmp_path):
    """The file records the face's rms slope by differences inside it (``rms_slope_inside``:
    the parent's slope, about 0.1) beside the spectral one, which counts the step at the
    edges; the run's first line shows both."""
    import h5py
    from conftest import cli

    out = tmp_path / "cut.h5"
    args = ["punch", "--grid", str(N), "--hurst", "0.7", "--rms-slope", "0.1"]
    args += ["--cutoff-ratio", str(N // 4), "--seed", "3", "--cut-from", str(M)]
    r = cli(*args, "--approaches", "0.002", "--output", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        inside, spectral = f.attrs["rms_slope_inside"], f.attrs["rms_slope"]
        assert inside == pytest.approx(rms_slope(f["heights"][:], (1 / N, 1 / N)), rel=1e-12)
    assert inside == pytest.approx(0.1, rel=0.25) and spectral > 1.2 * inside
    r = cli(*args, "--approaches", "0.002", "--output", str(tmp_path / "again.h5"))
    first = r.stdout.splitlines()[0]
    assert f"h'_rms = {spectral:.4g} (the face taken as periodic; {inside:.4g} inside it)" in first
