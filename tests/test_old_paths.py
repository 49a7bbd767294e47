"""The module paths from before the layer folders still import, warn, and give the same
objects as the new paths."""

import importlib
import sys

import pytest

from petsc_contact._moved import MOVED


def fresh(name):
    sys.modules.pop(name, None)
    return importlib.import_module(name)


def test_an_old_path_warns_and_gives_the_new_objects():
    from petsc_contact.geometries.periodic import PeriodicProblem
    from petsc_contact.physics.surface import self_affine

    with pytest.warns(DeprecationWarning, match="petsc_contact.physics.surface"):
        old = fresh("petsc_contact.surface")
    assert old.self_affine is self_affine
    with pytest.warns(DeprecationWarning, match="geometries.periodic"):
        assert fresh("petsc_contact.problem").PeriodicProblem is PeriodicProblem
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = old.nothing


def test_the_split_punch_module_offers_both_halves():
    from petsc_contact.geometries.punch import PunchProblem
    from petsc_contact.workflows.punch_sweep import PunchSolver, punch_contact

    with pytest.warns(DeprecationWarning, match="geometries.punch and .*punch_sweep"):
        old = fresh("petsc_contact.punch")
    assert old.PunchProblem is PunchProblem and old.PunchSolver is PunchSolver
    assert old.punch_contact is punch_contact and "verify_punch" in dir(old)


def test_an_old_module_is_an_attribute_of_the_package():
    import petsc_contact
    from petsc_contact.conventions.grid import Grid

    sys.modules.pop("petsc_contact.grid", None)
    vars(petsc_contact).pop("grid", None)
    with pytest.warns(DeprecationWarning, match="conventions.grid"):
        assert petsc_contact.grid.Grid is Grid
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = petsc_contact.nothing


@pytest.mark.parametrize("old", sorted(MOVED))
def test_every_old_path_leads_to_an_existing_module(old):
    with pytest.warns(DeprecationWarning):
        module = fresh(f"petsc_contact.{old}")
    assert dir(module), f"petsc_contact.{old} offers nothing"


def test_the_old_tao_python_type_still_solves(tmp_path):
    """``-tao_python_type petsc_contact.cg.PreconditionedCG`` (the type's old path, in users'
    options files) picks the same solver as the new path: the same iterations and gap."""
    import h5py
    from conftest import cli

    scene = "--grid 64 --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 2 --cutoff-ratio 16 --seed 4"
    gaps = []
    for path in ("petsc_contact.cg", "petsc_contact.backend.cg"):
        out = tmp_path / f"{path}.h5"
        run = cli(
            "periodic", *scene.split(), "--pressures", "1e-3", "--output", str(out), "--quiet",
            "-tao_type", "python", "-tao_python_type", f"{path}.PreconditionedCG",
        )  # fmt: skip
        assert run.returncode == 0, run.stderr
        with h5py.File(out) as f:
            assert f["converged"][0] and f["iterations"][0] > 0
            gaps.append((f["iterations"][0], f["mean_gap"][0]))
    assert gaps[0] == gaps[1]
