"""Reading measured files as SurfaceTopography reads them: undefined points, channels, the
content deciding over the extension, whole refusals, overrides recorded, and SurfaceTopography
``Topography`` objects in the Python API.  Every file is made here (SurfaceTopography's own
writers, h5py, numpy)."""

import h5py
import numpy as np
import pytest
from conftest import cli
from SurfaceTopography import Topography as STTopography
from SurfaceTopography import open_topography

from petsc_contact import periodic_contact, punch_contact
from petsc_contact.io.topography import NotAMap, read_topography
from petsc_contact.physics.preparation import fill_undefined
from petsc_contact.workflows.predictions import predict_map

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
    (tmp_path / "notes.txt").write_text("these are my notes\nnot a map\n")
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
    plain = periodic_contact(h, SIDES, 1.0, [1e-3], options=opts)
    assert mine[0].scalars["mean_gap"] == pytest.approx(plain[0].scalars["mean_gap"], rel=1e-12)
    force = 1e-3 * SIDES[0] * SIDES[1]
    mine = punch_contact(topo, forces=[force], options=opts)
    plain = punch_contact(h, SIDES, 1.0, forces=[force], options=opts)
    assert mine[0].scalars["approach"] == pytest.approx(plain[0].scalars["approach"], rel=1e-12)
    assert predict_map(topo).u0 == pytest.approx(predict_map(h, SIDES).u0, rel=1e-12)
    holes = STTopography(_holes(h), SIDES, unit="um")
    for call in (lambda: periodic_contact(holes, pressures=[1e-3]), lambda: predict_map(holes)):
        with pytest.raises(ValueError, match="6 undefined points: fill them first"):
            call()
    filled = fill_undefined(np.ma.filled(_holes(h), np.nan), "harmonic")
    assert periodic_contact(filled, SIDES, pressures=[1e-3], options=opts)[0].converged
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


def test_filled_points_are_recorded_and_warned_about(tmp_path):
    """Filled heights: the 'filled' map in the output, the share in the header and the
    attributes, a warning above 5%, and the contact on filled pixels reported apart."""
    h = _map()
    mask = np.zeros(h.shape, bool)
    mask[5:15, 5:20] = True  # 12.5% of the map, on a hill and a valley alike
    STTopography(np.ma.masked_array(h, mask=mask), SIDES, unit="um").to_x3p(
        str(tmp_path / "holes.x3p")
    )
    args = ["--heights", str(tmp_path / "holes.x3p"), "--fill-undefined", "harmonic"]
    r = cli("periodic", *args, "--pressures", "1e-3,1e-2", "--fields", "--output",
            str(tmp_path / "f.h5"))  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "12.5% of the map's heights were undefined and are filled (harmonic)" in r.stderr
    assert "12.5%), read by" in r.stdout and "filled (harmonic)" in r.stdout
    with h5py.File(tmp_path / "f.h5") as f:
        assert np.array_equal(f["filled"][...], mask) and f.attrs["filled_fraction"] == 0.125
        contact, filled_share = f["contact"][...], f["filled_contact_fraction"][:]
        expected = [(c & mask).sum() / c.sum() for c in contact]
        assert filled_share == pytest.approx(expected, rel=1e-12)
        assert np.all((f["filled_load_fraction"][:] >= 0) & (f["filled_load_fraction"][:] <= 1))
