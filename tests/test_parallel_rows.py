"""No rank holds the grid: on 4 and 8 ranks every rank writes its own rows of the maps, fields
and resume state, the assembled file is the serial run's, and a run paused or killed on one
rank count goes on on another (docs/parallel.md)."""

from __future__ import annotations

import json
import shutil
import textwrap
from pathlib import Path
from subprocess import CompletedProcess

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python
from kill_at import same_result

pytestmark = pytest.mark.slow  # MPI launches: started first (tests/conftest.py)

# 60 rows: 8 ranks hold 8 or 7 rows each (no slab ends on a chunk), 4 ranks 15
SWEEP = "periodic --grid 60 --hurst 0.7 --rms-slope 0.1 --seed 3 --sweep 3,1e-4,1e-2 --stiffness"
TIMES = ("solve_time", "stiffness_time")  # wall time: the columns that differ
RESIDUALS = (  # rounding-level residuals: to 1e-10 absolute, not relative
    "complementarity",
    "force_balance",
    "gradient_norm",
    "kkt_residual",
    "min_pressure",
    "stiffness_residual",
)


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The uninterrupted serial run every other is held against."""
    out = tmp_path_factory.mktemp("serial") / "serial.h5"
    r = cli(*SWEEP.split(), "--fields", "--quiet", "--output", str(out))
    assert r.returncode == 0, r.stderr
    return out


def _same_file(a: Path, b: Path) -> None:
    """Every dataset of ``b`` is ``a``'s: maps and fields to 1e-12 of their largest value,
    scalars to 1e-10 (residuals near rounding to 1e-10 absolute), their attributes' names
    equal."""
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert sorted(fa) == sorted(fb)
        for name in fa:
            x, y = fa[name][...], fb[name][...]
            assert x.shape == y.shape and x.dtype == y.dtype, name
            assert dict(fa[name].attrs).keys() == dict(fb[name].attrs).keys(), name
            if name in TIMES or x.dtype.kind not in "fiub":
                continue
            if x.ndim == 3 or name in ("heights", "x", "y"):
                scale = max(np.abs(x.astype(float)).max(), 1.0)
                assert np.allclose(x, y, rtol=0, atol=1e-12 * scale), name
            else:
                floor = 1e-10 if name in RESIDUALS else 0.0
                assert np.allclose(x, y, rtol=1e-10, atol=floor, equal_nan=True), name
        assert fa["gap"].chunks == fb["gap"].chunks


def test_four_and_eight_ranks_write_the_serial_file(tmp_path, serial, watched):
    """--fields --stiffness on 4 ranks (the watched run, :func:`watched`) and 8: the file is
    the serial run's, and every reader reads it."""
    import xarray

    from petsc_contact import read_frame

    outputs = {4: watched / "mpi4.h5", 8: tmp_path / "mpi8.h5"}
    r = cli(*SWEEP.split(), "--fields", "--quiet", "--output", str(outputs[8]), mpi=8)
    assert r.returncode == 0, r.stderr
    for ranks, out in outputs.items():
        _same_file(serial, out)
        assert sorted(p.name for p in out.parent.glob(f"mpi{ranks}.*")) == [
            f"mpi{ranks}.csv",
            f"mpi{ranks}.h5",
        ]
    assert len(read_frame(str(out))) == 3
    with xarray.open_dataset(out, engine="h5netcdf") as data:
        assert data["gap"].dims == ("step", "x", "y")


def test_paused_on_eight_goes_on_on_three_then_one(serial, paused_on_eight):
    """Paused after each step (``--stop-after 0``) on 8 ranks, then 3, then finished on one:
    each resume reads its rows of the other rank count's state slabs, and the file is the
    uninterrupted serial run's to rounding. Before the resume on 3 ranks, in its launch
    (:func:`_read_on_three`), each rank reads the state saved on 8: it opens (and
    CRC-checks) only the slabs that hold its rows (20 of 60: 3 or 4 of the 8), and reads its
    rows right."""
    from petsc_contact.conventions.grid import block_rows

    folder, args = _paused_again(paused_on_eight)
    out = folder / "paused.h5"
    assert len(list(folder.glob("paused.h5.state.*of8.npz"))) == 8
    said, r = _read_on_three(folder, *args, "--stop-after", "0", "--resume")
    assert r.returncode == 75, r.stderr
    for rank, mine in enumerate(said):
        assert mine["opened"] == _slabs_holding(block_rows(60, 3, rank)), mine
        assert mine["problem"] == "" and mine["rows"] is True
    assert sorted(p.name for p in folder.glob("paused.h5.state*")) == [
        f"paused.h5.state.{k}of3.npz" for k in range(3)
    ]  # the 8 slabs of the older state removed once the 3 were written
    r = cli(*args, "--resume")
    assert r.returncode == 0, r.stderr
    same_result(serial, out, fields=True)
    with h5py.File(out) as f:
        segments = json.loads(f.attrs["resumed"])
    assert [s["from_saved_state"] for s in segments] == [True, True]


