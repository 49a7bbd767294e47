"""The GPU check in one go: the GPU tests, the floor, the sweeps, the largest grid, Fig. 2.

usage (on a machine with CuPy and a CUDA GPU, in the repository's root, no network needed)::

    python3 benchmarks/gpu.py --out DIR [--budget 540] [--grids 8192] [--largest 32768]
        [--stages tests,floor,sweeps,ranks,largest,fig2,profile] [--device gpu]

1. makes the package importable from the working tree (``pip install --no-deps --no-index
   --no-build-isolation -e .`` where a new process does not import it from there already,
   else ``PYTHONPATH``; ``--no-install``: ``PYTHONPATH`` only): nothing is downloaded;
2. ``tests``: ``pytest -m gpu tests/test_gpu.py tests/test_device_punch.py`` (the device
   against its CPU stand-in, with CuPy's FFT functions and with the kept-buffer cuFFT plans,
   the preconditioner in float64 and in float32);
3. ``floor``: at each grid and ``--largest``, a double real round trip through
   :class:`~petsc_contact.devices.fft.ArrayFFT` with CuPy's ``rfft2``/``irfft2``, the same
   through its own cuFFT plans (``PETSC_CONTACT_CUFFT_PLANS=on``), a float32 round trip
   through the plans (the preconditioner's), and one fused pass (``y += a x``); CUDA events,
   median of 10;
4. ``sweeps``: at each grid the paper-bandwidth sweep (H = 0.7, rms slope 0.1,
   ``L/lambda_r = 1``, ``L/lambda_1 = n/2``, seed 1, 12 loads from 1e-7 to 1e-1 E*,
   ``--stiffness``) three times: as the package runs it by default, with the cuFFT plans,
   and with the plans and ``-petsc_contact_pc_float32``: wall, iterations, seconds per
   iteration against 3.5 round trips and 10 passes, the device memory the pool held (bytes
   per point), and the later runs' answers against the first's step by step;
5. ``ranks``: ``mpiexec -n 2`` of a small ``--device gpu`` run: one GPU's transforms are one
   rank's, so it must be refused in one line (recorded, with the exit status);
6. ``largest``: a 3-load sweep (1e-4 to 1e-2) at ``--largest`` by the command line with the
   plans (the leanest in memory), the device's peak memory in use watched from this process
   (bytes per point), killed when the budget runs out;
7. ``fig2``: one of the paper's Fig. 2 pieces (8192^2, H = 0.5, seed 8, 25 loads with the
   stiffness) by the command line on the device with the plans and the float32
   preconditioner, against its committed CPU file (``data/paper/fig2/H0.5_seed8.h5``) step
   by step (skipped on the host);
8. ``profile``: the first grid's sweep under cProfile, with the plans and float32
   (``profile_N.txt``).

A stage is skipped once too little of ``--budget`` is left for it (it says so).  Writes
``gpu.json`` (every figure), ``gpu.log`` (what was printed) and the profile to ``--out``.
Without CuPy or a GPU it records why in ``gpu.json`` and exits with status 69.  ``--device
cpu-array`` runs the same stages on the CPU stand-in (small ``--grids`` and ``--largest``;
wall clocks instead of CUDA events, no pool), which checks the script without a GPU.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PAPER = {"hurst": 0.7, "rolloff_ratio": 1, "seed": 1, "rms_slope": 0.1}
ROUND_TRIPS, PASSES = 3.5, 10  # per iteration of the CG (docs/gpu.md)
PLANS = "PETSC_CONTACT_CUFFT_PLANS"
FLOAT32 = ["-petsc_contact_pc_float32"]
STAGES = ("tests", "floor", "sweeps", "ranks", "largest", "fig2", "profile")
NEEDS = {"floor": 30, "sweeps": 120, "ranks": 20, "largest": 150, "fig2": 90, "profile": 60}
FIG2 = ["--grid", "8192", "--hurst", "0.5", "--rms-slope", "0.1", "--cutoff-ratio", "4096"]
FIG2 += ["--seed", "8", "--sweep", "25,1e-8,1e-2", "--stiffness", "--scalars-only"]
FIG2_FILE = ROOT / "data" / "paper" / "fig2" / "H0.5_seed8.h5"
CONFIGS = {"default": ("off", []), "plans": ("on", []), "plans_float32": ("on", FLOAT32)}


def importable(install: bool = True) -> str:
    """Install the working tree without the network, or put it on the path (this process
    reads it from the path either way: an editable install shows in new processes only).
    Nothing is installed where a new process imports the package from this tree already,
    or without ``install`` (another checkout's install is left alone)."""
    sys.path.insert(0, str(ROOT))
    where = subprocess.run(
        [sys.executable, "-c", "import petsc_contact; print(petsc_contact.__file__)"],
        capture_output=True,
        text=True,
    ).stdout.strip()
    if where.startswith(str(ROOT)):
        return "importable from the tree already"
    if not install:
        os.environ["PYTHONPATH"] = f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
        return "PYTHONPATH (--no-install)"
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


def timed(fn: Callable[[], object], xp: Any, repeat: int = 10) -> float:
    """Median seconds of ``fn()`` on the device (CUDA events; the wall clock on the host),
    after one warm-up."""
    fn()
    times = []
    for _ in range(repeat):
        if xp.__name__ == "numpy":
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
            continue
        begin, stop = xp.cuda.Event(), xp.cuda.Event()
        begin.record()
        fn()
        stop.record()
        stop.synchronize()
        times.append(xp.cuda.get_elapsed_time(begin, stop) / 1e3)
    return sorted(times)[len(times) // 2]


def floor(n: int, device: Any) -> dict[str, float]:
    """The round trips (CuPy's functions, the plans, the plans in float32) and the pass at
    ``n^2`` (seconds)."""
    import numpy as np

    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import ArrayFFT

    xp, grid = device.xp, Grid(n, 1.0)
    x = xp.asarray(np.random.default_rng(1).random((n, n)))
    out = xp.empty_like(x)
    result: dict[str, float] = {}
    for name, plans, dtype in (
        ("round_trip", "off", np.float64),
        ("round_trip_plans", "on", np.float64),
        ("round_trip_plans_float32", "on", np.float32),
    ):
        os.environ[PLANS] = plans
        fft = ArrayFFT(grid, device, dtype)

        def round_trip(fft: Any = fft) -> None:
            fft.forward_from(x)
            fft.backward_into(out)

        result[name] = timed(round_trip, xp)
        del fft
    result["pass"] = timed(lambda: device.passes.axpy(0.5, x, out), xp)
    return result


def surface(n: int, device: str) -> Any:
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.device import get_device
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.physics.surface import self_affine

    grid = Grid(n, 1.0)
    return self_affine(grid, make_fft(grid, get_device(device)), cutoff_ratio=n / 2, **PAPER)


COLUMNS = ("nominal_pressure", "iterations", "solve_time", "stiffness", "stiffness_iterations")
COLUMNS += ("stiffness_time", "mean_gap", "area_fraction", "converged", "tao_reason")


def sweep(n: int, loads: list[float], device: Any, config: str) -> dict[str, Any]:
    """One sweep with the stiffness on ``device`` in ``config`` (:data:`CONFIGS`): its
    table and where the time went."""
    from petsc_contact.workflows.periodic_sweep import periodic_contact

    plans, options = CONFIGS[config]
    os.environ[PLANS] = plans
    pool = None if device.on_host else device.xp.get_default_memory_pool()
    if pool is not None:
        pool.free_all_blocks()
    start = time.perf_counter()
    h = surface(n, device.name)
    surface_time = time.perf_counter() - start
    start = time.perf_counter()
    steps = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device=device.name,
        options=options,
    )  # fmt: skip
    wall = time.perf_counter() - start
    rows = [{k: s.scalars[k] for k in COLUMNS} for s in steps]
    its = sum(r["iterations"] for r in rows)
    solve = sum(r["solve_time"] for r in rows)
    stiffness = sum(r["stiffness_time"] for r in rows)
    held = 0 if pool is None else pool.total_bytes()
    return {
        "grid": n,
        "config": config,
        "loads": len(loads),
        "surface_time": surface_time,
        "wall": wall,
        "solve_time": solve,
        "stiffness_time": stiffness,
        "outside_solves": wall - solve - stiffness,  # the observables, transfers, set-up
        "iterations": its,
        "per_iteration": solve / max(its, 1),
        "all_converged": all(r["converged"] for r in rows),
        "pool_bytes": held,
        "bytes_per_point": held / n**2,
        "steps": rows,
        "device": device.describe(),
    }


def against_floor(result: dict[str, Any], f: dict[str, float] | None) -> None:
    """Add the floor of an iteration to ``result`` (3.5 round trips and 10 passes), with the
    round trip of its configuration (CuPy's functions or the plans)."""
    if not f:
        return
    trip = f["round_trip"] if result["config"] == "default" else f["round_trip_plans"]
    result["floor_per_iteration"] = ROUND_TRIPS * trip + PASSES * f["pass"]
    result["per_iteration_over_floor"] = result["per_iteration"] / result["floor_per_iteration"]


def agreement(a: dict[str, Any], b: dict[str, Any]) -> dict[str, float]:
    """Two sweeps' answers step by step: the largest relative differences and iterations."""

    def worst(key: str) -> float:
        return float(max(abs(y[key] / x[key] - 1) for x, y in pairs))

    pairs = list(zip(a["steps"], b["steps"], strict=True))
    its = max(abs(x["iterations"] - y["iterations"]) for x, y in pairs)
    return {"mean_gap": worst("mean_gap"), "stiffness": worst("stiffness"), "iterations": its}


def profiled_sweep(n: int, loads: list[float], device: Any, path: Path) -> dict[str, Any]:
    """:func:`sweep` (plans, float32) under cProfile, its 60 costliest calls (cumulative)
    written to ``path`` (the host waits at each synchronisation, so a device's work shows
    where it is awaited)."""
    import cProfile
    import io
    import pstats

    profiler = cProfile.Profile()
    profiler.enable()
    try:
        result = sweep(n, loads, device, "plans_float32")
    finally:
        profiler.disable()
    text = io.StringIO()
    pstats.Stats(profiler, stream=text).sort_stats("cumulative").print_stats(60)
    path.write_text(text.getvalue())
    return {k: result[k] for k in ("wall", "solve_time", "stiffness_time", "iterations")}


class Run:
    """The check's state: its arguments, report, log and clock."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args, self.began = args, time.perf_counter()
        args.out.mkdir(parents=True, exist_ok=True)
        self.log = open(args.out / "gpu.log", "a")  # noqa: SIM115 (open for the whole run)
        self.report: dict[str, Any] = {"date": time.strftime("%Y-%m-%d %H:%M:%S %Z")}
        self.device: Any = None

    def say(self, text: str) -> None:
        line = f"[{time.perf_counter() - self.began:6.1f} s] {text}"
        print(line, flush=True)
        self.log.write(line + "\n")
        self.log.flush()

    def left(self) -> float:
        return self.args.budget - (time.perf_counter() - self.began)

    def save(self) -> None:
        (self.args.out / "gpu.json").write_text(json.dumps(self.report, indent=1, default=str))

    def stage(self, name: str, fn: Callable[[], None]) -> None:
        """Run stage ``name`` if asked and if the budget leaves it room; a failure is
        recorded and the next stage goes on."""
        if name not in self.args.stages.split(","):
            return
        if self.left() < NEEDS.get(name, 0):
            self.say(f"{name}: skipped, {self.left():.0f} s of the budget left")
            self.report.setdefault("skipped", []).append(name)
            return
        try:
            fn()
        except Exception as error:
            self.report.setdefault("errors", {})[name] = traceback.format_exc()
            self.say(f"{name} failed: {error!r}")
        self.save()


def tests(run: Run) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-m", "gpu"]
        + ["tests/test_gpu.py", "tests/test_device_punch.py"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    tail = done.stdout[-3000:] + done.stderr[-2000:]
    run.report["tests"] = {"exit": done.returncode, "tail": tail}
    run.say(f"pytest -m gpu: exit {done.returncode}: {done.stdout.strip().splitlines()[-1:]}")
    if done.returncode:
        run.log.write(done.stdout + done.stderr)


def floors(run: Run) -> None:
    run.report["floor"] = {}
    for n in [*run.args.grid_list, run.args.largest]:
        if run.left() < NEEDS["floor"]:
            break
        try:
            f = run.report["floor"][n] = floor(n, run.device)
        except Exception as error:  # out of memory among them
            run.say(f"{n}^2: the floor does not fit ({error!r})")
            break
        finally:
            if not run.device.on_host:
                run.device.xp.get_default_memory_pool().free_all_blocks()
        run.say(
            f"{n}^2 floor: round trip {f['round_trip'] * 1e3:.3f} ms (CuPy's functions), "
            f"{f['round_trip_plans'] * 1e3:.3f} ms (plans), "
            f"{f['round_trip_plans_float32'] * 1e3:.3f} ms (plans, float32), "
            f"pass {f['pass'] * 1e3:.3f} ms"
        )


def sweeps(run: Run) -> None:
    import numpy

    loads = list(numpy.logspace(-7, -1, 12))
    run.report["sweeps"] = []
    for n in run.args.grid_list:
        done: dict[str, dict[str, Any]] = {}
        for config in CONFIGS:
            if run.left() < NEEDS["sweeps"] / 3:
                run.say(f"{n}^2 {config} sweep skipped: budget")
                continue
            result = done[config] = sweep(n, loads, run.device, config)
            against_floor(result, run.report.get("floor", {}).get(n))
            if config != "default" and "default" in done:
                result["against_default"] = agreement(done["default"], result)
            run.report["sweeps"].append(result)
            run.save()
            run.say(
                f"{n}^2 {config}: wall {result['wall']:.1f} s (solve {result['solve_time']:.1f}"
                f" s, stiffness {result['stiffness_time']:.1f} s, outside "
                f"{result['outside_solves']:.1f} s), {result['iterations']} iterations, "
                f"{result['per_iteration'] * 1e3:.2f} ms each "
                f"({result.get('per_iteration_over_floor', float('nan')):.2f}x floor), "
                f"{result['bytes_per_point']:.0f} B/point, converged "
                f"{result['all_converged']}, against the default "
                f"{result.get('against_default')}"
            )


def cli(
    args: list[str], ranks: int = 0, timeout: float | None = None, **env: str
) -> subprocess.CompletedProcess | None:
    """The command line in a process of its own (under ``mpiexec -n ranks``); ``None`` when
    it ran past ``timeout`` seconds (and was killed)."""
    cmd = [sys.executable, "-m", "petsc_contact.cli", *args]
    if ranks:
        cmd = [shutil.which("mpiexec") or "mpiexec", "--oversubscribe", "-n", str(ranks), *cmd]
    environ = {**os.environ, **env, "OMPI_ALLOW_RUN_AS_ROOT": "1"}
    environ["OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"] = "1"
    try:
        return subprocess.run(
            cmd, capture_output=True, text=True, cwd=ROOT, env=environ, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        return None


class DeviceMemory:
    """The device's memory in use, polled every 0.2 s while in a ``with`` block (all
    processes': ``cudaMemGetInfo``), its peak over what was in use at the start; 0 on the
    host."""

    def __init__(self, device: Any) -> None:
        self.device, self.peak = device, 0
        self._stop = threading.Event()

    def used(self) -> int:
        free, total = self.device.xp.cuda.runtime.memGetInfo()
        return int(total - free)

    def _poll(self, base: int) -> None:
        while not self._stop.wait(0.2):
            self.peak = max(self.peak, self.used() - base)

    def __enter__(self) -> DeviceMemory:
        if not self.device.on_host:
            self.device.xp.get_default_memory_pool().free_all_blocks()
            self._thread = threading.Thread(target=self._poll, args=(self.used(),), daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if not self.device.on_host:
            self._stop.set()
            self._thread.join()


def ranks(run: Run) -> None:
    if shutil.which("mpiexec") is None:
        run.report["ranks"] = {"error": "no mpiexec on this machine"}
        run.say("ranks: no mpiexec")
        return
    out = run.args.out / "ranks.h5"
    args = ["periodic", "--grid", "256", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "1"]
    args += ["--pressures", "1e-3", "--device", run.device.name, "--output", str(out)]
    done = cli([*args, "--overwrite", "--quiet"], ranks=2, timeout=max(run.left() - 10, 10))
    if done is None:
        run.report["ranks"] = {"error": "timed out"}
        return
    lines = (done.stdout + done.stderr).strip().splitlines()
    run.report["ranks"] = {"exit": done.returncode, "said": lines[-6:]}
    run.say(f"2 ranks on one {run.device.name}: exit {done.returncode}: {lines[-2:]}")


def largest(run: Run) -> None:
    """The 3-load sweep at ``--largest`` by the command line with the plans, the device's
    peak memory watched from here, stopped (killed) when the budget runs out."""
    import h5py

    n = run.args.largest
    out = run.args.out / f"largest_{n}.h5"
    args = ["periodic", "--grid", str(n), "--hurst", "0.7", "--rms-slope", "0.1"]
    args += ["--rolloff-ratio", "1", "--cutoff-ratio", str(n // 2), "--seed", "1"]
    args += ["--pressures", "1e-4,1e-3,1e-2", "--stiffness", "--scalars-only", "--quiet"]
    args += ["--skip-memory-check", "--device", run.device.name, "--output", str(out)]
    start = time.perf_counter()
    with DeviceMemory(run.device) as memory:
        done = cli([*args, "--overwrite"], timeout=max(run.left() - 15, 30), **{PLANS: "on"})
    result: dict[str, Any] = {"grid": n, "wall": time.perf_counter() - start}
    result |= {"peak_bytes": memory.peak, "bytes_per_point": memory.peak / n**2}
    if done is None or done.returncode:
        result["exit"] = "timed out" if done is None else done.returncode
        result["said"] = "" if done is None else (done.stdout + done.stderr)[-2000:]
    else:
        with h5py.File(out) as f:
            result["steps"] = {k: f[k][:].tolist() for k in ("iterations", "mean_gap")}
            result["converged"] = bool(f["converged"][:].all())
    run.report["largest"] = result
    run.say(
        f"{n}^2 3-load sweep: {result.get('exit', 'done')}, wall {result['wall']:.1f} s, "
        f"{result['bytes_per_point']:.0f} B/point at the peak, {result.get('steps')}"
    )


def fig2(run: Run) -> None:
    import h5py
    import numpy

    if run.device.on_host:
        run.report["fig2"] = {"skipped": "8192^2 on the host: 25 minutes on 2 cores"}
        run.say("fig2: skipped on the host")
        return
    out = run.args.out / "H0.5_seed8.h5"
    start = time.perf_counter()
    args = [*FIG2, "--device", run.device.name, "--output", str(out), "--overwrite", *FLOAT32]
    done = cli(args, timeout=max(run.left() - 10, 30), **{PLANS: "on"})
    wall = time.perf_counter() - start
    result: dict[str, Any] = {"wall": wall, "command": args}
    result["exit"] = "timed out" if done is None else done.returncode
    if done is not None and done.returncode == 0:
        with h5py.File(out) as mine, h5py.File(FIG2_FILE) as cpu:
            for key in ("mean_gap", "stiffness", "iterations"):
                a, b = mine[key][:], cpu[key][:]
                diff = numpy.abs(a - b) if key == "iterations" else numpy.abs(a / b - 1)
                result[key] = float(diff.max())
    elif done is not None:
        result["said"] = (done.stdout + done.stderr)[-2000:]
    run.report["fig2"] = result
    run.say(f"Fig. 2 piece H0.5_seed8 on the device: {result}")


def profile(run: Run) -> None:
    import numpy

    n = run.args.grid_list[0]
    path = run.args.out / f"profile_{n}.txt"
    loads = list(numpy.logspace(-7, -1, 12))
    prof = run.report["profiled"] = profiled_sweep(n, loads, run.device, path)
    run.say(f"{n}^2 sweep under cProfile: wall {prof['wall']:.1f} s, {path.name}")


def start(run: Run) -> bool:
    """Record the commit, the install and the device; ``False`` (recorded) without one."""
    report = run.report
    report["commit"] = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    report["install"] = importable(not run.args.no_install)
    import numpy

    from petsc_contact.devices.device import DeviceUnavailable, get_device

    try:
        run.device = get_device(run.args.device)
    except DeviceUnavailable as why:
        report["error"] = str(why)
        run.say(f"no device: {why}")
        run.save()
        return False
    report["versions"] = {"numpy": numpy.__version__}
    if not run.device.on_host:
        report["versions"]["cupy"] = run.device.xp.__version__
    report["device"] = run.device.describe()
    run.say(f"{report['device']} {report['versions']}")
    return True


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--budget", type=float, default=540.0, help="seconds for every stage")
    ap.add_argument("--grids", default="8192")
    ap.add_argument("--largest", type=int, default=32768)
    ap.add_argument("--stages", default=",".join(STAGES))
    ap.add_argument("--device", default="gpu", help="gpu, or cpu-array to check the script")
    ap.add_argument("--skip-tests", action="store_true", help="the stages less tests")
    ap.add_argument("--no-install", action="store_true", help="PYTHONPATH, no pip install")
    args = ap.parse_args()
    args.grid_list = [int(g) for g in args.grids.split(",") if g]
    if args.skip_tests:
        args.stages = ",".join(s for s in args.stages.split(",") if s != "tests")
    run = Run(args)
    if not start(run):
        return 69
    for name, fn in (("tests", tests), ("floor", floors), ("sweeps", sweeps), ("ranks", ranks),
                     ("largest", largest), ("fig2", fig2), ("profile", profile)):  # fmt: skip
        run.stage(name, lambda fn=fn: fn(run))
    run.report["elapsed"] = time.perf_counter() - run.began
    run.save()
    run.say("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
