"""Shared helpers: run the CLI as a user does, and build grids in-process."""

from __future__ import annotations

import contextlib
import ctypes
import gc
import importlib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import traceback
import warnings
from collections.abc import Callable
from pathlib import Path

# as the package sets them for its command line (petsc_contact/__init__.py), before numpy is
# imported: a threaded BLAS beside FFTW's threads slows every in-process run many times
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np
import pytest

from petsc_contact.devices.fft import THREADS_VARIABLE

# -n N's workers share the cores: one FFT thread each (and in the processes they start), not
# one per core each, whose contention took a fifth more CPU (the README's commands, 2 cores)
if int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) > 1:
    os.environ.setdefault(THREADS_VARIABLE, "1")

ROOT = Path(__file__).resolve().parents[1]


def cli(
    *args: str, mpi: int = 0, process: bool = False, timeout: float = 300
) -> subprocess.CompletedProcess:
    """Run ``petsc-contact ARGS``: in this process by default (:func:`cli_in_process`), in a
    fresh interpreter with ``process=True`` (a test of the process: signals, pipes, the
    environment, what a start loads, the exit), under ``mpiexec -n mpi`` if ``mpi``."""
    if mpi or process:
        return python("-m", "petsc_contact.cli", *args, mpi=mpi, timeout=timeout)
    return cli_in_process(*args)


def cli_in_process(*args: str) -> subprocess.CompletedProcess:
    """``petsc_contact.cli.main.main(ARGS)`` in this process, as a subprocess would report it
    (:func:`in_process`)."""
    entry = importlib.import_module("petsc_contact.cli.main")  # the module, not the function
    return in_process(["petsc-contact", *args], lambda: entry.main(list(args)))


def in_process(argv: list[str], call: Callable[[], int | None]) -> subprocess.CompletedProcess:
    """``call()`` in this process, reported as the subprocess running ``argv`` would be: the
    exit status (its return value, a ``SystemExit``'s, or 1 after an uncaught exception's
    traceback) and the text written on file descriptors 1 and 2 (PETSc's too), with the
    process's state restored afterwards (signal handlers, standard streams, hooks, warning
    filters, the environment, the working directory, PETSc's options database)."""
    from petsc_contact.backend import _petsc

    petsc = _petsc.init([])  # initialised once, so that a call's options are inserted, not kept
    database = petsc.Options()
    options_before = database.getAll()
    handlers = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT, signal.SIGPIPE)}
    streams = (sys.stdout, sys.stderr, sys.stdin)
    hook = sys.unraisablehook
    environ = dict(os.environ)
    cwd = os.getcwd()
    done_kernels = _kernels_done()
    saved_fds = (os.dup(1), os.dup(2))
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            with warnings.catch_warnings(), contextlib.ExitStack() as files:
                os.environ.pop("PETSC_DIR", None)  # the package must find PETSc by itself
                text = {"encoding": "utf-8", "closefd": False, "buffering": 1}
                sys.stdout = files.enter_context(open(1, "w", **text))
                sys.stderr = files.enter_context(open(2, "w", **text))
                sys.stdin = files.enter_context(open(os.devnull))
                try:
                    status = call()
                except SystemExit as exc:
                    code = exc.code
                    status = code if isinstance(code, int) else (0 if code is None else 1)
                    if code is not None and not isinstance(code, int):
                        print(code, file=sys.stderr)
                except BaseException:  # as the interpreter reports an uncaught exception
                    traceback.print_exc()
                    status = 1
                for stream in (sys.stdout, sys.stderr):
                    with contextlib.suppress(Exception):
                        stream.flush()
                _libc_flush()
        finally:
            sys.stdout, sys.stderr, sys.stdin = streams
            os.dup2(saved_fds[0], 1)
            os.dup2(saved_fds[1], 2)
            for fd in saved_fds:
                os.close(fd)
            for signum, handler in handlers.items():
                signal.signal(signum, handler)
            sys.unraisablehook = hook
            os.environ.clear()
            os.environ.update(environ)
            os.chdir(cwd)
            _restore_options(database, options_before)
            _kernels_done(done_kernels)
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace")
        stderr = err.read().decode("utf-8", "replace")
    return subprocess.CompletedProcess(argv, int(status or 0), stdout, stderr)


