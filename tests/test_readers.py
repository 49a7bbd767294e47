"""Reading measured files as SurfaceTopography reads them: undefined points, channels, the
content deciding over the extension, whole refusals, overrides recorded, and SurfaceTopography
``Topography`` objects in the Python API; text maps as their bytes come (byte-order marks, line
ends, separators) read as the plain file or refused in one line.  Every file is made here
(SurfaceTopography's own writers, h5py, numpy, bytes)."""

import codecs

import h5py
import numpy as np
import pytest
from conftest import cli
from SurfaceTopography import Topography as STTopography
from SurfaceTopography import open_topography

from petsc_contact import periodic_contact, punch_contact
from petsc_contact.io import topography as topography_module
from petsc_contact.io.topography import NotAMap, read_topography
from petsc_contact.paper.predictions import predict_map
from petsc_contact.physics.preparation import fill_undefined

SIDES = (4.0, 3.0)  # um


def _map(shape=(40, 30), seed=1, amplitude=0.02):
    """A smooth periodic map in um (rms slope about 0.05 on 4 um x 3 um)."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(*(np.arange(n) / n for n in shape), indexing="ij")
    return amplitude * sum(
        rng.standard_normal() * np.cos(2 * np.pi * (i * x + j * y) + rng.uniform(0, 2 * np.pi))
        for i in range(1, 4)
        for j in range(-3, 4)
    )


def _holes(h):
    """``h`` with a 3 x 2 hole in it, as a masked array."""
    mask = np.zeros(h.shape, bool)
    mask[10:13, 5:7] = True
    return np.ma.masked_array(h, mask=mask)


def _run(tmp_path, name, *args):
    out = tmp_path / f"{name}.h5"
    r = cli("periodic", *args, "--pressures", "1e-3,1e-2", "--quiet", "--output", str(out))
    return r, out


def test_undefined_points_are_masked_and_refused(tmp_path):
    """An X3P file with a hole: read as NaN, refused without --fill-undefined, and with it the
    same answer as the map with NaN given as .npy and filled the same way."""
    h = _map()
    STTopography(_holes(h), SIDES, unit="um").to_x3p(str(tmp_path / "holes.x3p"))
    topo = read_topography(str(tmp_path / "holes.x3p"))
    assert topo.undefined == 6 and np.isnan(topo.heights[10:13, 5:7]).all()
    assert topo.lengths == pytest.approx((4e-6, 3e-6)) and topo.unit == "m"  # X3P is in metres
    r, out = _run(tmp_path, "refused", "--heights", str(tmp_path / "holes.x3p"))
    assert r.returncode == 2 and "6 heights are undefined" in r.stderr and not out.exists()

    np.save(tmp_path / "holes.npy", np.ma.filled(_holes(h), np.nan))
    fill = ["--fill-undefined", "harmonic"]
    r, a = _run(tmp_path, "x3p", "--heights", str(tmp_path / "holes.x3p"), *fill)
    assert r.returncode == 0, r.stderr
    r, b = _run(
        tmp_path,
        "npy",
        "--heights",
        str(tmp_path / "holes.npy"),
        "--length",
        "4um,3um",
        "--height-unit",
        "um",
        *fill,
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(a) as fa, h5py.File(b) as fb:
        # the same map in m and in um: mean gaps in their own unit, 1e6 apart
        assert fa["mean_gap"][:] * 1e6 == pytest.approx(fb["mean_gap"][:], rel=1e-9)
        assert fa["area_fraction"][:] == pytest.approx(fb["area_fraction"][:], abs=1e-12)
        assert fa.attrs["heights_reader"].startswith("SurfaceTopography")


def test_channels_are_chosen_and_recorded(tmp_path):
    """Several maps in one file: the default channel, or one by name or index; the run
    records which; an unknown channel is refused with the list of channels."""
    h, g = _map(seed=1), _map(seed=2)
    with h5py.File(tmp_path / "two.h5", "w") as f:
        f["first"], f["second"] = h, g
    np.savez(tmp_path / "two.npz", first=h, second=g)
    for name in ("two.h5", "two.npz"):
        path = str(tmp_path / name)
        assert np.array_equal(read_topography(path, "second").heights, g)
        assert np.array_equal(read_topography(path, 1).heights, g)
        assert read_topography(path, "1").channel == "second"
        with pytest.raises(NotAMap, match="its channels: 0 'first', 1 'second'"):
            read_topography(path, "third")
    default = read_topography(str(tmp_path / "two.h5"))  # SurfaceTopography's default: the first
    assert default.channel == "first" and default.default_channel
    assert np.array_equal(default.heights, h) and default.channels == ("first", "second")

    r, out = _run(tmp_path, "second", "--heights", str(tmp_path / "two.h5"), "--channel", "second")
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        assert f.attrs["heights_channel"] == "second" and f.attrs["heights_channel_index"] == 1
        assert np.array_equal(f["heights"][...], g)
    r, _ = _run(tmp_path, "bad", "--heights", str(tmp_path / "two.h5"), "--channel", "9")
    assert r.returncode == 2 and "channel '9'" in r.stderr and "1 'second'" in r.stderr


def test_the_content_decides_not_the_extension(tmp_path):
    """An X3P file named .dat is no text matrix: SurfaceTopography reads it, sides and all."""
    h = _map()
    STTopography(h, SIDES, unit="um").to_x3p(str(tmp_path / "scan.x3p"))
    (tmp_path / "scan.dat").write_bytes((tmp_path / "scan.x3p").read_bytes())
    topo = read_topography(str(tmp_path / "scan.dat"))
    assert topo.lengths == pytest.approx((4e-6, 3e-6)) and topo.unit == "m"
    assert np.allclose(topo.heights, h * 1e-6, rtol=1e-12, atol=0)


def test_text_headers_give_sides_and_unit(tmp_path):
    """A text export with a header (SurfaceTopography's own) keeps its sides and unit; a
    bare matrix keeps the package's orientation (rows are x)."""
    h = _map()
    STTopography(h, SIDES, unit="um").to_matrix(str(tmp_path / "export.txt"))
    topo = read_topography(str(tmp_path / "export.txt"))
    assert topo.lengths == pytest.approx(SIDES) and topo.unit == "um"
    assert np.allclose(topo.heights, h, rtol=1e-6, atol=1e-9)
    theirs = open_topography(str(tmp_path / "export.txt")).topography()
    assert np.array_equal(topo.heights, theirs.heights())
    np.savetxt(tmp_path / "bare.txt", h)
    assert read_topography(str(tmp_path / "bare.txt")).heights.shape == h.shape


def test_line_scans_and_nonsense_are_refused_with_every_reason(tmp_path):
    """A two-column x z profile is a line scan (it used to read as an n x 2 map); a file
    no reader parses gives every reader's reason, on one line."""
    x = np.linspace(0, 1, 50)
    np.savetxt(tmp_path / "profile.csv", np.c_[x, np.sin(6 * x)], delimiter=",")
    with pytest.raises(NotAMap, match="line scan"):
        read_topography(str(tmp_path / "profile.csv"))
    (tmp_path / "notes.txt").write_text(
        "my notes of 3 May\nnot a map\n"
    )  # a number: every reader is asked
    with pytest.raises(ValueError) as refused:
        read_topography(str(tmp_path / "notes.txt"))
    text = str(refused.value)
    assert "\n" not in text
    for reader in ("SurfaceTopography", "XYZReader", "AscReader", "text: not a numeric matrix"):
        assert reader in text, text
    r, _ = _run(tmp_path, "notes", "--heights", str(tmp_path / "notes.txt"))
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "AscReader" in r.stderr
    # any 2 n^2 bytes are an elevation tile to one reader: a guess, refused
    (tmp_path / "noise.bin").write_bytes(np.random.default_rng(0).bytes(2 * 16 * 16))
    with pytest.raises(ValueError, match="HGTReader takes it, by its size alone: a guess"):
        read_topography(str(tmp_path / "noise.bin"))


def test_metadata_is_overridden_only_when_asked(tmp_path):
    """Sides and unit of a file are replaced with --override-metadata, and recorded as such;
    the answer equals that of the bare map given those sides and unit."""
    h = _map()
    STTopography(h, SIDES, unit="um").to_netcdf(str(tmp_path / "scan.nc"))
    np.save(tmp_path / "scan.npy", h)
    scan = ["--heights", str(tmp_path / "scan.nc")]
    r, _ = _run(tmp_path, "no", *scan, "--length", "8um,6um")
    assert r.returncode == 2 and "--override-metadata" in r.stderr
    r, a = _run(tmp_path, "sides", *scan, "--length", "8um,6um", "--override-metadata")
    assert r.returncode == 0, r.stderr
    npy = ["--heights", str(tmp_path / "scan.npy"), "--height-unit", "um"]
    r, b = _run(tmp_path, "npy", *npy, "--length", "8um,6um")
    assert r.returncode == 0, r.stderr
    r, c = _run(tmp_path, "unit", *scan, "--height-unit", "nm", "--override-metadata")
    assert r.returncode == 0, r.stderr
    r, d = _run(tmp_path, "npy-nm", *npy[:2], "--height-unit", "nm", "--length", "4um,3um")
    assert r.returncode == 0, r.stderr
    with h5py.File(a) as fa, h5py.File(b) as fb, h5py.File(c) as fc, h5py.File(d) as fd:
        assert fa["mean_gap"][:] == pytest.approx(fb["mean_gap"][:], rel=1e-12)
        assert fc["mean_gap"][:] == pytest.approx(fd["mean_gap"][:], rel=1e-12)
        assert fa.attrs["metadata_overridden"] == '["length"]'
        assert fc.attrs["metadata_overridden"] == '["height_unit"]'
        assert fa.attrs["file_unit"] == "um" and fa.attrs["file_lengths"] == "[4.0, 3.0]"
        assert fb.attrs["metadata_overridden"] == "[]"


def test_python_takes_surface_topography_objects(petsc):
    """periodic_contact, punch_contact and predict_map take a SurfaceTopography Topography
    with its sides; a map with undefined points is refused, not solved."""
    h = _map()
    topo = STTopography(h, SIDES, unit="um")
    opts = ["-tao_gatol", "1e-10"]
    mine = periodic_contact(topo, modulus=1.0, pressures=[1e-3], options=opts)
    plain = periodic_contact(h, length=SIDES, modulus=1.0, pressures=[1e-3], options=opts)
    assert mine[0].scalars["mean_gap"] == pytest.approx(plain[0].scalars["mean_gap"], rel=1e-12)
    force = 1e-3 * SIDES[0] * SIDES[1]
    mine = punch_contact(topo, forces=[force], options=opts)
    plain = punch_contact(h, length=SIDES, modulus=1.0, forces=[force], options=opts)
    assert mine[0].scalars["approach"] == pytest.approx(plain[0].scalars["approach"], rel=1e-12)
    assert predict_map(topo).u0 == pytest.approx(predict_map(h, length=SIDES).u0, rel=1e-12)
    holes = STTopography(_holes(h), SIDES, unit="um")
    for call in (lambda: periodic_contact(holes, pressures=[1e-3]), lambda: predict_map(holes)):
        with pytest.raises(ValueError, match="6 undefined points: fill them first"):
            call()
    filled = fill_undefined(np.ma.filled(_holes(h), np.nan), "harmonic")
    assert periodic_contact(filled, length=SIDES, pressures=[1e-3], options=opts)[0].converged
    with pytest.raises(ValueError, match="contradicts"):
        periodic_contact(topo, length=(8.0, 6.0), pressures=[1e-3])


def test_a_numpy_mismatch_is_named(monkeypatch):
    """petsc4py compiled against another numpy fails with numpy's own words; the package says
    what it means and what to do."""
    from petsc_contact.backend import _petsc

    with pytest.raises(ImportError, match="compiled against another numpy.*setup.sh"):  # noqa: SIM117
        with _petsc._loading():
            raise ValueError("numpy.dtype size changed, may indicate binary incompatibility")
    with pytest.raises(ImportError, match="petsc4py cannot be loaded \\(libpetsc.so"):  # noqa: SIM117
        with _petsc._loading():
            raise ImportError("libpetsc.so.3.18: cannot open shared object file")


@pytest.mark.parametrize(
    "geometry, loads", [("periodic", ("--pressures", "1e-3,1e-2")), ("punch", ("--sweep", "2"))]
)
def test_filled_points_are_recorded_and_warned_about(tmp_path, geometry, loads):
    """Filled heights: the 'filled' map in the output, the share in the header and the
    attributes, a warning above 5%, and the contact on filled pixels reported apart, on
    both geometries."""
    h = _map()
    mask = np.zeros(h.shape, bool)
    mask[5:15, 5:20] = True  # 12.5% of the map, on a hill and a valley alike
    STTopography(np.ma.masked_array(h, mask=mask), SIDES, unit="um").to_x3p(
        str(tmp_path / "holes.x3p")
    )
    args = ["--heights", str(tmp_path / "holes.x3p"), "--fill-undefined", "harmonic"]
    r = cli(geometry, *args, *loads, "--fields", "--output", str(tmp_path / "f.h5"))
    assert r.returncode == 0, r.stderr
    assert "12.5% of the map's heights were undefined and are filled (harmonic)" in r.stderr
    assert "12.5%), read by" in r.stdout and "filled (harmonic)" in r.stdout
    with h5py.File(tmp_path / "f.h5") as f:
        assert np.array_equal(f["filled"][...], mask) and f.attrs["filled_fraction"] == 0.125
        contact, filled_share = f["contact"][...], f["filled_contact_fraction"][:]
        expected = [(c & mask).sum() / c.sum() for c in contact]
        assert filled_share == pytest.approx(expected, rel=1e-12)
        assert np.all((f["filled_load_fraction"][:] >= 0) & (f["filled_load_fraction"][:] <= 1))


GRID = np.round(np.random.default_rng(3).standard_normal((16, 16)), 4)


def _matrix(sep=" ", rows=GRID):
    """``rows`` as a text matrix, one line a row (``:g`` writes each value exactly)."""
    return "".join(sep.join(f"{v:g}" for v in row) + "\n" for row in rows)


PLAIN, CSV = _matrix(), _matrix(",")

SAME = {  # name: (extension, the file's bytes), each read as the plain file
    "utf-8 byte-order mark": (".txt", codecs.BOM_UTF8 + PLAIN.encode()),
    "utf-16 le byte-order mark": (".txt", codecs.BOM_UTF16_LE + PLAIN.encode("utf-16-le")),
    "utf-16 be byte-order mark": (".dat", codecs.BOM_UTF16_BE + PLAIN.encode("utf-16-be")),
    "crlf": (".txt", PLAIN.replace("\n", "\r\n").encode()),
    "cr": (".asc", PLAIN.replace("\n", "\r").encode()),
    "tabs": (".txt", _matrix("\t").encode()),
    "trailing blank lines": (".txt", (PLAIN + "\n \n\t\n").encode()),
    "trailing whitespace": (".txt", PLAIN.replace("\n", " \t\n").encode()),
    "comment lines": (".txt", ("# a map\n" + PLAIN + "# end\n").encode()),
    "csv": (".csv", CSV.encode()),
    "csv, byte-order mark and crlf": (".csv", codecs.BOM_UTF8 + CSV.replace("\n", "\r\n").encode()),
    "csv, trailing commas and blank lines": (".csv", (CSV.replace("\n", ",\n") + "\n\n").encode()),
    "csv, spaces after commas": (".csv", _matrix(", ").encode()),
}


@pytest.mark.parametrize("with_st", [True, False], ids=["SurfaceTopography", "text reader"])
@pytest.mark.parametrize("name", SAME)
def test_text_maps_read_as_the_plain_file(tmp_path, monkeypatch, name, with_st):
    """A byte-order mark (UTF-8, UTF-16), any line ends, tabs, trailing blank lines and
    whitespace: the map the plain file holds, with SurfaceTopography or without it."""
    monkeypatch.setattr(topography_module, "surface_topography_available", lambda: with_st)
    (tmp_path / "plain.txt").write_text(PLAIN)
    ext, data = SAME[name]
    (tmp_path / f"map{ext}").write_bytes(data)
    plain = read_topography(str(tmp_path / "plain.txt"))
    topo = read_topography(str(tmp_path / f"map{ext}"))
    assert np.array_equal(plain.heights, GRID) and np.array_equal(topo.heights, GRID)
    assert (topo.lengths, topo.unit) == (None, None)


@pytest.mark.parametrize("marks", ["byte-order mark", "utf-16 and crlf"])
def test_text_headers_survive_a_byte_order_mark(tmp_path, marks):
    """A text export with a header, marked: the same sides, unit and heights (the mark made
    the first header line unreadable, no harm; on a bare matrix it cost the first row)."""
    STTopography(_map(), SIDES, unit="um").to_matrix(str(tmp_path / "export.txt"))
    text = (tmp_path / "export.txt").read_text()
    data = {
        "byte-order mark": codecs.BOM_UTF8 + text.encode(),
        "utf-16 and crlf": text.replace("\n", "\r\n").encode("utf-16"),
    }[marks]
    (tmp_path / "marked.txt").write_bytes(data)
    plain, topo = (read_topography(str(tmp_path / n)) for n in ("export.txt", "marked.txt"))
    assert np.array_equal(topo.heights, plain.heights)
    assert (topo.lengths, topo.unit) == (plain.lengths, plain.unit) == (SIDES, "um")


def _cell(text, row, col, value, sep=" "):
    """``text`` with the value at ``row``, ``col`` (from 0) replaced by ``value``."""
    lines = text.splitlines()
    fields = lines[row].split(sep)
    fields[col] = value
    lines[row] = sep.join(fields)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    "ext, text",
    [
        (".txt", _cell(PLAIN, 3, 4, "nan")),
        (".txt", _cell(PLAIN, 3, 4, "NaN")),
        (".dat", _cell(PLAIN, 3, 4, "Bad")),  # SurfaceTopography's word for it
        (".csv", _cell(CSV, 3, 4, "", ",")),
        (".csv", _cell(CSV, 3, 4, " NAN ", ",")),
    ],
    ids=["nan", "NaN", "Bad", "empty csv cell", "csv NAN"],
)
def test_undefined_heights_stay_undefined(tmp_path, ext, text):
    """An undefined height reads as NaN (never 0), every other height as written."""
    (tmp_path / f"map{ext}").write_text(text)
    topo = read_topography(str(tmp_path / f"map{ext}"))
    expected = GRID.copy()
    expected[3, 4] = np.nan
    assert topo.undefined == 1 and np.array_equal(topo.heights, expected, equal_nan=True)


