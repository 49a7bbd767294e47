"""The side-by-side timing of the peer comparisons (benchmarks/side_by_side.py): every
repetition runs every solver once, in order, and the ratios are of the medians."""

from __future__ import annotations

import importlib

import pytest
from conftest import ROOT


def test_alternated_medians_and_ratios(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    side = importlib.import_module("side_by_side")
    calls: list[str] = []
    times = {"ours": iter([1.0, 9.0, 2.0]), "peer": iter([8.0, 10.0, 40.0])}

    def solver(name: str):
        def solve() -> dict:
            calls.append(name)
            return {"time": next(times[name])}

        return solve

    results, loads = side.alternate({"ours": solver("ours"), "peer": solver("peer")}, 3)
    assert calls == ["ours", "peer"] * 3  # alternated, not three of one then three of the other
    assert len(loads) == 3 and all(len(pair) == 2 for pair in loads)
    cells = side.medians(results, ("ours",))
    # medians 2 and 10: the outliers (9 s, 40 s) do not move them; ratio ours/peer 0.2
    assert cells == {"ours": "2 | 1.000", "peer": "10 | 0.200"}
