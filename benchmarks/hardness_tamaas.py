"""The hardness cap against Tamaas's KatoSaturated on a surface this package never generated.

A numpy-seeded random surface (white noise filtered by ``|q|^-1.8`` up to half the Nyquist
wavevector, rms slope 0.1; not :mod:`petsc_contact.physics.surface`'s generator) is saved
once to a ``.npy`` file that both read.  The periodic cell with ``--hardness`` (posed in
the pressure) and Tamaas's ``KatoSaturated`` (``benchmarks/peers/run_tamaas_kato.py``, in the
peers' venv: :mod:`peer_env`) each solve every nominal pressure from first touch.

Accuracy: every answer is compared with a reference solved by the package at
``-tao_gatol 1e-13`` (its gap residual; docs/solvers.md): the relative errors of the contact
and plastic areas and the largest pressure difference over the hardness.  Tamaas's tolerance
is a relative criterion on its own residual, not the same measure: ``--tamaas-tol`` takes
several, so that the one as accurate as ours is found by its errors.

Speed: the solve alone on both sides (the package's ``solve_time``: TAO's solve; Tamaas's
``solve()``; the surface, the model, the FFT plans and, for Tamaas, the interpreter's start
are left out of both), the package's default solver on ``--device cpu`` (a TAO type) and
the same solver on NumPy (``--device cpu-array``), after one untimed warm-up of each.  The
solvers run alternated, ``--repetitions`` times; printed: each one's errors, iterations, the
median time and the ratio ours/Tamaas, the load average around each repetition.  One
command::

    PYTHONPATH=. python benchmarks/hardness_tamaas.py --grid 256 --pressures 5e-3 \
        --hardness 0.02 --tamaas-tol 1e-6,1e-8 --repetitions 3
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

PEERS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers")
REFERENCE = ("-tao_gatol", "1e-13")
OURS = ("ours, cpu", "ours, cpu-array")


def surface(n: int, seed: int) -> np.ndarray:
    """The surface of the module docstring, on an ``n x n`` cell of side 1."""
    rng = np.random.default_rng(seed)
    q = np.hypot(np.fft.fftfreq(n)[:, None], np.fft.fftfreq(n)[None, :])
    q[0, 0] = np.inf
    spectrum = q**-1.8 * (rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n)))
    spectrum[q > 0.25] = 0
    h = np.fft.ifft2(spectrum).real
    h -= h.mean()
    gx, gy = np.gradient(h, 1.0 / n)
    return h * 0.1 / np.sqrt(np.mean(gx**2 + gy**2))


def ours(h: np.ndarray, p0: float, hardness: float, device: str, options=()) -> dict:
    """The capped periodic cell at ``p0`` on ``device``: solve time, areas, pressure field."""
    from petsc_contact import Run, run_contact

    run = Run(heights=h, length=1.0, pressures=[p0], hardness=hardness, fields=True,
              device=device, options=tuple(options))  # fmt: skip
    (step,) = run_contact(run, progress=False).steps
    s = step.scalars
    assert step.converged, s["verification"]
    return {"time": s["solve_time"], "iterations": s["iterations"], "field": step.pressure,
            "area_fraction": s["area_fraction"],
            "plastic_area_fraction": s["plastic_area_fraction"]}  # fmt: skip


def tamaas(path: str, p0: float, hardness: float, tol: float, out: str) -> dict:
    """Tamaas's KatoSaturated at ``tol``, its pressure field read back."""
    args = [os.path.join(PEERS, "run_tamaas_kato.py"), path, "1", "1", str(p0), str(hardness)]
    text = subprocess.run([peer_python() or "", *args, str(tol), out], capture_output=True,
                          text=True, check=True).stdout  # fmt: skip
    (row,) = [json.loads(line) for line in text.splitlines() if line.startswith("{")]
    return {**row, "iterations": "", "field": np.load(f"{out}_1.npy")}


def errors(row: dict, reference: dict, hardness: float) -> str:
    """The row's relative area errors and largest pressure error over the hardness."""
    cells = [abs(row[k] / reference[k] - 1) for k in ("area_fraction", "plastic_area_fraction")]
    cells.append(float(np.abs(row["field"] - reference["field"]).max() / hardness))
    return " | ".join(f"{c:.1e}" for c in cells)


def table(n: int, p0: float, a: argparse.Namespace) -> None:
    """One grid and pressure: reference, warm-ups, alternated repetitions, the Markdown rows."""
    h = surface(n, a.seed)
    solvers: dict[str, Callable[[], dict]] = {
        "ours, cpu": lambda: ours(h, p0, a.hardness, "cpu"),
        "ours, cpu-array": lambda: ours(h, p0, a.hardness, "cpu-array"),
    }
    with tempfile.TemporaryDirectory() as folder:
        path, out = os.path.join(folder, "h.npy"), os.path.join(folder, "p")
        np.save(path, h)
        for tol in a.tamaas_tol.split(","):
            solvers[f"Tamaas, tol {tol}"] = lambda tol=float(tol): tamaas(
                path, p0, a.hardness, tol, out
            )
        reference = ours(h, p0, a.hardness, "cpu", REFERENCE)
        for name in OURS:
            solvers[name]()  # warm-up: numba's kernels, FFTW's plans
        results, loads = alternate(solvers, a.repetitions)
    times = medians(results, OURS)
    for name, rows in results.items():
        print(f"| {n} | {p0:g} | {name} | {errors(rows[-1], reference, a.hardness)} | "
              f"{rows[-1]['iterations']} | {times[name]} |", flush=True)  # fmt: skip
    print(load_line(loads), file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", default="256", help="grids, comma-separated")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--hardness", type=float, default=0.02)
    parser.add_argument("--pressures", default="5e-3", help="comma-separated")
    parser.add_argument("--tamaas-tol", default="1e-6,1e-8", help="comma-separated")
    parser.add_argument("--repetitions", type=int, default=3)
    a = parser.parse_args()
    if peer_python() is None:
        sys.exit("no peers' venv: see benchmarks/peer_env.py")
    print(f"{stamp()}; H/E* = {a.hardness:g}", file=sys.stderr)
    print("| grid | p0/E* | solver | area rel. err. | plastic area rel. err. | max abs dp / H | "
          "iterations | median solve (s) | ours cpu / this | ours cpu-array / this |\n"
          + "| --- " * 10 + "|")  # fmt: skip
    for n in map(int, a.grid.split(",")):
        for p0 in map(float, a.pressures.split(",")):
            table(n, p0, a)


if __name__ == "__main__":
    main()
