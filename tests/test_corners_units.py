"""Units and pictures: every table, map and plot in the units the run was given (with the
field's prefixes: MPa/um for a stiffness per area, µm on a figure's axes), dimensionless only
without units and alike in both geometries; runs drawn beside a theory converted into its
units or refused; the pictures' legends name only what is in view."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact.conventions.units import display_scale, format_quantity, typeset
from petsc_contact.io import plot
from petsc_contact.paper.redraw import field_map, redraw
from petsc_contact.paper.theory_run import compared_runs

P = np.geomspace(1e-5, 1e-1, 5)  # log-spaced loads, in units of E* (1 GPa where a unit)
SCENE = "--grid 32 --hurst 0.7 --rms-slope 0.1 --seed 3".split()


def run_file(path: Path, length_unit: str = "", pressure_unit: str = "", **attrs: Any) -> Path:
    """A periodic run's file (loads P, mean gaps, stiffnesses) recording the units given."""
    with h5py.File(path, "w") as f:
        f.attrs.update({"geometry": "periodic", "modulus": 1.0, "rms_height": 0.5,
                        "lengths": (2.0, 2.0), "length_unit": length_unit,
                        "pressure_unit": pressure_unit, **attrs})  # fmt: skip
        f["nominal_pressure"], f["mean_gap"], f["stiffness"] = P, 1 - P, 10 * P
        f["area_fraction"], f["converged"] = P**0.9, np.ones(P.size, bool)
    return path


def theory_result(crossover: float = 1e-4) -> SimpleNamespace:
    """A theory's spectrum and prediction at the loads P, its p_c at ``crossover``."""
    q = np.geomspace(0.1, 3.0, 40)
    return SimpleNamespace(
        wavevector=q, psd=q**-3.4, nominal_pressure=P, mean_gap=1 - P, stiffness=10 * P,
        area_fraction=np.minimum(10 * P, 1.0), hurst_fit=0.7, rms_height=0.5,
        crossover_pressure=crossover, crossover_pressure_paper=4 * crossover, fit_range=(0.2, 2.0),
    )  # fmt: skip


# the one formatting: conventions.units


@pytest.mark.parametrize(
    "value, unit, shown",
    [(0.01986, "GPa/um", "19.86 MPa/um"), (1.986e4, "GPa/m", "19.86 MPa/um"),
     (0.3, "MPa/nm", "300 MPa/um"), (2e3, "kPa/mm", "2 kPa/um"), (1e-4, "GPa", "100 kPa")],
)  # fmt: skip
def test_stiffness_per_area_is_a_pressure_per_the_run_length(value, unit, shown):
    """A stiffness per area is a pressure per micrometre, the field's custom, whatever the
    run's length unit (a run's GPa/um is read as MPa/um, never as TPa/m)."""
    assert format_quantity(value, unit) == shown


def test_figures_write_micro_as_mu():
    assert [typeset(u) for u in ("um", "MPa/um", "1/um", "uN", "mm")] == [
        "µm", "MPa/µm", "1/µm", "µN", "mm"
    ]  # fmt: skip
    assert display_scale(0.05, "GPa") == (1e3, "MPa") and display_scale(1.0, "") == (1.0, "")


def test_the_printed_table_shows_stiffness_in_mpa_per_um(tmp_path):
    """A run with units prints its stiffness per area as a pressure per um (kPa/um, MPa/um),
    the unit its file's `stiffness` is in (GPa/um) with a prefix: the table and the file
    agree (it printed TPa/m)."""
    out = tmp_path / "run.h5"
    loads = ["--modulus", "1GPa", "--length", "500um", "--pressures", "1MPa", "--stiffness"]
    r = cli("periodic", *SCENE, *loads, "--output", str(out))
    assert r.returncode == 0, r.stderr
    row = r.stdout.splitlines()[-2]
    assert row.lstrip().startswith("1/1") and "Pa/um" in row and "Pa/m " not in row, row
    with h5py.File(out, "r") as f:
        k = float(f["stiffness"][0])
        assert f["stiffness"].attrs["units"] == "GPa/um"
    assert format_quantity(k, "GPa/um") in row


