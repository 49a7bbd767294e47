"""The pictures: log axes where the loads are log-spaced, labels with the units a file
records, one ``p0`` axis for the load plots and the theory, visible error bars, a legend for
every line, and ``plot`` redrawing a file's load plot without writing over other pictures."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact.cli.arguments import build_parser
from petsc_contact.cli.tools import run_plot
from petsc_contact.io import plot

P = np.geomspace(1e-5, 1e-1, 5)  # log-spaced loads, in units of E*


def png_size(path: Path) -> tuple[int, int]:
    """Width and height of the PNG ``path`` (from its header)."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def assert_picture(path: Path) -> None:
    """``path`` is a PNG of a figure's size (hundreds of pixels each way)."""
    width, height = png_size(path)
    assert 400 < width < 2000 and 300 < height < 1000, (width, height)
    assert path.stat().st_size > 10_000


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """The figures the plotting functions finish, in order."""
    figures: list[Any] = []
    finish = plot._finish

    def record(fig: Any, axes: Any, path: str | None) -> Any:
        figures.append(fig)
        return finish(fig, axes, path)

    monkeypatch.setattr(plot, "_finish", record)
    return figures


def sweep_steps(converged: bool = True) -> list[dict[str, Any]]:
    """A periodic run's table at the loads :data:`P`."""
    return [
        {"nominal_pressure": p, "area_fraction": p**0.9, "mean_gap": -np.log(p) / 10,
         "stiffness": 10 * p, "converged": converged or i < 4}
        for i, p in enumerate(P)
    ]  # fmt: skip


def punch_steps() -> list[dict[str, Any]]:
    """A punch's table at log-spaced approaches."""
    d = np.geomspace(1e-3, 1.0, 6)
    return [
        {"approach": a, "force": a**1.5, "nominal_pressure": a**1.5 / 1e4,
         "interfacial_stiffness": a**0.5, "converged": True}
        for a in d
    ]  # fmt: skip


def theory_result() -> SimpleNamespace:
    """A theory's spectrum and prediction (as :func:`plot.plot_theory` takes it)."""
    q = np.geomspace(0.1, 3.0, 40)
    return SimpleNamespace(
        wavevector=q, psd=q**-3.4, nominal_pressure=P, mean_gap=-np.log(P) / 10,
        stiffness=10 * P, area_fraction=np.minimum(10 * P, 1.0), hurst_fit=0.7, rms_height=1.0,
        crossover_pressure=1e-4, crossover_pressure_paper=4e-4, fit_range=(0.2, 2.0),
    )  # fmt: skip


def test_punch_plot_is_log_log_in_the_run_units(tmp_path: Path) -> None:
    """Force against approach and stiffness against pressure on log axes, in the run's units
    with the prefix that suits the values' typical size (approaches of 1 nm to 1 um in nm)
    when the run has units, dimensionless otherwise."""
    png = tmp_path / "punch.png"
    units = {"length": "um", "pressure": "GPa", "force": "GPa*um^2"}
    fig = plot.plot_punch(str(png), punch_steps(), units)
    assert_picture(png)
    force, stiffness = fig.axes
    for ax in fig.axes:
        assert (ax.get_xscale(), ax.get_yscale()) == ("log", "log")
    assert "(nm)" in force.get_xlabel() and "(µN)" in force.get_ylabel()
    assert "(Pa)" in stiffness.get_xlabel() and "(MPa/µm)" in stiffness.get_ylabel()
    bare = plot.plot_punch(None, punch_steps()[-2:])
    assert bare.axes[0].get_ylabel() == plot.P0_LABEL == bare.axes[1].get_xlabel()
    formatter = bare.axes[0].xaxis.get_major_formatter()  # less than two decades: 0.2, 0.5
    assert formatter(0.2, 0) == "0.2" and formatter(1.0, 0) == "1"


def test_sweep_and_theory_put_p0_on_the_same_axis(tmp_path: Path) -> None:
    """Every panel of the load plot and the theory's three predictions: p0/E* on a log x
    axis with the same label; the mean gap linear, area and stiffness log, labelled alike.
    The theory's figure is not written (its picture is another test's: the axes are the
    point here)."""
    png = tmp_path / "sweep.png"
    sweep = plot.plot_sweep(str(png), sweep_steps(converged=False), 1.0, 1.0)
    assert_picture(png)
    theory = plot.plot_theory(None, theory_result(), 1.0)
    gap, stiffness, area = theory.axes[1:]
    for ax in (*sweep.axes, gap, stiffness, area):
        assert ax.get_xscale() == "log" and ax.get_xlabel() == plot.P0_LABEL
    assert [ax.get_yscale() for ax in sweep.axes] == ["log", "linear", "log"]
    assert [ax.get_yscale() for ax in (area, gap, stiffness)] == ["log", "linear", "log"]
    assert sweep.axes[0].get_ylabel() == area.get_ylabel() == plot.AREA_LABEL
    assert sweep.axes[1].get_ylabel() == gap.get_ylabel() == plot.GAP_LABEL
    assert sweep.axes[2].get_ylabel() == stiffness.get_ylabel() == plot.STIFFNESS_LABEL
    assert "NOT converged" in [t.get_text() for t in sweep.axes[0].get_legend().get_texts()]


