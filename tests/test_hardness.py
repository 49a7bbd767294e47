"""A hardness cap on the punch's pressure (Kato's perfectly plastic surface layer): the
elastic answer far below the cap, the fully plastic flat punch exactly, Kato's conditions on
a rough face, the exact stiffness with the plastic pixels held at the cap, the same answer from
every solver, and the refusals."""

from dataclasses import dataclass

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import Run, run_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.conventions.warnings import FullContact
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.capped_periodic import CappedPeriodicProblem
from petsc_contact.geometries.punch import PunchProblem
from petsc_contact.interactions.hardness import HardnessCap
from petsc_contact.physics.surface import self_affine
from petsc_contact.substrates.half_space import PeriodicHalfSpace
from petsc_contact.workflows.punch_steps import PunchSolver
from petsc_contact.workflows.punch_sweep import punch_contact

ROUNDING = 4e-16  # the cap is the scaled bound H/p_s times p_s: H to an ulp or two
APPROACH = 3e-3  # 3 h_rms: 7.5% of the face in contact, elastic peak pressure 0.043 E*
HARDNESS = 3e-3  # 14% of the face at the cap at APPROACH


@pytest.fixture(scope="module")
def rough():
    grid = Grid(64, 1.0)
    return self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=16, seed=3, rms_height=1e-3
    )


def capped(heights, hardness=HARDNESS, **kw):
    if "forces" not in kw:
        kw.setdefault("approaches", [APPROACH])
    return punch_contact(heights, length=1.0, modulus=1.0, hardness=hardness, progress=False, **kw)


@pytest.mark.parametrize("loads", [{"approaches": [APPROACH]}, {"forces": [2e-4, 5e-4]}])
def test_a_hardness_far_above_the_pressures_is_the_hard_wall(rough, loads):
    """A cap 1e4 times the elastic peak pressure changes nothing: the same iterations (Newton's
    too) and the same answer bit for bit, no pixel at the cap."""
    wall = punch_contact(rough, length=1.0, modulus=1.0, progress=False, **loads)
    cap = capped(rough, hardness=1e3, **loads)
    for a, b in zip(wall, cap, strict=True):
        assert b.converged and b.scalars["plastic_area_fraction"] == 0
        for name in ("iterations", "force", "approach", "area_fraction", "total_stiffness"):
            assert a.scalars[name] == b.scalars[name], name


def test_the_flat_punch_past_full_flow_carries_the_hardness_everywhere():
    """A flat punch pressed beyond the approach at which the uniform pressure ``H`` closes
    every gap, ``max(G H 1)``, is fully plastic: ``p = H`` on every pixel (the force ``H A``
    exactly), the plastic displacement ``delta - G H 1`` (exact: the discrete solution), and
    nothing held: no stiffness (and every pixel in contact: full contact, with its warning)."""
    n, hardness = 32, 0.01
    grid = Grid(n, 1.0)
    problem = PunchProblem(grid, np.zeros((n, n)), 1.0)
    elastic = problem.compliance.apply_array(np.full((n, n), hardness), np.empty((n, n)))
    delta = 1.05 * elastic.max()
    with pytest.warns(FullContact):
        (step,) = capped(np.zeros((n, n)), hardness, approaches=[delta], fields=True)
    s = step.scalars
    assert step.converged, s["verification"]
    assert s["plastic_area_fraction"] == 1.0 and s["area_fraction"] == 1.0
    assert step.pressure == pytest.approx(hardness, rel=ROUNDING, abs=0)  # the bound
    assert s["force"] == pytest.approx(hardness, rel=1e-14)  # H times the unit area
    w = step.field("plastic_displacement")
    assert w == pytest.approx(delta - elastic, rel=1e-9, abs=1e-9 * delta)  # solver's tolerance
    assert s["total_stiffness"] == 0


