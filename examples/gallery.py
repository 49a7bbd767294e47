"""The pictures of docs/gallery.md, from a map this script makes and the commands it lists.

usage: .venv/bin/python examples/gallery.py [--output docs/gallery] [--grid 256]

The map: a self-affine surface (H = 0.8, rms slope 0.05) of 50 um x 50 um, in nm, tilted
by 0.5 um across, with an undefined patch and a few undefined points, written as an ISO
25178 X3P file by SurfaceTopography (as an instrument's software would).  Then each command
of ``COMMANDS`` runs as a user would type it, and the PNGs land in ``--output``.
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
from collections.abc import Callable

import numpy as np

COMMANDS = [
    "periodic --heights scan.x3p --fill-undefined harmonic --detrend slope --modulus 1GPa "
    "--pressures 1MPa,10MPa,50MPa --fields --output scan.h5",
    "plot scan.h5 --field pressure --step 1 --output pressure.png",
    "plot scan.h5 --field contact --step 2 --output contact.png",
    "plot scan.h5 --field gap --step 2 --output gap.png",
    "plot scan.h5 --field heights --output heights.png",
    "plot scan.h5 --field filled --output filled.png",
    "periodic --heights scan.x3p --fill-undefined harmonic --detrend slope --modulus 1GPa "
    "--sweep 12,1e-5,1e-1 --stiffness --output sweep.h5 --plot sweep.png",
    "theory --heights scan.x3p --fill-undefined harmonic --detrend slope --modulus 1GPa "
    "--output theory.h5 --plot theory.png --compare sweep.h5",
    "punch --heights scan.x3p --fill-undefined harmonic --detrend slope --modulus 1GPa "
    "--pressures 1MPa,3MPa,10MPa,30MPa --fields --output punch.h5 --plot punch.png",
    "plot punch.h5 --field pressure --step 2 --output punch_pressure.png",
]


def make_map(path: str, n: int) -> None:
    """The scan: paper Eq. 5's spectrum, in nm on 50 um, tilted, with undefined points."""
    from SurfaceTopography import Topography

    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import SerialFFT
    from petsc_contact.physics.surface import self_affine

    grid = Grid(n, 50.0)
    h = self_affine(grid, SerialFFT(grid), hurst=0.8, rolloff_ratio=4, cutoff_ratio=n / 4,
                    seed=7, rms_slope=0.05)  # fmt: skip
    x = np.arange(n)[:, None] / n
    nm = 1e3 * (h + 0.5 * x)  # um to nm, a tilt of 0.5 um across the map
    mask = np.zeros(nm.shape, bool)
    mask[n // 5 : n // 5 + n // 10, n // 2 : n // 2 + n // 6] = True  # a dropout
    mask[np.random.default_rng(3).random(nm.shape) < 0.002] = True  # lost points
    Topography(np.ma.masked_array(nm, mask), (5e4, 5e4), unit="nm").to_x3p(path)


def arguments(command: str) -> list[str]:
    """A command of :data:`COMMANDS` as ``petsc-contact``'s arguments (quiet, but for a plot)."""
    words = shlex.split(command)
    return words if command.startswith("plot") else [*words, "--quiet"]


def in_a_process(words: list[str], folder: str) -> None:
    """``petsc-contact WORDS`` in ``folder``, a process of its own, as a user types it."""
    subprocess.run([sys.executable, "-m", "petsc_contact.cli", *words], cwd=folder, check=True)


def draw(output: str, grid: int, run: Callable[[list[str], str], None] = in_a_process) -> None:
    """The map (``grid`` pixels a side) and every picture of :data:`COMMANDS` in ``output``,
    each command run by ``run(arguments, folder)``; only the PNGs are kept."""
    os.makedirs(output, exist_ok=True)
    make_map(os.path.join(output, "scan.x3p"), grid)
    for command in COMMANDS:
        print(f"$ petsc-contact {command}", flush=True)
        run(arguments(command), output)
    for name in os.listdir(output):
        if not name.endswith(".png"):
            os.remove(os.path.join(output, name))


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--output", default=os.path.join("docs", "gallery"))
    ap.add_argument("--grid", type=int, default=256)
    args = ap.parse_args(argv)
    draw(args.output, args.grid)


if __name__ == "__main__":
    main()
