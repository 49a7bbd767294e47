"""One vocabulary: every form of a height map goes through every door (``Run``,
``periodic_contact``, ``punch_contact``, ``predict_map``) with the same result; the library's
functions take keywords named as ``Run``'s fields, and the forms a user naturally writes
(``sweep=4``, ``pressures=1e-3``, ``grid="64x32"``) are read as the command line reads them."""

import inspect
from dataclasses import fields
from pathlib import Path

import h5py
import numpy as np
import pytest
from SurfaceTopography import Topography as STTopography

from petsc_contact import (
    Run,
    periodic_contact,
    predict_map,
    punch_contact,
    read_topography,
    run_contact,
)
from petsc_contact.io.topography import Topography, as_topography

pytestmark = pytest.mark.filterwarnings(  # a smooth map, no power law: p_c is meaningless
    "ignore::petsc_contact.paper.predictions.TheoryWarning"
)
SIDES = (4.0, 3.0)  # um
PRESSURE, APPROACH = 1e-3, 2e-3
OPTIONS = ("-tao_gatol", "1e-10")
ADHESIVE = {"adhesion": "exponential", "work_of_adhesion": 1e-5, "interaction_range": 5e-3}


@pytest.fixture(scope="module")
def heights():
    """A smooth periodic 32 x 32 map (rms slope about 0.05 on 4 um x 3 um)."""
    rng = np.random.default_rng(1)
    x, y = np.meshgrid(*(np.arange(32) / 32,) * 2, indexing="ij")
    return 0.02 * sum(
        rng.standard_normal() * np.cos(2 * np.pi * (i * x + j * y) + rng.uniform(0, 2 * np.pi))
        for i in range(1, 4)
        for j in range(-3, 4)
    )


@pytest.fixture(scope="module")
def forms(heights, tmp_path_factory):
    """The map in every form, each with its sides (given beside the array)."""
    path = tmp_path_factory.mktemp("doors") / "map.h5"
    with h5py.File(path, "w") as f:
        f["heights"] = heights
        f.attrs["length"], f.attrs["unit"] = SIDES, "um"
    return {
        "array": (heights, {"length": SIDES}),
        "read_topography": (read_topography(str(path)), {}),
        "SurfaceTopography": (STTopography(heights, SIDES, unit="um"), {}),
        "path": (str(path), {}),
        "pathlib": (Path(path), {}),
    }


def _same(door, values):
    """Every entry equal to the first to 1e-12."""
    first = next(iter(values.values()))
    for form, value in values.items():
        assert value == pytest.approx(first, rel=1e-12), (door, form)


def test_every_form_through_every_door(forms, petsc):
    """The mean gap (the punch's force, u0) of each form equals the array's with its sides,
    from each entry point (Run records a path's text)."""
    door = {
        "periodic": lambda h, kw: periodic_contact(h, **kw, pressures=PRESSURE, options=OPTIONS)[
            0
        ].scalars["mean_gap"],
        "punch": lambda h, kw: punch_contact(h, **kw, approaches=APPROACH, options=OPTIONS)[
            0
        ].scalars["force"],
        "predict_map": lambda h, kw: predict_map(h, **kw).u0,
        "Run": lambda h, kw: run_contact(Run(heights=h, **kw, pressures=PRESSURE)).table[0][
            "mean_gap"
        ],
    }
    for name, solve in door.items():
        _same(name, {form: solve(h, kw) for form, (h, kw) in forms.items()})


def test_the_one_conversion(heights):
    """as_topography: a Topography as it is, a masked array's masked points undefined, a
    channel refused where there is one map, an array that is no map refused."""
    topo = Topography(heights, SIDES, "um")
    assert as_topography(topo) is topo
    masked = np.ma.masked_array(heights, mask=heights > 0.05)
    assert as_topography(masked).undefined == np.count_nonzero(heights > 0.05)
    with pytest.raises(ValueError, match="an array holds one map: it has no channels"):
        as_topography(heights, channel=1)
    with pytest.raises(ValueError, match="2-D"):
        as_topography(heights[0])
    with pytest.raises(ValueError, match="no sides of its own: give length="):
        periodic_contact(heights, pressures=PRESSURE)
    with pytest.raises(ValueError, match="contradicts the map's own sides"):
        predict_map(topo, length=1.0)
    holes = Topography(np.where(masked.mask, np.nan, heights), SIDES)
    with pytest.raises(ValueError, match="undefined points: fill them first"):
        predict_map(holes)


