"""Shared helpers: run the CLI as a user does, and build grids in-process."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def cli(*args: str, mpi: int = 0, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run ``petsc-contact ARGS`` (under ``mpiexec -n mpi`` if ``mpi``) with this interpreter."""
    return python("-m", "petsc_contact.cli", *args, mpi=mpi, timeout=timeout)


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
