"""Adhesion against Tamaas's adhesive solver on a surface this package never generated.

The numpy-seeded surface of :mod:`hardness_tamaas` is saved to a file; the periodic cell with
an adhesive law at prescribed mean gaps (the loading machine,
:func:`~petsc_contact.workflows.adhesive_steps.adhesive_mean_gap_sweep`, ``-tao_type
blmvm``) and Tamaas's ``PolonskyKeerRey`` posed in the gap with its
``ExponentialAdhesionFunctional`` or ``MaugisAdhesionFunctional``
(``benchmarks/peers/run_tamaas_adhesion.py``, in the peers' venv: :mod:`peer_env`) solve
the same mean gaps in the same order, each from the last.

Tolerances: ours is TAO's gradient norm, the rms residual ``p + phi'(g)`` on the free pixels
in units of the pressure scale (``-tao_gatol``, default ``1e-8``), with the mean gap held to
``1e-6`` of its target; Tamaas's is its own relative complementarity error, not the same
measure, so ``--tamaas-tol`` takes several and every answer is compared with Tamaas's at the
tightest one (the mean pressure's difference in units of ``w/rho`` and the area's in
pixels): the tolerance at which Tamaas is as accurate as ours is read off the errors.

Speed: every solver runs in turn (``alternate``: ours, then Tamaas at each tolerance,
``--repetitions`` times), one thread each (ours' FFTW plans of one thread;
``OMP_NUM_THREADS=1`` and its kin: the script starts itself again with them set where they
were not); each one's time is the sum over the mean gaps of its solves (ours: the steps,
the loading machine's corrections included; Tamaas: ``solve()``; the surface, the models and
FFT plans left out), as wall time and as the process's CPU time (the machine is shared: the
CPU time is the robust one).  Printed: the errors per mean gap,
then per solver the median wall and CPU times and the ratios ours / it, the load average
around each repetition::

    PYTHONPATH=. python benchmarks/adhesion_tamaas.py --grid 512 --law exponential \
        --work 1e-4 --range 5e-3 --rms-gaps 1.2,0.6 --tamaas-tol 1e-6,1e-8
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import numpy as np
from hardness_tamaas import surface
from peer_env import peer_python
from side_by_side import alternate, load_line, stamp

PEERS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers")
ONE_THREAD = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


def ours(h: np.ndarray, law: str, w: float, rho: float, gaps: list[float], options: str) -> dict:
    """The adhesive cell at the mean gaps in order as a run poses it (``periodic_contact``: the
    first from the hard wall's answer), on one core (the FFTs' threads too): one row each, the
    wall and CPU times."""
    from petsc_contact import periodic_contact

    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    wall, cpu = time.perf_counter(), time.process_time()
    steps = periodic_contact(
        h, length=1.0, modulus=1.0, mean_gaps=gaps, adhesion=law, work_of_adhesion=w,
        interaction_range=rho, options=options, progress=False,
    )  # fmt: skip
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    rows = []
    for step in steps:
        assert step.converged, step.scalars["verification"]
        rows.append({"mean_pressure": step.scalars["nominal_pressure"], **step.scalars})
    return {"rows": rows, "time": wall, "cpu": cpu}


def tamaas(path: str, law: str, w: float, rho: float, gaps: list[float], tol: float) -> dict:
    """Tamaas's adhesive PolonskyKeerRey at ``tol``: one row each, the summed solve times."""
    python = peer_python()
    if python is None:
        sys.exit("no peers' venv: see benchmarks/peer_env.py")
    args = [os.path.join(PEERS, "run_tamaas_adhesion.py"), path, "1", "1", law, str(w)]
    args += [str(rho), ",".join(map(str, gaps)), str(tol)]
    text = subprocess.run([python, *args], capture_output=True, text=True, check=True).stdout
    rows = [json.loads(line) for line in text.splitlines() if line.startswith("{")]
    return {"rows": rows, "time": sum(r["time"] for r in rows), "cpu": sum(r["cpu"] for r in rows)}


