"""Speed of petsc-contact's solvers against Tamaas and ContactMechanics on the same surface.

usage: .venv/bin/python benchmarks/speed.py [--grid 512 2048] [--types python tron] [--repeat 3]
       [--surfaces easy paper]
Surfaces (H = 0.7, rms slope 0.1, seed 1): "easy", L/lambda_r = 2 and L/lambda_1 = 64; "paper",
the paper's bandwidth, L/lambda_r = 1 and roughness down to two pixels (L/lambda_1 = n/2).
Prints per surface, solver and load: iterations, FFT round trips (transforms counted in the
step, set-up included, halved: a projected CG step skips one inverse transform), wall time
(median of --repeat solves: single timings vary by 30% on a shared 2-core machine), time per
round trip over one measured FFT round trip (the "ratio"; forward + spectral multiply +
backward, median of 5 batches of 20), the same ratio against the FFT time measured inside that
solve ("in-solve": one over the share of the solve spent in FFTs, immune to the machine's drift
between the FFT benchmark and the solve), and the peers' times in the same run: Tamaas
PolonskyKeerRey (tolerance 1e-8) and ContactMechanics's two constrained CGs, Polonsky-Keer
(penetration tolerance 1e-8 h_rms) and Bugnicourt (largest gap residual 1e-8 h_rms; run
displacement controlled at Polonsky-Keer's offset for the load, see
peers/run_contactmechanics.py), all cold-started like ours, if they are installed (in the
package's venv: ``.venv/bin/pip install -e '.[peers]'``; or in a venv of their own, see
peer_env.py).
All four reach the same mean gap to 1e-8 (printed, so a mismatch shows).  "/cm" is the ratio to
the faster of ContactMechanics's two solvers for that load.  Type "python" is the default
solver.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np
from peer_env import peer_python

from petsc_contact import periodic_contact
from petsc_contact.backend.operator import FourierOperator
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import SerialFFT, make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.physics.surface import self_affine

HERE = os.path.dirname(os.path.abspath(__file__))
PEERS = os.path.join(HERE, "peers")


def fft_round_trip(grid: Grid) -> float:
    """One FFT round trip (forward, kernel multiply, backward): median of 5 batches of 20."""
    fft = make_fft(grid)
    x = np.random.default_rng(0).standard_normal(grid.local_shape)
    op = FourierOperator(grid, fft, np.ones(fft.spectrum.shape))
    out = np.empty_like(x)
    op.apply_array(x, out)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(20):
            op.apply_array(x, out)
        times.append((time.perf_counter() - start) / 20)
    return float(np.median(times))


class FFTClock:
    """Accumulate the wall time spent in the serial FFT backend's transforms, and count them."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.transforms = 0
        self._saved: dict[str, object] = {}

    def __enter__(self) -> FFTClock:
        for name in ("forward", "backward", "forward_from", "backward_into"):
            method = getattr(SerialFFT, name)
            self._saved[name] = method

            def timed(*args, _method=method, **kwargs):
                start = time.perf_counter()
                try:
                    return _method(*args, **kwargs)
                finally:
                    self.seconds += time.perf_counter() - start
                    self.transforms += 1

            setattr(SerialFFT, name, timed)
        return self

    def __exit__(self, *exc: object) -> None:
        for name, method in self._saved.items():
            setattr(SerialFFT, name, method)


PEER_RUNS = (("run_tamaas.py",), ("run_contactmechanics.py", "--bugnicourt"))


def peer(
    script: str, path: str, pressures: list[float], *extra: str
) -> dict[str, dict[float, dict]]:
    """Run a peer's script (:func:`peer_env.peer_python`); results by solver and pressure
    (empty without the peers)."""
    python = peer_python()
    if python is None:
        return {}
    out = subprocess.run(
        [
            python,
            os.path.join(PEERS, script),
            path,
            "1",
            "1",
            ",".join(map(str, pressures)),
            "1e-8",
            *extra,
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    results: dict[str, dict[float, dict]] = {}
    for line in out.splitlines():
        if line.startswith("{"):
            row = json.loads(line)
            results.setdefault(row["solver"], {})[row["pressure"]] = row
    return results


def parse_args() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, nargs="+", default=[512])
    ap.add_argument("--types", nargs="+", default=["python", "tron"])
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e-3, 1e-2])
    ap.add_argument(
        "--full-fraction",
        type=float,
        default=None,
        help="also run at this fraction of the full-contact pressure -min(K h)",
    )
    ap.add_argument("--no-peers", action="store_true", help="skip Tamaas and ContactMechanics")
    ap.add_argument("--repeat", type=int, default=3, help="solves per case; the median is shown")
    ap.add_argument("--surfaces", nargs="+", choices=("easy", "paper"), default=["easy"])
    return ap.parse_args()


