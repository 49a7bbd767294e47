"""ContactMechanics on a prepared (rectangular) height map, periodic or free boundary.

Runs in benchmarks/peers/.venv.
usage: .venv/bin/python run_cm_map.py HEIGHTS.npy LX,LY MODULUS periodic|free P1,P2,...
Solves with ContactMechanics's constrained CG (Polonsky-Keer) under load control, tightly
converged, and prints one JSON line per nominal pressure: mean_gap (over the map; for the
free boundary over the footprint), contact_pixels, offset, iterations, converged.
"""

import json
import sys

import numpy as np
from ContactMechanics import FreeFFTElasticHalfSpace, PeriodicFFTElasticHalfSpace
from ContactMechanics.Optimization import constrained_conjugate_gradients


def main() -> None:
    path, sides, modulus, geometry, pressures = sys.argv[1:6]
    h = np.load(path)
    size = tuple(float(v) for v in sides.split(","))
    kind = PeriodicFFTElasticHalfSpace if geometry == "periodic" else FreeFFTElasticHalfSpace
    substrate = kind(h.shape, float(modulus), physical_sizes=size)
    h_rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    for p0 in map(float, pressures.split(",")):
        res = constrained_conjugate_gradients(
            substrate, h, external_force=p0 * size[0] * size[1],
            pentol=1e-12 * h_rms, forcetol=1e-12, thermotol=1e-12, maxiter=200000)
        u = res.x[: h.shape[0], : h.shape[1]] if geometry == "free" else res.x
        gap = u - h - res.offset
        print(json.dumps({
            "geometry": geometry, "pressure": p0, "mean_gap": float(gap.mean()),
            "contact_pixels": int(np.count_nonzero(res.active_set[: h.shape[0], : h.shape[1]])),
            "offset": float(res.offset), "iterations": int(res.nit),
            "converged": bool(res.success)}), flush=True)


if __name__ == "__main__":
    main()
