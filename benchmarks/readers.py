"""The package's reading of instrument files against SurfaceTopography's own, file by file.

For every file in the folders given (for example SurfaceTopography's public test files,
``test/file_format_examples`` of its repository) and every channel of it, reads the map
twice: with :func:`petsc_contact.io.topography.read_topography` and directly with
SurfaceTopography (``open_topography(...).topography(channel_index=...)``).  Prints a
Markdown table: the format, shape, sides, unit and undefined points as read, and whether
the heights, sides, unit and mask agree (``same``), or what the package answered instead.

    .venv/bin/python benchmarks/readers.py FOLDER [FOLDER ...]
"""

from __future__ import annotations

import argparse
import glob
import os
import warnings

import numpy as np

from petsc_contact.conventions.units import unit_name
from petsc_contact.io.topography import read_topography


def _direct(path: str) -> list[tuple[int, str, object]]:
    """Every channel of ``path`` as SurfaceTopography reads it (or why it cannot)."""
    from SurfaceTopography import open_topography

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            reader = open_topography(path)
        except Exception as exc:
            return [(0, "", f"unreadable ({type(exc).__name__})")]
        out: list[tuple[int, str, object]] = []
        for c in reader.channels:
            try:
                sizes = None if c.physical_sizes is not None else (1.0,) * c.dim
                out.append((c.index, str(c.name), reader.topography(c.index, physical_sizes=sizes)))
            except Exception as exc:
                out.append((c.index, str(c.name), f"unreadable ({type(exc).__name__})"))
        return out


def _compare(path: str, index: int, theirs: object) -> str:
    try:
        mine = read_topography(path, channel=index)
    except Exception as exc:
        return "refused (not a height)" if "not a height" in str(exc) else f"refused: {exc}"
    if isinstance(theirs, str):
        return f"read, where SurfaceTopography: {theirs}"
    h = np.ma.filled(np.ma.asarray(theirs.heights(), dtype=float), np.nan)  # type: ignore[attr-defined]
    same_heights = np.array_equal(h, mine.heights, equal_nan=True)
    if not same_heights and np.array_equal(h.T, mine.heights, equal_nan=True):
        return "same, transposed (a bare matrix: its rows are x)"
    sizes = theirs.physical_sizes if mine.lengths is not None else None  # type: ignore[attr-defined]
    same_sides = sizes is None or np.allclose(sizes, mine.lengths, rtol=1e-12)
    unit = theirs.unit  # type: ignore[attr-defined]
    same_unit = (mine.unit is None and unit is None) or (
        isinstance(unit, str) and mine.unit == unit_name(unit)
    )
    problems = [
        what
        for what, ok in (("heights", same_heights), ("sides", same_sides), ("unit", same_unit))
        if not ok
    ]
    return "same" if not problems else "differ: " + ", ".join(problems)


def _channel(path: str, index: int, theirs: object) -> str:
    """The package's verdict on one channel."""
    if isinstance(theirs, str) or theirs.dim != 2:  # type: ignore[attr-defined]
        try:
            read_topography(path, channel=index)
            return "read, but SurfaceTopography reads no map"
        except Exception as exc:
            reason = "line scan" if "line scan" in str(exc) else "unreadable"
            return f"refused ({reason})"
    return _compare(path, index, theirs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args()
    print("| file | format | channels: verdict | shape | sides | unit | undefined |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for path in sorted(p for f in args.folders for p in glob.glob(os.path.join(f, "*"))):
        channels = _direct(path) or [(0, "", "no channels")]
        verdicts = [_channel(path, index, theirs) for index, _, theirs in channels]
        counts = {v: verdicts.count(v) for v in dict.fromkeys(verdicts)}
        summary = ", ".join(f"{n} {v}" for v, n in counts.items())
        first = channels[0][2]
        kind = _format(path)
        if isinstance(first, str) or first.dim != 2:  # type: ignore[attr-defined]
            print(f"| {os.path.basename(path)} | {kind} | {summary} | | | | |")
            continue
        h = np.ma.asarray(first.heights())  # type: ignore[attr-defined]
        sizes = first.physical_sizes  # type: ignore[attr-defined]
        print(
            f"| {os.path.basename(path)} | {kind} | {summary} | {h.shape[0]} x {h.shape[1]} | "
            f"{sizes[0]:.4g} x {sizes[1]:.4g} | {first.unit} | "  # type: ignore[attr-defined]
            f"{np.ma.count_masked(h)} |"
        )


def _format(path: str) -> str:
    from SurfaceTopography import open_topography

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return type(open_topography(path)).__name__.removesuffix("Reader")
        except Exception:
            return "none"


if __name__ == "__main__":
    main()
