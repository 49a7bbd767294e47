"""A rectangular measured map end to end, against ContactMechanics on the same prepared heights.

usage: .venv/bin/python benchmarks/measured_map.py [--nx 384 --ny 192] [--workdir DIR]

Makes a map as an instrument delivers it: 384 x 192 points on 150 um x 100 um (oblong
pixels), heights in nm, tilted, with a few undefined points.  Prepares and solves it with
``petsc-contact periodic`` and ``petsc-contact punch`` (``--height-unit nm --length
150um,100um --detrend slope --fill-undefined harmonic``, tightly converged), then gives the
prepared heights the runs stored to ContactMechanics (benchmarks/peers/run_cm_map.py, in the
peers' venv) at the same nominal pressures, and compares mean gaps and contact pixels.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import h5py
import numpy as np
from peer_env import peer_python

HERE = os.path.dirname(os.path.abspath(__file__))
PRESSURES = "1e-3,1e-2"  # in units of E* (the modulus is 1)
TIGHT = ["-tao_gatol", "1e-12"]


def instrument_map(nx: int, ny: int) -> np.ndarray:
    """Heights in nm: a self-affine surface (H = 0.8, rms slope ~0.05 on 150 x 100 um),
    tilted, with NaN holes."""
    rng = np.random.default_rng(11)
    qx = np.fft.fftfreq(nx, 150.0 / nx)[:, None]
    qy = np.fft.rfftfreq(ny, 100.0 / ny)[None, :]
    q = np.hypot(qx, qy)
    filt = np.where(q > 0, np.maximum(q, 1 / 150.0) ** -1.8, 0.0)
    noise = np.fft.rfft2(rng.standard_normal((nx, ny)))
    h = np.fft.irfft2(noise * filt, (nx, ny))
    slopes = np.gradient(h, 150.0 / nx, axis=0), np.gradient(h, 100.0 / ny, axis=1)
    h *= 0.05 / np.sqrt(sum(np.mean(s**2) for s in slopes))  # rms slope 0.05 (um/um)
    h = 1e3 * h + 2.0 * np.arange(nx)[:, None] / nx * 1e3  # nm, tilted by 2 um over the map
    h[40:44, 50:53] = np.nan
    h[200, 100] = np.nan
    return h


def ours(command: str, path: str, out: str) -> None:
    loads = ["--pressures", PRESSURES] if command == "periodic" else ["--forces", _forces()]
    argv = [sys.executable, "-m", "petsc_contact.cli", command, "--heights", path]
    argv += ["--height-unit", "nm", "--length", "150um,100um", "--detrend", "slope"]
    argv += ["--fill-undefined", "harmonic", *loads, "--fields", "--quiet", "--output", out]
    subprocess.run([*argv, *TIGHT], check=True)


def _forces() -> str:
    return ",".join(f"{p * 150.0 * 100.0:g}" for p in map(float, PRESSURES.split(",")))


def cm(heights: str, geometry: str) -> list[dict]:
    python = peer_python()
    if python is None:
        raise SystemExit("ContactMechanics is not installed (see benchmarks/peer_env.py)")
    run = subprocess.run(
        [
            python,
            os.path.join(HERE, "peers", "run_cm_map.py"),
            heights,
            "150,100",
            "1",
            geometry,
            PRESSURES,
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    return [json.loads(line) for line in run.stdout.splitlines() if line.startswith("{")]


def compare(out: str, geometry: str, prepared: str) -> list[dict]:
    """Our steps next to ContactMechanics's: relative mean-gap difference, pixel difference."""
    rows = []
    with h5py.File(out) as f:
        np.save(prepared, f["heights"][...])
        gaps = f["gap"][...]
        contact = f["contact"][...]
    for k, theirs in enumerate(cm(prepared, geometry)):
        mine = float(gaps[k].mean())
        rows.append(
            {
                "geometry": geometry,
                "pressure": theirs["pressure"],
                "mean_gap": mine,
                "cm_mean_gap": theirs["mean_gap"],
                "relative_difference": abs(mine - theirs["mean_gap"]) / abs(theirs["mean_gap"]),
                "contact_pixels": int(contact[k].sum()),
                "cm_contact_pixels": theirs["contact_pixels"],
                "cm_converged": theirs["converged"],
            }
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, default=384)
    ap.add_argument("--ny", type=int, default=192)
    ap.add_argument("--workdir", default="measured-map")
    args = ap.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    path = os.path.join(args.workdir, "map_nm.npy")
    np.save(path, instrument_map(args.nx, args.ny))
    rows = []
    for command, geometry in (("periodic", "periodic"), ("punch", "free")):
        out = os.path.join(args.workdir, f"{command}.h5")
        ours(command, path, out)
        rows += compare(out, geometry, os.path.join(args.workdir, f"prepared_{command}.npy"))
    print(
        f"{'geometry':>9} {'p0/E*':>8} {'mean gap (um)':>15} {'CM':>15} {'rel diff':>9} "
        f"{'pixels':>7} {'CM':>7}"
    )
    for r in rows:
        print(
            f"{r['geometry']:>9} {r['pressure']:>8.0e} {r['mean_gap']:>15.9e} "
            f"{r['cm_mean_gap']:>15.9e} {r['relative_difference']:>9.1e} "
            f"{r['contact_pixels']:>7d} {r['cm_contact_pixels']:>7d}"
        )
    with open(os.path.join(args.workdir, "comparison.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
