"""Paper Eq. 2's flat-punch reference: the exact square, King's estimate, the grid's value."""

import warnings

import numpy as np
import pytest

from petsc_contact.geometries import punch
from petsc_contact.reference import flat_punch
from petsc_contact.workflows.punch_sweep import punch_contact

EXACT = 1.15230  # pi C E* L, C = 0.3667874 (Read 1997): the rigid square's stiffness / (E* L)
KING = 1.14192  # 1.012 x 2 E* L / sqrt(pi)


def flat(n, **kw):
    """The scalars of a flat square punch of side 1 (``E* = 1``) on ``n x n`` pixels."""
    (step,) = punch_contact(np.zeros((n, n)), length=1.0, modulus=1.0, approaches=[1e-3], **kw)
    assert step.converged
    return step.scalars


def test_constants():
    """The square's exact stiffness from its capacitance; King's beta 0.9% below it."""
    assert flat_punch.square_stiffness(1.0, 1.0) == pytest.approx(EXACT, rel=1e-5)
    assert flat_punch.stiffness(1.0, 1.0) == pytest.approx(EXACT, rel=1e-5)
    square, king = flat_punch.SQUARE_BETA, flat_punch.KING_BETA
    assert square == pytest.approx(1.0212, abs=1e-4)
    assert flat_punch.stiffness(2.0, 3.0, king) == pytest.approx(KING * 3 * np.sqrt(2), rel=1e-5)
    assert king / square - 1 == pytest.approx(-0.009, abs=5e-4)


def test_grid_flat_punch_converges_to_the_exact_square():
    """The same grid's flat punch approaches ``pi C E* L`` from below as ``1/n``: measured,
    0.0105, 0.0053, 0.0027 below it at 32, 64, 128 pixels a side (0.017% at 2048, the paper's
    punch files), so each doubling halves the error (ratios 1.9-2.1 asked), 128 pixels are
    within 0.3%, and the Richardson extrapolation ``2 K_128 - K_64`` within 0.02% (it is
    0.005% off)."""
    k = {n: flat(n)["flat_punch_stiffness"] for n in (32, 64, 128)}
    errors = [EXACT - k[n] for n in (32, 64, 128)]
    assert all(e > 0 for e in errors)
    assert errors[0] / errors[1] == pytest.approx(2.0, abs=0.1)
    assert errors[1] / errors[2] == pytest.approx(2.0, abs=0.1)
    assert k[128] == pytest.approx(EXACT, rel=3e-3)
    assert 2 * k[128] - k[64] == pytest.approx(EXACT, rel=2e-4)


@pytest.mark.parametrize(
    ("reference", "expected", "beta"), [("analytic", EXACT, 1.0212), ("king", KING, 1.012)]
)
def test_analytic_and_king(reference, expected, beta):
    """``analytic`` is the exact square, ``king`` King's estimate; each step records both
    ``K_flat`` and its shape factor, and Eq. 2 uses that ``K_flat``."""
    s = flat(16, flat_stiffness=reference)
    assert s["flat_punch_stiffness"] == pytest.approx(expected, rel=1e-5)
    assert s["flat_punch_beta"] == pytest.approx(beta, abs=1e-4)
    assert s["full_contact"] and np.isnan(s["interfacial_stiffness"])  # Eq. 2 is noise there
    heights = np.random.default_rng(1).normal(size=(16, 16)) * 1e-2
    (step,) = punch_contact(heights, length=1.0, approaches=[1e-2], flat_stiffness=reference)
    r = step.scalars
    assert step.converged and not r["full_contact"]
    assert r["flat_punch_stiffness"] == s["flat_punch_stiffness"]
    assert r["interfacial_stiffness"] == pytest.approx(
        punch.interfacial_stiffness(r["total_stiffness"], r["flat_punch_stiffness"]), rel=1e-12
    )


def test_grid_records_its_beta():
    """The grid's reference records the shape factor of its own flat punch."""
    s = flat(16)
    assert s["flat_punch_beta"] == pytest.approx(
        s["flat_punch_stiffness"] * np.sqrt(np.pi) / 2, rel=1e-12
    )


def test_king_is_for_the_square_only():
    """King's estimate is refused on the disk (whose analytic value is exact) and on a mask."""
    with pytest.raises(ValueError, match="king is King's estimate for a square footprint"):
        flat(16, flat_stiffness="king", footprint="disk")
    mask = np.ones((16, 16), dtype=bool)
    mask[0] = False
    with pytest.raises(ValueError, match="not square"):
        flat(16, flat_stiffness="king", footprint=mask)
    with pytest.raises(ValueError, match="grid, analytic, king"):
        flat(16, flat_stiffness="pharr")
    s = flat(16, flat_stiffness="analytic", footprint="disk")
    assert s["flat_punch_beta"] == 1.0


def test_pharr_beta_is_deprecated():
    """``geometries.punch.PHARR_BETA`` still reads King's 1.012, with a warning."""
    with pytest.warns(DeprecationWarning, match="KING_BETA"):
        assert punch.PHARR_BETA == flat_punch.KING_BETA
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert punch.flat_punch_stiffness(1.0, 1.0) == pytest.approx(EXACT, rel=1e-5)
