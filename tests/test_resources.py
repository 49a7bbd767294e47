"""The memory a run is refused for: the estimate covers what a whole command takes, and a run
that would not fit is refused in one line before anything is allocated."""

from __future__ import annotations

import pytest
from conftest import cli, python

from petsc_contact.conventions.resources import estimated_bytes

PEAK = """
import sys
from petsc_contact.cli.main import main
code = main(sys.argv[1:])
with open("/proc/self/status") as f:  # this process's own peak (getrusage's includes the parent's)
    print(code, next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmHWM")))
"""


def peak_bytes(*args: str) -> int:
    """The peak resident memory of one ``petsc-contact`` command in a fresh process."""
    r = python("-c", PEAK, *args, "--quiet", timeout=600)
    code, peak = r.stdout.split()[-2:]
    assert r.returncode == 0 and code == "0", r.stdout + r.stderr
    return int(peak)


@pytest.mark.parametrize("geometry", ["periodic", "punch"])
def test_the_estimate_covers_a_whole_run(geometry, tmp_path):
    """A 512^2 run with the exact stiffness and an output file (its resume state written at
    every step) needs at most the estimate over what a 64^2 run of the same command needs
    (the process and its imports), and not less than 0.8 of it (an estimate that refuses
    runs that fit is a defect too)."""
    loads = ["--sweep", "4,1e-6,1e-2"] if geometry == "periodic" else ["--approaches", "2e-3,5e-3"]
    base = [geometry, "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "1", *loads]
    out = ["--stiffness", "--output", str(tmp_path / "o.h5"), "--overwrite"]
    small = peak_bytes(*base, "--grid", "64", *out)
    large = peak_bytes(*base, "--grid", "512", "--cutoff-ratio", "256", *out)
    need = estimated_bytes(512**2, geometry)
    assert 0.8 * need <= large - small <= need, (large - small) / 512**2


def test_a_run_that_does_not_fit_is_refused_in_one_line(tmp_path):
    args = ["--grid", "65536", "--hurst", "0.7", "--rms-slope", "0.1", "--pressures", "1e-3"]
    r = cli("periodic", *args, "--output", str(tmp_path / "o.h5"))
    assert r.returncode != 0 and "Traceback" not in r.stderr, r.stderr
    assert "GiB" in r.stderr and "--skip-memory-check" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "o.h5").exists()


AFTER = """
import sys
from petsc_contact import Run, run_contact
from petsc_contact.conventions.resources import release_freed


def rss():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmRSS"))


base = Run(hurst=0.5, rms_slope=0.1, sweep=(3, 1e-6, 1e-3), output=sys.argv[1], overwrite=True)
run_contact(base.with_(grid=64))  # the imports and caches a run loads
release_freed()
before = rss()
run_contact(base.with_(grid=1024))
held = rss()
release_freed()
print(before, held, rss())
"""


def test_a_finished_run_gives_its_memory_back_before_the_next_check(tmp_path):
    """A study runs its pieces in one process: what the last piece freed is given back before
    the next piece's check reads the memory available (it held on to most of a run's peak)."""
    r = python("-c", AFTER, str(tmp_path / "o.h5"), timeout=300)
    assert r.returncode == 0, r.stderr
    before, held, after = (int(v) for v in r.stdout.split()[-3:])
    assert held - before > 0.5 * estimated_bytes(1024**2, "periodic"), (before, held)
    assert after - before < 0.25 * (held - before), (before, held, after)
