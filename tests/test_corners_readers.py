"""Corners of reading and preparing a measured map: a text file with bytes that are no text,
a header line that makes the orientation a guess, ``predict_map`` prepared as a run is, and a
measured map's default sweep and its unresolved steps."""

import warnings

import h5py
import numpy as np
import pandas as pd
import pytest
from conftest import cli, smooth_map

from petsc_contact.conventions.warnings import DoubtfulMap
from petsc_contact.io.topography import NotAMap, read_topography, surface_topography_available
from petsc_contact.paper.predictions import predict_map
from petsc_contact.physics.preparation import detrend
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.runner import run_contact

needs_st = pytest.mark.skipif(
    not surface_topography_available(), reason="SurfaceTopography not installed"
)


def _map(shape=(16, 32), seed=0, amplitude=1e-3):
    """:func:`conftest.smooth_map`, 16 x 32 unless told."""
    return smooth_map(shape, seed, amplitude)


def _one_line_refusal(result, *words, warned=0):
    """Exit status 2, one error line on stderr naming ``words`` (after ``warned`` warnings),
    nothing solved."""
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 + warned and "warning" not in lines[-1], result.stderr
    for word in words:
        assert word in lines[-1], lines[-1]
    assert "step" not in result.stdout


def test_nul_bytes_in_a_text_map_are_refused(tmp_path):
    """A 16 x 32 text matrix with 8 bytes set to NUL, and one padded with NULs after a crash,
    are refused in one line naming the line and the byte (SurfaceTopography read the first as
    32 x 15, the damaged row dropped as a header); a binary file is left to the readers."""
    np.savetxt(tmp_path / "m.txt", _map())
    data = bytearray((tmp_path / "m.txt").read_bytes())
    for k in range(8):
        data[900 + 37 * k] = 0
    (tmp_path / "nul.txt").write_bytes(bytes(data))
    (tmp_path / "pad.dat").write_bytes((tmp_path / "m.txt").read_bytes() + b"\0" * 4096)
    (tmp_path / "bell.csv").write_bytes(b"1,2,3\n4,\x075,6\n7,8,9\n")
    for name, where in (("nul.txt", "line 2, byte"), ("pad.dat", "line 17, byte 1:")):
        with pytest.raises(NotAMap, match=f"{where}.*0x00 \\(NUL\\) is not text"):
            read_topography(str(tmp_path / name))
        with pytest.raises(ValueError, match="save it again as UTF-8"):
            predict_map(str(tmp_path / name), length=1.0)
    with pytest.raises(ValueError, match="line 2, byte 3: 0x07 is not text"):
        read_topography(str(tmp_path / "bell.csv"))
    out = str(tmp_path / "out.h5")
    result = cli(
        "periodic", "--heights", str(tmp_path / "nul.txt"), "--pressures", "1e-3", "--output", out
    )
    _one_line_refusal(result, "NUL", "line 2")
    rng = np.random.default_rng(1)
    (tmp_path / "instrument.dat").write_bytes(rng.integers(0, 256, 5000, np.uint8).tobytes())
    with pytest.raises(ValueError) as caught:
        read_topography(str(tmp_path / "instrument.dat"))
    assert "is not text (" not in str(caught.value)  # every reader tried, none could


def _with_header(path, h, header="x c1 c2 c3"):
    with open(path, "w") as f:
        f.write(header + "\n")
        for row in h:
            f.write(" ".join(f"{v:.17g}" for v in row) + "\n")


