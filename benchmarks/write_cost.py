"""What durable results cost: the share of a sweep's wall time spent writing them.

usage: .venv/bin/python benchmarks/write_cost.py [--grid 2048] [--loads 12] [--no-fields]

Runs ``petsc-contact periodic`` in this process on the paper-bandwidth surface of
docs/performance.md (H = 0.7, L/lambda_r = 1, roughness down to two pixels, seed 1) with
``--stiffness`` and ``--fields``, and times every call of the durable store
(:class:`petsc_contact.io.store.StepStore`: creating the run's files, committing each step
with its fields and state, assembling ``OUT.h5`` at the end).  Prints the write time, the
run's wall time and their ratio: a share of one process's time, immune to the machine's
drift between runs.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from collections.abc import Callable
from typing import Any

from petsc_contact.cli.main import main
from petsc_contact.io.store import StepStore

SPENT = {"create": 0.0, "append": 0.0, "finish": 0.0}


def _timed(name: str, method: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        began = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            SPENT[name] += time.perf_counter() - began

    return wrapper


def run() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=2048)
    ap.add_argument("--loads", type=int, default=12)
    ap.add_argument("--no-fields", action="store_true")
    args = ap.parse_args()
    StepStore.create = classmethod(_timed("create", StepStore.create.__func__))  # type: ignore[method-assign]
    StepStore.append = _timed("append", StepStore.append)  # type: ignore[method-assign]
    StepStore.finish = _timed("finish", StepStore.finish)  # type: ignore[method-assign]
    n = args.grid
    with tempfile.TemporaryDirectory(dir=".") as folder:
        out = os.path.join(folder, "sweep.h5")
        argv = f"periodic --grid {n} --hurst 0.7 --rms-slope 0.1 --rolloff-ratio 1"
        argv += f" --cutoff-ratio {n // 2} --seed 1 --sweep {args.loads},1e-7,1e-1 --stiffness"
        argv += " --quiet" + ("" if args.no_fields else " --fields")
        began = time.perf_counter()
        status = main([*argv.split(), "--output", out])
        wall = time.perf_counter() - began
        size = os.path.getsize(out) / 2**20
    writes = sum(SPENT.values())
    print(f"# periodic {n}^2, {args.loads} loads, fields: {not args.no_fields}, exit {status}")
    print(
        f"wall {wall:.2f} s, writing {writes:.2f} s ({100 * writes / wall:.2f}%): create "
        f"{SPENT['create']:.2f} s, commits {SPENT['append']:.2f} s, assembly "
        f"{SPENT['finish']:.2f} s; OUT.h5 {size:.0f} MiB"
    )


if __name__ == "__main__":
    run()
