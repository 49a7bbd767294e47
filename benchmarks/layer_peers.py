"""The elastic layer on a rigid base against ContactMechanics's, on a surface neither made.

usage: PYTHONPATH=. python benchmarks/layer_peers.py [--grid 256] [--thickness 0.015625 0.125]
       [--poisson 0.3 0.45] [--pressures 1e-3 1e-2]
       PYTHONPATH=. python benchmarks/layer_peers.py --speed --grid 256 1024 \
       --thickness 0.125 --poisson 0.3 --pressures 1e-2 --cm-tol 1e-6 1e-8 --repetitions 3

The surface is numpy's (``default_rng(60)``: a random-phase power law, H = 0.8, rolled off
at L/2, rms slope 0.1 on a unit cell), saved once and read by both.  For each bonded layer
(thickness in units of L, Poisson ratio): the largest relative difference between the two
stiffness multipliers on the grid's wavevectors (``q != 0``), then each nominal pressure
(units of E* = 1) solved by the package (``-tao_gatol 1e-12``) and by ContactMechanics's
Polonsky-Keer CG (benchmarks/peers/run_cm_layer.py in the peers' venv, penetration
``1e-10 h_rms``): mean gap, contact area and by how many pixels the contact sets' sizes
differ.  Prints a Markdown table.

``--speed`` times instead, per grid, layer and pressure: a reference solved by the package at
``-tao_gatol 1e-13``; then, alternated ``--repetitions`` times, the package's default solver
on ``--device cpu`` (a TAO type) and on ``--device cpu-array`` (NumPy), each after one
untimed warm-up, and ContactMechanics's CG at each penetration tolerance ``--cm-tol``
(times ``h_rms``: its largest and rms penetration of the contact, and its largest change of
displacement in an iteration, must fall below it; a bound in length, as ours on the gap).
The solve alone on both sides (ours ``solve_time``, its ``constrained_conjugate_gradients``;
surfaces, substrates, FFT plans and its interpreter's start left out).  Printed: each
answer's relative errors of area and mean gap and its largest pressure error over ``p0``,
the iterations, the median time, the ratios ours/this and the load around each repetition.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable

import numpy as np
from peer_env import peer_python
from side_by_side import alternate, load_line, medians, stamp

from petsc_contact.substrates.layer import PeriodicLayer
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.runner import run_contact

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = ("-tao_gatol", "1e-13")
OURS = ("ours, cpu", "ours, cpu-array")


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


def contactmechanics(
    path: str, case: tuple[float, float], pressures: list[float], tol: float = 1e-10
) -> tuple:
    """ContactMechanics's stiffness array and its rows, one per pressure (with its pressure
    field, ``field``)."""
    stiffness, out = path.replace(".npy", "_k.npy"), path.replace(".npy", "_p")
    argv = [peer_python() or "", os.path.join(HERE, "peers", "run_cm_layer.py"), path, "1", "1"]
    argv += [*map(str, case), ",".join(map(str, pressures)), str(tol), stiffness, out]
    text = subprocess.run(argv, capture_output=True, text=True, check=True).stdout
    rows = [json.loads(line) for line in text.splitlines() if line]
    for k, row in enumerate(rows, 1):
        row["field"] = np.load(f"{out}_{k}.npy")
    return np.load(stiffness), rows


def ours(h: np.ndarray, case: tuple[float, float], p0: float, device: str, options=()) -> dict:
    """The layer ``case`` (thickness, Poisson ratio) at ``p0`` on ``device``."""
    run = Run(heights=h, length=1.0, pressures=(p0,), thickness=case[0], poisson=case[1],
              fields=True, device=device, options=tuple(options))  # fmt: skip
    (step,) = run_contact(run, progress=False).steps
    s = step.scalars
    assert step.converged, s["verification"]
    return {"time": s["solve_time"], "iterations": s["iterations"], "field": step.pressure,
            "area_fraction": s["area_fraction"], "mean_gap": s["mean_gap"]}  # fmt: skip


def errors(row: dict, reference: dict, p0: float) -> str:
    """The row's relative errors of area and mean gap, its largest pressure error over p0."""
    cells = [abs(row[k] / reference[k] - 1) for k in ("area_fraction", "mean_gap")]
    cells.append(float(np.abs(row["field"] - reference["field"]).max() / p0))
    return " | ".join(f"{c:.1e}" for c in cells)


def speed(n: int, case: tuple[float, float], p0: float, args: argparse.Namespace) -> None:
    """The rows of ``--speed`` for one grid, layer and pressure."""
    h = surface(n)
    solvers: dict[str, Callable[[], dict]] = {
        "ours, cpu": lambda: ours(h, case, p0, "cpu"),
        "ours, cpu-array": lambda: ours(h, case, p0, "cpu-array"),
    }
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "h.npy")
        np.save(path, h)
        for tol in args.cm_tol:
            solvers[f"ContactMechanics, pentol {tol:g} h_rms"] = lambda tol=tol: contactmechanics(
                path, case, [p0], tol
            )[1][0]
        reference = ours(h, case, p0, "cpu", REFERENCE)
        for name in OURS:
            solvers[name]()  # warm-up: numba's kernels, FFTW's plans
        results, loads = alternate(solvers, args.repetitions)
    times = medians(results, OURS)
    for name, rows in results.items():
        print(f"| {n} | {case[0]:g} | {case[1]:g} | {p0:g} | {name} | "
              f"{errors(rows[-1], reference, p0)} | {rows[-1]['iterations']} | "
              f"{times[name]} |", flush=True)  # fmt: skip
    print(load_line(loads), file=sys.stderr)


def speed_tables(args: argparse.Namespace) -> None:
    """``--speed``: the header, then :func:`speed` for every grid, layer and pressure."""
    print(stamp(), file=sys.stderr)
    print("| grid | T/L | nu | p0/E* | solver | area rel. err. | mean gap rel. err. | "
          "max abs dp / p0 | iterations | median solve (s) | ours cpu / this | "
          "ours cpu-array / this |\n" + "| --- " * 12 + "|")  # fmt: skip
    for n in args.grid:
        for case in ((t, nu) for t in args.thickness for nu in args.poisson):
            for p0 in args.pressures:
                speed(n, case, p0, args)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, nargs="+", default=[256])
    ap.add_argument("--thickness", type=float, nargs="+", default=[1 / 64, 1 / 8])
    ap.add_argument("--poisson", type=float, nargs="+", default=[0.3, 0.45])
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e-3, 1e-2])
    ap.add_argument("--speed", action="store_true", help="time instead (module docstring)")
    ap.add_argument("--cm-tol", type=float, nargs="+", default=[1e-6, 1e-8])
    ap.add_argument("--repetitions", type=int, default=3)
    args = ap.parse_args()
    if args.speed:
        speed_tables(args)
        return
    (n,) = args.grid
    h = surface(n)
    print("| T/L | nu | max rel. diff. of K(q) | p0/E* | mean gap / h_rms, ours | "
          "ContactMechanics | rel. diff. | area, ours | contact pixels apart |\n"
          + "| --- " * 9 + "|")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "h.npy")
        np.save(path, h)
        for thickness in args.thickness:
            for nu in args.poisson:
                theirs, rows = contactmechanics(path, (thickness, nu), args.pressures)
                layer = PeriodicLayer(1.0, thickness, nu, "bonded")
                k_diff = multiplier_difference(layer, theirs, n)
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
                          f"{s['area_fraction']:.5f} | {apart} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
