"""The figure scripts run end to end at toy size and write their PNG and HDF5 files."""

import subprocess
import sys

import h5py
import pytest
from conftest import ROOT


@pytest.mark.parametrize(
    "script, args",
    [
        ("fig2_theta.py", []),
        ("fig5_spectrum.py", ["--grid", "64"]),
        (
            "fig4_alpha_extrapolation.py",
            "--grid 64 --ratios 8 16 32 --seeds 2 --pressures 1e-4 3e-2 8 --fit-points 3".split(),
        ),
        ("fig1_stiffness.py", ["--grid", "64", "--pressures", "1e-5", "1e-2", "6"]),
        (
            "fig3_finite_size.py",
            [
                "--grid",
                "64",
                "--hursts",
                "0.7",
                "--seeds",
                "2",
                "--pressures",
                "1e-4",
                "3e-2",
                "8",
                "--fit-points",
                "3",
            ],
        ),
    ],
)
def test_example_runs(tmp_path, script, args):
    out = tmp_path / "fig"
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), *args, "--output", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "fig.png").stat().st_size > 1000
    with h5py.File(tmp_path / "fig.h5") as f:
        assert len(f.keys()) > 0
