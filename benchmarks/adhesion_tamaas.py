"""Adhesion against Tamaas's adhesive solver on a surface this package never generated.

The numpy-seeded surface of :mod:`hardness_tamaas` is saved to a file; the periodic cell with
an adhesive law at prescribed mean gaps (the loading machine,
:func:`~petsc_contact.workflows.adhesive_steps.adhesive_mean_gap_sweep`, ``-tao_type
blmvm``) and Tamaas's ``PolonskyKeerRey`` posed in the gap with its
``ExponentialAdhesionFunctional`` or ``MaugisAdhesionFunctional``
(``benchmarks/peers/run_tamaas_adhesion.py``, in the peers' venv: :mod:`peer_env`) solve
the same mean gaps in the same order.  Printed per mean gap: the mean pressure and area of
each, their differences (the pressure's in units of the adhesive stress ``w/rho``) and each
one's time::

    PYTHONPATH=. python benchmarks/adhesion_tamaas.py --grid 128 --law exponential \
        --work 1e-4 --range 5e-3 --mean-gaps 6e-3,3e-3
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from hardness_tamaas import surface
from peer_env import peer_python

PEERS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers")


def ours(h: np.ndarray, law: str, w: float, rho: float, gaps: list[float]) -> list[dict]:
    """The adhesive cell at the mean gaps in order, one row each."""
    from petsc_contact.backend._petsc import scoped_options
    from petsc_contact.backend.tao import PetscBackend
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.geometries.adhesive_periodic import AdhesivePeriodicProblem
    from petsc_contact.interactions.adhesion import Adhesion
    from petsc_contact.workflows.adhesive_steps import adhesive_mean_gap_sweep

    grid = Grid(h.shape[0], 1.0)
    rows = []
    with scoped_options(["-tao_type", "blmvm"]):
        problem = AdhesivePeriodicProblem(
            grid, make_fft(grid), h, 1.0, Adhesion(law, w, rho), PetscBackend()
        )
        start = time.perf_counter()
        for step in adhesive_mean_gap_sweep(problem, gaps):
            assert step.converged, step.scalars["verification"]
            rows.append({**step.scalars, "time": time.perf_counter() - start})
            start = time.perf_counter()
    return rows


def tamaas(path: str, law: str, w: float, rho: float, gaps: list[float]) -> list[dict]:
    """Tamaas's adhesive PolonskyKeerRey at tolerance 1e-12."""
    python = peer_python()
    if python is None:
        sys.exit("no peers' venv: see benchmarks/peer_env.py")
    args = [os.path.join(PEERS, "run_tamaas_adhesion.py"), path, "1", "1", law, str(w)]
    args += [str(rho), ",".join(map(str, gaps)), "1e-12"]
    text = subprocess.run([python, *args], capture_output=True, text=True, check=True).stdout
    return [json.loads(line) for line in text.splitlines() if line.startswith("{")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", type=int, default=128)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--law", default="exponential", choices=("exponential", "maugis"))
    parser.add_argument("--work", type=float, default=1e-4)
    parser.add_argument("--range", type=float, default=5e-3)
    parser.add_argument("--mean-gaps", default="6e-3,3e-3")
    a = parser.parse_args()
    gaps = [float(g) for g in a.mean_gaps.split(",")]
    h = surface(a.grid, a.seed)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "h.npy")
        np.save(path, h)
        theirs = tamaas(path, a.law, a.work, a.range, gaps)
    mine = ours(h, a.law, a.work, a.range, gaps)
    print("| mean gap | p0 (ours) | p0 (Tamaas) | dp0 / (w/rho) | area (ours) | area (Tamaas) "
          "| ours (s) | Tamaas (s) |")  # fmt: skip
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for m, t in zip(mine, theirs, strict=True):
        dp = abs(m["nominal_pressure"] - t["mean_pressure"]) / (a.work / a.range)
        print(
            f"| {m['target_mean_gap']:g} | {m['nominal_pressure']:.6g} | "
            f"{t['mean_pressure']:.6g} | {dp:.1e} | {m['area_fraction']:.5f} | "
            f"{t['area_fraction']:.5f} | {m['time']:.2f} | {t['time']:.2f} |"
        )


if __name__ == "__main__":
    main()
