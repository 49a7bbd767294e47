"""The notebook and script user: a progress bar where a person watches and none where the
output is captured, tables a notebook shows, ``dir(petsc_contact)`` listing the API, and
warnings that name Python's keywords at the caller's own line."""

from __future__ import annotations

import io
import sys
import types
import warnings

import numpy as np
import pytest
from conftest import python
from test_warnings import _tilted

import petsc_contact
import petsc_contact.io.progress as progress_module
from petsc_contact import Run, periodic_contact, predict_map, punch_contact, run_contact
from petsc_contact.conventions.warnings import (
    DoubtfulMap,
    PetscContactWarning,
    Unconverged,
    UnusedOptions,
    command_line,
    option,
)
from petsc_contact.paper.predictions import TheoryWarning

SCENE = {"grid": 32, "hurst": 0.7, "rms_slope": 0.1, "pressures": [1e-3, 1e-2]}


class Terminal(io.StringIO):
    """Standard error as a terminal: what is written to it is kept."""

    def isatty(self) -> bool:
        return True


def test_a_bar_on_a_terminal_redrawn_in_place(monkeypatch):
    """``run_contact`` without ``progress``: one line rewritten after ``\\r`` on a terminal,
    each step's count, the iterations within a step, and a new line at the end."""
    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    monkeypatch.setattr(progress_module, "EVERY", 0.0)  # every iteration redraws
    result = run_contact(Run(**SCENE))
    shown = terminal.getvalue()
    assert result.status == "complete"
    assert shown.startswith("\r[") and shown.endswith("\n") and shown.count("\n") == 1
    assert "0/2 steps" in shown and "1/2 steps" in shown and "2/2 steps" in shown
    assert "step 1: iteration" in shown and "step 2: iteration" in shown


def test_no_bar_where_the_output_is_captured(monkeypatch):
    """A captured standard error (no terminal, no notebook), ``progress=False`` on a
    terminal, and a user's callback in the bar's place: nothing written."""
    captured = io.StringIO()
    monkeypatch.setattr(sys, "stderr", captured)
    run_contact(Run(**SCENE))
    assert captured.getvalue() == ""

    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    run_contact(Run(**SCENE), progress=False)
    told = []
    run_contact(Run(**SCENE), lambda i, total, scalars: told.append((i, total)))
    run_contact(Run(**SCENE), progress=None)  # as before: nothing
    assert terminal.getvalue() == ""
    assert told == [(0, 2), (1, 2)]


def test_the_bar_calls_the_users_monitor_and_sweeps_show_it(monkeypatch, tmp_path):
    """``periodic_contact`` shows the bar too; a ``monitor`` given beside it is still told of
    every iteration (and can stop the solve)."""
    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    iterations = []
    h = np.load(_tilted(tmp_path)[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PetscContactWarning)
        steps = periodic_contact(
            h, length=1.0, pressures=[1e-3, 2e-3], monitor=lambda *a: iterations.append(a[0])
        )
    assert len(steps) == 2 and iterations and 0 in iterations
    assert "2/2 steps" in terminal.getvalue()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PetscContactWarning)
        stopped = periodic_contact(h, length=1.0, pressures=1e-3, monitor=lambda it, *_: it >= 1)
    assert stopped[0].scalars["iterations"] <= 1 and not stopped[0].converged


def test_a_warning_goes_below_the_bar(monkeypatch, tmp_path):
    """A warning shown during a run starts on its own line: the bar's line is ended first."""
    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    path, options = _tilted(tmp_path)

    def to_stderr(message, category, filename, lineno, file=None, line=None):
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno))

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = to_stderr
        run_contact(Run(heights=str(path), **options), progress=True)
        monkeypatch.setattr(progress_module, "EVERY", 0.0)
        run_contact(Run(**SCENE, options=("-tao_max_it", "1")))  # warns before the bar ends
    lines = terminal.getvalue().split("\n")
    assert any("2/2 steps" in line for line in lines)
    warned = [line for line in lines if __file__ in line]
    assert any("Unconverged" in line for line in warned), lines
    assert all(line.startswith(__file__) for line in warned), lines  # none after a bar


def test_a_notebook_gets_an_updating_display(monkeypatch):
    """In a notebook (an IPython kernel's shell), one display, updated in place with an HTML
    ``<progress>``; nothing on standard error."""
    shown, updates = [], []

    class Handle:
        def update(self, obj):
            updates.append(obj.data)

    class HTML:
        def __init__(self, data):
            self.data = data

    def display(obj, display_id=False):
        shown.append(obj.data)
        return Handle()

    kernel_shell = types.SimpleNamespace(kernel=object())
    fake = types.ModuleType("IPython")
    fake.get_ipython = lambda: kernel_shell
    fake.display = types.SimpleNamespace(HTML=HTML, display=display)
    monkeypatch.setitem(sys.modules, "IPython", fake)
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    run_contact(Run(**SCENE))
    assert len(shown) == 1 and "<progress" in shown[0] and "0/2 steps" in shown[0]
    assert '<progress value="2" max="2">' in updates[-1] and "2/2 steps" in updates[-1]
    assert sys.stderr.getvalue() == ""


