"""The README's Python section runs as written (in a folder holding the file it reads)."""

import re
import warnings
from pathlib import Path

import numpy as np
from conftest import ROOT
from SurfaceTopography import Topography

from petsc_contact.conventions.warnings import Unconverged


def _blocks() -> list[str]:
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Python", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_readme_python_section_runs(tmp_path, monkeypatch, petsc):
    """Every Python block of the README's Python section, on a 64 x 64 scan of 1.28 um with a
    few nm of roughness, written as the X3P file the README reads."""
    rng = np.random.default_rng(3)
    x, y = np.meshgrid(*(np.arange(64) / 64,) * 2, indexing="ij")
    h = sum(
        rng.standard_normal() * np.cos(2 * np.pi * (i * x + j * y) + rng.uniform(0, 6.3))
        for i in range(1, 5)
        for j in range(-4, 5)
    )
    Topography(2e-9 * h, (1.28e-6, 1.28e-6), unit="m").to_x3p(str(tmp_path / "scan.x3p"))
    monkeypatch.chdir(tmp_path)
    blocks = _blocks()
    assert len(blocks) == 2
    with warnings.catch_warnings():  # the README's runs converge: no step is flagged
        warnings.simplefilter("error", Unconverged)
        for block in blocks:
            exec(compile(block, "README.md", "exec"), {})
    assert Path("scan.h5").exists() and Path("scan.csv").exists() and Path("scan.png").exists()
    assert Path("punch.h5").exists()
    import xarray as xr

    with xr.open_dataset("scan.h5", engine="h5netcdf") as data:
        assert data["pressure"].dims == ("step", "x", "y") and data.sizes["step"] == 2
        assert float(data["x"][0]) == 1.28e-6 / 64 / 2
