"""Timing the package's solvers and a peer's side by side on a shared machine.

Each repetition runs every solver once, in the same order, so that a change of load falls
on all of them alike; the one-minute load average is recorded before and after each
repetition, and each solver's median over the repetitions is compared as a ratio.  A solver
is a function returning a dict with at least ``time`` (the solve alone, in seconds).
"""

from __future__ import annotations

import datetime
import os
import statistics
import subprocess
from collections.abc import Callable


def load() -> float:
    """The machine's one-minute load average."""
    return os.getloadavg()[0]


def stamp() -> str:
    """Date, commit and machine, as a measurement in docs carries them."""
    here = os.path.dirname(os.path.abspath(__file__))
    git = ["git", "-C", here, "rev-parse", "--short", "HEAD"]
    commit = subprocess.run(git, capture_output=True, text=True, check=False).stdout.strip()
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return f"{date}, commit {commit or '?'}, {os.cpu_count()} cores ({cpu()})"


def cpu() -> str:
    """The processor's model name (Linux), else ``?``."""
    try:
        with open("/proc/cpuinfo") as info:
            names = [
                line.split(":", 1)[1].strip() for line in info if line.startswith("model name")
            ]
    except OSError:
        return "?"
    return names[0] if names else "?"


def alternate(
    solvers: dict[str, Callable[[], dict]], repetitions: int
) -> tuple[dict[str, list[dict]], list[tuple[float, float]]]:
    """Every solver once per repetition, in order: their results, and the load before and
    after each repetition."""
    results: dict[str, list[dict]] = {name: [] for name in solvers}
    loads = []
    for _ in range(repetitions):
        before = load()
        for name, solve in solvers.items():
            results[name].append(solve())
        loads.append((before, load()))
    return results, loads


def medians(results: dict[str, list[dict]], ours: tuple[str, ...]) -> dict[str, str]:
    """Per solver of :func:`alternate`'s ``results``, Markdown cells: its median time, then
    the ratio of each of ``ours``' medians to it."""
    median = {
        name: statistics.median(row["time"] for row in rows) for name, rows in results.items()
    }
    return {
        name: " | ".join(
            [f"{median[name]:.3g}", *(f"{median[m] / median[name]:.3f}" for m in ours)]
        )
        for name in results
    }


def load_line(loads: list[tuple[float, float]]) -> str:
    """The loads of :func:`alternate`, one ``before -> after`` per repetition."""
    return "load average per repetition: " + ", ".join(f"{a:.1f} -> {b:.1f}" for a, b in loads)
