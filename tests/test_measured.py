"""Measured maps: readers, units, preparation (fill, detrend) and the warnings, as a user
meets them on the command line."""

import h5py
import numpy as np
import pytest
from conftest import cli, smooth_map

from petsc_contact.conventions.units import factor, parse_lengths
from petsc_contact.io.topography import read_topography, surface_topography_available
from petsc_contact.physics.preparation import detrend, edge_mismatch, fill_undefined, rms_slope

_map = smooth_map


def test_units():
    assert parse_lengths("100um").values == (100.0,) and parse_lengths("100um").unit == "um"
    both = parse_lengths("2mm,1 mm")
    assert both.values == (2.0, 1.0) and both.unit == "mm" and both.pair == (2.0, 1.0)
    assert parse_lengths("1.5").unit is None and parse_lengths("1.5").pair == 1.5
    assert parse_lengths("3µm").unit == "um"
    assert factor("nm", "um") == pytest.approx(1e-3) and factor(None, "um") == 1.0
    for bad in ("0", "-1um", "1parsec", "1um,2nm", "1,2,3", "um"):
        with pytest.raises(ValueError):
            parse_lengths(bad)


def test_readers_agree(tmp_path):
    """.npy, .npz, whitespace text with a comment, .csv, HDF5 with sides and unit, NetCDF:
    the same heights."""
    h = _map()
    np.save(tmp_path / "m.npy", h)
    np.savez(tmp_path / "m.npz", other=np.zeros(3), heights=h)
    np.savetxt(tmp_path / "m.txt", h, header="exported heights")
    np.savetxt(tmp_path / "m.csv", h, delimiter=",")
    with h5py.File(tmp_path / "m.h5", "w") as f:
        f["group/heights_map"] = h
        f.attrs["length"], f.attrs["unit"] = [2.0, 1.5], "µm"
    with h5py.File(tmp_path / "m.nc", "w") as f:  # NetCDF-4 is HDF5
        f["heights"] = h
    for name in ("m.npy", "m.npz", "m.txt", "m.csv", "m.h5", "m.nc"):
        topo = read_topography(str(tmp_path / name))
        assert np.allclose(topo.heights, h, rtol=1e-15, atol=0), name
    topo = read_topography(str(tmp_path / "m.h5"))
    assert topo.lengths == (2.0, 1.5) and topo.unit == "um"


@pytest.mark.skipif(not surface_topography_available(), reason="SurfaceTopography not installed")
def test_instrument_files_through_surface_topography(tmp_path):
    """A NetCDF map written by SurfaceTopography comes back with its sides and unit."""
    from SurfaceTopography import Topography

    h = _map((40, 24))
    Topography(h, (4.0, 2.4), unit="nm").to_netcdf(str(tmp_path / "st.nc"))
    topo = read_topography(str(tmp_path / "st.nc"))
    assert topo.reader.startswith("SurfaceTopography")
    assert topo.lengths == pytest.approx((4.0, 2.4)) and topo.unit == "nm"
    assert np.allclose(topo.heights, h)


def _x3p(path, heights, spacing):
    """A minimal ISO 25178-72 (X3P) file: a zip of main.xml and the heights in metres,
    stored y-major as the format wants."""
    import zipfile

    nx, ny = heights.shape
    axis = "<{0}><AxisType>I</AxisType><DataType>D</DataType><Increment>{1}</Increment></{0}>"
    xml = (
        "<ISO5436_2><Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType>"
        f"<Axes>{axis.format('CX', spacing[0])}{axis.format('CY', spacing[1])}"
        "<CZ><AxisType>A</AxisType><DataType>D</DataType></CZ></Axes></Record1>"
        f"<Record3><MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ>"
        "</MatrixDimension><DataLink><PointDataLink>bindata/data.bin</PointDataLink>"
        "</DataLink></Record3></ISO5436_2>"
    )
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("main.xml", xml)
        z.writestr("bindata/data.bin", np.ascontiguousarray(heights.T, dtype="<f8").tobytes())