def test_one_signature_style():
    """After the map, every parameter is a keyword, named as Run's field where Run has one."""
    own = {"comm", "device", "beta", "monitor", "progress", "flat"}
    names = {f.name for f in fields(Run)} | own
    for function in (periodic_contact, punch_contact, predict_map):
        first, *rest = inspect.signature(function).parameters.values()
        assert first.name == "heights"
        assert all(p.kind is p.KEYWORD_ONLY for p in rest), function.__name__
        assert {p.name for p in rest} <= names, function.__name__


def test_positional_calls_warn_and_work(heights, petsc):
    """Positional arguments after the map work for one more release, with a warning that
    names the keywords; given twice, they are refused."""
    keywords = periodic_contact(heights, length=SIDES, modulus=2.0, pressures=[PRESSURE])
    with pytest.warns(DeprecationWarning, match="length=, modulus=, pressures= by keyword"):
        positional = periodic_contact(heights, SIDES, 2.0, [PRESSURE])
    assert positional[0].scalars["mean_gap"] == keywords[0].scalars["mean_gap"]
    with pytest.warns(DeprecationWarning, match="punch_contact"):
        (step,) = punch_contact(heights, SIDES, 1.0, [APPROACH])
    assert step.converged
    with pytest.warns(DeprecationWarning, match="predict_map"):
        assert predict_map(heights, SIDES).u0 == predict_map(heights, length=SIDES).u0
    with pytest.raises(TypeError, match="two values for 'length'"):
        periodic_contact(heights, SIDES, length=SIDES)


def test_punch_takes_run_s_names(heights, petsc):
    """punch_contact's stiffness and progress (index from 0) equal Run's punch with the
    exact stiffness; flat= still works, with a warning, as flat_stiffness=."""
    seen = []
    steps = punch_contact(
        heights,
        length=SIDES,
        approaches=[APPROACH, 2 * APPROACH],
        stiffness=True,
        progress=lambda i, n, s: seen.append((i, n)),
    )
    run = Run(geometry="punch", heights=heights, length=SIDES, approaches=(APPROACH, 2 * APPROACH))
    table = run_contact(run.with_(stiffness=True)).table
    assert seen == [(0, 2), (1, 2)]
    for step, row in zip(steps, table, strict=True):
        for name in ("force", "stiffness", "interfacial_stiffness"):
            assert step.scalars[name] == pytest.approx(row[name], rel=1e-12), name
    new = punch_contact(heights, length=SIDES, approaches=APPROACH, flat_stiffness="analytic")
    with pytest.warns(DeprecationWarning, match="flat_stiffness="):
        old = punch_contact(heights, length=SIDES, approaches=APPROACH, flat="analytic")
    assert old[0].scalars["interfacial_stiffness"] == new[0].scalars["interfacial_stiffness"]


@pytest.mark.parametrize(
    "model",
    [
        {"mean_gaps": "half"},
        {"pressures": PRESSURE, "hardness": "half"},
        {"pressures": PRESSURE, "thickness": 1.0, "poisson": 0.3, "base": "frictionless"},
        {"pressures": PRESSURE, **ADHESIVE},
    ],
    ids=["mean_gaps", "hardness", "layer", "adhesion"],
)
def test_periodic_takes_run_s_models(heights, model, petsc):
    """periodic_contact's mean gaps (displacement control), hardness, layer and adhesion give
    Run's answer on the same map: the same driver solves both, so they agree to rounding
    (1e-12; Run's map goes through the scene's reading). The hardness is half the hard wall's
    largest pressure, so that the cap is reached; the mean gap half that at first touch; the
    adhesive law is solved by a TAO type."""
    given = dict(model)
    options = OPTIONS + (("-tao_type", "blmvm") if "adhesion" in given else ())
    if given.get("mean_gaps") == "half":
        given["mean_gaps"] = 0.5 * (heights.max() - heights.mean())
    if given.get("hardness") == "half":
        (wall,) = periodic_contact(heights, length=SIDES, pressures=PRESSURE, options=OPTIONS)
        given["hardness"] = 0.5 * wall.scalars["max_pressure"]
    (step,) = periodic_contact(heights, length=SIDES, options=options, **given)
    loads = {k: (v,) for k, v in given.items() if k in ("pressures", "mean_gaps")}
    run = Run(heights=heights, length=SIDES, options=options, **{**given, **loads})
    (row,) = run_contact(run).table
    assert step.converged and row["converged"]
    names = ["nominal_pressure", "mean_gap", "area_fraction"]
    names += ["plastic_area_fraction"] if "hardness" in given else []
    for name in names:
        assert step.scalars[name] == pytest.approx(row[name], rel=1e-12), name
    if "hardness" in given:
        assert step.scalars["cap_reached"] and step.scalars["plastic_area_fraction"] > 0


