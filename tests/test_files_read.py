"""Every file the package writes reads as a table (``read_frame``: the documented columns, in
the documented order) and as labelled arrays (xarray: named dimensions, none ``phony_dim``)."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import Run, read_frame, run_contact, run_ensemble
from petsc_contact.io.results import group_name
from petsc_contact.io.schema import FRAMES

SURFACE = dict(grid=32, hurst=0.7, rms_slope=0.1, seed=3)
CLI_SURFACE = ("--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "3")
DIMENSIONS = {  # the dimensions each kind's file names, at least
    "periodic": {"step", "bin", "edge", "patch_bin", "x", "y"},
    "punch": {"step", "bin", "edge", "patch_bin"},
    "periodic ensemble": {"seed", "step"},
    "theory": {"step", "wavevector"},
    "compare": {"iteration"},
    "experiment": {"row"},
}


@pytest.fixture(scope="module")
def files(tmp_path_factory, petsc):
    """One file of each kind, on a 32 x 32 grid: its path by kind."""
    folder = tmp_path_factory.mktemp("files")
    out = {kind: str(folder / f"{kind.replace(' ', '_')}.h5") for kind in FRAMES}
    run = Run(**SURFACE, pressures=(1e-3, 1e-2), stiffness=True, fields=True)
    run_contact(run.with_(output=out["periodic"]))
    run_contact(Run(**SURFACE, geometry="punch", forces=(1e-3, 2e-3), output=out["punch"]))
    run_ensemble(run.with_(fields=False, output=out["periodic ensemble"]), [0, 1])
    for kind, extra in (
        ("theory", ()),
        ("compare", ("--pressures", "1e-3", "--solvers", "cg,tron")),
    ):
        r = cli(kind, *CLI_SURFACE, *extra, "--quiet", "--output", out[kind])
        assert r.returncode == 0, r.stderr
    table = folder / "squeeze.csv"  # p = exp(s / 1e-4): K = p / 1e-4 before the block's share
    np.savetxt(
        table, np.column_stack([np.geomspace(1e3, 1e5, 9), 1e-4 * np.log(np.geomspace(1, 1e2, 9))])
    )
    squeeze = ("--table", str(table), "--modulus", "4e6", "--thickness", "1e-2")
    r = cli("experiment", *squeeze, "--quiet", "--output", out["experiment"])
    assert r.returncode == 0, r.stderr
    return out


def _groups(path: str) -> list[str]:
    """The groups holding a file's tables: each solver's of a comparison, else the root."""
    with h5py.File(path, "r") as f:
        solvers = json.loads(f.attrs.get("solvers", "[]"))
    return [group_name(solver) for solver in solvers] or ["/"]


@pytest.mark.parametrize("kind", FRAMES)
def test_read_frame_gives_the_documented_columns_in_order(files, kind):
    frame = read_frame(files[kind])
    documented = FRAMES[kind].columns
    assert len(frame) > 0 and list(frame.index.names) == list(FRAMES[kind].index)
    assert list(frame.columns) == [c for c in documented if c in frame.columns]
    with h5py.File(files[kind], "r") as f:
        held = {name for g in _groups(files[kind]) for name in f[g] if name in documented}
    assert set(frame.columns) == held and held


def test_a_runs_frame_is_its_table(files):
    """The file's table and the one the run returns hold the same values, in one order."""
    run = Run(**SURFACE, geometry="punch", forces=(1e-3, 2e-3))
    mine, again = run_contact(run).to_dataframe(), read_frame(files["punch"])
    assert list(mine.columns) == list(again.columns) and list(again.index) == [1, 2]
    assert np.allclose(mine["mean_gap"], again["mean_gap"], rtol=1e-12)
    assert list(again["verification"]) == list(mine["verification"])


def test_the_other_kinds_frames_hold_their_values(files):
    ensemble = read_frame(files["periodic ensemble"])
    assert list(ensemble["mean_gap_count"]) == [2, 2]
    assert np.allclose(ensemble["nominal_pressure"], [1e-3, 1e-2])
    theory = read_frame(files["theory"])
    assert (np.diff(theory["mean_gap"]) < 0).all()  # the gap closes as the load grows
    experiment = read_frame(files["experiment"])
    assert list(experiment.index) == list(range(1, 10)) and experiment.index.name == "row"
    defined = experiment.dropna()  # K = K*/(1 - K* d/E') is larger than K* where defined
    assert len(defined) > 3 and (defined["stiffness"] > defined["measured_stiffness"]).all()
    compare = read_frame(files["compare"])
    assert list(compare.index.get_level_values("solver").unique()) == ["cg", "tron"]
    assert compare.loc["cg"].index.name == "iteration"


def test_read_frame_refuses_a_file_of_no_kind(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(ValueError, match="not a file read_frame reads"):
        read_frame(str(path))


@pytest.mark.parametrize("kind", FRAMES)
def test_xarray_names_every_dimension(files, kind):
    xarray = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    named = set()
    for group in _groups(files[kind]):
        with xarray.open_dataset(files[kind], engine="h5netcdf", group=group) as data:
            named |= set(data.sizes)
    assert DIMENSIONS[kind] <= named
    assert not [d for d in named if d.startswith("phony_dim")]
