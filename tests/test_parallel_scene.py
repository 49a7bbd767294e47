"""No rank holds the grid when the scene is made: on several ranks a measured map is read and
prepared on the run's first rank only, which sends every other rank its rows, and a face cut
from a larger surface moves from the parent's slabs to the face's; the runs equal the serial
ones (docs/parallel.md). The runs are made on 4 ranks (:data:`RANKS`), each of which then
holds filled pixels of the map and rows of a cut face that another rank held in the parent;
the memory each rank allocates is measured on 8, where a rank's slab is an eighth."""

from __future__ import annotations

import json
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import cli, in_process, python
from test_measured import _map

from petsc_contact.physics.preparation import rms_slope

pytestmark = pytest.mark.slow  # MPI launches: started first (tests/conftest.py)

FACE = "--grid 32 --hurst 0.7 --rms-slope 0.1 --seed 3 --approaches 0.002,0.01 --stiffness"
RANKS = 4  # each rank a core on 2 cores is half the oversubscription of 8
HOLES = [(2, 4), (3, 4), (17, 20), (30, 9), (45, 31)]  # undefined pixels in each rank's rows
MAP = "--heights {folder}/holes.npy --fill-undefined harmonic"
RUNS = {  # every run of the file, made serially (in this process) and on RANKS by one launch
    "punch": f"punch {FACE}",
    "cut": f"punch {FACE} --cut-from 4",
    "map-periodic": f"periodic {MAP} --pressures 1e-4,1e-3",
    "map-punch": f"punch {MAP} --approaches 1e-3",
}
FIELDS = ("heights", "x", "y", "gap", "pressure")  # to 1e-12 of their largest value
SCALARS = ("mean_gap", "force", "nominal_pressure", "stiffness")  # to 1e-10 relative
OUTPUT = ["--fields", "--quiet", "--output"]
PIECE = Path("punch") / "cut_r1_seed1.h5"  # the study's first punch piece, in its data folder
REALISED = ("rms_slope_inside", "parent_rms_height", "parent_rms_slope")  # a cut face's
LAUNCH = """
import json
import sys
from petsc_contact.cli.main import main
from petsc_contact.cli.study import STATUS, _piece
from petsc_contact.paper.paper_study import punch_pieces, run_pieces

for args in json.loads(sys.argv[1]):
    if main(args):
        sys.exit(f"failed: {args}")
todo = punch_pieces(128)[:1]  # the cut face of L_p/lambda_r = 1, seed 1: 16^2 cut from 64^2
assert todo[0].run.cut_from == 4
sys.exit(STATUS[run_pieces(todo, sys.argv[2], 10, lambda run: _piece(run, True), print)])
"""


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path]]:
    """Every run of :data:`RUNS` with ``--fields``, and the study's first punch piece at
    ``--shrink 128`` by the study's piece runner: the serial file (the runs made in this
    process) and the :data:`RANKS` ranks' file (one ``mpiexec``)."""
    folder = tmp_path_factory.mktemp("scene")
    holes = _map()
    holes[tuple(zip(*HOLES, strict=True))] = np.nan
    np.save(folder / "holes.npy", holes)
    (folder / "launch.py").write_text(textwrap.dedent(LAUNCH))
    files = {name: (folder / f"{name}.0.h5", folder / f"{name}.{RANKS}.h5") for name in RUNS}
    files["piece"] = (folder / "data0" / PIECE, folder / f"data{RANKS}" / PIECE)
    for ranks in (0, RANKS):
        commands = [
            [*line.format(folder=folder).split(), *OUTPUT, str(files[name][ranks > 0])]
            for name, line in RUNS.items()
        ]
        argv = [str(folder / "launch.py"), json.dumps(commands), str(folder / f"data{ranks}")]
        r = python(*argv, mpi=ranks, timeout=300) if ranks else _launched_here(argv)
        assert r.returncode == 0, r.stderr
    return files


def _launched_here(argv: list[str]):
    """:data:`LAUNCH` run in this process with ``sys.argv = argv`` (:func:`in_process`)."""
    code = compile(textwrap.dedent(LAUNCH), argv[0], "exec")

    def launch() -> None:
        before = sys.argv
        sys.argv = argv
        try:
            exec(code, {"__name__": "__main__"})
        finally:
            sys.argv = before

    return in_process(["python", *argv], launch)


def _same_run(serial: Path, parallel: Path) -> None:
    """The :data:`RANKS` ranks' file is the serial one: its heights, filled pixels and fields
    (where written) to 1e-12 of their largest value, its gaps, forces and stiffnesses to
    1e-10."""
    with h5py.File(serial) as a, h5py.File(parallel) as b:
        assert b.attrs["mpi_size"] == RANKS and sorted(a) == sorted(b)
        for name in (n for n in FIELDS if n in a):
            x, y = a[name][...], b[name][...]
            assert np.allclose(x, y, rtol=0, atol=1e-12 * np.abs(x).max()), name
        for name in (n for n in SCALARS if n in a):
            assert np.allclose(a[name][...], b[name][...], rtol=1e-10, atol=0), name
        if "filled" in a:
            assert np.array_equal(a["filled"][...], b["filled"][...])