def test_run_reads_the_natural_forms(petsc):
    """sweep=4, a load alone, text with commas, a grid as text or one item, options as a
    string: read as the command line reads them; a wrong count refused naming the option."""
    surface = dict(hurst=0.7, rms_slope=0.1)
    assert Run(grid=16, **surface, sweep=4) == Run(grid=16, **surface, sweep=(4,))
    assert len(run_contact(Run(grid=16, **surface, sweep=4)).table) == 4
    assert Run(pressures=1e-3).pressures == (1e-3,)
    assert Run(pressures="1e-3, 2MPa").pressures == ("1e-3", "2MPa")
    assert Run(geometry="punch", forces=1e-3).forces == (1e-3,)
    assert Run(grid="64x32").grid == (64, 32) and Run(grid=(16,)).grid == 16
    assert Run(options="-tao_type bncg").options == ("-tao_type", "bncg")
    refusals = {
        "--sweep": dict(sweep=(4, 1e-3)),
        "--grid": dict(grid=16.5),
        "--length": dict(length=(1.0, 2.0, 3.0)),
    }
    for option, given in refusals.items():
        with pytest.raises(ValueError, match=option):
            Run(**given)
    with pytest.raises(ValueError, match="--grid"):
        Run(grid=(16, 8, 4))


@pytest.mark.parametrize(
    "field, value, text",
    [
        ("cut_from", 0, "0"),
        ("cut_from", 1.5, "1.5"),
        ("stop_after", float("nan"), "nan"),
        ("stop_after", -1, "-1"),
        ("sweep", (1,), "1"),
        ("sweep", "4,1e-3", "4,1e-3"),
        ("sweep", (4, 1e-3, 1e-8), "4,1e-3,1e-8"),
    ],
)
def test_run_and_the_command_line_refuse_with_one_rule(field, value, text):
    """``--cut-from``, ``--stop-after`` and ``--sweep`` are read by one rule each (their
    option's parser): ``Run`` refuses what the command line refuses, in the same words after
    the option's name."""
    from conftest import cli

    flag = "--" + field.replace("_", "-")
    geometry = "punch" if field == "cut_from" else "periodic"
    with pytest.raises(ValueError) as refused:
        Run(geometry=geometry, grid=16, hurst=0.7, rms_slope=0.1, **{field: value})
    loads = () if field == "sweep" else ("--approaches" if field == "cut_from" else "--pressures",
                                         "1e-3")  # fmt: skip
    r = cli(geometry, "--grid", "16", "--hurst", "0.7", "--rms-slope", "0.1", *loads,
            f"{flag}={text}", "--output", "never.h5")  # fmt: skip
    assert r.returncode == 2, r.stderr
    said = r.stderr.strip().splitlines()[-1].split(f"argument {flag}: ", 1)[1]
    assert said.startswith(str(refused.value).removeprefix(f"{flag}: ")), (said, refused.value)


def test_punch_takes_run_s_footprints(petsc):
    """``footprint="disk"`` (Run's word) gives Run's disk punch, with its shape factor 1;
    a mask of the same disk gives the same answer given that factor."""
    from petsc_contact.geometries.punch import disk_footprint

    face = 1e-3 * np.random.default_rng(4).standard_normal((32, 32))
    run = Run(geometry="punch", heights=face, length=1.0, approaches=(1e-3,), footprint="disk")
    (row,) = run_contact(run).table
    (step,) = punch_contact(face, length=1.0, approaches=1e-3, footprint="disk")
    (masked,) = punch_contact(
        face, length=1.0, approaches=1e-3, footprint=disk_footprint(32), beta=1.0
    )
    for name in ("force", "interfacial_stiffness"):
        assert step.scalars[name] == pytest.approx(row[name], rel=1e-12), name
        assert masked.scalars[name] == pytest.approx(row[name], rel=1e-12), name
    with pytest.raises(ValueError, match="square, disk or a mask"):
        punch_contact(face, length=1.0, approaches=1e-3, footprint="round")