@needs_st
def test_a_header_line_is_said_and_sides_for_the_rows_refused(tmp_path, petsc):
    """A text map with a header line that gives no sides is read transposed
    (SurfaceTopography's orientation), with a DoubtfulMap warning that says so; --length
    LX,LY that fits the rows as written, not the map as read, is refused in one line, the
    swapped sides are taken.  A bare matrix is read as written, without a word."""
    h = _map()
    _with_header(tmp_path / "head.txt", h)
    with pytest.warns(DoubtfulMap, match="line 1: 'x c1 c2 c3' is no row of numbers.*32 x 16"):
        topo = read_topography(str(tmp_path / "head.txt"))
    assert topo.guessed and np.array_equal(topo.heights, h.T)
    np.savetxt(tmp_path / "bare.txt", h)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DoubtfulMap)
        assert not read_topography(str(tmp_path / "bare.txt")).guessed
    path = str(tmp_path / "head.txt")
    out = str(tmp_path / "out.h5")
    result = cli(
        "periodic", "--heights", path, "--length", "1,2", "--pressures", "1e-3", "--output", out
    )
    _one_line_refusal(result, "--length 1,2 fits the rows as written", "--length 2,1", warned=1)
    with pytest.raises(ValueError, match="fits the rows as written"), pytest.warns(DoubtfulMap):
        predict_map(path, length=(1.0, 2.0))
    with pytest.warns(DoubtfulMap, match="is no row of numbers"):
        result = run_contact(Run(heights=path, length="2,1", pressures=[1e-3]), progress=False)
    assert list(result.record["lengths"]) == [2.0, 1.0] and result.converged
    assert any("is no row of numbers" in text for text in result.warnings)


def _tilted(tmp_path):
    """A map with a strong tilt (the instrument's), saved as .npy; and the map itself."""
    h = _map((32, 32))
    x = np.arange(32)[:, None] / 32
    tilted = h + 0.1 * x
    np.save(tmp_path / "tilted.npy", tilted)
    return str(tmp_path / "tilted.npy"), tilted


@pytest.mark.filterwarnings("ignore::petsc_contact.paper.predictions.TheoryWarning")
def test_predict_map_takes_the_run_s_preparation(tmp_path):
    """predict_map takes Run's preparation keywords and prepares the map as a run does: the
    tilted map warns as the run does, detrend='slope' removes the tilt, a height unit scales
    the heights to the sides' unit, undefined heights are filled when asked."""
    path, tilted = _tilted(tmp_path)
    with pytest.warns(DoubtfulMap, match="opposite edges differ"):
        raw = predict_map(path, length=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DoubtfulMap)
        flat = predict_map(path, length=1.0, detrend="slope")
    plane = detrend(tilted, (1 / 32, 1 / 32), "slope")
    assert flat.rms_height == pytest.approx(np.sqrt(np.mean((plane - plane.mean()) ** 2)), 1e-9)
    assert raw.rms_height > 3 * flat.rms_height
    with pytest.warns(DoubtfulMap, match="rms slope"):  # nm on um: a slope of 1e-4
        scaled = predict_map(path, length="1um", height_unit="nm", detrend="slope", modulus="1GPa")
    assert scaled.rms_height == pytest.approx(1e-3 * flat.rms_height, rel=1e-9)
    holes = np.where(np.arange(32 * 32).reshape(32, 32) % 97 == 0, np.nan, plane)
    np.save(tmp_path / "holes.npy", holes)
    with pytest.raises(ValueError, match="undefined"):
        predict_map(str(tmp_path / "holes.npy"), length=1.0)
    filled = predict_map(str(tmp_path / "holes.npy"), length=1.0, fill_undefined="harmonic")
    assert np.isfinite(filled.u0)
    with pytest.raises(ValueError, match="detrend"):
        predict_map(path, length=1.0, detrend="tilt")