def _pandas():
    """GRID as ``pandas.DataFrame(GRID).to_csv()`` writes it: column numbers, then each row
    after its number."""
    labels = "," + ",".join(str(j) for j in range(16)) + "\n"
    return labels + "".join(f"{i}," + line for i, line in enumerate(CSV.splitlines(True)))


RAGGED = "".join(
    " ".join(f"{v:g}" for v in (row[:-1] if i == 5 else row)) + "\n" for i, row in enumerate(GRID)
)
REFUSED = {  # name: (extension, text, the refusal)
    "a short row": (".txt", RAGGED, "line 6 has 15 values, the rows above it 16"),
    "a short row after a header": (
        ".txt",
        "# Width: 4 um\n\nValue units: um\n" + RAGGED,
        "line 9 has 15 values, the rows above it 16",
    ),
    "a long csv row": (".csv", _cell(CSV, 2, 4, "1,2", ","), "line 3 has 17 values"),
    "decimal commas": (".txt", PLAIN.replace(".", ","), "line 1: value 1 .* \\(a decimal comma"),
    "a word in a row": (".txt", _cell(PLAIN, 3, 4, "abc"), "line 4: value 5 'abc' is not a number"),
    "a word in the first row": (".txt", _cell(PLAIN, 0, 0, "NA"), "line 1: value 1 'NA'"),
    "a dash in the last row": (".dat", _cell(PLAIN, 15, 9, "-"), "line 16: value 10 '-'"),
    "a word in a csv row": (".csv", _cell(CSV, 7, 0, "n/a", ","), "line 8: value 1 'n/a'"),
    "a comment on a row": (".txt", _cell(PLAIN, 2, 15, "1 # x"), "line 3: value 17 '#'"),
    "a comment on the first row": (".txt", _cell(PLAIN, 0, 15, "1 #x"), "line 1: value 17 '#x'"),
    "a row of words inside the map": (".txt", _cell(PLAIN, 4, 0, "x y z"), "line 5: value 1 'x'"),
    "pandas' labels": (".csv", _pandas(), "line 1 is column numbers, not heights"),
    "a single row": (".txt", _matrix(rows=GRID[:1]), "at least 2 x 2 points.*\\(1, 16\\)"),
    "a single column": (".txt", _matrix(rows=GRID[:, :1]), "line scan"),
    "only a header": (".txt", "x y z\n# nothing measured\n", "holds no numbers, only text"),
    "only blank lines": (".txt", "\n  \n\n", "holds no numbers"),
}


