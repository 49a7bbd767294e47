"""An elastic layer of finite thickness on a rigid base (substrates/layer.py): its stiffness
multiplier against the plane-strain boundary-value problem it solves and its limits, and
whole contacts on it against the half-space, between solvers and by its exact stiffness."""

import numpy as np
import pytest

from petsc_contact.backend.stiffness import sweep_stiffness
from petsc_contact.physics.greens import layer_factor
from petsc_contact.substrates.layer import PeriodicLayer
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.runner import run_contact

POISSONS = (0.0, 0.25, 0.3, 0.45, 0.5)


def boundary_value_factor(s, nu, base):
    """``f`` from the layer's plane-strain problem solved numerically: the Airy function
    ``F(z) = (A + B z) cosh z + (C + D z) sinh z`` (``z = q depth``) with ``F(0) = p/q^2``,
    no shear on top (``F'(0) = 0``) and the base's two conditions at ``z = s``; the surface
    displacement is ``(1 - nu) q F'''(0) / 2G``, so ``f = 2 F(0) / F'''(0)``."""
    c, h = np.cosh(s), np.sinh(s)
    derivatives = [  # F, F', F'', F''' at s, as rows over (A, B, C, D)
        [c, s * c, h, s * h],
        [h, c + s * h, c, h + s * c],
        [c, 2 * h + s * c, h, 2 * c + s * h],
        [h, 3 * c + s * h, c, 3 * h + s * c],
    ]
    F, F1, F2, F3 = (np.array(row) for row in derivatives)
    normal = (1 - nu) * F3 - (2 - nu) * F1  # u_z at the base
    second = (1 - nu) * F2 + nu * F if base == "bonded" else F1  # u_x, or the shear
    rows = [[1, 0, 0, 0], [0, 1, 1, 0], normal, second]
    a, b, c3, d = np.linalg.solve(np.array(rows, dtype=float), [1.0, 0, 0, 0])
    return 2 * a / (3 * b + c3)


@pytest.mark.parametrize("base", ["bonded", "frictionless"])
@pytest.mark.parametrize("nu", POISSONS)
def test_the_closed_form_solves_the_layer_s_boundary_value_problem(nu, base):
    """The closed form equals the numerical solution of the four boundary conditions, from
    thin to thick (``s = 0.05 ... 8``: a well-conditioned 4x4 solve; ``1e-9`` covers its
    condition number, about ``e^{2s}``, times ``eps``)."""
    for s in (0.05, 0.3, 1.0, 2.5, 8.0):
        assert layer_factor(s, nu, base) == pytest.approx(boundary_value_factor(s, nu, base), 1e-9)


@pytest.mark.parametrize("nu", POISSONS)
def test_a_thick_layer_is_the_half_space(nu):
    """``f - 1 = e^{-2s} ((1 + 2s)^2 + kappa^2)/kappa`` (bonded) and ``2 (1 + 2s) e^{-2s}``
    (frictionless) to first order in ``e^{-2s}``: the next order is below ``1e-3`` of it from
    ``s = 5``; from ``s = 25`` ``f`` is 1 to rounding."""
    kappa = 3 - 4 * nu
    for s in (5.0, 8.0, 12.0):
        t = np.exp(-2 * s)
        bonded = layer_factor(s, nu, "bonded") - 1
        frictionless = layer_factor(s, nu, "frictionless") - 1
        assert bonded == pytest.approx(t * ((1 + 2 * s) ** 2 + kappa**2) / kappa, rel=1e-3)
        assert frictionless == pytest.approx(2 * (1 + 2 * s) * t, rel=1e-3)
    for base in ("bonded", "frictionless"):
        thick = layer_factor(np.array([25.0, 1e3, 1e9]), nu, base)
        assert np.all(np.abs(thick - 1) <= 4 * np.finfo(float).eps)


@pytest.mark.parametrize("nu", (0.0, 0.25, 0.3, 0.45))
def test_a_thin_bonded_layer_is_oedometric(nu):
    """``K -> M/T`` with the oedometric modulus ``M = E(1 - nu)/((1 + nu)(1 - 2 nu))``, that is
    ``E* (1 - nu)^2/(1 - 2 nu)``: the relative correction is ``O(s^2/(1 - 2 nu))``, below
    ``1e-5`` at ``s = 1e-3`` for ``nu <= 0.45``."""
    modulus, thickness, q = 2.0, 1e-3, np.array([1.0, 0.1])
    layer = PeriodicLayer(modulus, thickness, nu, "bonded")
    young = modulus * (1 - nu**2)
    oedometric = young * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    assert layer.stiffness(q) == pytest.approx(oedometric / thickness, rel=1e-5)


