"""The hardness cap against Tamaas's KatoSaturated on a surface this package never generated.

A numpy-seeded random surface (white noise filtered by ``|q|^-1.8`` up to half the Nyquist
wavevector, rms slope 0.1; not :mod:`petsc_contact.physics.surface`'s generator) is saved to
a file; the periodic cell with ``--hardness`` (posed in the pressure) and Tamaas's
``KatoSaturated`` (``benchmarks/peers/run_tamaas_kato.py``, in the peers' venv:
:mod:`peer_env`) solve it at the same nominal pressures.  Printed per pressure: the area and
plastic area of each, their differences, the largest pressure difference over the hardness,
and each one's time::

    PYTHONPATH=. python benchmarks/hardness_tamaas.py --grid 128 --hardness 0.02 \
        --pressures 1e-3,5e-3
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
from peer_env import peer_python

PEERS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers")


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


def ours(h: np.ndarray, pressures: list[float], hardness: float) -> list[dict]:
    """The capped periodic cell, one row per pressure with its pressure field."""
    from petsc_contact import Run, run_contact

    rows = []
    for p0 in pressures:  # each from first touch, as Tamaas's solves
        run = Run(heights=h, length=1.0, pressures=[p0], hardness=hardness, fields=True)
        start = time.perf_counter()
        (step,) = run_contact(run).steps
        elapsed = time.perf_counter() - start
        s = step.scalars
        assert step.converged, s["verification"]
        rows.append({**s, "time": elapsed, "field": step.pressure})
    return rows


def tamaas(path: str, pressures: list[float], hardness: float, out: str) -> list[dict]:
    """Tamaas's KatoSaturated at tolerance 1e-10, its pressure fields read back."""
    python = peer_python()
    if python is None:
        sys.exit("no peers' venv: see benchmarks/peer_env.py")
    args = [os.path.join(PEERS, "run_tamaas_kato.py"), path, "1", "1"]
    args += [",".join(map(str, pressures)), str(hardness), "1e-10", out]
    text = subprocess.run([python, *args], capture_output=True, text=True, check=True).stdout
    rows = [json.loads(line) for line in text.splitlines() if line.startswith("{")]
    for k, row in enumerate(rows, 1):
        row["field"] = np.load(f"{out}_{k}.npy")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", type=int, default=128)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--hardness", type=float, default=0.02)
    parser.add_argument("--pressures", default="1e-3,5e-3")
    a = parser.parse_args()
    pressures = [float(p) for p in a.pressures.split(",")]
    h = surface(a.grid, a.seed)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "h.npy")
        np.save(path, h)
        theirs = tamaas(path, pressures, a.hardness, os.path.join(folder, "p"))
    mine = ours(h, pressures, a.hardness)
    print("| p0/E* | area (ours) | area (Tamaas) | plastic (ours) | plastic (Tamaas) | "
          "max abs dp / H | ours (s) | Tamaas (s) |")  # fmt: skip
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for m, t in zip(mine, theirs, strict=True):
        dp = np.abs(m["field"] - t["field"]).max() / a.hardness
        print(
            f"| {m['nominal_pressure']:g} | {m['area_fraction']:.5f} | {t['area_fraction']:.5f} "
            f"| {m['plastic_area_fraction']:.5f} | {t['plastic_area_fraction']:.5f} | {dp:.1e} "
            f"| {m['time']:.2f} | {t['time']:.2f} |"
        )


if __name__ == "__main__":
    main()