def _with_dropout(tmp_path, n=64):
    """A measured map in nm on 100 um with one dropout pixel 50 times its rms deep, which sets
    its full-contact pressure far above the rest of its loads."""
    h = _map((n, n), seed=3, amplitude=40.0)  # nm
    h[n // 3, n // 2] -= 50 * h.std()
    np.save(tmp_path / "dropout.npy", h)
    return Run(
        heights=str(tmp_path / "dropout.npy"),
        length="100um",
        height_unit="nm",
        modulus="1GPa",
        sweep=(6,),
        detrend="height",
    )


def test_a_measured_map_s_default_sweep_ends_near_half_the_area(tmp_path, petsc):
    """The default sweep of a measured map runs from its first resolved contact to about half
    the area, not to 0.9 of the full contact its dropout pixel sets (every step there above
    99% contact before)."""
    run = _with_dropout(tmp_path)
    result = run_contact(run, progress=False)
    area = [s["area_fraction"] for s in result.table]
    assert 0.25 < area[-1] < 0.75, area
    assert all(a < 0.75 for a in area) and area == sorted(area)
    assert 16 / 64**2 <= area[0] < 0.05, area  # the first resolved contact, about
    assert all(s["contact_resolved"] for s in result.table)


def test_a_contact_of_a_few_pixels_is_flagged(tmp_path, petsc):
    """A step whose contact is one pixel (a spike) is flagged contact_resolved = False in
    the result's table, the file and OUT.csv, and marked UNRESOLVED in the CLI's table."""
    h = _map((32, 32), amplitude=1e-3)
    h[5, 7] += 30 * h.std()  # one pixel far above the rest: the first contact
    np.save(tmp_path / "spike.npy", h)
    run = Run(heights=str(tmp_path / "spike.npy"), pressures=[1e-6, 1e-2])
    first, last = run_contact(run, progress=False).table
    assert not first["contact_resolved"] and round(first["area_fraction"] * 32 * 32) == 1
    assert last["contact_resolved"] and first["converged"]
    out = tmp_path / "spike.h5"
    shown = cli(
        "periodic", "--heights", run.heights, "--pressures", "1e-6,1e-2", "--output", str(out)
    )
    assert shown.returncode == 0, shown.stderr
    marked = [line for line in shown.stdout.splitlines() if "UNRESOLVED" in line]
    assert len(marked) == 1 and marked[0].lstrip().startswith("1/2"), shown.stdout
    with h5py.File(out) as f:
        assert list(f["contact_resolved"][()]) == [False, True]
    table = pd.read_csv(tmp_path / "spike.csv", comment="#")
    assert list(table["contact_resolved"]) == [False, True]


def test_a_length_with_a_unit_beside_a_map_with_sides_is_refused_by_the_sweeps():
    """``periodic_contact`` takes the sides as the map's numbers: ``length='1mm'`` beside a
    map of 100 um sides is refused in one line, not dropped for the map's own sides."""
    from petsc_contact import periodic_contact
    from petsc_contact.io.topography import Topography

    topo = Topography(heights=_map((8, 8)), lengths=(100.0, 100.0), unit="um", reader="x3p")
    with pytest.raises(ValueError, match="length='1mm'.*numbers in the map's unit here \\(um\\)"):
        periodic_contact(topo, length="1mm", modulus=1.0, pressures=[1e-3], progress=False)


def test_a_dos_end_of_file_mark_is_no_damage(tmp_path):
    """A text map ending in DOS's Ctrl-Z reads as the same map without it."""
    h = _map((8, 8))
    text = "\r\n".join(" ".join(f"{v:.17g}" for v in row) for row in h) + "\r\n"
    (tmp_path / "plain.txt").write_text(text, newline="")
    (tmp_path / "dos.txt").write_bytes(text.encode() + b"\x1a")
    plain, dos = (read_topography(str(tmp_path / n)).heights for n in ("plain.txt", "dos.txt"))
    assert np.array_equal(plain, dos) and plain.shape == (8, 8)


def test_a_map_smaller_than_a_resolved_contact_still_gets_a_default_sweep(tmp_path):
    """A 4 x 3 map (fewer pixels than a resolved contact needs) sweeps finite loads, each
    step marked unresolved."""
    np.save(tmp_path / "tiny.npy", np.random.default_rng(2).standard_normal((4, 3)) * 1e-2)
    result = run_contact(
        Run(heights=str(tmp_path / "tiny.npy"), length=1.0, sweep=4), progress=False
    )
    loads = [s["nominal_pressure"] for s in result.table]
    assert len(loads) == 4 and np.all(np.isfinite(loads)) and loads[0] > 0
    assert not any(s["contact_resolved"] for s in result.table)
