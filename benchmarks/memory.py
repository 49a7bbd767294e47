"""Peak memory per grid point of one load step, per geometry and solver.

usage: .venv/bin/python benchmarks/memory.py [--grids 1024 2048 4096] [--punch-grids 512 1024]
Each case runs in a fresh process; peak resident memory (ru_maxrss) minus the resident memory
of the same process before the grid is allocated, divided by n^2, is bytes per grid point.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CHILD = r"""
import json, resource, sys, time
import numpy as np
import petsc_contact
from petsc_contact import periodic_contact, punch_contact, scenes, _petsc
_petsc.init([])
geometry, n, solver = sys.argv[1], int(sys.argv[2]), sys.argv[3]
opts = [] if solver == "cg" else ["-tao_type", solver]
h, _ = scenes.surface(n, 0.7, 2.0, n / 4, 1)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t = time.perf_counter()
if geometry == "periodic":
    (s,) = periodic_contact(h, 1.0, 1.0, [1e-3], options=opts)
else:
    (s,) = punch_contact(h, 1.0, 1.0, approaches=[3 * h.std()], options=opts)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"geometry": geometry, "n": n, "solver": solver, "peak_GiB": peak / 2**30,
                  "bytes_per_point": (peak - base + h.nbytes) / n**2,
                  "iterations": s.scalars["iterations"], "time": time.perf_counter() - t,
                  "converged": s.converged}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--punch-grids", type=int, nargs="*", default=[512, 1024, 2048])
    ap.add_argument("--solvers", nargs="+", default=["cg", "tron", "bqnls"])
    args = ap.parse_args()
    cases = [("periodic", n, s) for n in args.grids for s in args.solvers]
    cases += [("punch", n, "cg") for n in args.punch_grids]
    for geometry, n, solver in cases:
        out = subprocess.run(
            [sys.executable, "-c", CHILD, geometry, str(n), solver], capture_output=True, text=True
        )
        line = [text for text in out.stdout.splitlines() if text.startswith("{")]
        if not line:
            print(f"{geometry} {n} {solver}: failed: {out.stderr.strip().splitlines()[-1:]}")
            continue
        r = json.loads(line[0])
        print(
            f"{geometry:>8} {n:>5} {solver:>6}: {r['bytes_per_point']:6.0f} B/point, "
            f"peak {r['peak_GiB']:.2f} GiB, {r['iterations']} its, {r['time']:.1f} s, "
            f"converged {r['converged']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