def test_a_thin_incompressible_bonded_layer_stiffens_as_one_over_t_cubed():
    """``nu = 1/2``: ``K -> 3 E*/(4 q^2 T^3)`` (``3 G/(q^2 T^3)``, the squeeze flow of a thin
    incompressible film), relative correction ``O(s^2)``; finite (no NaN) down to ``s = 1e-8``,
    non-increasing, and continuous as ``nu -> 1/2``: at ``1/2 - 1e-12`` ``f`` moves by
    ``3 (1 - 2 nu)/s^2`` relative, below ``1e-7`` from ``s = 1e-2``."""
    modulus, q = 1.0, 1.0
    for thickness in (1e-3, 1e-5):
        k = PeriodicLayer(modulus, thickness, 0.5).stiffness(np.array([q]))
        assert k == pytest.approx(3 * modulus / (4 * q**2 * thickness**3), rel=1e-5)
    s = np.geomspace(1e-8, 1e3, 50)
    incompressible = layer_factor(s, 0.5, "bonded")
    assert np.all(np.isfinite(incompressible)) and np.all(np.diff(incompressible) <= 0)
    near = layer_factor(s[s > 1e-2], 0.5 - 1e-12, "bonded")
    assert near == pytest.approx(incompressible[s > 1e-2], rel=1e-7)


def test_a_thin_frictionless_layer_slides():
    """Frictionless base: the layer slides, its in-plane stress vanishes and ``K -> E*/T``
    (plane strain: ``E/(1 - nu^2)``), with a correction ``O(s^4)``; independent of ``nu``."""
    modulus, thickness, q = 3.0, 1e-2, np.array([1.0, 0.5])
    for nu in (0.0, 0.5):
        k = PeriodicLayer(modulus, thickness, nu, "frictionless").stiffness(q)
        assert k == pytest.approx(modulus / thickness, rel=1e-7)


def test_the_mean_mode_carries_no_stiffness():
    """``q = 0`` is the load's (prescribed), so the multiplier is 0 there as on the
    half-space; the preconditioner's free mean-mode compliance is ``1/K(q0)``."""
    layer = PeriodicLayer(1.0, 0.01, 0.3)
    q = np.array([0.0, 2 * np.pi])
    k = layer.stiffness(q)
    assert k[0] == 0.0 and k[1] > np.pi
    assert layer.mean_mode_compliance(2 * np.pi, 0.0) == pytest.approx(1 / k[1], rel=1e-14)
    assert layer.mean_mode_compliance(2 * np.pi, 4.0) == 0.25


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ({"thickness": -1.0}, "--thickness must be positive"),
        ({"thickness": "0um"}, "--thickness must be positive"),
        ({"thickness": 0.1, "poisson": 0.6}, "--poisson must be from 0 to 0.5"),
        ({"thickness": 0.1, "poisson": -0.1}, "--poisson must be from 0 to 0.5"),
        ({"thickness": 0.1, "base": "glued"}, "--base must be one of bonded, frictionless"),
        ({"thickness": 0.1, "geometry": "punch"}, "--thickness is the periodic geometry's"),
        ({"thickness": 0.1, "hardness": 0.5}, "--thickness with --hardness"),
    ],
)
def test_a_layer_that_cannot_be_is_refused_in_one_line(given, message):
    with pytest.raises(ValueError, match=message):
        Run(grid=16, hurst=0.7, rms_slope=0.1, pressures=1e-3, **given)


SCENE = Run(
    grid=64, hurst=0.7, rms_slope=0.1, rolloff_ratio=2, cutoff_ratio=16, seed=3, pressures=1e-3
)


def solved(**changes):
    result = run_contact(SCENE.with_(**changes), progress=False)
    (step,) = result.steps
    assert step.converged
    return step.scalars


def test_a_layer_far_thicker_than_the_cell_is_the_half_space(petsc):
    """``T = 10 L``: ``f = 1`` to the last bit from ``s = 2 pi 10`` on, so the answer is the
    half-space's bit for bit, iterations included."""
    half, thick = solved(), solved(thickness=10.0)
    for name in ("mean_gap", "area_fraction", "iterations", "kkt_residual"):
        assert thick[name] == half[name]