@pytest.mark.parametrize("loads", [{"approaches": [APPROACH]}, {"forces": [3e-4]}])
def test_kato_conditions_on_a_rough_face(rough, loads):
    """Kato's law on every pixel of a capped rough punch: ``0 <= p <= H``; the force is the
    pressure's sum (and the target under load control, to Newton's 1e-6); the gap of a pixel
    below the cap is not negative beyond the solver's tolerance (an rms of 1e-8 of the rms
    recess over the 64^2 pixels: one pixel's at most 64 times that); the plastic displacement
    is positive exactly on the pixels at ``p = H``, which are in contact and part of the
    area."""
    (step,) = capped(rough, fields=True, **loads)
    s = step.scalars
    assert step.converged, s["verification"]
    p, w, gap = step.pressure, step.field("plastic_displacement"), step.gap
    assert p.min() >= 0 and s["max_pressure"] == p.max() == pytest.approx(HARDNESS, rel=ROUNDING)
    assert s["force"] == pytest.approx(p.sum() / p.size, rel=1e-12)
    if "forces" in loads:
        assert s["force"] == pytest.approx(loads["forces"][0], rel=1e-6)
    plastic = w > 0
    assert np.array_equal(plastic, p >= HARDNESS * (1 - ROUNDING))
    assert np.all(step.contact[plastic]) and np.all(gap[plastic] == 0)
    assert s["plastic_area_fraction"] == plastic.mean() > 0.05
    assert s["area_fraction"] > s["plastic_area_fraction"]
    assert s["min_gap"] > -64e-8 * np.sqrt(np.mean((rough.max() - rough) ** 2))
    assert s["kkt_residual"] < 1e-7


def test_a_force_reached_past_a_fully_plastic_approach():
    """A cap just above the nominal pressure (``H = 1.05 p0``): Newton's tangent from the
    first contact overshoots to an approach where every pixel flows (the force ``H A``, no
    slope), whose answer a solve at a smaller approach accepts unchanged; Newton bisects down
    out of it, not stopping there, and reaches the force (to its 1e-6)."""
    grid = Grid(32, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=8, seed=1, rms_slope=0.1
    )
    (step,) = capped(h, 1.05e-3, forces=[1e-3])
    assert step.converged, step.scalars["verification"]
    assert step.scalars["force"] == pytest.approx(1e-3, rel=1e-6)
    assert 0 < step.scalars["plastic_area_fraction"] < 1


def test_the_stiffness_holds_the_plastic_pixels_at_the_cap(rough):
    """``dF/dδ`` with the elastic contact held and the plastic pixels at the cap is the
    derivative of the capped force: a central difference of ``F(δ)`` within 2% (the contact
    and plastic sets change inside the difference step, as for the hard wall), and well below
    the stiffness of the same contact held elastically (the plastic pixels carry no more
    load)."""
    d, eps = APPROACH, 2e-5
    lo, mid, hi = (s.scalars for s in capped(rough, approaches=[d - eps, d, d + eps]))
    assert mid["total_stiffness"] == pytest.approx(
        (hi["force"] - lo["force"]) / (2 * eps), rel=0.02
    )
    (wall,) = punch_contact(rough, length=1.0, modulus=1.0, approaches=[d], progress=False)
    assert mid["total_stiffness"] < 0.8 * wall.scalars["total_stiffness"]


@pytest.mark.parametrize(
    "solver",
    [
        {"options": ["-tao_type", "blmvm"]},
        {"options": ["-tao_type", "bncg"]},
        {"options": ["-tao_type", "tron"]},
        {"device": "cpu-array"},
    ],
)
def test_every_solver_gives_the_same_capped_answer(rough, solver):
    """TAO's bound types and the package's own array CG against the default (TAO with the
    package's CG) under the cap: the same contact and plastic pixels, force and pressure
    field to the gap tolerance 1e-8 l (the pressure differs by ``E*/a`` times the gap's
    error, ~1e-6 of the cap at 64 pixels)."""
    (ref,) = capped(rough, fields=True)
    (other,) = capped(rough, fields=True, **solver)
    a, b = ref.scalars, other.scalars
    assert other.converged, b["verification"]
    assert b["plastic_area_fraction"] == a["plastic_area_fraction"]
    assert b["area_fraction"] == a["area_fraction"]
    assert b["force"] == pytest.approx(a["force"], rel=1e-6)
    assert np.abs(other.pressure - ref.pressure).max() < 1e-5 * HARDNESS