def _restore_options(database, before: dict) -> None:
    """PETSc's options database as it was: a call's options deleted, changed ones reset."""
    for name, value in database.getAll().items():
        if name not in before:
            database.delValue(name)
        elif before[name] != value:
            database.setValue(name, before[name])
    for name, value in before.items():
        if not database.hasName(name):
            database.setValue(name, value)


def _libc_flush() -> None:
    """Flush C's ``stdout`` and ``stderr`` (PETSc's monitors print there), buffered in a file."""
    libc = ctypes.CDLL(None)
    libc.fflush(None)


def _kernels_done(value: bool | None = None) -> bool:
    """Whether the numba kernels were compiled in this process (set with ``value``): a fresh
    process compiles (or loads) them, and says so on a cold cache."""
    from petsc_contact.numerics import kernels

    if value is not None:
        kernels._done = value
    return kernels._done


def python(*args: str, mpi: int = 0, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run this interpreter with ``ARGS`` (under ``mpiexec -n mpi`` if ``mpi``), as root too."""
    cmd = [sys.executable, *args]
    if mpi:
        cmd = [shutil.which("mpiexec") or "mpiexec", "--oversubscribe", "-n", str(mpi), *cmd]
    env = dict(os.environ)
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", PYTHONPATH=str(ROOT))
    env.pop("PETSC_DIR", None)  # the package must find PETSc by itself
    return subprocess.run(
        cmd, capture_output=True, text=True, timeout=timeout, env=env, stdin=subprocess.DEVNULL
    )


# what the command line's runs import and keep for the life of the process
WARM = ("petsc_contact.cli.main", "petsc_contact.cli.runs", "petsc_contact.cli.study",
        "petsc_contact.cli.comparison", "petsc_contact.cli.ensemble_command",
        "petsc_contact.cli.theory_command",
        "petsc_contact.cli.tools", "petsc_contact.workflows.runner", "petsc_contact.io.plot",
        "h5py", "matplotlib.pyplot", "mpi4py.MPI", "pandas", "scipy.sparse")  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first, in their order, then the rest: ``-n 2`` (with
    pyproject's ``--dist loadfile``: a file's tests together on one worker) hands the files
    out in this order as its workers free up, so the longest are not left for the end, when
    one worker would run them while the other idles (a worker's last file is a short one)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


def pytest_collection_finish(session: pytest.Session) -> None:
    """Exempt what a test process keeps for its whole life from Python's cyclic garbage
    collection (``gc.freeze``): the modules the command line's runs import (:data:`WARM`),
    PETSc and the numba kernels loaded. The command line collects garbage fully at each run
    (its memory check, its PETSc clean-up): in a worker holding some 230,000 such objects,
    each collection read them all, 0.1 s, 17% of tests/test_cli.py's time; frozen, it reads
    only what the tests made since. Cycles made later are collected as before."""
    for name in WARM:
        importlib.import_module(name)
    from petsc_contact.backend import _petsc
    from petsc_contact.numerics import kernels

    _petsc.init([])
    done = _kernels_done()
    kernels.compile_kernels(announce=False)
    _kernels_done(done)  # a run still compiles (or loads) them as in a fresh process
    gc.collect()
    gc.freeze()


@pytest.fixture(scope="session")
def petsc():
    from petsc_contact.backend import _petsc

    return _petsc.init([])


def smooth_map(shape=(48, 32), seed=0, amplitude=1e-3):
    """A smooth periodic map (a few Fourier modes), rms slope about 0.03 on a unit cell."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(*(np.arange(n) / n for n in shape), indexing="ij")
    h = sum(
        rng.standard_normal() * np.cos(2 * np.pi * (i * x + j * y) + rng.uniform(0, 2 * np.pi))
        for i in range(1, 4)
        for j in range(-3, 4)
    )
    return amplitude * h
