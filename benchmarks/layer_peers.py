"""The elastic layer on a rigid base against ContactMechanics's, on a surface neither made.

usage: .venv/bin/python benchmarks/layer_peers.py [--grid 256] [--thickness 0.015625 0.125]
       [--poisson 0.3 0.45] [--pressures 1e-3 1e-2]

The surface is numpy's (``default_rng(60)``: a random-phase power law, H = 0.8, rolled off
at L/2, rms slope 0.1 on a unit cell), saved and given to both.  For each bonded layer
(thickness in units of L, Poisson ratio): the largest relative difference between the two
stiffness multipliers on the grid's wavevectors (``q != 0``), then each nominal pressure
(units of E* = 1) solved by the package (``-tao_gatol 1e-12``) and by ContactMechanics's
Polonsky-Keer CG (benchmarks/peers/run_cm_layer.py in the peers' venv, penetration
``1e-10 h_rms``): mean gap, contact area (and by how many pixels the contact sets' sizes
differ) and wall time of each.  Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile

import numpy as np
from peer_env import peer_python

from petsc_contact.substrates.layer import PeriodicLayer
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.runner import run_contact

HERE = os.path.dirname(os.path.abspath(__file__))


def surface(n: int) -> np.ndarray:
    """A random-phase self-affine surface from numpy's generator (H = 0.8, roll-off at L/2),
    rms slope 0.1 on a unit cell."""
    rng = np.random.default_rng(60)
    k = np.hypot(np.fft.fftfreq(n, 1 / n)[:, None], np.fft.rfftfreq(n, 1 / n)[None, :])
    spectrum = np.where(k > 0, np.maximum(k, 2.0) ** -1.8, 0.0)
    h = np.fft.irfft2(spectrum * np.exp(2j * np.pi * rng.random(k.shape)), (n, n))
    slopes = np.gradient(h, 1 / n, axis=0), np.gradient(h, 1 / n, axis=1)
    return h * 0.1 / np.sqrt(sum(np.mean(s**2) for s in slopes))


def multiplier_difference(layer: PeriodicLayer, theirs: np.ndarray, n: int) -> float:
    """The largest relative difference between ``layer``'s multiplier and ContactMechanics's
    (its wavevectors ``min(i, n - i)/L`` per axis, in cycles per length), ``q = 0`` left out."""
    i, j = (np.arange(m) for m in theirs.shape)
    kx, ky = np.minimum(i, n - i)[:, None], np.minimum(j, n - j)[None, :]
    q = 2 * np.pi * np.hypot(kx, ky)
    ours = layer.stiffness(q)
    return float(np.max(np.abs(ours[q > 0] / theirs[q > 0] - 1)))


def contactmechanics(path: str, case: tuple[float, float], pressures: list[float]) -> tuple:
    """ContactMechanics's stiffness array and its rows, one per pressure."""
    stiffness = path.replace(".npy", "_k.npy")
    argv = [peer_python() or "", os.path.join(HERE, "peers", "run_cm_layer.py"), path, "1", "1"]
    argv += [*map(str, case), ",".join(map(str, pressures)), "1e-10", stiffness]
    out = subprocess.run(argv, capture_output=True, text=True, check=True).stdout
    return np.load(stiffness), [json.loads(line) for line in out.splitlines() if line]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=256)
    ap.add_argument("--thickness", type=float, nargs="+", default=[1 / 64, 1 / 8])
    ap.add_argument("--poisson", type=float, nargs="+", default=[0.3, 0.45])
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e-3, 1e-2])
    args = ap.parse_args()
    h = surface(args.grid)
    print("| T/L | nu | max rel. diff. of K(q) | p0/E* | mean gap / h_rms, ours | "
          "ContactMechanics | rel. diff. | area, ours | contact pixels apart | time (s), ours | "
          "ContactMechanics |\n" + "| --- " * 11 + "|")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "h.npy")
        np.save(path, h)
        for thickness in args.thickness:
            for nu in args.poisson:
                theirs, rows = contactmechanics(path, (thickness, nu), args.pressures)
                layer = PeriodicLayer(1.0, thickness, nu, "bonded")
                k_diff = multiplier_difference(layer, theirs, args.grid)
                tight = ("-tao_gatol", "1e-12")
                run = Run(heights=h, length=1.0, pressures=tuple(args.pressures),
                          thickness=thickness, poisson=nu, options=tight)  # fmt: skip
                steps = run_contact(run, progress=False).steps
                for step, cm in zip(steps, rows, strict=True):
                    s, h_rms = step.scalars, float(h.std())
                    gap, their_gap = s["mean_gap"] / h_rms, cm["mean_gap"] / h_rms
                    apart = round((s["area_fraction"] - cm["area_fraction"]) * h.size)
                    print(f"| {thickness:g} | {nu:g} | {k_diff:.1e} | {cm['pressure']:g} | "
                          f"{gap:.8f} | {their_gap:.8f} | {gap / their_gap - 1:.1e} | "
                          f"{s['area_fraction']:.5f} | {apart} | "
                          f"{s['solve_time']:.2f} | {cm['time']:.2f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