# maps and load plots


def test_a_pressure_map_is_drawn_with_a_prefix(tmp_path):
    """A pressure map of a run in GPa whose contact pressures are about 10 MPa has its
    colour bar in MPa (not 1e-5..1e-1 GPa), its axes in µm."""
    path = run_file(tmp_path / "f.h5", "um", "GPa")
    pressure = np.zeros((1, 16, 16))
    pressure[0, :4] = np.geomspace(1e-3, 5e-2, 64).reshape(4, 16)
    with h5py.File(path, "a") as f:
        f["pressure"] = pressure
    found = field_map(str(path), "pressure", 1)
    assert found.label == "pressure (MPa)"
    np.testing.assert_allclose(found.values, 1e3 * pressure[0])
    fig = plot.plot_map(None, found.values, found.lengths, found.length_unit, label=found.label)
    assert fig.axes[0].get_xlabel() == "x (µm)" and "(MPa)" in fig.axes[1].get_ylabel()


def test_load_plots_are_in_the_run_units_in_both_geometries():
    """With units, the periodic load plot is in them (p0 in MPa, the gap in µm, K in
    MPa/µm), as the punch's is; without, both are dimensionless (p0/E*)."""
    steps = [{"nominal_pressure": p, "area_fraction": p**0.9, "mean_gap": 2 - p,
              "stiffness": 10 * p, "converged": True} for p in P]  # fmt: skip
    units = {"length": "um", "pressure": "GPa", "force": "GPa*um^2"}
    sweep = plot.plot_sweep(None, steps, 1.0, 0.5, units)
    area, gap, stiffness = sweep.axes
    assert area.get_xlabel() == "nominal pressure $p_0$ (MPa)"
    assert "(µm)" in gap.get_ylabel() and "(MPa/µm)" in stiffness.get_ylabel()
    np.testing.assert_allclose(stiffness.get_lines()[0].get_ydata(), 1e3 * 10 * P)
    punch_steps = [{"approach": 1e-3 * p**0.5, "force": p * 100, "nominal_pressure": p,
                    "interfacial_stiffness": 10 * p, "converged": True} for p in P]  # fmt: skip
    punch = plot.plot_punch(None, punch_steps, units, 1.0, 0.5)
    assert punch.axes[1].get_xlabel() == area.get_xlabel()
    assert punch.axes[1].get_ylabel() == stiffness.get_ylabel()
    bare_sweep = plot.plot_sweep(None, steps, 1.0, 0.5)
    bare_punch = plot.plot_punch(None, punch_steps, None, 1.0, 0.5)
    assert bare_sweep.axes[0].get_xlabel() == plot.P0_LABEL == bare_punch.axes[1].get_xlabel()
    assert bare_punch.axes[1].get_ylabel() == plot.STIFFNESS_LABEL
    assert bare_punch.axes[0].get_xlabel() == plot.APPROACH_LABEL
    np.testing.assert_allclose(bare_punch.axes[0].get_lines()[0].get_xdata(), 2e-3 * P**0.5)


def test_plot_redraws_a_run_in_its_units(tmp_path, monkeypatch):
    """`plot --sweep` of a periodic run with units draws it in them (it drew p0/E*)."""
    figures: list[Any] = []
    finish = plot._finish
    monkeypatch.setattr(plot, "_finish", lambda fig, *a: figures.append(fig) or finish(fig, *a))
    redraw(str(run_file(tmp_path / "u.h5", "um", "GPa")))
    assert figures[-1].axes[0].get_xlabel() == "nominal pressure $p_0$ (MPa)"
    redraw(str(run_file(tmp_path / "n.h5")))
    assert figures[-1].axes[0].get_xlabel() == plot.P0_LABEL


# theory --compare: a run beside the theory in the theory's units


