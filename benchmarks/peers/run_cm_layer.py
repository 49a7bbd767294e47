"""ContactMechanics's elastic layer on a rigid base: its stiffness and contacts on a saved
surface.

Runs in benchmarks/peers/.venv (PyPI contactmechanics, numpy 2).
usage: .venv/bin/python run_cm_layer.py SURFACE.npy LENGTH ESTAR THICKNESS POISSON P1,P2,... TOL
       STIFFNESS.npy [OUT]
``PeriodicFFTElasticHalfSpace(..., thickness=, poisson=)`` takes Young's modulus: it is given
``E = E* (1 - nu^2)``, so that its contact modulus is ``E*``.  Writes its surface stiffness
(pressure per displacement on the real-FFT grid, wavevectors in ContactMechanics's order) to
STIFFNESS.npy, then solves each nominal pressure with ContactMechanics's constrained CG
(Polonsky-Keer) under load control, the allowed penetration TOL * h_rms, from its own start.
Prints one JSON line per pressure: pressure, mean_gap, area_fraction, iterations, time (the
solve alone), converged; with OUT, saves each pressure field as OUT_K.npy (K from 1).
"""

import json
import sys
import time

import numpy as np
from ContactMechanics import PeriodicFFTElasticHalfSpace
from ContactMechanics.Optimization import constrained_conjugate_gradients


def main() -> None:
    path, length, estar, thickness, poisson, pressures, tol, stiffness = sys.argv[1:9]
    out = sys.argv[9] if len(sys.argv) > 9 else None
    h = np.load(path)
    n, nu = h.shape[0], float(poisson)
    size = (float(length),) * 2
    young = float(estar) * (1 - nu**2)
    substrate = PeriodicFFTElasticHalfSpace(
        (n, n), young, physical_sizes=size, thickness=float(thickness), poisson=nu
    )
    np.save(stiffness, 1 / substrate.greens_function)
    h_rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    for k, p0 in enumerate(map(float, pressures.split(",")), 1):
        start = time.perf_counter()
        # ContactMechanics: u >= h + offset on contact; pixel forces, compressive negative
        res = constrained_conjugate_gradients(
            substrate, h, external_force=p0 * size[0] * size[1],
            pentol=float(tol) * h_rms, forcetol=1e-10, thermotol=1e-10, maxiter=200000)  # fmt: skip
        elapsed = time.perf_counter() - start
        gap = res.x - h - res.offset
        if out is not None:  # its pixel forces, compressive positive, over the pixel's area
            np.save(f"{out}_{k}.npy", res.jac * (n / size[0]) ** 2)
        print(json.dumps({"pressure": p0, "mean_gap": float(gap.mean()),
                          "area_fraction": float(np.count_nonzero(res.active_set) / h.size),
                          "iterations": int(res.nit), "time": elapsed,
                          "converged": bool(res.success)}), flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