def test_a_rank_killed_on_four_resumed_on_two(tmp_path, serial):
    """Rank 0 killed on 4 ranks after committing step 2 (before its state was saved), resumed
    on 2: every step there, equal to the serial run to the solver's tolerance."""
    out = tmp_path / "killed.h5"
    args = [*SWEEP.split(), "--fields", "--quiet", "--output", str(out)]
    r = python(str(ROOT / "tests" / "kill_at.py"), "after:commit:3", "--", *args, mpi=4)
    assert r.returncode != 0 and not out.exists()
    r = cli(*args, "--resume", mpi=2)
    assert r.returncode == 0, r.stderr
    assert "starts from first touch" in r.stderr
    same_result(serial, out, fields=True)


WATCHED = """
import os
import sys
import h5py
import numpy as np
from mpi4py import MPI
from petsc_contact.cli.main import main
from petsc_contact.conventions import grid as grids

def refuse(self, local):
    raise AssertionError("a field gathered")

grids.Grid.gather = refuse
largest = [0]

def watch(size):
    largest[0] = max(largest[0], int(size))

def wrapped(method, size):
    def call(self, *args, **kwargs):
        out = method(self, *args, **kwargs)
        watch(size(args, kwargs, out))
        return out
    return call

data = lambda args, kwargs, out: np.size(kwargs.get("data", 0))
h5py.Group.create_dataset = wrapped(h5py.Group.create_dataset, data)
h5py.Dataset.__getitem__ = wrapped(h5py.Dataset.__getitem__, lambda a, k, out: np.size(out))
h5py.Dataset.__setitem__ = wrapped(h5py.Dataset.__setitem__, lambda a, k, out: np.size(a[1]))
savez = np.savez
np.savez = lambda f, **arrays: (watch(max(np.size(v) for v in arrays.values())), savez(f, **arrays))
if main([*sys.argv[2:], "--output", sys.argv[1]]):
    sys.exit("the run failed")
with open(os.path.join(os.path.dirname(sys.argv[1]), f"largest.{MPI.COMM_WORLD.rank}"), "w") as out:
    out.write(str(largest[0]))
"""