def test_compared_runs_are_converted_into_the_theory_units(tmp_path):
    """A run in GPa and um beside a theory in MPa and mm: pressures x1000, gaps /1000,
    stiffnesses x1e6, drawn where the theory's own values would be."""
    path = run_file(tmp_path / "u.h5", "um", "GPa")
    ((name, table),) = compared_runs([str(path)], {"length": "mm", "pressure": "MPa"})
    assert name == "u.h5"
    np.testing.assert_allclose(table["nominal_pressure"], 1e3 * P)
    np.testing.assert_allclose(table["mean_gap"], 1e-3 * (1 - P))
    np.testing.assert_allclose(table["stiffness"], 1e6 * 10 * P)
    ((_, same),) = compared_runs([str(run_file(tmp_path / "n.h5"))], {"length": "", "pressure": ""})
    np.testing.assert_allclose(same["nominal_pressure"], P)


@pytest.mark.parametrize("theory_units", ["with", "without"])
def test_theory_compare_refuses_a_run_whose_units_differ_in_kind(tmp_path, theory_units):
    """A unit-free run (written with modulus=1e9) beside a theory in --modulus 1GPa, or a run
    in GPa beside a unit-free theory: one line, exit 2, nothing written or computed."""
    run = run_file(tmp_path / "run.h5", *(("", "") if theory_units == "with" else ("um", "GPa")))
    units = ["--modulus", "1GPa", "--length", "100um"] if theory_units == "with" else []
    out, png = tmp_path / "t.h5", tmp_path / "t.png"
    r = cli("theory", *SCENE, *units, "--output", str(out), "--plot", str(png),
            "--compare", str(run))  # fmt: skip
    assert r.returncode == 2, r.stderr
    (line,) = r.stderr.strip().splitlines()
    assert "run.h5" in line and "unit-free" in line and "give both units" in line, line
    assert not out.exists() and not png.exists() and "p0" not in r.stdout


# the pictures: only what is in view, what each line is


@pytest.mark.parametrize("crossover, shown", [(1e-4, True), (1e-9, False), (5.0, False)])
def test_theory_legend_names_only_lines_in_view(crossover, shown):
    """p_c is marked (and named in the legend) where it lies among the pressures drawn;
    otherwise neither drawn nor named, and the axis keeps the loads' range."""
    fig = plot.plot_theory(None, theory_result(crossover), 1.0)
    stiffness = fig.axes[2]
    labels = [t.get_text() for t in stiffness.get_legend().get_texts()]
    assert any("p_c" in label for label in labels) == shown
    low, high = stiffness.get_xlim()
    for line in stiffness.get_lines():
        x = np.asarray(line.get_xdata(), dtype=float)
        assert np.all((x >= low) & (x <= high)), line.get_label()


def test_compare_draws_no_reference_in_the_pressure_error_panel():
    """The reference's pressure error is zero by its definition: only its residual is drawn."""
    t = np.geomspace(1e-3, 1e-1, 5)
    trajectory = SimpleNamespace(name="cg", time=t, pressure_error=t / 10,
                                 natural_residual=t / 100, converged=True)  # fmt: skip
    fig = plot.plot_compare(None, [trajectory], {"natural_residual": 1e-12})
    error, residual = fig.axes
    assert [line.get_label() for line in error.get_lines()] == ["cg"]
    assert plot.REFERENCE in [line.get_label() for line in residual.get_lines()]


def ensemble_summary(**extra: Any) -> dict[str, np.ndarray]:
    """Two seeds with the same stiffness per area ``P`` (and area fraction)."""
    summary = {"seeds": np.arange(2), "nominal_pressure": P, **extra}
    for name in ("area_fraction", "stiffness"):
        summary |= {name: np.array([P, P]), f"{name}_mean": P, f"{name}_sem": 0 * P}
    return summary


