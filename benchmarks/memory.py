"""Peak memory per grid point of one load step or of a sweep, per geometry and solver.

usage: .venv/bin/python benchmarks/memory.py [--grids 1024 2048 4096] [--punch-grids 512 1024]
       [--loads N]  (N > 1: a sweep of N loads with the exact stiffness at each, as the study's)
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
from petsc_contact import periodic_contact, punch_contact
from petsc_contact.backend import _petsc
from petsc_contact.workflows import scenes
_petsc.init([])
geometry, n, solver, loads = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
opts = [] if solver == "cg" else ["-tao_type", solver]
h, _ = scenes.surface(n, 0.7, 2.0, n / 4, 1)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t = time.perf_counter()
scale = np.geomspace(1e-3, 1.0, loads) if loads > 1 else np.ones(1)
if geometry == "periodic":
    steps = periodic_contact(h, 1.0, 1.0, 1e-2 * scale, options=opts, stiffness=loads > 1)
else:
    approaches = 3 * h.std() * scale
    steps = punch_contact(h, 1.0, 1.0, approaches=approaches, options=opts)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"geometry": geometry, "n": n, "solver": solver, "peak_GiB": peak / 2**30,
                  "bytes_per_point": (peak - base + h.nbytes) / n**2,
                  "iterations": sum(s.scalars["iterations"] for s in steps),
                  "time": time.perf_counter() - t, "converged": all(s.converged for s in steps)}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grids", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--punch-grids", type=int, nargs="*", default=[512, 1024, 2048])
    ap.add_argument("--solvers", nargs="+", default=["cg", "tron", "bqnls"])
    ap.add_argument("--loads", type=int, default=1, help="loads per run (default: one step)")
    args = ap.parse_args()
    cases = [("periodic", n, s) for n in args.grids for s in args.solvers]
    cases += [("punch", n, "cg") for n in args.punch_grids]
    for geometry, n, solver in cases:
        out = subprocess.run(
            [sys.executable, "-c", CHILD, geometry, str(n), solver, str(args.loads)],
            capture_output=True,
            text=True,
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
