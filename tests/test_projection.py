"""The projection to 65536^2 (benchmarks/projection.py): it runs, it starts from the memory
per rank measured in docs/parallel.md, on one rank it gives the measured serial peak, and
the table docs/parallel.md shows is its output."""

from __future__ import annotations

import importlib
import json
import re
import sys

import pytest
from conftest import ROOT

PARALLEL = ROOT / "docs" / "parallel.md"


def _run(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture, *args: str) -> str:
    """What ``benchmarks/projection.py ARGS`` prints."""
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    monkeypatch.setattr(sys, "argv", ["projection.py", *args])
    importlib.import_module("projection").main()
    return capsys.readouterr().out


def _measured() -> dict[int, tuple[float, float]]:
    """docs/parallel.md's memory per rank: the largest rank's peak and the per-process
    constant (GiB), by rank count."""
    section = PARALLEL.read_text().split("### Memory per rank")[1].split("\n#")[0]
    rows = re.findall(
        r"^\| (\d+) \| ([\d.]+) \| ([\d.]+) \|(?: [\d.]+ \|){2} ([\d.]+) \|", section, re.M
    )
    return {int(p): (float(largest), float(constant)) for p, _, largest, constant in rows}


def test_the_projection_starts_from_the_measured_memory(monkeypatch, capsys):
    """Its inputs are docs/parallel.md's table; on one rank at the measured grid it gives the
    measured serial peak, and on 2, 4 and 8 ranks the measured peaks within their run-to-run
    variation (0.1 GiB)."""
    inputs = json.loads((ROOT / "benchmarks" / "projection.json").read_text())["memory_per_rank"]
    measured = _measured()
    assert len(measured) == 4
    assert measured == {
        p: (largest, constant)
        for p, largest, constant in zip(
            inputs["ranks"], inputs["largest_GiB"], inputs["constant_GiB"], strict=True
        )
    }, "benchmarks/projection.json is not docs/parallel.md's memory per rank"
    said = _run(monkeypatch, capsys, "--json", "--grids", "4096", "--nodes", "1", "2", "4", "8",
                "--ranks-per-node", "1")  # fmt: skip
    rows = {row["ranks"]: row["rank_GiB"] for row in json.loads(said)["steps"]}
    assert rows[1] == pytest.approx(measured[1][0], rel=1e-12)
    for p in (2, 4, 8):
        assert abs(rows[p] - measured[p][0]) < 0.1, (p, rows[p])


def test_docs_show_the_projection_it_prints(monkeypatch, capsys):
    """Every line of the default projection is in docs/parallel.md's "Projection to 65536^2"."""
    section = PARALLEL.read_text().split("## Projection to 65536^2")[1]
    printed = [line for line in _run(monkeypatch, capsys).splitlines() if line]
    missing = [line for line in printed if line not in section]
    assert len(printed) > 20 and not missing, missing