@pytest.fixture(scope="module")
def watched(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The folder of the sweep with ``--fields`` run on 4 ranks by :data:`WATCHED` (the
    command line's ``main`` with ``Grid.gather`` refusing and every array handed to HDF5 or
    ``np.savez`` measured): ``mpi4.h5``, its table, and each rank's largest array."""
    folder = tmp_path_factory.mktemp("watched")
    script = folder / "watched.py"
    script.write_text(textwrap.dedent(WATCHED))
    out = folder / "mpi4.h5"
    r = python(str(script), str(out), *SWEEP.split(), "--fields", "--quiet", mpi=4)
    assert r.returncode == 0, r.stderr
    return folder


def test_no_rank_holds_a_field_to_write_it(watched):
    """On 4 ranks with ``Grid.gather`` refusing, the largest array any rank hands HDF5 or
    ``np.savez``, or reads back to assemble the file, is at most a slab (15 of 60 rows) or a
    band of the assembly (at most one chunk's rows of one slab)."""
    sizes = [int(p.read_text()) for p in watched.glob("largest.*")]
    assert len(sizes) == 4 and max(sizes) <= 15 * 60, sizes
    assert (watched / "mpi4.h5").exists()


READER = """
import json, os, sys
import h5py
import numpy as np
from mpi4py import MPI
from petsc_contact.conventions.grid import Grid
from petsc_contact.io.store import read_resume

out, seen = sys.argv[1], sys.argv[2]
opened = []
watching = [True]
sys.addaudithook(lambda event, args: watching[0] and event == "open" and opened.append(args[0]))
with h5py.File(out + ".partial", "r") as f:
    parameters = json.loads(f.attrs["parameters"])
grid = Grid(60, 1.0, MPI.COMM_WORLD)
finished = read_resume(out, parameters, grid)
rows = None if finished.state is None else finished.state[grid.rows]
watching[0] = False
said = {"opened": sorted({os.path.basename(str(p)) for p in opened if ".state." in str(p)}),
        "problem": finished.state_problem, "rows": None}
if rows is not None:  # against every slab read whole
    slabs = sorted(p for p in os.listdir(os.path.dirname(out)) if ".state." in p)
    whole = np.concatenate([np.load(os.path.join(os.path.dirname(out), p))["state"] for p in slabs])
    said["rows"] = bool(np.array_equal(rows, whole[grid.rows]))
with open(os.path.join(seen, str(grid.comm.rank)), "w") as f:
    json.dump(said, f)
if len(sys.argv) > 3:  # then the run resumed on these ranks by the command line
    from petsc_contact.cli.main import main

    sys.exit(main(sys.argv[3:]))
"""


@pytest.fixture(scope="module")
def paused_on_eight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sweep with ``--fields`` run on 8 ranks and paused after its first step
    (``--stop-after 0``), in ``run/``: ``paused.h5.partial``, its parts and 8 state slabs,
    kept whole in ``pristine/``. A resume is of the output it was started on, so each test
    resumes or damages ``run/`` put back as it was paused (:func:`_paused_again`)."""
    folder = tmp_path_factory.mktemp("paused8")
    (folder / "run").mkdir()
    r = cli(*_paused_args(folder / "run"), "--stop-after", "0", mpi=8)
    assert r.returncode == 75, r.stderr
    shutil.copytree(folder / "run", folder / "pristine")
    return folder


def _paused_args(folder: Path) -> list[str]:
    """The paused sweep's arguments, its output in ``folder``."""
    return [*SWEEP.split(), "--fields", "--quiet", "--output", str(folder / "paused.h5")]


def _paused_again(paused: Path) -> tuple[Path, list[str]]:
    """The run paused on 8 ranks put back as it was paused: its folder and the arguments
    that resume it."""
    shutil.rmtree(paused / "run")
    shutil.copytree(paused / "pristine", paused / "run")
    return paused / "run", _paused_args(paused / "run")


def _read_on_three(folder: Path, *resume: str) -> tuple[list[dict], CompletedProcess]:
    """What each of 3 ranks opened and found reading the resume state of ``folder``, then
    the command line ``resume`` run on those ranks in the same launch (if given): the
    launch's result."""
    script, seen = folder / "reader.py", folder / "seen"
    script.write_text(textwrap.dedent(READER))
    seen.mkdir()
    r = python(str(script), str(folder / "paused.h5"), str(seen), *resume, mpi=3)
    said = [json.loads((seen / str(rank)).read_text()) for rank in range(3)]
    return said, r


def _slabs_holding(rows: slice) -> list[str]:
    """The 8-rank state slabs of 60 rows that hold any of ``rows``."""
    from petsc_contact.conventions.grid import block_rows

    spans = [block_rows(60, 8, k) for k in range(8)]
    held = [k for k, s in enumerate(spans) if s.start < rows.stop and s.stop > rows.start]
    return [f"paused.h5.state.{k}of8.npz" for k in held]


def test_a_damaged_state_slab_is_refused_on_every_rank(serial, paused_on_eight):
    """Bad bytes in one state slab of a run paused on 8 ranks, which only the last of 3
    resuming ranks reads: every rank refuses the state with the same words, and the resume
    on 3 ranks (in the readers' launch) says so once, starts its next step from first touch
    and ends on the serial run's result."""
    from petsc_contact.io.parts import mapped

    folder, args = _paused_again(paused_on_eight)
    damaged = folder / "paused.h5.state.6of8.npz"
    offset = mapped(str(damaged), "state").offset
    data = bytearray(damaged.read_bytes())
    data[offset : offset + 64] = bytes(b ^ 0xFF for b in data[offset : offset + 64])
    damaged.write_bytes(bytes(data))
    said, r = _read_on_three(folder, *args, "--resume")
    assert [s["problem"] for s in said] == [f"{damaged} is damaged (state.npy fails its CRC)"] * 3
    assert [s["rows"] for s in said] == [None] * 3
    assert damaged.name not in said[0]["opened"] + said[1]["opened"]
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("6of8.npz is damaged") == 1, r.stderr
    assert "step 2 starts from first touch" in r.stderr
    same_result(serial, folder / "paused.h5", fields=True)
    with h5py.File(folder / "paused.h5") as f:
        assert [s["from_saved_state"] for s in json.loads(f.attrs["resumed"])] == [False]


def test_slabs_are_named_by_rank_and_count():
    """The slab names and the rows each holds (``io.parts``)."""
    from petsc_contact.io.parts import slab_name, slab_of, slab_rows, slabs

    assert slab_name("step-000001.h5", 0, 1) == "step-000001.h5"
    assert slab_name("step-000001.h5", 2, 8) == "step-000001.2of8.h5"
    assert slab_of("step-000001.h5", "step-000001.2of8.h5") == (2, 8)
    assert slab_of("step-000001.h5", "step-000011.2of8.h5") is None
    digests = {"step-000001.1of2.h5": "b", "step-000001.0of2.h5": "a", "heights.h5": "c"}
    assert slabs("step-000001.h5", digests) == ["step-000001.0of2.h5", "step-000001.1of2.h5"]
    assert slabs("step-000002.h5", digests) == ["step-000002.h5"]
    assert slab_rows("step-000001.h5", "step-000001.1of2.h5", 5) == slice(3, 5)


def test_a_saved_state_is_read_a_rank_s_rows_at_a_time(tmp_path):
    """A state saved as slabs on 3 ranks reads back on 2 rank by rank, each reading only the
    slabs that hold its rows."""
    from petsc_contact.conventions.grid import block_rows
    from petsc_contact.io.parts import SlabRows, mapped

    whole = np.arange(10 * 4, dtype=float).reshape(10, 4)
    pieces = []
    for rank in range(3):
        rows = block_rows(10, 3, rank)
        where = tmp_path / f"s.{rank}of3.npz"
        np.savez(where, state=whole[rows], after_step=1)
        pieces.append((rows.start, mapped(str(where), "state")))
    source = SlabRows(pieces, 10)
    assert source.shape == (10, 4)
    for rank in range(2):
        rows = block_rows(10, 2, rank)
        assert np.array_equal(source[rows], whole[rows])
    assert np.array_equal(SlabRows(pieces[1:], 10)[4:7], whole[4:7])  # only the slabs it needs


def test_a_rank_without_spectrum_columns_takes_part(tmp_path):
    """16^2 on 4 ranks: FFTW-MPI's transposed spectrum (its default blocks, ceil(9/4) = 3 of
    the 9 columns ``qy`` per rank) leaves the last rank no columns (its empty range starting
    at 0), as 64^2 does on 8 ranks (5 of 33); that rank must not take the q = 0 entry for
    its own and stop while the others wait in the transform. The run finishes and equals
    the serial one. (Fewer ranks leave a rank empty only on grids of 7 columns or fewer: on
    3 ranks, 6 or 7; on 2, none.)"""
    args = "periodic --grid 16 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3,1e-2 --stiffness"
    runs = {}
    for ranks in (0, 4):
        runs[ranks] = tmp_path / f"r{ranks}.h5"
        r = cli(*args.split(), "--quiet", "--output", str(runs[ranks]), mpi=ranks, timeout=120)
        assert r.returncode == 0, r.stderr
    with h5py.File(runs[0]) as a, h5py.File(runs[4]) as b:
        assert b.attrs["fft_backend"] == "FFTWMPI" and b.attrs["mpi_size"] == 4
        np.testing.assert_allclose(b["mean_gap"][:], a["mean_gap"][:], rtol=1e-10)
        np.testing.assert_allclose(b["stiffness"][:], a["stiffness"][:], rtol=1e-10)


def test_an_argument_error_on_several_ranks_is_one_line():
    """Every rank parses the same command line; the first prints the error, all exit 2."""
    r = cli("periodic", "--grid", "32", mpi=3, timeout=60)
    assert r.returncode == 2
    assert r.stderr.count("petsc-contact: error: the following arguments are required") == 1