@pytest.mark.parametrize("hardness", [0, -1e-3, np.inf, np.nan])
def test_a_hardness_that_is_not_positive_and_finite_is_refused(hardness):
    with pytest.raises(ValueError, match="--hardness must be positive and finite"):
        Run(geometry="punch", hardness=hardness, approaches=[0.1])
    with pytest.raises(ValueError, match="--hardness must be positive and finite"):
        HardnessCap(hardness)


CELL = {"grid": 64, "hurst": 0.8, "rms_slope": 0.1, "seed": 3}  # elastic peak 0.17 E* at 5e-3
PRESSURES = (1e-3, 5e-3)


def cell(**kw):
    return run_contact(Run(**CELL, pressures=PRESSURES, **kw)).steps


@pytest.mark.parametrize("geometry", ["periodic", "punch"])
def test_a_cap_the_pressures_never_reach_is_the_hard_wall_bit_for_bit(tmp_path, geometry):
    """A hardness 100 times the hard wall's largest pressure: every dataset the hard-wall run
    wrote (iterations, mean gap, the fields, ...) is written again bit for bit, with no pixel
    at the cap, no plastic displacement and (periodic) each step saying the cap was not
    reached."""
    common = [geometry, "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1", "--quiet"]
    loads = ["--forces", "1e-4,3e-4"] if geometry == "punch" else ["--pressures", "1e-3,5e-3"]
    common += [*loads, "--fields", "--stiffness"]
    wall, capped = tmp_path / "wall.h5", tmp_path / "capped.h5"
    assert cli(*common, "--output", str(wall)).returncode == 0
    with h5py.File(wall) as f:
        hardness = float(100 * f["max_pressure"][:].max())
    done = cli(*common, "--hardness", f"{hardness!r}", "--output", str(capped))
    assert done.returncode == 0, done.stderr
    with h5py.File(wall) as a, h5py.File(capped) as b:
        names = [k for k, v in a.items() if isinstance(v, h5py.Dataset)]
        assert {"iterations", "mean_gap", "stiffness", "gap", "pressure"} <= set(names)
        for name in names:
            if a[name].attrs.get("units") != "s":  # wall times differ from run to run
                x, y = a[name][()], b[name][()]
                nan = np.asarray(x).dtype.kind == "f"
                assert np.array_equal(x, y, equal_nan=nan), name
        assert np.all(b["plastic_area_fraction"][:] == 0)
        assert np.all(b["plastic_displacement"][:] == 0)
        if geometry == "periodic":
            assert not np.any(b["cap_reached"][:])


@dataclass(frozen=True)
class StifferMean:
    """The half-space with a mean-mode compliance ten times the longest wavelength's."""

    modulus: float
    name = "half-space, stiffer mean"

    def stiffness(self, q):
        return PeriodicHalfSpace(self.modulus).stiffness(q)

    def mean_mode_compliance(self, q0, interfacial_stiffness):
        return 10 * PeriodicHalfSpace(self.modulus).mean_mode_compliance(q0, 0.0)


def test_the_capped_cell_does_not_depend_on_the_mean_modes_compliance():
    """The mean mode's compliance ``c`` only moves the approach: with ``10 c`` the same
    pressure and gap fields (to the gap tolerance, 1e-8 of the rms height over the 64^2
    pixels, and the pressure's ``E*/a`` times that), area and stiffness."""
    grid = Grid(64, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.8, rolloff_ratio=1, cutoff_ratio=32, seed=3, rms_slope=0.1
    )
    fields = []
    for substrate in (None, StifferMean(1.0)):
        problem = CappedPeriodicProblem(
            grid, make_fft(grid), h, 1.0, HardnessCap(0.02), substrate=substrate
        )
        with PunchSolver(problem) as solver:
            step = solver.at_force(5e-3, fields=True, stiffness=True)
        assert step.converged, step.scalars["verification"]
        fields.append((step, problem.approach))
    (a, delta_a), (b, delta_b) = fields
    assert abs(delta_b - delta_a) > 1e-3  # the approach takes up 9 c p0
    assert b.scalars["area_fraction"] == a.scalars["area_fraction"]
    assert b.scalars["plastic_area_fraction"] == a.scalars["plastic_area_fraction"]
    assert b.scalars["stiffness"] == pytest.approx(a.scalars["stiffness"], rel=1e-6)
    h_rms = np.sqrt(np.mean(h**2))
    assert np.abs(b.gap - a.gap).max() < 64e-8 * h_rms
    assert np.abs(b.pressure - a.pressure).max() < 1e-5 * 0.02