@pytest.mark.skipif(not surface_topography_available(), reason="SurfaceTopography not installed")
def test_an_instrument_file_on_the_command_line(tmp_path):
    """An X3P file (sizes and heights in metres) runs as it is: the lengths and unit come
    from the file, and the answer is that of the same map given as .npy with its units."""
    h = _map((40, 24), amplitude=2e-9)  # metres: a few nm on a 4 um x 2.4 um map
    _x3p(tmp_path / "scan.x3p", h, (1e-7, 1e-7))
    np.save(tmp_path / "scan.npy", h * 1e9)
    out = ["--pressures", "1e-3", "--quiet", "--output"]
    r = cli("periodic", "--heights", str(tmp_path / "scan.x3p"), *out, str(tmp_path / "a.h5"))
    assert r.returncode == 0, r.stderr
    r = cli(
        "periodic",
        "--heights",
        str(tmp_path / "scan.npy"),
        "--height-unit",
        "nm",
        "--length",
        "4e-6m,2.4e-6m",
        *out,
        str(tmp_path / "b.h5"),
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "b.h5") as b:
        assert a.attrs["length_unit"] == "m"
        assert list(a.attrs["lengths"]) == pytest.approx([4e-6, 2.4e-6])
        assert a["mean_gap"][0] == pytest.approx(b["mean_gap"][0], rel=1e-12)


def test_unreadable_files_say_why(tmp_path):
    (tmp_path / "scan.xyz").write_text("0 0 1\n1 0 2\n")
    (tmp_path / "bad.h5").write_bytes(b"\x89HDF\r\n\x1a\nnot really")
    for name, words in {
        "scan.xyz": "more likely a line scan",
        "bad.h5": "NetCDF",
        "none.npy": "does not exist",
    }.items():
        with pytest.raises((OSError, ValueError), match=words):
            read_topography(str(tmp_path / name))


def test_fill_undefined():
    h = _map()
    holes = h.copy()
    holes[10:13, 5:9] = np.nan
    with pytest.raises(ValueError, match="3 x 4|12 heights"):
        fill_undefined(holes, "error")
    mean = fill_undefined(holes, "mean")
    assert np.allclose(mean[10:13, 5:9], np.nanmean(holes))
    # the discrete Laplace equation holds a linear function exactly inside the map
    i, j = np.indices(h.shape)
    plane = 0.3 * i - 0.2 * j
    punched = plane.copy()
    punched[20:30, 3:7] = np.nan
    assert np.allclose(fill_undefined(punched, "harmonic"), plane, atol=1e-10)
    # at the edge (no neighbour beyond it) the fill stays within its measured surroundings
    punched[20:30, 0:7] = np.nan
    edge = fill_undefined(punched, "harmonic")[20:30, 0:7]
    assert plane[19:31, 0:8].min() <= edge.min() and edge.max() <= plane[19:31, 0:8].max()
    assert fill_undefined(h, "error") is h  # nothing to fill: untouched


def test_detrend_removes_plane_and_bow():
    """On oblong pixels: a tilt is removed by ``slope``, a tilt plus bow by ``curvature``;
    what remains is the map minus its own fit (unchanged by a second detrend)."""
    h = _map()
    spacing = (0.02, 0.05)
    x, y = np.indices(h.shape) * np.array(spacing)[:, None, None]
    tilted = h + 0.1 * x - 0.3 * y + 4.0
    bowed = tilted + 2.0 * x * x - 0.5 * x * y + y * y
    flat = detrend(h, spacing, "slope")
    assert np.allclose(detrend(tilted, spacing, "slope"), flat, atol=1e-12)
    assert np.allclose(detrend(bowed, spacing, "curvature"), detrend(h, spacing, "curvature"))
    assert abs(detrend(tilted, spacing, "height").mean()) < 1e-12
    assert detrend(h, spacing, "none") is h
    assert np.allclose(detrend(flat, spacing, "slope"), flat, atol=1e-15)


def test_checks_behind_the_warnings():
    h = _map()
    assert edge_mismatch(h) < 2  # periodic
    tilted = h + 1e-3 * np.arange(h.shape[0])[:, None]
    assert edge_mismatch(tilted) > 5
    assert rms_slope(h, (1 / 48, 1 / 32)) == pytest.approx(
        rms_slope(1e3 * h, (1e3 / 48, 1e3 / 32)), rel=1e-12
    )