def test_a_generated_punch_on_several_ranks(runs):
    """A punch on a generated 32^2 face with the exact stiffness: the serial run."""
    _same_run(*runs["punch"])


def test_a_cut_face_on_several_ranks(runs):
    """``--cut-from 4`` (a 32^2 face of a 128^2 parent): the face, the solves and the
    parent's and inside slopes are the serial run's, ``rms_slope_inside`` that of the file's
    heights."""
    _same_run(*runs["cut"])
    with h5py.File(runs["cut"][0]) as a, h5py.File(runs["cut"][1]) as b:
        for name in REALISED:
            assert b.attrs[name] == pytest.approx(a.attrs[name], rel=1e-12), name
        inside = rms_slope(b["heights"][...], (1 / 32, 1 / 32))
        assert b.attrs["rms_slope_inside"] == pytest.approx(inside, rel=1e-12)


@pytest.mark.parametrize("geometry", ["periodic", "punch"])
def test_a_measured_map_on_several_ranks(runs, geometry):
    """A 48 x 32 map with undefined pixels in each of the 4 ranks' rows (12 of the 48 each),
    filled harmonically: heights,
    filled pixels, fields and scalars are the serial run's."""
    serial, parallel = runs[f"map-{geometry}"]
    _same_run(serial, parallel)
    with h5py.File(serial) as a, h5py.File(parallel) as b:
        assert np.count_nonzero(b["filled"][...]) == len(HOLES)
        assert b.attrs["rms_slope_inside"] == pytest.approx(a.attrs["rms_slope_inside"])


def test_a_study_piece_on_several_ranks(runs):
    """The study's first punch piece (a cut face) at ``--shrink 128``, run by the study's
    piece runner: the serial piece."""
    _same_run(*runs["piece"])


def test_a_map_that_cannot_be_read_fails_on_every_rank(tmp_path):
    """Read on the first rank only, the map's failure is every rank's: one line, exit 2."""
    holes = _map()
    holes[5, 5] = np.nan
    np.save(tmp_path / "holes.npy", holes)
    args = ["periodic", "--heights", str(tmp_path / "holes.npy"), "--pressures", "1e-3"]
    r = cli(*args, "--output", str(tmp_path / "o.h5"), mpi=3, timeout=60)
    assert r.returncode == 2 and r.stderr.count("choose --fill-undefined") == 1, r.stderr


HELD = """
import json
import sys
import tracemalloc
from mpi4py import MPI
from petsc_contact.conventions import grid as grids
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.scene import prepare_scene

def refuse(self, *args):
    raise AssertionError("a whole field gathered, or read by every rank")

grids.Grid.gather = refuse
grids.Grid.scatter = refuse
runs = {
    "map": Run(heights=sys.argv[1], fill_undefined="harmonic"),
    "cut": Run(geometry="punch", grid=64, hurst=0.7, rms_slope=0.1, seed=3, cut_from=4),
}
peaks = {}
for name, run in runs.items():
    prepare_scene(run)  # the imports and the FFT plans made
    tracemalloc.start()
    prepare_scene(run)
    peaks[name] = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
with open(f"{sys.argv[2]}.{MPI.COMM_WORLD.rank}", "w") as out:
    json.dump(peaks, out)
"""


def test_no_rank_but_the_reader_holds_the_map(tmp_path):
    """On 8 ranks, with ``Grid.gather`` and ``Grid.scatter`` refusing, the most memory a rank
    allocates (``tracemalloc``: numpy's arrays included) while making the scene: a 256^2 map
    is held by the first rank (at least its 512 KiB) and by no other (under 0.9 of it); a
    64^2 face cut from a 256^2 parent by no rank at all."""
    whole = 256 * 256 * 8
    holes = _map((256, 256))
    holes[100, 100] = np.nan
    np.save(tmp_path / "map.npy", holes)
    script = tmp_path / "held.py"
    script.write_text(textwrap.dedent(HELD))
    r = python(str(script), str(tmp_path / "map.npy"), str(tmp_path / "peaks"), mpi=8)
    assert r.returncode == 0, r.stderr
    peaks = [json.loads((tmp_path / f"peaks.{rank}").read_text()) for rank in range(8)]
    assert peaks[0]["map"] >= whole, peaks
    assert max(p["map"] for p in peaks[1:]) < 0.9 * whole, peaks
    assert max(p["cut"] for p in peaks) < 0.9 * whole, peaks