def run_peers(h: np.ndarray, pressures: list[float]) -> dict:
    """Every peer's runs on ``h``, printed; ``{peer: {p0: result}}``."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "h.npy")
        np.save(path, h)
        peers = {}
        for run in PEER_RUNS:
            peers.update(peer(run[0], path, pressures, *run[1:]))
    for name, rows in peers.items():
        for p0, r in rows.items():
            flag = "" if r.get("converged", True) else "  NOT CONVERGED"
            print(
                f"# {name:>16} p0 {p0:.0e}: {r['time']:8.3f} s, {r['iterations']} its, "
                f"mean gap {r['mean_gap']:.8e}{flag}"
            )
    return peers


def ours(h: np.ndarray, tao_type: str, p0: float, repeat: int, rt: float, peers: dict) -> str:
    """The median of ``repeat`` solves with ``-tao_type tao_type`` as a table row."""
    runs = []
    for _ in range(repeat):
        with FFTClock() as clock:
            (run,) = periodic_contact(h, 1.0, 1.0, [p0], options=["-tao_type", tao_type])
        runs.append((run, clock.seconds, clock.transforms))
    s, fft_seconds, transforms = sorted(runs, key=lambda r: r[0].scalars["solve_time"])[
        len(runs) // 2
    ]
    d = s.scalars
    ffts = transforms // 2  # round trips (a projected step skips one inverse)
    peer_time = {
        k: peers.get(k, {}).get(p0, {}).get("time", np.nan)
        for k in ("tamaas", "cm-polonsky-keer", "cm-bugnicourt")
    }
    cm_best = np.fmin(peer_time["cm-polonsky-keer"], peer_time["cm-bugnicourt"])
    rel = [d["solve_time"] / peer_time["tamaas"], d["solve_time"] / cm_best]
    flag = "" if s.converged else "  NOT CONVERGED"
    return (
        f"{tao_type:>8} {p0:>7.0e} {d['iterations']:>5d} {ffts:>6d} "
        f"{d['solve_time']:>8.3f} {d['solve_time'] / (ffts * rt):>6.2f} "
        f"{d['solve_time'] / fft_seconds:>8.2f} {d['mean_gap']:>14.8e} "
        f"{rel[0]:>8.3f} {rel[1]:>8.3f}{flag}"
    )


def main() -> None:
    args = parse_args()
    for n, surface in ((n, s) for s in args.surfaces for n in args.grid):
        grid = Grid(n, 1.0)
        rolloff, cutoff = (2, 64) if surface == "easy" else (1, n // 2)
        h = self_affine(
            grid,
            make_fft(grid),
            hurst=0.7,
            rolloff_ratio=rolloff,
            cutoff_ratio=cutoff,
            seed=1,
            rms_slope=0.1,
        )
        pressures = list(args.pressures)
        if args.full_fraction:
            problem = PeriodicProblem(grid, make_fft(grid), h, 1.0)
            pressures.append(float(f"{args.full_fraction * problem.full_contact_pressure():.4g}"))
        rt = fft_round_trip(grid)
        print(
            f"# n = {n}, {surface} surface (L/lambda_r = {rolloff}, L/lambda_1 = {cutoff}): "
            f"FFT round trip {rt * 1e3:.3f} ms"
        )
        peers = {} if args.no_peers else run_peers(h, pressures)
        print(
            f"{'solver':>8} {'p0':>7} {'its':>5} {'FFTs':>6} {'time_s':>8} {'ratio':>6}"
            f" {'in-solve':>8}"
            f" {'mean_gap':>14} {'/tamaas':>8} {'/cm':>8}"
        )
        for t in args.types:
            for p0 in pressures:
                print(ours(h, t, p0, args.repeat, rt, peers), flush=True)


if __name__ == "__main__":
    main()
