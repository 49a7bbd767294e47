"""The GPU check in one go: the GPU tests, the FFT-and-pass floor, and the timing table.

usage (on a machine with CuPy and a CUDA GPU, in the repository's root, no network needed)::

    python3 benchmarks/gpu.py --out DIR [--budget 420] [--grids 2048,4096,8192] [--largest 16384]

1. makes the package importable from the working tree (``pip install --no-deps --no-index
   --no-build-isolation -e .``, else ``PYTHONPATH``): nothing is downloaded;
2. runs ``pytest -m gpu tests/test_gpu.py tests/test_device_punch.py`` (the device against
   its CPU stand-in: periodic sweeps at 256^2-1024^2, the punch at 128^2 and 256^2);
3. measures the floor at each grid: a cuFFT double real round trip (``rfft2`` + ``irfft2``
   through :class:`~petsc_contact.devices.fft.ArrayFFT`) and one fused pass
   (``y += a x``, an ``ElementwiseKernel``), CUDA events, median of 10;
4. times the paper-bandwidth sweep at each grid (H = 0.7, rms slope 0.1, ``L/lambda_r = 1``,
   ``L/lambda_1 = n/2``, seed 1, 12 loads from 1e-7 to 1e-1 E*, ``--stiffness``): wall,
   iterations, seconds per iteration against 3.5 round trips and 10 passes, the stiffness
   solves, and the device memory the pool held (bytes per point);
5. the 8192^2 sweep again with the unfused passes (:class:`ArrayPasses`: what the fused
   kernels of :mod:`~petsc_contact.devices.fused` save), the 8192^2 sweep under cProfile
   (where the wall goes: ``profile_8192.txt``), one 8192^2 step from first touch
   (``p0 = 1e-3 E*``) and a short sweep at ``--largest``.

Every stage is skipped once ``--budget`` seconds have passed.  Writes ``gpu.json`` (every
figure), ``gpu.log`` (what was printed) and the profile to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
import traceback
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PAPER = {"hurst": 0.7, "rolloff_ratio": 1, "seed": 1, "rms_slope": 0.1}
ROUND_TRIPS, PASSES = 3.5, 10  # per iteration of the CG (docs/gpu.md)


def importable() -> str:
    """Install the working tree without the network, or put it on the path (this process
    reads it from the path either way: an editable install shows in new processes only)."""
    sys.path.insert(0, str(ROOT))
    done = subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-index"]
        + ["--no-build-isolation", "-e", str(ROOT)],
        capture_output=True,
        text=True,
    )
    if done.returncode == 0:
        return "pip install -e (no network)"
    os.environ["PYTHONPATH"] = f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
    return f"PYTHONPATH (pip said: {done.stderr.strip().splitlines()[-1:]})"


def timed(fn: Any, repeat: int = 10) -> float:
    """Median seconds of ``fn()`` on the device (CUDA events), after one warm-up."""
    import cupy

    fn()
    times = []
    for _ in range(repeat):
        start, stop = cupy.cuda.Event(), cupy.cuda.Event()
        start.record()
        fn()
        stop.record()
        stop.synchronize()
        times.append(cupy.cuda.get_elapsed_time(start, stop) / 1e3)
    return sorted(times)[len(times) // 2]


def floor(n: int) -> dict[str, float]:
    """The round trip and the fused pass at ``n^2`` (seconds)."""
    import cupy

    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.device import get_device
    from petsc_contact.devices.fft import ArrayFFT

    fft = ArrayFFT(Grid(n, 1.0), get_device("gpu"))
    x = cupy.random.random((n, n))
    out = cupy.empty_like(x)

    def round_trip() -> None:
        fft.forward_from(x)
        fft.backward_into(out)

    axpy = cupy.ElementwiseKernel("float64 a, float64 x", "float64 y", "y += a * x", "axpy")
    return {"round_trip": timed(round_trip), "pass": timed(lambda: axpy(0.5, x, out))}


def surface(n: int, device: str) -> Any:
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.device import get_device
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.physics.surface import self_affine

    grid = Grid(n, 1.0)
    return self_affine(grid, make_fft(grid, get_device(device)), cutoff_ratio=n / 2, **PAPER)


def sweep(n: int, loads: list[float], floors: dict[str, float] | None) -> dict[str, Any]:
    """One sweep with the stiffness on the GPU: its table and where the time went."""
    import cupy

    from petsc_contact.devices.device import get_device
    from petsc_contact.workflows.periodic_sweep import periodic_contact

    pool = cupy.get_default_memory_pool()
    pool.free_all_blocks()
    start = time.perf_counter()
    h = surface(n, "gpu")
    surface_time = time.perf_counter() - start
    start = time.perf_counter()
    steps = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device="gpu"
    )
    wall = time.perf_counter() - start
    rows = [
        {
            k: s.scalars[k]
            for k in (
                "nominal_pressure",
                "iterations",
                "solve_time",
                "stiffness",
                "stiffness_iterations",
                "stiffness_time",
                "mean_gap",
                "area_fraction",
                "converged",
                "tao_reason",
            )
        }
        for s in steps
    ]
    its = sum(r["iterations"] for r in rows)
    solve = sum(r["solve_time"] for r in rows)
    out: dict[str, Any] = {
        "grid": n,
        "loads": len(loads),
        "surface_time": surface_time,
        "wall": wall,
        "solve_time": solve,
        "stiffness_time": sum(r["stiffness_time"] for r in rows),
        # the wall outside the timed solves: the observables and the fields' transfers
        "outside_solves": wall - solve - sum(r["stiffness_time"] for r in rows),
        "iterations": its,
        "per_iteration": solve / max(its, 1),
        "all_converged": all(r["converged"] for r in rows),
        "pool_bytes": pool.total_bytes(),
        "bytes_per_point": pool.total_bytes() / n**2,
        "steps": rows,
        "device": get_device("gpu").describe(),
    }
    if floors is not None:
        out["floor_per_iteration"] = ROUND_TRIPS * floors["round_trip"] + PASSES * floors["pass"]
        out["per_iteration_over_floor"] = out["per_iteration"] / out["floor_per_iteration"]
    return out


def plain_passes_sweep(n: int, loads: list[float], report: dict[str, Any]) -> dict[str, Any]:
    """:func:`sweep` with the GPU's passes as :class:`ArrayPasses` (one CuPy kernel per
    operator) instead of the fused kernels: what the fusion saves, on the same surface."""
    from petsc_contact.devices import device
    from petsc_contact.devices.passes import ArrayPasses

    fused = device.Device.__dict__["passes"]
    device.Device.passes = property(lambda self: ArrayPasses(self.xp))
    try:
        return sweep(n, loads, report["floor"].get(n))
    finally:
        device.Device.passes = fused


def profiled_sweep(n: int, loads: list[float], path: Path) -> dict[str, Any]:
    """:func:`sweep` under cProfile, its 60 costliest calls (cumulative) written to ``path``
    (the host waits at each synchronisation, so a device's work shows where it is awaited)."""
    import cProfile
    import io
    import pstats

    profiler = cProfile.Profile()
    profiler.enable()
    try:
        result = sweep(n, loads, None)
    finally:
        profiler.disable()
    text = io.StringIO()
    pstats.Stats(profiler, stream=text).sort_stats("cumulative").print_stats(60)
    path.write_text(text.getvalue())
    return {k: result[k] for k in ("wall", "solve_time", "stiffness_time", "iterations")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--budget", type=float, default=420.0, help="seconds for every stage")
    ap.add_argument("--grids", default="2048,4096,8192")
    ap.add_argument("--largest", type=int, default=16384)
    ap.add_argument("--skip-tests", action="store_true")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    log = open(args.out / "gpu.log", "a")  # noqa: SIM115 (open for the whole run)

    def say(text: str) -> None:
        line = f"[{time.perf_counter() - began:6.1f} s] {text}"
        print(line, flush=True)
        log.write(line + "\n")
        log.flush()

    def left() -> float:
        return args.budget - (time.perf_counter() - began)

    report: dict[str, Any] = {"date": time.strftime("%Y-%m-%d %H:%M:%S %Z")}
    report["commit"] = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    report["install"] = importable()
    import cupy
    import numpy

    from petsc_contact.devices.device import get_device

    report["versions"] = {"cupy": cupy.__version__, "numpy": numpy.__version__}
    report["device"] = get_device("gpu").describe()
    say(f"{report['device']} cupy {cupy.__version__}, numpy {numpy.__version__}")

    def save() -> None:
        (args.out / "gpu.json").write_text(json.dumps(report, indent=1, default=str))

    if not args.skip_tests:
        done = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-m", "gpu"]
            + ["tests/test_gpu.py", "tests/test_device_punch.py"],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        report["tests"] = {
            "exit": done.returncode,
            "tail": done.stdout[-3000:] + done.stderr[-2000:],
        }
        say(f"pytest -m gpu: exit {done.returncode}: {done.stdout.strip().splitlines()[-1:]}")
        if done.returncode:
            log.write(done.stdout + done.stderr)
        save()
    grids = [int(g) for g in args.grids.split(",") if g]
    report["floor"] = {}
    for n in [*grids, args.largest]:
        if left() < 30:
            break
        try:
            report["floor"][n] = floor(n)
            cupy.get_default_memory_pool().free_all_blocks()
        except cupy.cuda.memory.OutOfMemoryError:
            say(f"{n}^2: the floor does not fit")
            break
        f = report["floor"][n]
        say(
            f"{n}^2 floor: round trip {f['round_trip'] * 1e3:.3f} ms, pass {f['pass'] * 1e3:.3f} ms"
        )
    save()
    loads = list(numpy.logspace(-7, -1, 12))
    report["sweeps"] = []
    for n in grids:
        if left() < 60:
            say(f"{n}^2 sweep skipped: budget")
            continue
        try:
            result = sweep(n, loads, report["floor"].get(n))
        except Exception as error:  # recorded, and the next stage goes on
            report["sweeps"].append({"grid": n, "error": traceback.format_exc()})
            say(f"{n}^2 sweep failed: {error!r}")
            save()
            continue
        report["sweeps"].append(result)
        save()
        say(
            f"{n}^2 12-load sweep with stiffness: wall {result['wall']:.1f} s (solve "
            f"{result['solve_time']:.1f} s, stiffness {result['stiffness_time']:.1f} s, "
            f"outside the solves {result['outside_solves']:.1f} s), "
            f"{result['iterations']} iterations, {result['per_iteration'] * 1e3:.2f} ms each "
            f"({result.get('per_iteration_over_floor', float('nan')):.2f}x floor), "
            f"{result['bytes_per_point']:.0f} B/point, converged {result['all_converged']}"
        )
    if left() > 90 and 8192 in grids:  # the same sweep with the array module's passes
        try:
            report["plain_passes_8192"] = plain = plain_passes_sweep(8192, loads, report)
            say(
                f"8192^2 sweep with the unfused passes: wall {plain['wall']:.1f} s, solve "
                f"{plain['solve_time']:.1f} s, {plain['per_iteration'] * 1e3:.2f} ms each"
            )
        except Exception as error:
            report["plain_passes_8192"] = {"error": traceback.format_exc()}
            say(f"8192^2 with the unfused passes failed: {error!r}")
        save()
    if left() > 100 and 8192 in grids:  # where the time goes
        try:
            path = args.out / "profile_8192.txt"
            report["profiled_8192"] = prof = profiled_sweep(8192, loads, path)
            say(f"8192^2 sweep under cProfile: wall {prof['wall']:.1f} s, {path.name}")
        except Exception as error:
            report["profiled_8192"] = {"error": traceback.format_exc()}
            say(f"8192^2 under cProfile failed: {error!r}")
        save()
    if left() > 60 and 8192 in grids:
        try:
            one = sweep(8192, [1e-3], report["floor"].get(8192))
            report["first_touch_8192"] = one
            wall, its = one["wall"], one["iterations"]
            say(f"8192^2 one step from first touch: wall {wall:.1f} s, {its} its")
        except Exception as error:
            report["first_touch_8192"] = {"error": traceback.format_exc()}
            say(f"8192^2 first touch failed: {error!r}")
        save()
    if left() > 120:
        try:
            big = sweep(args.largest, [1e-4, 1e-3, 1e-2], report["floor"].get(args.largest))
            report["largest"] = big
            say(
                f"{args.largest}^2 3-load sweep: wall {big['wall']:.1f} s, "
                f"{big['iterations']} its, {big['bytes_per_point']:.0f} B/point, "
                f"converged {big['all_converged']}"
            )
        except Exception as error:  # out of memory among them: recorded
            report["largest"] = {"grid": args.largest, "error": traceback.format_exc()}
            say(f"{args.largest}^2 failed: {error!r}")
        save()
    report["elapsed"] = time.perf_counter() - began
    save()
    say("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