@pytest.mark.parametrize(
    "solver",
    [{}, {"options": ("-tao_type", "blmvm")}, {"options": ("-tao_type", "bncg")},
     {"device": "cpu-array"}],
)  # fmt: skip
def test_kato_conditions_on_the_periodic_cell(solver):
    """Kato's law on the capped cell, from TAO (the package's CG, blmvm, bncg) and the
    package's array CG alike: ``mean(p) = p0`` (Newton's 1e-6), ``0 <= p <= H``, the
    plastic displacement positive exactly where ``p = H``, those pixels in contact, and the
    same areas and pressure field from every solver (an rms gap tolerance of 1e-8 h_rms, one
    pixel's at most 64 times that, times the pixel stiffness ~100 E*: 4e-7 E* = 2e-5 H)."""
    reference = cell(hardness=0.02, fields=True)
    steps = cell(hardness=0.02, fields=True, **solver)
    for p0, step, ref in zip(PRESSURES, steps, reference, strict=True):
        s, p, w = step.scalars, step.pressure, step.field("plastic_displacement")
        assert step.converged, s["verification"]
        assert p.mean() == pytest.approx(p0, rel=1e-6)
        assert p.min() >= 0 and p.max() == pytest.approx(0.02, rel=ROUNDING)
        assert np.array_equal(w > 0, p >= 0.02 * (1 - ROUNDING))
        assert np.all(step.contact[w > 0]) and s["plastic_area_fraction"] == (w > 0).mean()
        assert s["area_fraction"] == ref.scalars["area_fraction"]
        assert s["plastic_area_fraction"] == ref.scalars["plastic_area_fraction"] > 0.04
        assert np.abs(p - ref.pressure).max() < 5e-5 * 0.02


def test_a_capped_sweep_is_its_loads_solved_one_by_one():
    """``--sweep`` with ``--hardness``: each load solved on the hard wall along the sweep's
    continuation, capped where that reaches the cap; the low loads below the cap are the
    hard wall's sweep bit for bit, the capped ones the loads solved alone (``--pressures``)
    to the solvers' tolerances (the pressure field within 2e-5 H, as across solvers above), the
    same contact and plastic pixels."""
    loads = {"sweep": (4, 1e-5, 5e-3)}  # the hard wall's peak: 0.03 to 0.17 E*
    swept_steps = cell(hardness=0.05, fields=True, **loads)
    wall = cell(**loads)
    reached = [s.scalars["cap_reached"] for s in swept_steps]
    assert reached[0] is False and reached[-1] is True
    for step, plain in zip(swept_steps, wall, strict=True):
        p0 = step.scalars["nominal_pressure"]
        assert step.converged, step.scalars["verification"]
        if not step.scalars["cap_reached"]:
            assert step.scalars["iterations"] == plain.scalars["iterations"]
            assert step.scalars["mean_gap"] == plain.scalars["mean_gap"]
            continue
        (alone,) = run_contact(Run(**CELL, pressures=(p0,), hardness=0.05, fields=True)).steps
        a, b = step.scalars, alone.scalars
        assert a["area_fraction"] == b["area_fraction"] and a["plastic_area_fraction"] > 0
        assert a["plastic_area_fraction"] == b["plastic_area_fraction"]
        assert np.abs(step.pressure - alone.pressure).max() < 2e-5 * 0.05