def test_measured_rectangle_in_units(tmp_path):
    """A 48 x 32 map in nm on 96 um x 64 um: the run works in um, records the unit, and
    gives the same answer as the same map given in um without units."""
    h_nm = _map(amplitude=50.0)  # rms slope ~0.03 in nm over um after conversion
    np.save(tmp_path / "nm.npy", h_nm)
    np.save(tmp_path / "um.npy", h_nm * 1e-3)
    common = ["--pressures", "1e-3,1e-2", "--quiet", "--fields"]
    r = cli(
        "periodic",
        *["--heights", str(tmp_path / "nm.npy"), "--height-unit", "nm", "--length", "96um,64um"],
        *common,
        "--output",
        str(tmp_path / "a.h5"),
    )
    assert r.returncode == 0 and not r.stderr, r.stderr
    r = cli(
        "periodic",
        *["--heights", str(tmp_path / "um.npy"), "--length", "96,64"],
        *common,
        "--output",
        str(tmp_path / "b.h5"),
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "b.h5") as b:
        assert a.attrs["length_unit"] == "um" and list(a.attrs["lengths"]) == [96.0, 64.0]
        assert "um" in a.attrs["units"] and a["pressure"].shape == (2, 48, 32)
        assert a["mean_gap"].attrs["units"] == "um" and b["mean_gap"].attrs["units"] == "length"
        assert a["elastic_energy"].attrs["units"] == "pressure*um"
        assert np.allclose(a["heights"][...], b["heights"][...], rtol=1e-15)
        assert np.allclose(a["mean_gap"][:], b["mean_gap"][:], rtol=1e-12)
    r = cli("plot", str(tmp_path / "a.h5"), "--field", "contact")
    assert r.returncode == 0, r.stderr
    r = cli(
        "punch",
        "--heights",
        str(tmp_path / "nm.npy"),
        "--height-unit",
        "nm",
        "--length",
        "96um",
        "--forces",
        "1e-3",
        "--quiet",
        "--output",
        str(tmp_path / "p.h5"),
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "p.h5") as f:
        assert list(f.attrs["lengths"]) == [96.0, 64.0]  # one length: square pixels


def test_warnings_and_preparation_on_the_command_line(tmp_path):
    """Wrong units draw the rms-slope warning; a tilted map the edge warning (naming the
    free-boundary geometry), which --detrend slope removes; NaN heights run once filled."""
    h = _map()
    np.save(tmp_path / "steep.npy", h * 1e4)
    tilted = h + 5e-2 * np.arange(h.shape[0])[:, None] / h.shape[0]
    np.save(tmp_path / "tilted.npy", tilted)
    holes = h.copy()
    holes[5:8, 5:8] = np.nan
    np.save(tmp_path / "holes.npy", holes)
    out = ["--pressures", "1e-3", "--quiet", "--output", str(tmp_path / "o.h5"), "--overwrite"]
    r = cli("periodic", "--heights", str(tmp_path / "steep.npy"), *out)
    assert r.returncode == 0 and "rms slope" in r.stderr and "units" in r.stderr
    r = cli("periodic", "--heights", str(tmp_path / "tilted.npy"), *out)
    assert r.returncode == 0 and "edges" in r.stderr and "punch" in r.stderr
    r = cli("periodic", "--heights", str(tmp_path / "tilted.npy"), "--detrend", "slope", *out)
    assert r.returncode == 0 and not r.stderr, r.stderr
    r = cli("periodic", "--heights", str(tmp_path / "holes.npy"), *out)
    assert r.returncode == 2 and "--fill-undefined" in r.stderr
    r = cli(
        "periodic", "--heights", str(tmp_path / "holes.npy"), "--fill-undefined", "harmonic", *out
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "o.h5") as f:
        assert np.all(np.isfinite(f["heights"][...])) and f["converged"][0]


def test_contradictory_units_are_refused(tmp_path):
    with h5py.File(tmp_path / "m.h5", "w") as f:
        f["heights"] = _map()
        f.attrs["length"], f.attrs["unit"] = [2.0, 1.5], "um"
    m = str(tmp_path / "m.h5")
    out = ["--pressures", "1e-3", "--output", str(tmp_path / "o.h5")]
    for args, words in (
        (["--height-unit", "nm"], "contradicts the file's unit"),
        (["--length", "3um"], "contradicts the file's"),
    ):
        r = cli("periodic", "--heights", m, *args, *out)
        assert r.returncode == 2 and words in r.stderr, r.stderr
        assert not (tmp_path / "o.h5").exists()
    r = cli("periodic", "--heights", m, "--length", "2000nm,1500nm", *out, "--quiet")
    assert r.returncode == 0, r.stderr  # the same sides in another unit