@pytest.mark.parametrize("name", REFUSED)
def test_misread_text_maps_are_refused_in_one_line(tmp_path, name):
    """A text map that would read wrong (a row dropped as a header, rows shifted, a decimal
    comma, a placeholder for an undefined height) is refused, naming the line as the file
    counts it."""
    ext, text, refusal = REFUSED[name]
    path = tmp_path / f"map{ext}"
    path.write_text(text)
    with pytest.raises(ValueError, match=refusal) as refused:
        read_topography(str(path))
    assert "\n" not in str(refused.value) and str(path) in str(refused.value)


def test_empty_files_and_folders_are_refused(tmp_path):
    """Not a file with heights: an empty file, a folder, a name not in use; the CLI exits 2
    with the reason on one line for a short row."""
    (tmp_path / "empty.txt").write_bytes(b"")
    for path, reason in [
        (tmp_path / "empty.txt", "is empty"),
        (tmp_path, "is a folder, not a regular file"),
        (tmp_path / "none.txt", "does not exist"),
    ]:
        with pytest.raises((OSError, ValueError), match=reason):
            read_topography(str(path))
    (tmp_path / "ragged.txt").write_text(RAGGED)
    r, _ = _run(tmp_path, "ragged", "--heights", str(tmp_path / "ragged.txt"), "--length", "1")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "line 6 has 15 values, the rows above it 16" in r.stderr
