"""setup.sh's package step, run with stand-in ``dpkg-query`` and ``apt-get`` first on PATH
(nothing on the machine is queried or installed), and shellcheck on the shell scripts."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT

# dpkg-query -W -f=FORMAT PACKAGE: every package is installed ("ii ") except those named in
# $STANDIN_MISSING (one "name" or "name status" a line: never seen, or seen with that status)
DPKG_QUERY = r"""#!/bin/bash
echo "dpkg-query $*" >>"$STANDIN_LOG"
p="${*: -1}"
while read -r name status; do
  if [ "$name" = "$p" ]; then
    if [ -z "$status" ]; then
      echo "dpkg-query: no packages found matching $p" >&2
      exit 1
    fi
    printf '%s ' "$status"
    exit 0
  fi
done <"$STANDIN_MISSING"
printf 'ii '
"""

# apt-get ARGS: logged; the subcommand named in $STANDIN_APT_FAILS fails as apt does
APT_GET = r"""#!/bin/bash
echo "apt-get $*" >>"$STANDIN_LOG"
for a in "$@"; do
  if [ "$a" = "${STANDIN_APT_FAILS:-}" ]; then
    echo "Reading package lists..."
    echo "E: Unable to locate package libpetsc-real-dev" >&2
    exit 100
  fi
done
echo "apt-get $1: done"
"""


def _setup(
    tmp_path: Path,
    missing: str = "",
    apt_fails: str = "",
    script: Path = ROOT / "setup.sh",
    args: tuple[str, ...] = ("--packages-only",),
) -> tuple[subprocess.CompletedProcess, list[str]]:
    """Run ``SCRIPT ARGS`` with the stand-ins; returns the process and the logged calls."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    for name, text in (("dpkg-query", DPKG_QUERY), ("apt-get", APT_GET)):
        (bin_dir / name).write_text(text)
        (bin_dir / name).chmod(0o755)
    log, missing_file = tmp_path / "calls.log", tmp_path / "missing"
    log.write_text("")
    missing_file.write_text(missing)
    env = dict(os.environ)
    env.update(
        PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
        STANDIN_LOG=str(log),
        STANDIN_MISSING=str(missing_file),
        STANDIN_APT_FAILS=apt_fails,
        PETSC_DIR=str(tmp_path / "no-petsc"),  # past the package step, set-up stops at once
    )
    proc = subprocess.run(
        ["bash", str(script), *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    return proc, log.read_text().splitlines()


def _queried(calls: list[str]) -> list[str]:
    return [c.split()[-1] for c in calls if c.startswith("dpkg-query ")]


def _apt(calls: list[str]) -> list[str]:
    return [c for c in calls if c.startswith("apt-get ")]


def test_only_the_missing_packages_are_installed(tmp_path):
    """Two packages missing (one never seen, one removed with its configuration kept): apt-get
    update, then one install of exactly those two."""
    proc, calls = _setup(tmp_path, "libfftw3-mpi-dev rc\nopenmpi-bin\n")
    assert proc.returncode == 0, proc.stderr
    queried = _queried(calls)
    assert {"libpetsc-real-dev", "libfftw3-mpi-dev", "openmpi-bin", "python3-dev"} <= set(queried)
    assert _apt(calls) == [
        "apt-get update -q",
        "apt-get install -y -q --no-install-recommends libfftw3-mpi-dev openmpi-bin",
    ]
    assert "libfftw3-mpi-dev openmpi-bin" in proc.stdout


def test_the_petsc_metapackage_alone_missing_is_installed(tmp_path):
    proc, calls = _setup(tmp_path, "libpetsc-real-dev\n")
    assert proc.returncode == 0, proc.stderr
    assert _apt(calls) == [
        "apt-get update -q",
        "apt-get install -y -q --no-install-recommends libpetsc-real-dev",
    ]


def test_nothing_is_installed_when_all_are_there(tmp_path):
    proc, calls = _setup(tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert len(_queried(calls)) >= 9
    assert _apt(calls) == []
    assert "all" in proc.stdout and "installed" in proc.stdout


@pytest.mark.parametrize("fails", ["install", "update"])
def test_a_failing_apt_get_stops_the_set_up(tmp_path, fails):
    """The whole set-up (a copy of setup.sh, alone in its folder) stops at the failing apt-get
    with apt's message, one line naming what failed, and apt's exit status; nothing after it
    runs (no install after a failed update, no venv)."""
    copy = tmp_path / "repo" / "setup.sh"
    copy.parent.mkdir()
    shutil.copy(ROOT / "setup.sh", copy)
    proc, calls = _setup(tmp_path, "libpetsc-real-dev\n", fails, copy, ())
    assert proc.returncode == 100, proc.stdout + proc.stderr
    assert "E: Unable to locate package libpetsc-real-dev" in proc.stderr
    assert "Reading package lists..." in proc.stderr  # apt's whole output, stdout included
    note = [line for line in proc.stderr.splitlines() if line.startswith("setup.sh: ")]
    assert len(note) == 1 and f"apt-get {fails}" in note[0] and "failed" in note[0], note
    expected = ["update"] if fails == "update" else ["update", "install"]
    assert [c.split()[1] for c in _apt(calls)] == expected
    assert "2/6" not in proc.stdout
    assert not (copy.parent / ".venv").exists()


def test_a_wrong_argument_is_refused(tmp_path):
    proc, calls = _setup(tmp_path, args=("--packages",))
    assert proc.returncode == 2 and "usage" in proc.stderr
    assert calls == []


@pytest.mark.skipif(shutil.which("shellcheck") is None, reason="shellcheck is not installed")
def test_shellcheck_is_clean():
    proc = subprocess.run(
        ["shellcheck", "setup.sh", ".ci/run"], cwd=ROOT, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