def test_a_periodic_load_the_cap_cannot_carry_is_refused():
    """``p0 >= H``: the whole surface flows; a sweep whose top reaches the cap (the default
    range's, to 0.9 of full contact, does) is refused as well."""
    with pytest.raises(ValueError, match="--pressures: a nominal pressure of 0.02 is not below"):
        run_contact(Run(**CELL, pressures=(1e-3, 0.02), hardness=0.02))
    with pytest.raises(ValueError, match="--sweep: a nominal pressure of .* is not below"):
        run_contact(Run(**CELL, sweep=(3,), hardness=0.02))


def test_a_force_the_cap_cannot_carry_is_refused(rough):
    """A nominal pressure over the face at or above the hardness: refused in one line before
    anything is solved (the whole face would flow, and no approach reaches it)."""
    with pytest.raises(ValueError, match="not below the hardness 0.003: the whole surface"):
        capped(rough, forces=[1e-3, HARDNESS])


@pytest.mark.parametrize("geometry", ["punch", "periodic"])
def test_the_command_line_keeps_the_plastic_displacement(tmp_path, geometry):
    """``punch --hardness H --fields`` (and ``periodic``): each step's
    ``plastic_area_fraction``, the field ``plastic_displacement`` (positive exactly where the
    pressure is at the cap), both with units and descriptions, drawn by ``plot``; a load
    above ``H`` (the punch's: times the face's area) refused in one line."""
    out = tmp_path / "capped.h5"
    common = [geometry, "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1", "--quiet"]
    loads = "--forces" if geometry == "punch" else "--pressures"
    shown = [a for a in common if a != "--quiet"]
    done = cli(*shown, loads, "1e-4,2e-4", "--hardness", "0.01", "--fields", "--output", str(out))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    header = next(line for line in lines if line.split()[:1] == ["step"])
    assert " area    plastic " in header  # the printed table: right-aligned, 10 wide
    end = header.index(" plastic") + len(" plastic")
    rows = [line[end - 10 : end].strip() for line in lines if line.split()[0] in ("1/2", "2/2")]
    with h5py.File(out) as f:
        fraction = f["plastic_area_fraction"][:]
        assert rows == [f"{x:.5g}" for x in fraction]
        w, p = f["plastic_displacement"][:], f["pressure"][:]
        assert f["plastic_displacement"].attrs["units"] == "length"
        assert "hardness cap" in f["plastic_displacement"].attrs["description"]
        assert "description" in f["plastic_area_fraction"].attrs
    assert np.all(fraction > 0)
    assert np.array_equal(w > 0, p >= 0.01 * (1 - ROUNDING))
    assert fraction == pytest.approx((w > 0).mean(axis=(1, 2)), abs=0)
    drawn = tmp_path / "w.png"
    plotted = cli("plot", str(out), "--field", "plastic_displacement", "--output", str(drawn))
    assert plotted.returncode == 0 and drawn.stat().st_size > 0, plotted.stderr
    refused = cli(*common, loads, "0.02", "--hardness", "0.01", "--output", str(tmp_path / "x.h5"))
    assert refused.returncode != 0
    assert "not below the hardness 0.01" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_compare_with_a_hardness(tmp_path):
    """``compare --hardness``: the cell posed in the pressure, the reference by Newton at
    ``-tao_gatol 1e-12``, every solver at its approach: each converges, to the reference's
    pressure within 1e-5 (the default tolerance 1e-8 of the gap, times the pixel stiffness
    over ``p0``: ~1e-6), and the reference's natural residual is at its tolerance's level."""
    out = tmp_path / "compare.h5"
    done = cli(
        "compare", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1", "--pressures",
        "5e-3", "--hardness", "0.02", "--solvers", "cg,blmvm,bncg,tron", "--quiet",
        "--output", str(out),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    with h5py.File(out) as f:
        assert f.attrs["reference_natural_residual"] < 1e-9
        for name in ("cg", "blmvm", "bncg", "tron"):
            assert f[name].attrs["converged"], name
            assert f[name]["pressure_error"][-1] < 1e-5, name
