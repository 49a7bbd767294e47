"""Time ContactMechanics's Polonsky-Keer constrained CG on a saved surface.

Runs in benchmarks/peers/.venv (PyPI contactmechanics, numpy 2).
usage: .venv/bin/python run_contactmechanics.py SURFACE.npy LENGTH MODULUS P1,P2,... PENTOL
PENTOL is the allowed penetration relative to the surface's rms height.
Prints one JSON line per pressure: pressure, mean_gap, area_fraction, iterations, time.
"""

import json
import sys
import time

import numpy as np
from ContactMechanics import PeriodicFFTElasticHalfSpace
from ContactMechanics.Optimization import constrained_conjugate_gradients


def main() -> None:
    path, length, modulus, pressures, pentol = sys.argv[1:6]
    h = np.load(path)
    n = h.shape[0]
    size = (float(length),) * 2
    substrate = PeriodicFFTElasticHalfSpace((n, n), float(modulus), physical_sizes=size)
    h_rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    for p0 in map(float, pressures.split(",")):
        start = time.perf_counter()
        # ContactMechanics: u >= h + offset on contact; pixel forces, compressive negative
        res = constrained_conjugate_gradients(
            substrate, h, external_force=p0 * size[0] * size[1],
            pentol=float(pentol) * h_rms, forcetol=1e-10, thermotol=1e-10, maxiter=200000)
        elapsed = time.perf_counter() - start
        gap = res.x - h - res.offset
        print(json.dumps({"pressure": p0, "mean_gap": float(gap.mean()),
                          "area_fraction": float(np.count_nonzero(res.active_set) / gap.size),
                          "iterations": int(res.nit), "time": elapsed,
                          "converged": bool(res.success)}), flush=True)


if __name__ == "__main__":
    main()
