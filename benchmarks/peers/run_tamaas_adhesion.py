"""Tamaas's adhesive Polonsky-Keer-Rey (posed in the gap) on a saved surface, at prescribed
mean gaps (runs in benchmarks/peers/.venv).

usage: .venv/bin/python run_tamaas_adhesion.py SURFACE.npy LENGTH MODULUS LAW W RHO G1,G2,... TOL
LAW is exponential or maugis. Prints one JSON line per mean gap: solver ("tamaas"), mean_gap
(asked), mean_gap_reached, mean_pressure, area_fraction (the pixels at zero gap), time (the
solve's wall time), cpu (its process CPU time).
"""

import json
import sys
import time

import numpy as np
import tamaas as tm

FUNCTIONALS = {
    "exponential": tm.ExponentialAdhesionFunctional,
    "maugis": tm.MaugisAdhesionFunctional,
}


def main() -> None:
    path, length, modulus, law, w, rho, gaps, tol = sys.argv[1:9]
    h = np.load(path)
    n = h.shape[0]
    tm.set_log_level(tm.LogLevel.error)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(length)] * 2, [n, n])
    model.E, model.nu = float(modulus), 0.0  # E* = E / (1 - nu^2) = E
    gap = tm.PolonskyKeerRey.gap
    solver = tm.PolonskyKeerRey(model, h, float(tol), gap, gap)
    solver.max_iter = 100000
    adhesion = FUNCTIONALS[law](h)
    adhesion.parameters = {"rho": float(rho), "surface_energy": float(w)}
    solver.addFunctionalTerm(adhesion)
    for g0 in map(float, gaps.split(",")):
        start, cpu = time.perf_counter(), time.process_time()
        solver.solve(g0)
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
        p = np.array(model.traction).reshape(n, n)
        g = np.array(model.displacement).reshape(n, n) - h

        row = {
            "solver": "tamaas",
            "mean_gap": g0,
            "mean_gap_reached": float(g.mean()),
            "mean_pressure": float(p.mean()),
            "area_fraction": float(np.count_nonzero(g <= 0) / g.size),
            "time": elapsed,
            "cpu": cpu,
        }
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