def test_ensemble_scales_each_seed_by_its_own_rms_height(tmp_path):
    """Seeds of h_rms 1 and 3: each seed's K h_rms/E* is its own (P and 3P), the mean and
    its error are over the scaled seeds (2P +- P), and the title says so."""
    fig = plot.plot_ensemble(None, ensemble_summary(), 1.0, np.array([1.0, 3.0]))
    stiffness = fig.axes[1]
    seeds = [line.get_ydata() for line in stiffness.get_lines() if line.get_color() == "0.6"]
    np.testing.assert_allclose(seeds, [P, 3 * P])
    bars = stiffness.containers[0]
    np.testing.assert_allclose(bars.lines[0].get_ydata(), 2 * P)
    np.testing.assert_allclose(bars.lines[2][0].get_segments()[0][:, 1], [P[0], 3 * P[0]])
    assert stiffness.get_ylabel() == plot.STIFFNESS_LABEL
    assert "its own" in stiffness.get_title()


def test_ensemble_file_is_drawn_in_its_seeds_units(tmp_path, monkeypatch):
    """An ensemble of runs in GPa and um is drawn in MPa and MPa/µm, no h_rms involved."""
    figures: list[Any] = []
    finish = plot._finish
    monkeypatch.setattr(plot, "_finish", lambda fig, *a: figures.append(fig) or finish(fig, *a))
    seeds = [run_file(tmp_path / f"e_seed{k}.h5", "um", "GPa", rms_height=h)
             for k, h in ((1, 1.0), (2, 3.0))]  # fmt: skip
    with h5py.File(tmp_path / "e.h5", "w") as f:
        f.attrs.update(geometry="periodic ensemble", seed_files=json.dumps([str(s) for s in seeds]))
        for name, values in ensemble_summary().items():
            f[name] = values
    redraw(str(tmp_path / "e.h5"))
    stiffness = figures[-1].axes[1]
    assert stiffness.get_xlabel() == "nominal pressure $p_0$ (MPa)"
    assert stiffness.get_ylabel() == "stiffness per area $K$ (MPa/µm)"
    np.testing.assert_allclose(stiffness.containers[0].lines[0].get_ydata(), 1e3 * P)


def test_the_removed_unit_helpers_warn_and_agree_with_display_scale():
    """``display_unit`` and ``display_force`` stay until 0.3.0, each with a
    DeprecationWarning, giving what they gave: 2e-5 m as 20 um, 2e-3 N as 2 mN."""
    from petsc_contact.conventions.units import display_force, display_unit

    with pytest.warns(DeprecationWarning, match="display_scale"):
        assert display_unit(2e-5, "m") == (pytest.approx(1e6), "um")
    with pytest.warns(DeprecationWarning, match="display_scale"):
        forces, unit = display_force(np.array([2e-3, 1e-3]))
    assert unit == "mN" and forces == pytest.approx([2.0, 1.0])


def test_a_flat_punch_without_units_is_not_labelled_by_its_zero_rms_height():
    """A flat punch (``h_rms = 0``) without units is drawn in the map's own numbers and says
    so: no ``/h_rms`` in a label, no division by zero."""
    from petsc_contact.io.plot import plot_punch

    steps = [
        {"approach": a, "force": f, "nominal_pressure": f, "interfacial_stiffness": k,
         "converged": True}
        for a, f, k in ((1e-3, 1e-3, 1.0), (2e-3, 2e-3, 1.0))
    ]  # fmt: skip
    fig = plot_punch(None, steps, None, modulus=1.0, h_rms=0.0)
    labels = [ax.get_xlabel() + ax.get_ylabel() for ax in fig.axes]
    assert "map's units" in labels[0] and not any("h_\\mathrm{rms}" in s for s in labels)


def test_a_panel_with_nothing_to_draw_says_so(tmp_path):
    """A flat punch is at full contact at every approach: its stiffness panel (every value
    NaN) is drawn with a note, not a failure of the log axis."""
    from petsc_contact import punch_contact
    from petsc_contact.io.plot import plot_punch

    with pytest.warns(Warning):
        steps = punch_contact(
            np.zeros((16, 16)), length=1.0, approaches=[1e-4, 1e-3], progress=False
        )
    fig = plot_punch(str(tmp_path / "flat.png"), [s.scalars for s in steps], None, h_rms=0.0)
    assert (tmp_path / "flat.png").stat().st_size > 0
    assert "no value to draw" in fig.axes[1].texts[0].get_text()
