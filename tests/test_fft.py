"""The serial FFT backend keeps FFTW's measured plans on disk between runs, with the threads
it is given."""

import os

import pytest
from conftest import python

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import THREADS_VARIABLE, SerialFFT, default_threads

SCRIPT = r"""
import pyfftw
from petsc_contact.devices.fft import SerialFFT, _Wisdom
from petsc_contact.conventions.grid import Grid
_Wisdom.load(pyfftw)
before = pyfftw.export_wisdom()
SerialFFT(Grid(96, 1.0), threads=1)
print("measured" if pyfftw.export_wisdom() != before else "reused")
"""


def run() -> str:
    r = python("-c", SCRIPT, timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout.strip()


def test_wisdom_reused_by_the_next_run(tmp_path, monkeypatch):
    """The first process measures and writes the file; the next one plans from it without
    measuring; an unreadable file is ignored and replaced; ``off`` writes nothing."""
    path = tmp_path / "wisdom"
    monkeypatch.setenv("PETSC_CONTACT_FFTW_WISDOM", str(path))
    assert run() == "measured" and path.stat().st_size > 0
    kept = path.read_bytes()
    assert run() == "reused" and path.read_bytes() == kept
    path.write_bytes(b"not wisdom")
    assert run() == "measured" and path.read_bytes() != b"not wisdom"
    monkeypatch.setenv("PETSC_CONTACT_FFTW_WISDOM", "off")
    path.unlink()
    assert run() == "measured" and not path.exists()


def test_the_threads_variable_sets_the_serial_fft_s_threads(monkeypatch):
    """``PETSC_CONTACT_FFT_THREADS`` gives the serial FFT its threads; unset, the cores this
    process may use; a value that is not a whole number >= 1 is refused, naming it."""
    monkeypatch.setenv(THREADS_VARIABLE, "3")
    assert default_threads() == 3 and SerialFFT(Grid(16, 1.0)).threads == 3
    monkeypatch.delenv(THREADS_VARIABLE)
    assert default_threads() == len(os.sched_getaffinity(0))
    for bad in ("0", "two", "-1", "1.5"):
        monkeypatch.setenv(THREADS_VARIABLE, bad)
        with pytest.raises(ValueError, match=THREADS_VARIABLE):
            default_threads()