def accuracy(results: dict[str, list[dict]], reference: str, gaps: list[float], a) -> None:
    """Per mean gap, each solver's mean pressure and area against ``reference``'s."""
    n = a.grid_now**2
    print(f"\n{a.grid_now}^2, against {reference}: |dp0| / (w/rho), d(area) in pixels\n")
    print("| mean gap | p0 (reference) | area (reference) | " + " | ".join(results) + " |")
    print("| --- " * (3 + len(results)) + "|")
    ref_rows = results[reference][-1]["rows"]
    for i, g in enumerate(gaps):
        ref = ref_rows[i]
        cells = []
        for runs in results.values():
            row = runs[-1]["rows"][i]
            dp = abs(row["mean_pressure"] - ref["mean_pressure"]) / (a.work / a.range)
            cells.append(f"{dp:.1e}, {round((row['area_fraction'] - ref['area_fraction']) * n)}")
        print(f"| {g:.4g} | {ref['mean_pressure']:.8g} | {ref['area_fraction']:.5f} | "
              + " | ".join(cells) + " |")  # fmt: skip


def speed(results: dict[str, list[dict]], n: int) -> None:
    """Per solver, the median wall and CPU times over the repetitions and ours / it."""
    print(f"\n{n}^2: times summed over the mean gaps, medians of the repetitions\n")
    print("| solver | iterations | wall (s) | CPU (s) | ours / this, wall | ours / this, CPU |")
    print("| --- | --- | --- | --- | --- | --- |")
    med = {
        k: [statistics.median(r[t] for r in runs) for t in ("time", "cpu")]
        for k, runs in results.items()
    }
    mine = med["ours"]
    for name, (wall, cpu) in med.items():
        its = sum(r.get("iterations", 0) for r in results[name][-1]["rows"]) or ""
        print(f"| {name} | {its} | {wall:.3g} | {cpu:.3g} | {mine[0] / wall:.3f} | "
              f"{mine[1] / cpu:.3f} |")  # fmt: skip


def compare(n: int, a: argparse.Namespace) -> None:
    """One grid: the alternated runs, the accuracy and speed tables."""
    h = surface(n, a.seed)
    rms = float(np.sqrt(np.mean(h**2)))
    if a.rms_gaps:
        gaps = [float(g) * rms for g in a.rms_gaps.split(",")]
    else:
        gaps = [float(g) for g in a.mean_gaps.split(",")]
    print(f"\n{n}^2: h_rms = {rms:.4g}, mean gaps {', '.join(f'{g:.4g}' for g in gaps)}")
    tols = [float(t) for t in a.tamaas_tol.split(",")]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "h.npy")
        np.save(path, h)
        solvers: dict[str, Callable[[], dict]] = {
            "ours": lambda: ours(h, a.law, a.work, a.range, gaps, a.options)
        }
        for tol in tols:
            solvers[f"Tamaas {tol:g}"] = lambda tol=tol: tamaas(
                path, a.law, a.work, a.range, gaps, tol
            )
        results, loads = alternate(solvers, a.repetitions)
    a.grid_now = n
    accuracy(results, f"Tamaas {min(tols):g}", gaps, a)
    speed(results, n)
    print("\n" + load_line(loads))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", default="128", help="grids, comma-separated")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--law", default="exponential", choices=("exponential", "maugis"))
    parser.add_argument("--work", type=float, default=1e-4)
    parser.add_argument("--range", type=float, default=5e-3)
    parser.add_argument("--mean-gaps", default="6e-3,3e-3")
    parser.add_argument("--rms-gaps", default="", help="mean gaps in rms heights (overrides)")
    parser.add_argument("--tamaas-tol", default="1e-6,1e-8", help="comma-separated")
    parser.add_argument("--options", default="-tao_type blmvm", help="ours' PETSc options")
    parser.add_argument("--repetitions", type=int, default=2)
    a = parser.parse_args()
    if any(os.environ.get(name) != "1" for name in ONE_THREAD):  # numpy is imported: start again
        env = {**os.environ, **dict.fromkeys(ONE_THREAD, "1")}
        os.execve(sys.executable, [sys.executable, *sys.argv], env)
    print(f"{stamp()}; {a.law}, w = {a.work:g}, rho = {a.range:g}; {os.getloadavg()}")
    for n in map(int, a.grid.split(",")):
        compare(n, a)


if __name__ == "__main__":
    main()