def test_sweeps_return_a_table_and_results_display_as_tables(tmp_path):
    """``periodic_contact`` and ``punch_contact`` return a list of steps that is also a
    table; ``RunResult``, ``Prediction`` and ``Run`` display in a notebook as tables."""
    h = np.load(_tilted(tmp_path)[0]) * 0.1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PetscContactWarning)
        steps = periodic_contact(h, length=1.0, pressures=[1e-3, 2e-3])
        punched = punch_contact(h[:16, :16], length=1.0, approaches=[1e-5, 2e-5])
    assert isinstance(steps, list) and steps[0].scalars["converged"] in (True, False)
    frame = steps.to_dataframe()
    assert list(frame.index) == [1, 2] and "mean_gap" in frame.columns
    assert "<table" in steps._repr_html_() and "mean_gap" in steps._repr_html_()
    assert len(punched.to_dataframe()) == 2 and "approach" in punched._repr_html_()

    result = run_contact(Run(**SCENE))
    page = result._repr_html_()
    assert "periodic run" in page and "complete" in page and "mean_gap" in page
    run_page = Run(**SCENE)._repr_html_()
    assert "hurst" in run_page and "0.7" in run_page and "seed" not in run_page
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PetscContactWarning)
        prediction = predict_map(h, length=1.0)
    assert "hurst_fit" in prediction._repr_html_() and "nominal pressures" in (
        prediction._repr_html_()
    )


def test_dir_lists_the_public_api_without_loading_it():
    """``dir(petsc_contact)`` lists ``Run`` and the rest of the API, not ``os``, and loads
    none of it (no numba, no PETSc)."""
    assert {"Run", "run_contact", "periodic_contact", "predict_map"} <= set(dir(petsc_contact))
    assert "os" not in dir(petsc_contact) and "PUBLIC" not in dir(petsc_contact)
    r = python(
        "-c",
        "import sys, petsc_contact; names = dir(petsc_contact); "
        "print('Run' in names, 'numba' in sys.modules, 'petsc4py' in sys.modules)",
    )
    assert r.stdout.split() == ["True", "False", "False"], r.stderr


def test_warnings_name_keywords_at_the_callers_line(tmp_path):
    """A warning from ``run_contact``, ``periodic_contact`` and ``predict_map`` is attributed
    to this file's line that called them, and names the Python keyword, not the flag."""
    path, options = _tilted(tmp_path)
    with pytest.warns(DoubtfulMap) as caught:
        run_contact(Run(heights=str(path), **options))
    (tilt,) = caught
    assert tilt.filename == __file__
    assert 'detrend="slope"' in str(tilt.message) and "--" not in str(tilt.message)
    assert 'geometry="punch"' in str(tilt.message)

    with pytest.warns(PetscContactWarning) as caught:
        periodic_contact(np.load(path), length=1.0, pressures=1e-3, options="-tao_max_it 1")
    assert [w.category for w in caught] == [DoubtfulMap, Unconverged]
    assert all(w.filename == __file__ for w in caught)
    with pytest.warns(UnusedOptions) as caught:  # said as a with block of the package ends
        run_contact(Run(**SCENE, options=("-tao_misspelt", "1")))
    assert [w.filename for w in caught] == [__file__]

    noise = np.random.default_rng(0).standard_normal((64, 64))  # no power law: H far off
    with pytest.warns(PetscContactWarning) as caught:
        predict_map(noise, length=1.0)
    assert TheoryWarning in [w.category for w in caught]
    assert all(w.filename == __file__ for w in caught)
    assert any("(length, height_unit)" in str(w.message) for w in caught)  # Python's names


def test_each_door_spells_an_option_its_way():
    """One place names an option: a keyword from Python, a flag on the command line."""
    assert option("detrend", "slope") == 'detrend="slope"'
    assert option("stop_after", 1.5) == "stop_after=1.5"
    assert option("height_unit") == "height_unit"
    with command_line():
        assert option("detrend", "slope") == "--detrend slope"
        assert option("height_unit") == "--height-unit"
        assert option("geometry", "punch") == "petsc-contact punch"
        assert option("overwrite", True) == "--overwrite"
    assert option("overwrite", True) == "overwrite=True"
    assert option("geometry", "punch") == 'geometry="punch"'
