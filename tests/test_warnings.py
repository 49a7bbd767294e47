"""The library warns, the command line prints: a map with filled heights and a tilted map
give the same warnings through ``run_contact`` and ``petsc-contact``, each a
``PetscContactWarning``, kept in the result and in the file's ``warnings`` attribute."""

from __future__ import annotations

import json
import re
import warnings

import h5py
import numpy as np
import pytest
from conftest import cli
from test_measured import _map

from petsc_contact import Run, periodic_contact, run_contact
from petsc_contact.conventions.warnings import (
    DoubtfulMap,
    FilledLoad,
    PetscContactWarning,
    Unconverged,
)

PREFIX = "petsc-contact: warning: "


def _filled(tmp_path):
    """30% of the heights undefined, scattered: filled, they carry their share of the load."""
    h = _map()
    h[np.random.default_rng(1).random(h.shape) < 0.3] = np.nan
    np.save(tmp_path / "holes.npy", h)
    return tmp_path / "holes.npy", {"fill_undefined": "harmonic", "pressures": [3e-3, 1e-2]}


def _tilted(tmp_path):
    """A map on a slope: its opposite edges differ, a step at the seam of a periodic run."""
    h = _map()
    np.save(tmp_path / "tilted.npy", h + 5e-2 * np.arange(h.shape[0])[:, None] / h.shape[0])
    return tmp_path / "tilted.npy", {"pressures": [1e-3]}


def _arguments(options):
    """The command line's spelling of ``Run`` keywords."""
    out = []
    for name, value in options.items():
        given = ",".join(f"{v:g}" for v in value) if isinstance(value, list) else value
        out += [f"--{name.replace('_', '-')}", given]
    return out


def _on_the_command_line(text):
    """A library warning's text as the command line words it: each ``name="value"`` as the
    flag ``--name value`` (the geometry as its command, ``petsc-contact punch``)."""

    def flag(m):
        name, value = m.group(1), m.group(2)
        if name == "geometry":
            return f"petsc-contact {value}"
        return f"--{name.replace('_', '-')} {value}"

    return re.sub(r'(\w+)="([^"]*)"', flag, text)


def _recorded(path):
    with h5py.File(path) as f:
        return json.loads(f.attrs["warnings"])


@pytest.mark.parametrize(
    ("make", "kinds", "words"),
    [
        (_filled, [DoubtfulMap, FilledLoad], ["heights were undefined", "rests on filled"]),
        (_tilted, [DoubtfulMap], ["opposite edges differ"]),
    ],
)
def test_both_doors_give_the_same_warnings(tmp_path, make, kinds, words):
    path, options = make(tmp_path)
    with pytest.warns(PetscContactWarning) as caught:
        result = run_contact(Run(heights=str(path), output=str(tmp_path / "lib.h5"), **options))
    assert [w.category for w in caught] == kinds
    assert result.warnings == [str(w.message) for w in caught]
    assert all(word in text for word, text in zip(words, result.warnings, strict=True))
    assert result.record["warnings"] == result.warnings == _recorded(tmp_path / "lib.h5")

    out = ["--output", str(tmp_path / "cli.h5"), "--quiet"]
    r = cli("periodic", "--heights", str(path), *_arguments(options), *out)
    assert r.returncode == 0, r.stderr
    said = [line.removeprefix(PREFIX) for line in r.stderr.splitlines()]
    worded = [_on_the_command_line(text) for text in result.warnings]  # flags, not keywords
    assert said == worded, r.stderr  # one line each, nothing else
    assert _recorded(tmp_path / "cli.h5") == worded


def test_a_map_given_as_an_array_warns_the_same(tmp_path):
    """The tilted map as an array with its sides: the same warning as from its file, which
    the result keeps whatever the filters say of showing it."""
    path, options = _tilted(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from_file = run_contact(Run(heights=str(path), **options))
    with pytest.warns(DoubtfulMap):
        given = run_contact(Run(heights=np.load(path), length=1.0, **options))
    assert given.warnings == from_file.warnings and len(given.warnings) == 1
    with pytest.warns(DoubtfulMap) as said:  # the sweep functions warn as the runner does
        periodic_contact(np.load(path), length=1.0, pressures=options["pressures"])
    assert [str(w.message) for w in said if w.category is DoubtfulMap] == from_file.warnings


def test_package_warnings_can_be_errors(tmp_path):
    """One class for all: ``simplefilter("error", PetscContactWarning)`` stops the run before
    its output is touched."""
    path, options = _tilted(tmp_path)
    with warnings.catch_warnings(), pytest.raises(DoubtfulMap, match="opposite edges"):
        warnings.simplefilter("error", PetscContactWarning)
        run_contact(Run(heights=str(path), output=str(tmp_path / "o.h5"), **options))
    assert not list(tmp_path.glob("o.h5*"))


def test_unconverged_steps_warn_through_both_doors(tmp_path):
    """A step TAO leaves unconverged (``-tao_max_it 1``) is kept and flagged, and said: the
    library warns (:class:`Unconverged`, in the result and the file's ``warnings``), which
    the command line prints as its one line before exit status 1.  ``run_contact`` gave no
    warning before: only ``result.converged`` told."""
    scene = {"grid": 32, "hurst": 0.7, "rms_slope": 0.1, "pressures": [1e-3, 1e-2]}
    run = Run(**scene, options=("-tao_max_it", "1"), output=str(tmp_path / "lib.h5"))
    with pytest.warns(Unconverged, match="2 of 2 load steps did NOT converge") as caught:
        result = run_contact(run)
    assert not result.converged and result.status == "complete"
    assert result.warnings == [str(w.message) for w in caught if w.category is Unconverged]
    assert "(first: step 1, TAO did not converge (DIVERGED_MAXITS))" in result.warnings[0]
    assert _recorded(tmp_path / "lib.h5") == result.warnings
    with pytest.warns(Unconverged, match="2 of 2 load steps"):  # resumed on its complete file
        again = run_contact(run.with_(resume=True))
    assert again.steps == [] and again.warnings == result.warnings
    out = str(tmp_path / "cli.h5")
    given = ("--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--pressures", "1e-3,1e-2")
    r = cli("periodic", *given, "--output", out, "--quiet", "-tao_max_it", "1")
    said = [line.removeprefix(PREFIX) for line in r.stderr.splitlines()]
    assert r.returncode == 1 and said == [result.warnings[0].replace("lib.h5", "cli.h5")]
    # warnings made errors: the file is whole first, then the run raises
    strict = run.with_(output=str(tmp_path / "strict.h5"))
    with warnings.catch_warnings(), pytest.raises(Unconverged, match="2 of 2 load steps"):
        warnings.simplefilter("error", PetscContactWarning)
        run_contact(strict)
    assert _recorded(tmp_path / "strict.h5") == [result.warnings[0].replace("lib.h5", "strict.h5")]
    assert not list(tmp_path.glob("strict.h5.*"))
    # the sweep functions say it too
    with pytest.warns(Unconverged, match=r"2 of 2 load steps did NOT converge \(first: step 1"):
        periodic_contact(_map(), length=1.0, pressures=[1e-3, 1e-2], options=("-tao_max_it", "1"))
