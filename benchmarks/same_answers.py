"""The answers of a fixed set of solves, to compare two commits bit for bit.

The stability matrix's scenes (``benchmarks/stability.py``) at 64^2 with every solver
``compare`` runs and the array solver, and a paper-bandwidth sweep of the speed table's kind
(512^2, with the exact stiffness; the two-level form on and off), cold and warm steps of 16
surfaces at 256^2 (H = 0.3 and 0.7, 8 seeds each): every step's scalars that
do not measure time, written as JSON.  Run it in each commit's tree (the tree's package is
imported) and compare the two files::

    cd TREE && PYTHONPATH=. python /path/to/benchmarks/same_answers.py --out A.json
    python benchmarks/same_answers.py --compare A.json B.json

FFTW's plans come from the machine's wisdom file, so both runs round alike.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np

TIMES = ("time", "seconds")
SOLVERS = {
    "cg": [],
    "pk": ["-options_file", "options/pk.opts"],
    "bncg": ["-tao_type", "bncg"],
    "blmvm": ["-tao_type", "blmvm"],
    "tron": ["-tao_type", "tron"],
    "bqnls": ["-tao_type", "bqnls"],
}


def scalars(steps: list) -> list[dict]:
    """Every step's scalars but times, as JSON takes them."""
    out = []
    for step in steps:
        row = {}
        for key, value in step.scalars.items():
            if any(t in key for t in TIMES):
                continue
            if isinstance(value, (bool, np.bool_)):
                row[key] = bool(value)
            elif isinstance(value, (int, float, np.integer, np.floating)):
                v = float(value)
                row[key] = v if math.isfinite(v) else repr(v)
            elif isinstance(value, str):
                row[key] = value
        out.append(row)
    return out


def answers(root: Path) -> dict[str, list[dict]]:
    """The solves (module docstring) by name."""
    sys.path.insert(0, str(root / "benchmarks"))
    from stability import rough, scenes

    from petsc_contact import periodic_contact, punch_contact

    out: dict[str, list[dict]] = {}
    quiet = {"progress": False}
    for name, h, length, modulus, p0 in scenes(64):
        for solver, options in SOLVERS.items():
            try:
                steps = periodic_contact(
                    h, length=length, modulus=modulus, pressures=[p0], options=options,
                    stiffness=solver == "cg", **quiet,
                )  # fmt: skip
                out[f"{name} / {solver}"] = scalars(steps)
            except (ValueError, RuntimeError) as error:
                out[f"{name} / {solver}"] = [{"refused": str(error)}]
        steps = periodic_contact(
            h, length=length, modulus=modulus, pressures=[p0], stiffness=True,
            device="cpu-array", **quiet,
        )  # fmt: skip
        out[f"{name} / cpu-array"] = scalars(steps)
    h = rough(512, seed=2)
    loads = [3e-4, 1e-3, 3e-3, 1e-2]
    for label, options in (("two-level", []), ("one-level", ["-petsc_contact_two_level", "0"])):
        steps = periodic_contact(
            h, length=1.0, modulus=1.0, pressures=loads, stiffness=True, options=options, **quiet
        )
        out[f"512^2 sweep / {label}"] = scalars(steps)
    for hurst in (0.3, 0.7):  # cold first steps and warm ones over many seeds
        for seed in range(1, 9):
            surface = rough(256, hurst=hurst, seed=seed)
            steps = periodic_contact(
                surface, length=1.0, modulus=1.0, pressures=[1e-3, 3e-3, 1e-2], **quiet
            )
            out[f"256^2 H={hurst} seed {seed}"] = scalars(steps)
    steps = punch_contact(rough(64), length=1.0, modulus=1.0, forces=[1e-5, 1e-4], stiffness=True,
                          **quiet)  # fmt: skip
    out["punch 64^2 by force"] = scalars(steps)
    return out


def compare(a: Path, b: Path) -> int:
    """Print every value that differs; the number of them."""
    first, second = json.loads(a.read_text()), json.loads(b.read_text())
    differ = 0
    for name in sorted(set(first) | set(second)):
        rows_a, rows_b = first.get(name), second.get(name)
        if rows_a is None or rows_b is None or len(rows_a) != len(rows_b):
            print(f"{name}: only in one, or other steps")
            differ += 1
            continue
        for i, (ra, rb) in enumerate(zip(rows_a, rows_b, strict=True)):
            for key in sorted(set(ra) | set(rb)):
                if ra.get(key) != rb.get(key):
                    print(f"{name} step {i + 1} {key}: {ra.get(key)!r} != {rb.get(key)!r}")
                    differ += 1
    total = sum(len(r) for rows in first.values() for r in rows)
    print(f"{len(first)} solves, {total} values: {differ} differ")
    return differ


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path)
    ap.add_argument("--compare", nargs=2, type=Path)
    args = ap.parse_args()
    if args.compare:
        sys.exit(1 if compare(*args.compare) else 0)
    warnings.simplefilter("ignore")
    result = answers(Path.cwd())
    args.out.write_text(json.dumps(result, indent=1, sort_keys=True))


if __name__ == "__main__":
    main()
