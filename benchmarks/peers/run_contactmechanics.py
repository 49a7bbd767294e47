"""Time ContactMechanics's constrained CGs on a saved surface.

Runs in benchmarks/peers/.venv (PyPI contactmechanics, numpy 2).
usage: .venv/bin/python run_contactmechanics.py SURFACE.npy LENGTH MODULUS P1,P2,... TOL [--bugnicourt]
Runs ContactMechanics's own constrained CG (Polonsky-Keer) under load control, with the
allowed penetration TOL * h_rms.  With --bugnicourt it then also runs the CG without
restarts (Bugnicourt et al. 2018) that ContactMechanics's systems run on their dual
(pressure) problem, ``dual_minimize_proxy(offset, solver="ccg-without-restart")``, with the
largest projected gap residual TOL * h_rms.  That solver is displacement controlled: it is
given the rigid offset Polonsky-Keer found for the load, so it solves the same problem
knowing one number of the answer.  Under load control instead (NuMPI's mean-value
constraint) it stalled near 6e-7 h_rms at p0 = 1e-2 E* on a 512^2 surface and then diverged.
Both start cold: from ContactMechanics's own initial guess, or a uniform pressure p0.
Prints one JSON line per pressure and solver: solver ("cm-polonsky-keer" or
"cm-bugnicourt"), pressure, mean_gap, area_fraction,
iterations, time, converged.
"""

import json
import sys
import time

import numpy as np
from ContactMechanics import PeriodicFFTElasticHalfSpace, make_system
from ContactMechanics.Optimization import constrained_conjugate_gradients
from SurfaceTopography import Topography


def polonsky_keer(substrate, h, size, p0, tol):
    """ContactMechanics's Polonsky-Keer CG: (result, gap, contact mask, seconds)."""
    start = time.perf_counter()
    # ContactMechanics: u >= h + offset on contact; pixel forces, compressive negative
    res = constrained_conjugate_gradients(
        substrate, h, external_force=p0 * size[0] * size[1],
        pentol=tol, forcetol=1e-10, thermotol=1e-10, maxiter=200000)
    elapsed = time.perf_counter() - start
    return res, res.x - h - res.offset, res.active_set, elapsed


def bugnicourt(substrate, h, size, p0, tol, offset):
    """Bugnicourt's CG on ContactMechanics's dual problem at the rigid ``offset``:
    (result, gap, contact mask, seconds)."""
    system = make_system(substrate=substrate, surface=Topography(h, size))
    uniform = np.full(h.shape, p0 * size[0] * size[1] / h.size)  # pixel forces of p0
    start = time.perf_counter()
    res = system.dual_minimize_proxy(offset, init_force=uniform, solver="ccg-without-restart",
                                     gtol=tol, maxiter=200000)
    elapsed = time.perf_counter() - start
    force = res.x.reshape(h.shape)
    return res, substrate.evaluate_disp(-force) - h - offset, force > 0, elapsed


def report(solver, p0, res, gap, contact, elapsed):
    print(json.dumps({"solver": solver, "pressure": p0, "mean_gap": float(gap.mean()),
                      "area_fraction": float(np.count_nonzero(contact) / gap.size),
                      "iterations": int(res.nit), "time": elapsed,
                      "converged": bool(res.success)}), flush=True)


def main() -> None:
    path, length, modulus, pressures, tol = sys.argv[1:6]
    h = np.load(path)
    n = h.shape[0]
    size = (float(length),) * 2
    substrate = PeriodicFFTElasticHalfSpace((n, n), float(modulus), physical_sizes=size)
    h_rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    tolerance = float(tol) * h_rms
    for p0 in map(float, pressures.split(",")):
        res, *rest = polonsky_keer(substrate, h, size, p0, tolerance)
        report("cm-polonsky-keer", p0, res, *rest)
        if "--bugnicourt" in sys.argv[6:]:
            report("cm-bugnicourt", p0, *bugnicourt(substrate, h, size, p0, tolerance, res.offset))


if __name__ == "__main__":
    main()
