"""Speed of petsc-contact's solvers against Tamaas on the same surface and loads.

usage: .venv/bin/python benchmarks/speed.py [--grid 512 2048] [--types tron bqnls]
Prints per solver and load: iterations, FFT round trips, wall time, time per round trip over
one measured FFT round trip (the "ratio"), and Tamaas PolonskyKeerRey's time (if its venv in
benchmarks/peers/.venv exists: python3 -m venv benchmarks/peers/.venv &&
benchmarks/peers/.venv/bin/pip install tamaas).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np

from petsc_contact import periodic_contact
from petsc_contact.fft import make_fft
from petsc_contact.grid import Grid
from petsc_contact.surface import self_affine

HERE = os.path.dirname(os.path.abspath(__file__))
PEERS = os.path.join(HERE, "peers")


def fft_round_trip(grid: Grid) -> float:
    fft = make_fft(grid)
    fft.real[...] = np.random.default_rng(0).standard_normal(grid.local_shape)
    fft.forward(), fft.backward()
    start = time.perf_counter()
    for _ in range(20):
        fft.forward()
        fft.backward()
    return (time.perf_counter() - start) / 20


def tamaas(path: str, pressures: list[float]) -> list[dict]:
    python = os.path.join(PEERS, ".venv", "bin", "python")
    if not os.path.exists(python):
        return []
    out = subprocess.run([python, os.path.join(PEERS, "run_tamaas.py"), path, "1", "1",
                          ",".join(map(str, pressures)), "1e-8"],
                         capture_output=True, text=True, check=True).stdout
    return [json.loads(line) for line in out.splitlines() if line.startswith("{")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, nargs="+", default=[512])
    ap.add_argument("--types", nargs="+", default=["tron", "bqnls"])
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e-3, 1e-2])
    ap.add_argument("--no-peers", action="store_true", help="skip Tamaas")
    args = ap.parse_args()
    for n in args.grid:
        grid = Grid(n, 1.0)
        h = self_affine(grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=64,
                        seed=1, rms_slope=0.1)
        rt = fft_round_trip(grid)
        print(f"# n = {n}: FFT round trip {rt * 1e3:.3f} ms")
        print(f"{'solver':>8} {'p0':>7} {'its':>5} {'FFTs':>6} {'time_s':>8} {'ratio':>6}"
              f" {'mean_gap':>14} {'tamaas_s':>9} {'speed-up':>8}")
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "h.npy")
            np.save(path, h)
            peer = ({} if args.no_peers else
                    {r["pressure"]: r for r in tamaas(path, args.pressures)})
        for t in args.types:
            for p0 in args.pressures:
                (s,) = periodic_contact(h, 1.0, 1.0, [p0], options=["-tao_type", t])
                d = s.scalars
                ffts = (d["objective_gradient_evaluations"] + d["hessian_applications"]
                        + d["preconditioner_applications"])
                ratio = d["solve_time"] / (ffts * rt)
                tm = peer.get(p0, {}).get("time", float("nan"))
                flag = "" if s.converged else "  NOT CONVERGED"
                print(f"{t:>8} {p0:>7.0e} {d['iterations']:>5d} {ffts:>6d} "
                      f"{d['solve_time']:>8.3f} {ratio:>6.2f} {d['mean_gap']:>14.8e} "
                      f"{tm:>9.3f} {tm / d['solve_time']:>8.2f}{flag}", flush=True)


if __name__ == "__main__":
    main()