def test_a_thin_layer_is_a_stiffer_contact(petsc):
    """A layer a quarter pixel thick (far below the shortest wavelength, 4 pixels) on a rigid
    base deforms less than the half-space: at the same load less area, a larger mean gap and
    a stiffer interface, the bonded base stiffer than the frictionless, the incompressible
    stiffest; each converges."""
    half = solved(stiffness=True)
    thin = {
        name: solved(thickness=1 / 256, stiffness=True, **given)
        for name, given in {
            "frictionless": {"base": "frictionless"},
            "bonded": {},
            "incompressible": {"poisson": 0.5},
        }.items()
    }
    order = [half, thin["frictionless"], thin["bonded"], thin["incompressible"]]
    for softer, stiffer in zip(order[:-1], order[1:], strict=True):
        assert stiffer["area_fraction"] < softer["area_fraction"]
        assert stiffer["mean_gap"] > softer["mean_gap"]
        assert stiffer["stiffness"] > softer["stiffness"]


def test_the_array_solver_and_tao_agree_on_a_layer(petsc):
    """The package's CG on NumPy arrays (``cpu-array``) and TAO's, both to ``1e-8 p0``: the
    mean gap to ``1e-8`` relative, the contact set the same, the exact stiffness to ``1e-8``
    (both held-set solves at ``rtol 1e-8``)."""
    layer = {"thickness": 1 / 128, "poisson": 0.45, "stiffness": True}
    tao = solved(**layer, options=("-tao_type", "bncg"))
    own = solved(**layer, device="cpu-array")
    assert own["mean_gap"] == pytest.approx(tao["mean_gap"], rel=1e-8)
    assert own["area_fraction"] == tao["area_fraction"]
    assert own["stiffness"] == pytest.approx(tao["stiffness"], rel=1e-6)


def test_the_exact_stiffness_of_a_layer_matches_the_sweep(petsc):
    """On a bonded layer of an eighth of the shortest wavelength, 1% pressure steps: the
    held-set stiffness (the layer's operator restricted to the open pixels) and
    ``-p d(ln p)/du_bar`` agree to 3%, as on the half-space (the contact set changes by a few
    pixels per step; the difference scheme is second order)."""
    p0 = np.geomspace(3e-3, 3.3e-3, 11)
    result = run_contact(
        SCENE.with_(pressures=tuple(p0), thickness=1 / 128, stiffness=True), progress=False
    )
    assert all(s.converged for s in result.steps)
    u = np.array([s.scalars["mean_gap"] for s in result.steps])
    exact = np.array([s.scalars["stiffness"] for s in result.steps])
    assert np.allclose(sweep_stiffness(p0, u)[2:-2], exact[2:-2], rtol=0.03)


def test_the_command_line_runs_a_layer_and_records_it(tmp_path):
    """``--thickness 2um`` on a cell of ``--length 128um`` is the layer of ``T = 2`` in the
    run's length unit: the same mean gap as ``Run(thickness=2.0)``, bit for bit, and the file
    records the layer's parameters; ``theory --compare`` refuses it."""
    import json

    import h5py

    from petsc_contact.paper.theory_run import check_compared
    from tests.conftest import cli

    out = tmp_path / "layer.h5"
    scene = ["--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "2"]
    layer = ["--thickness", "2um", "--poisson", "0.4", "--base", "frictionless"]
    done = cli("periodic", *scene, "--length", "128um", "--pressures", "1e-3", *layer,
               "--output", str(out), "--quiet")  # fmt: skip
    assert done.returncode == 0, done.stderr
    with h5py.File(out) as f:
        recorded = json.loads(f.attrs["parameters"])
        gap = f["mean_gap"][0]
    assert (recorded["thickness"], recorded["poisson"], recorded["base"]) == (
        "2um",
        0.4,
        "frictionless",
    )
    bare = Run(grid=32, hurst=0.7, rms_slope=0.1, seed=2, length=128.0, pressures=1e-3,
               thickness=2.0, poisson=0.4, base="frictionless")  # fmt: skip
    (step,) = run_contact(bare, progress=False).steps
    assert step.scalars["mean_gap"] == gap
    with pytest.raises(ValueError, match="a run on a layer .* the theory is the half-space's"):
        check_compared([str(out)], str(tmp_path / "theory.png"))  # Persson's is no layer's
