"""Tamaas's KatoSaturated on a saved surface (runs in benchmarks/peers/.venv).

usage: .venv/bin/python run_tamaas_kato.py SURFACE.npy LENGTH MODULUS P1,P2,... HARDNESS TOL OUT
Prints one JSON line per pressure: solver ("tamaas"), pressure, area_fraction,
plastic_area_fraction, max_pressure, iterations, time; saves each pressure field as
OUT_K.npy (K from 1).
"""

import json
import sys
import time

import numpy as np
import tamaas as tm


def main() -> None:
    path, length, modulus, pressures, hardness, tol, out = sys.argv[1:8]
    h = np.load(path)
    n = h.shape[0]
    tm.set_log_level(tm.LogLevel.error)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(length)] * 2, [n, n])
    model.E, model.nu = float(modulus), 0.0  # E* = E / (1 - nu^2) = E
    # Tamaas's surface points toward the elastic body as ours does: same heights.
    solver = tm.KatoSaturated(model, h, float(tol), float(hardness))
    solver.max_iter = 100000
    for k, p0 in enumerate(map(float, pressures.split(",")), 1):
        start = time.perf_counter()
        solver.solve(p0)
        elapsed = time.perf_counter() - start
        p = np.array(model.traction).reshape(n, n)
        np.save(f"{out}_{k}.npy", p)
        print(
            json.dumps(
                {
                    "solver": "tamaas",
                    "pressure": p0,
                    "area_fraction": float(np.count_nonzero(p > 0) / p.size),
                    "plastic_area_fraction": float(
                        np.count_nonzero(p >= float(hardness) * (1 - 1e-12)) / p.size
                    ),
                    "max_pressure": float(p.max()),
                    "time": elapsed,
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