def test_theory_draws_persson_s_area_beside_the_run_s(tmp_path: Path, drawn: list[Any]) -> None:
    """``theory --compare``: Persson's contact area is a column of the table and a dataset of
    the file (``area_fraction``, unit 1), and its panel draws it beside the run's own
    ``area_fraction`` at the run's loads (``A/A0`` on log axes, as the load plot draws it);
    the file drawn again (``plot``) has the panel, a file without the area (written before
    it was computed) the three panels it had."""
    surface = ("--grid", "64", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "3")
    run, out, png = tmp_path / "run.h5", tmp_path / "t.h5", tmp_path / "t.png"
    r = cli("periodic", *surface, "--pressures", "5e-3,2e-2", "--output", str(run), "--quiet")
    assert r.returncode == 0, r.stderr
    r = cli("theory", *surface, "--sweep", "4,1e-4,5e-2", "--output", str(out),
            "--plot", str(png), "--compare", str(run))  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[5].split() == ["p0", "mean_gap", "K", "A/A0"], r.stdout
    assert_picture(png)
    with h5py.File(out, "r") as f, h5py.File(run, "r") as g:
        theory, simulated = f["area_fraction"][...], g["area_fraction"][...]
        assert f["area_fraction"].attrs["units"] == "1"
        last = float(theory[-1])
    assert np.all(np.diff(theory) > 0) and 0 < theory[0] < last < 1
    area = drawn[-1].axes[3]
    assert area.get_title() == "contact area" and area.get_ylabel() == plot.AREA_LABEL
    assert (area.get_xscale(), area.get_yscale()) == ("log", "log")
    persson, points = area.get_lines()
    assert persson.get_label() == plot.PERSSON_AREA and points.get_label() == "run.h5"
    np.testing.assert_array_equal(persson.get_ydata(), theory)
    np.testing.assert_array_equal(points.get_ydata(), simulated)
    assert plot_command(str(out)) == 0 and len(drawn[-1].axes) == 4
    with h5py.File(out, "a") as f:
        del f["area_fraction"]
    assert plot_command(str(out)) == 0 and len(drawn[-1].axes) == 3


def test_ensemble_plot_has_visible_errors_and_a_title_per_panel(tmp_path: Path) -> None:
    """K h_rms/E* as the sweep plot labels it, error bars with caps over a band, each seed
    drawn, one title per panel and a suptitle naming the ensemble."""
    rng = np.random.default_rng(0)
    summary: dict[str, np.ndarray] = {"seeds": np.arange(4), "nominal_pressure": P}
    for name, values in (("area_fraction", P**0.9), ("stiffness", 10 * P)):
        table = values * (1 + 0.1 * rng.standard_normal((4, P.size)))
        summary |= {name: table, f"{name}_mean": table.mean(axis=0),
                    f"{name}_sem": table.std(axis=0, ddof=1) / 2}  # fmt: skip
    png = tmp_path / "ensemble.png"
    fig = plot.plot_ensemble(str(png), summary, 2.0, h_rms=0.5)
    assert_picture(png)
    area, stiffness = fig.axes
    assert stiffness.get_ylabel() == plot.STIFFNESS_LABEL and area.get_ylabel() == "$A/A_0$"
    assert area.get_title() != stiffness.get_title()
    assert "4 seeds" in fig.get_suptitle()
    (bars,) = stiffness.containers
    assert bars.lines[1], "error bars have caps"
    assert stiffness.collections, "a band of the standard error"
    np.testing.assert_allclose(bars.lines[0].get_ydata(), summary["stiffness_mean"] * 0.25)
    for ax in fig.axes:
        assert (ax.get_xscale(), ax.get_yscale(), ax.get_xlabel()) == ("log", "log", plot.P0_LABEL)


def test_compare_plot_says_what_the_grey_line_is(tmp_path: Path) -> None:
    """The reference's natural residual is drawn on the residual's panel only (its pressure
    error is zero by definition) and named in the legend."""
    t = np.geomspace(1e-3, 1e-1, 5)
    trajectory = SimpleNamespace(name="cg", time=t, pressure_error=t / 10,
                                 natural_residual=t / 100, converged=True)  # fmt: skip
    png = tmp_path / "compare.png"
    fig = plot.plot_compare(str(png), [trajectory], {"natural_residual": 1e-12})
    assert_picture(png)
    (legend,) = fig.legends
    labels = [t.get_text() for t in legend.get_texts()]
    assert labels == ["cg", plot.REFERENCE]
    error, residual = fig.axes
    assert plot.REFERENCE not in [line.get_label() for line in error.get_lines()]
    grey = [line for line in residual.get_lines() if line.get_label() == plot.REFERENCE]
    assert len(grey) == 1 and grey[0].get_ydata()[0] == 1e-12


# ``petsc-contact plot``: files made with h5py, the command run in this process


def plot_command(*argv: str) -> int:
    return run_plot(build_parser().parse_args(["plot", *argv]))


