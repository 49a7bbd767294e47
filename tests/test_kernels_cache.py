"""The numba kernels are compiled once, before any step: by the set-up
(``python -m petsc_contact.numerics.kernels``), or else when a problem is set up, saying so
in one line; no step's recorded time holds a compilation."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import h5py
import pytest
from conftest import ROOT, cli, python

from petsc_contact.devices import compiled
from petsc_contact.numerics import aggregates, kernels

pytestmark = pytest.mark.slow  # compiles every kernel: started first (tests/conftest.py)

SCENE = ("--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "1", "--quiet")


def _cached(cache: Path) -> set[str]:
    """The compiled kernels numba's cache holds (one file per kernel and argument types)."""
    return {p.name for p in cache.rglob("*.nbc")}


@pytest.fixture(scope="module")
def setup_cache(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """A cache filled by the set-up's step on an empty folder, and what that step printed."""
    cache = tmp_path_factory.mktemp("numba-setup")
    with pytest.MonkeyPatch.context() as env:
        env.setenv("NUMBA_CACHE_DIR", str(cache))
        r = python("-m", "petsc_contact.numerics.kernels")
    assert r.returncode == 0, r.stderr
    assert kernels.COLD_CACHE not in r.stderr  # the set-up says it in its own line
    return cache, r.stdout


def _seconds(setup_line: str) -> float:
    found = re.fullmatch(r"numba kernels compiled \((\d+) kernels, ([\d.]+) s\)\n", setup_line)
    assert found, setup_line
    assert int(found.group(1)) == len(_warmed())
    return float(found.group(2))


RUNS = """
import sys
from petsc_contact.cli.main import main
from petsc_contact.numerics import kernels

kernels.main()  # the set-up's step again: it loads every kernel, compiling none
for k, args in enumerate(
    [
        ["periodic", "--pressures", "1e-3,1e-2", "--stiffness"],
        ["punch", "--approaches", "0.01", "--footprint", "disk", "--stiffness"],
        ["periodic", "--pressures", "1e-3", "-tao_type", "blmvm"],
        ["punch", "--approaches", "0.01", "--footprint", "disk", "-tao_type", "blmvm"],
    ]
):
    if main([*args, *sys.argv[2:], "--output", f"{sys.argv[1]}/run{k}.h5"]):
        sys.exit(f"failed: {args}")
"""


def test_setup_compiles_every_kernel_and_runs_compile_nothing(setup_cache, monkeypatch):
    """After the set-up's step, the step run again in a fresh process loads every kernel
    from the cache (compiling none), and runs in that process then add nothing to the cache
    and say nothing, on the paths that pass the kernels other types: read-only Vec arrays
    (the stiffness solve, the ``blmvm`` preconditioner), an upper bound per pixel (the
    punch's disk footprint). One process makes the four runs: a kernel compiled for other
    types is compiled when a run first calls it, and written to the cache then."""
    cache, printed = setup_cache
    _seconds(printed)
    cached = _cached(cache)
    assert len(cached) >= len(compiled.specimen_calls()) + len(aggregates.specimen_calls())
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    script = cache.parent / "runs.py"
    script.write_text(RUNS)
    r = python(str(script), str(cache.parent), *SCENE)
    assert r.returncode == 0, r.stderr
    assert kernels.COLD_CACHE not in r.stderr, r.stderr
    assert _cached(cache) == cached, "a run compiled a kernel for other types"
    assert re.fullmatch(
        r"numba kernels loaded from the cache \(\d+ kernels, [\d.]+ s\)\n", r.stdout
    ), r.stdout


def test_a_cold_cache_says_so_once_and_no_step_times_it(setup_cache, tmp_path, monkeypatch):
    """On an empty cache a run says :data:`~petsc_contact.numerics.kernels.COLD_CACHE` once
    and compiles before its first step: that step's ``solve_time`` is a small part of the
    compilation (several seconds, measured by the set-up's step).  The step uses the
    two-level form (25% contact with ``max_fraction`` 0.9), whose parallel kernels take most
    of the compilation: compiled in the step, its ``solve_time`` was 3.2 s, not 0.03 s.
    The next run on the same cache says nothing."""
    compile_seconds = _seconds(setup_cache[1])
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    run = ("periodic", "--pressures", "1e-2,2e-2", "-petsc_contact_two_level_max_fraction", "0.9")
    for name in ("cold", "warm"):
        r = cli(*run, *SCENE, "--output", str(tmp_path / f"{name}.h5"), process=True)
        assert r.returncode == 0, r.stderr
        with h5py.File(tmp_path / f"{name}.h5") as f:
            first = float(f["solve_time"][0])
        assert first < compile_seconds / 5, (name, first, compile_seconds)
        said = r.stderr.splitlines().count(kernels.COLD_CACHE)
        assert said == (name == "cold"), r.stderr


def _warmed() -> set[tuple[str, str]]:
    """``(module, name)`` of every kernel :func:`~petsc_contact.numerics.kernels.compile_kernels`
    calls."""
    calls = compiled.specimen_calls() + aggregates.specimen_calls()
    return {(k.py_func.__module__, k.py_func.__name__) for k, _ in calls}


def test_every_numba_kernel_of_the_package_is_compiled_at_setup():
    """Every ``@njit`` function of the package is called by the set-up's compilation, or
    only from kernels it calls (compiled with them)."""
    warmed = _warmed()
    for path in (ROOT / "petsc_contact").rglob("*.py"):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        tree = ast.parse(path.read_text())
        functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
        jitted = {
            name
            for name, node in functions.items()
            if any("njit" in ast.unparse(d) for d in node.decorator_list)
        }
        callers = [functions[name] for mod, name in warmed if mod == module]
        called = {n.id for f in callers for n in ast.walk(f) if isinstance(n, ast.Name)}
        missing = {name for name in jitted if (module, name) not in warmed} - called
        assert not missing, f"{module}: {missing} are not compiled at set-up (specimen_calls)"
