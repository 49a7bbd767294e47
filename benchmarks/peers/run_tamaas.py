"""Time Tamaas's PolonskyKeerRey on a saved surface (runs in benchmarks/peers/.venv).

usage: .venv/bin/python run_tamaas.py SURFACE.npy LENGTH MODULUS P1,P2,... TOL
Prints one JSON line per pressure: solver ("tamaas"), pressure, mean_gap, area_fraction,
iterations, time.
"""

import json
import sys
import time

import numpy as np
import tamaas as tm


def main() -> None:
    path, length, modulus, pressures, tol = sys.argv[1:6]
    h = np.load(path)
    n = h.shape[0]
    tm.set_log_level(tm.LogLevel.error)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [float(length)] * 2, [n, n])
    model.E, model.nu = float(modulus), 0.0  # E* = E / (1 - nu^2) = E
    # Tamaas's surface points toward the elastic body as ours does: same heights.
    solver = tm.PolonskyKeerRey(model, h, float(tol), tm.PolonskyKeerRey.pressure,
                                tm.PolonskyKeerRey.pressure)
    solver.max_iter = 100000
    for p0 in map(float, pressures.split(",")):
        start = time.perf_counter()
        solver.solve(p0)
        elapsed = time.perf_counter() - start
        p = np.asarray(model.traction)
        u = np.asarray(model.displacement)
        gap = u - h - (u - h).min()
        print(json.dumps({"solver": "tamaas", "pressure": p0, "mean_gap": float(gap.mean()),
                          "area_fraction": float(np.count_nonzero(p > 0) / p.size),
                          "iterations": int(getattr(solver, "iterations", -1)),
                          "time": elapsed}), flush=True)


if __name__ == "__main__":
    main()