def results_file(path: Path, geometry: str, steps: list[dict[str, Any]], **attrs: Any) -> Path:
    """A run's file holding ``steps`` as its table, with root attributes ``attrs``."""
    with h5py.File(path, "w") as f:
        f.attrs.update(geometry=geometry, modulus=1.0, rms_height=1.0, **attrs)
        for name in steps[0]:
            f[name] = np.array([s[name] for s in steps])
    return path


def test_plot_redraws_a_run_without_fields(tmp_path: Path, drawn: list[Any]) -> None:
    """--sweep draws a periodic run's and a punch's load plot from the file (the punch in the
    units it records) as OUT_redrawn.png; without --sweep a map is asked for and named."""
    sweep = results_file(tmp_path / "sweep.h5", "periodic", sweep_steps())
    assert plot_command(str(sweep), "--sweep") == 0
    assert_picture(tmp_path / "sweep_redrawn.png")
    assert [ax.get_xlabel() for ax in drawn[-1].axes] == [plot.P0_LABEL] * 3
    units = {"length_unit": "um", "pressure_unit": "GPa", "force_unit": "GPa*um^2"}
    punch = results_file(tmp_path / "punch.h5", "punch", punch_steps(), **units)
    assert plot_command(str(punch), "--sweep", "--output", str(tmp_path / "f.png")) == 0
    assert_picture(tmp_path / "f.png")
    assert "(nm)" in drawn[-1].axes[0].get_xlabel()
    with pytest.raises(ValueError, match=r"\(run with --fields\); --sweep draws"):
        plot_command(str(sweep))


def test_plot_of_a_theory_file_keeps_the_theory_picture(tmp_path: Path, drawn: list[Any]) -> None:
    """A theory file is drawn as theory_redrawn.png, in the length unit it records; the
    theory command's theory.png is left as it was."""
    result = theory_result()
    theory = tmp_path / "theory.h5"
    with h5py.File(theory, "w") as f:
        for name in ("wavevector", "psd", "nominal_pressure", "mean_gap", "stiffness"):
            f[name] = getattr(result, name)
        f.attrs.update(geometry="theory", length_unit="um", modulus=1.0, hurst_fit=0.7,
                       rms_height=1.0, crossover_pressure=1e-4, crossover_pressure_appendix=2e-4,
                       crossover_pressure_paper=4e-4, fit_range=json.dumps([0.2, 2.0]))  # fmt: skip
    picture = tmp_path / "theory.png"
    picture.write_bytes(b"the theory command's picture")
    assert plot_command(str(theory)) == 0
    assert picture.read_bytes() == b"the theory command's picture"
    assert_picture(tmp_path / "theory_redrawn.png")
    spectrum = drawn[-1].axes[0]
    assert "(1/µm)" in spectrum.get_xlabel() and "(µm^4)" in spectrum.get_ylabel()


def test_plot_of_an_ensemble_file(tmp_path: Path, drawn: list[Any]) -> None:
    """An ensemble file is drawn with its stiffness scaled by the seeds' mean rms height."""
    seeds = []
    for seed, h in enumerate((1.0, 3.0)):
        path = results_file(tmp_path / f"e_seed{seed}.h5", "periodic", sweep_steps())
        with h5py.File(path, "a") as f:
            f.attrs["rms_height"] = h
        seeds.append(str(path))
    ensemble = tmp_path / "e.h5"
    with h5py.File(ensemble, "w") as f:
        f.attrs.update(geometry="periodic ensemble", seed_files=json.dumps(seeds))
        f["seeds"], f["nominal_pressure"] = [0, 1], P
        for name in ("area_fraction", "stiffness"):
            f[name] = np.array([P, P])
            f[f"{name}_mean"], f[f"{name}_sem"] = P, 0.1 * P
    assert plot_command(str(ensemble)) == 0
    assert_picture(tmp_path / "e_redrawn.png")
    stiffness = drawn[-1].axes[1]
    assert stiffness.get_ylabel() == plot.STIFFNESS_LABEL
    np.testing.assert_allclose(stiffness.containers[0].lines[0].get_ydata(), 2 * P)
    Path(seeds[1]).unlink()
    with pytest.raises(ValueError, match="e_seed1.h5 is missing"):
        plot_command(str(ensemble))


def test_plot_still_draws_maps(tmp_path: Path) -> None:
    """--field and --step draw a map as before, named OUT_FIELD_stepK.png."""
    run = results_file(tmp_path / "f.h5", "periodic", sweep_steps()[:2],
                       lengths=(2.0, 2.0), length_unit="um", pressure_unit="GPa")  # fmt: skip
    pressure = np.random.default_rng(1).lognormal(0, 3, (2, 16, 16))
    with h5py.File(run, "a") as f:
        f["pressure"], f["contact"] = pressure, pressure > 1
    assert plot_command(str(run), "--field", "pressure", "--step", "1") == 0
    assert_picture(tmp_path / "f_pressure_step1.png")
    assert plot_command(str(run), "--field", "contact") == 0
    assert_picture(tmp_path / "f_contact_step2.png")
