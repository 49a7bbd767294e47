"""Stability matrix: every solver on stiff and extreme scenes.

usage: .venv/bin/python benchmarks/stability.py [--grid 128] [--solvers cg pk tron ...]
       [--time-limit 20] [--stall-iterations 1000] [--markdown docs/stability.md]
       [--grids 32 1024] [--no-scenes] [--append] [--match TEXT] [--adhesive]
For each scene and solver: converged or not (the package's own verification), TAO's reason,
iterations, wall time and the pressure error reached against a reference solved at 1e-12.
``--adhesive``: the adhesive scenes instead, each a short load cycle by TAO's gradient
solvers (BLMVM, BNCG): every step converged, or the first that did not and why.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from mpi4py import MPI

from petsc_contact.backend import _petsc
from petsc_contact.backend._petsc import scoped_options
from petsc_contact.backend.tao import PetscBackend
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.adhesive_periodic import AdhesivePeriodicProblem
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.geometries.punch import PunchProblem
from petsc_contact.interactions.adhesion import Adhesion
from petsc_contact.interactions.hardness import HardnessCap
from petsc_contact.physics.surface import self_affine
from petsc_contact.substrates.layer import PeriodicLayer
from petsc_contact.substrates.substrate import PeriodicSubstrate
from petsc_contact.workflows.adhesive_steps import adhesive_sweep
from petsc_contact.workflows.compare import DEFAULT_SOLVERS, PressurePosed, compare, posed_cell
from petsc_contact.workflows.scene import Scene

Pose = Callable[[Grid, np.ndarray, float], PeriodicProblem | PressurePosed]
"""How a scene is posed from its grid, heights and modulus (default: the periodic half-space)."""


def rough(n: int, hurst: float = 0.7, slope: float = 0.1, seed: int = 1) -> np.ndarray:
    grid = Grid(n, 1.0, MPI.COMM_SELF)
    return self_affine(
        grid,
        make_fft(grid),
        hurst=hurst,
        rolloff_ratio=2,
        cutoff_ratio=n / 4,
        seed=seed,
        rms_slope=slope,
    )


def scenes(n: int) -> list[tuple[str, np.ndarray, float, float, float]]:
    """(name, heights, length, modulus, p0/E*) of each scene."""
    x = (np.arange(n) + 0.5) / n - 0.5
    sine = np.repeat(0.01 * np.cos(2 * np.pi * x)[:, None], n, axis=1)
    cap = -(x[:, None] ** 2 + x[None, :] ** 2) / 2.0
    h = rough(n)
    p_full = -np.min(
        np.fft.irfft2(
            0.5
            * np.hypot(*np.meshgrid(np.fft.fftfreq(n) * n, np.fft.rfftfreq(n) * n, indexing="ij"))
            * 2
            * np.pi
            * np.fft.rfft2(h),
            s=h.shape,
        )
    )
    out = [(f"rough p0={p:g}", h, 1.0, 1.0, p) for p in (1e-7, 1e-5, 1e-3, 1e-2, 5e-2)]
    out += [
        ("rough near full contact (0.95 p_full)", h, 1.0, 1.0, 0.95 * p_full),
        ("rough beyond full contact (2 p_full)", h, 1.0, 1.0, 2 * p_full),
    ]
    out += [(f"H={hh:g}", rough(n, hurst=hh), 1.0, 1.0, 1e-2) for hh in (0.1, 0.95)]
    out += [(f"slope={s:g}", rough(n, slope=s), 1.0, 1.0, s * 1e-1) for s in (0.01, 1.0)]
    out += [
        ("flat", np.zeros((n, n)), 1.0, 1.0, 1e-3),
        ("single sine, 30% of p*", sine, 1.0, 1.0, 0.3 * np.pi * 0.01),
        ("single asperity (sphere cap)", cap, 1.0, 1.0, 1e-6),
        ("heights + 1e6 h_rms", h + 1e6 * h.std(), 1.0, 1.0, 1e-2),
        ("E* = 1e-6 (p scaled)", h, 1.0, 1e-6, 1e-8),
        ("E* = 1e9 (p scaled)", h, 1.0, 1e9, 1e7),
        ("L = 1e-6 (h scaled)", h * 1e-6, 1e-6, 1.0, 1e-2),
        ("L = 1e3 (h scaled)", h * 1e3, 1e3, 1.0, 1e-2),
    ]
    return out


def layer_scenes(n: int) -> list[tuple[str, np.ndarray, float, float, float, Pose]]:
    """(name, heights, length, modulus, p0/E*, pose) of the thin layers: a quarter pixel
    thick, far thinner than the rough surface's shortest wavelength (4 pixels), so that the
    stiffness no longer grows as ``|q|`` (bonded: ``M/T`` for every ``q``; incompressible:
    ``3 E*/(4 q^2 T^3)``, stiffest at the longest wavelength)."""
    h, thickness = rough(n), 1.0 / (4 * n)
    bodies = {
        "bonded, nu=0.3": PeriodicLayer(1.0, thickness, 0.3, "bonded"),
        "frictionless": PeriodicLayer(1.0, thickness, 0.3, "frictionless"),
        "bonded, nu=0.5": PeriodicLayer(1.0, thickness, 0.5, "bonded"),
    }
    return [
        (f"layer T=a/4, {name}, p0={p:g}", h, 1.0, 1.0, p, on_substrate(body))
        for name, body in bodies.items()
        for p in (1e-3, 1e-2)
    ]


def on_substrate(body: PeriodicSubstrate) -> Pose:
    """The periodic cell on ``body``, posed in the gap."""
    return lambda grid, h, modulus: PeriodicProblem(
        grid, make_fft(grid), h, modulus, substrate=body
    )


def hardness_scenes(n: int) -> list[tuple[str, np.ndarray, float, float, float, Pose]]:
    """(name, heights, length, modulus, p0/E*, pose) of the capped scenes: the rough surface
    under a hardness ``H`` of 10, 2 and 1.05 times the nominal pressure (at 1.05 nearly the
    whole surface flows), posed in the pressure: the periodic cell
    (:class:`~petsc_contact.geometries.capped_periodic.CappedPeriodicProblem`) and the punch
    of the same face, whose nominal pressure is over its face."""
    h = rough(n)
    return [
        (f"hardness {ratio:g} p0, {kind}, p0={p:g}", h, 1.0, 1.0, p, capped(kind, ratio * p))
        for kind in ("periodic", "punch")
        for p in (1e-3, 1e-2)
        for ratio in (10, 2, 1.05)
    ]


def capped(kind: str, hardness: float) -> Pose:
    """The ``kind`` (periodic cell or punch) posed in the pressure under ``hardness``."""
    cap = HardnessCap(hardness)
    if kind == "periodic":
        return lambda grid, h, modulus: posed_cell(Scene(grid, make_fft(grid), h, {}), modulus, cap)
    return lambda grid, h, modulus: PressurePosed(PunchProblem(grid, h, modulus, interaction=cap))


TABOR = (0.1, 1.0, 10.0)  # Maugis' transition parameter of the adhesive scenes
ADHESIVE_SOLVERS = ("blmvm", "bncg")  # TAO's gradient solvers (the package's CG is a QP's)


def adhesive_scenes(n: int) -> list[tuple[str, np.ndarray, Adhesion, list[float]]]:
    """(name, heights, law, loads) of the adhesive scenes: Maugis' law on the sphere ``R = 1``
    and on the rough surface (``R``: the inverse of its rms curvature along ``x``), its
    attraction ``w/rho`` a tenth of the surface's full-contact pressure (partial contact
    survives it) and its range from the Tabor parameter ``mu = (R w^2 / (E*^2 rho^3))^(1/3)``,
    ``rho = (w/rho)^2 R / (mu^3 E*^2)``: at 0.1 (DMT's limit) beyond the heights, at 10
    (JKR's) far below a pixel.  Each is loaded to half the attraction, unloaded to zero and
    pulled at half the attraction (beyond the pull-off where contact is sparse)."""
    x = (np.arange(n) + 0.5) / n - 0.5
    cap = -(x[:, None] ** 2 + x[None, :] ** 2) / 2.0
    h = rough(n)
    curvature = np.sqrt(np.mean((np.gradient(np.gradient(h, 1 / n, axis=0), 1 / n, axis=0)) ** 2))
    grid, out = Grid(n, 1.0, MPI.COMM_SELF), []
    for surface, heights, radius in (("sphere", cap, 1.0), ("rough", h, 1 / curvature)):
        p_full = PeriodicProblem(grid, make_fft(grid), heights, 1.0).full_contact_pressure()
        strength = 0.1 * p_full
        for mu in TABOR:
            rho = strength**2 * radius / mu**3
            law = Adhesion("maugis", strength * rho, rho)
            loads = [0.5 * strength, 0.0, -0.5 * strength]
            out.append((f"{surface}, Maugis, Tabor {mu:g}", heights, law, loads))
    return out


def adhesive_row(name: str, h: np.ndarray, law: Adhesion, loads: list[float]) -> str:
    """One adhesive scene's row: for each of :data:`ADHESIVE_SOLVERS`, the steps converged
    (of all), their contact area fractions, iterations and time, or the first step that did
    not and its verdict (a pull-off, no equilibrium, unmarked; any other **FAIL**)."""
    grid, cells = Grid(h.shape[0], 1.0, MPI.COMM_SELF), []
    for solver in ADHESIVE_SOLVERS:
        with scoped_options(["-tao_type", solver]):
            problem = AdhesivePeriodicProblem(grid, make_fft(grid), h, 1.0, law, PetscBackend())
            start = time.perf_counter()
            steps = [s.scalars for s in adhesive_sweep(problem, loads)]
            elapsed = time.perf_counter() - start
        its = sum(s["iterations"] for s in steps)
        failed = [s for s in steps if not s["converged"]]
        areas = "/".join(f"{s['area_fraction']:.2g}" for s in steps)
        cell = f"ok {len(steps)}/{len(steps)} steps, areas {areas}, {its} its, {elapsed:.2g} s"
        if failed:
            s = failed[0]
            mark = "" if s["verification"].startswith("pulled off") else "**FAIL** "
            cell = (
                f"{mark}at p0 = {s['nominal_pressure']:.3g}, {its} its, {elapsed:.2g} s "
                f"({s['verification']})"
            )
        cells.append(cell)
    scene = f"{name} (w = {law.work:.2g}, w/rho = {law.strength:.2g}, rho = {law.range:.2g})"
    return f"| {scene} | " + " | ".join(cells) + " |"


def parse_args() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=128)
    ap.add_argument(
        "--grids",
        type=int,
        nargs="*",
        default=[32, 1024],
        help="extra grid sizes for the rough p0 = 1e-3 scene",
    )
    ap.add_argument("--solvers", nargs="+", default=list(DEFAULT_SOLVERS))
    ap.add_argument("--time-limit", type=float, default=20.0)
    ap.add_argument(
        "--stall-iterations",
        type=int,
        default=1000,
        help="stop a solver whose natural residual has not fallen 10%% below its "
        "best for this many iterations (0: never)",
    )
    ap.add_argument("--markdown", default=None, help="also write the table here")
    ap.add_argument("--match", default="", help="run only the scenes whose name has this text")
    ap.add_argument(
        "--append",
        action="store_true",
        help="append the table to --markdown instead of replacing the file",
    )
    ap.add_argument(
        "--scenes",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the scenes at --grid (--no-scenes: only the --grids rows)",
    )
    ap.add_argument(
        "--adhesive",
        action="store_true",
        help="run the adhesive scenes at --grid instead (their own table)",
    )
    return ap.parse_args()


def row(name: str, case: tuple, args: argparse.Namespace) -> str:
    """One scene's table row: every solver's verdict, iterations, time and error (on the
    periodic half-space, or as the case's last item poses it)."""
    h, length, modulus, p0, *pose = case
    grid = Grid(h.shape[0], length)
    problem = (
        pose[0](grid, h, modulus) if pose else PeriodicProblem(grid, make_fft(grid), h, modulus)
    )
    try:
        _, trajs = compare(
            problem, p0, args.solvers, args.time_limit, stall_iterations=args.stall_iterations
        )
    except RuntimeError as exc:
        cells = [f"reference failed: {exc}"] * len(args.solvers)
    else:
        cells = []
        for t in trajs:
            err = t.pressure_error[-1] if t.pressure_error else float("nan")
            mark = "ok" if t.converged else "**FAIL**"
            cells.append(
                f"{mark} {t.iterations} its, {t.solve_time:.2g} s, "
                f"err {err:.0e}" + ("" if t.converged else f" ({t.reason})")
            )
    return f"| {name} | " + " | ".join(cells) + " |"


def write_markdown(lines: list[str], args: argparse.Namespace) -> None:
    where = f"{args.grid}^2 unless stated" if args.scenes else "large grids"
    stall = (
        f", stopped after {args.stall_iterations} iterations without a 10% lower natural residual"
        if args.stall_iterations
        else ""
    )
    with open(args.markdown, "a" if args.append else "w") as f:
        f.write(
            f"{chr(10) if args.append else ''}Stability matrix, {where}, time limit "
            f"{args.time_limit:g} s per solver{stall} (`benchmarks/stability.py`). "
            "Each cell: "
            "verdict, TAO iterations, wall time, relative pressure error against a "
            "reference solved at 1e-12 (raised to 30 eps k h_rms / p0 where rounding needs "
            "it).\n\n" + "\n".join(lines) + "\n"
        )


def adhesive_main(args: argparse.Namespace) -> None:
    """The adhesive scenes' table (``--adhesive``)."""
    lines = [
        "| scene | " + " | ".join(ADHESIVE_SOLVERS) + " |",
        "| --- |" + " --- |" * len(ADHESIVE_SOLVERS),
    ]
    start = time.perf_counter()
    for name, *case in adhesive_scenes(args.grid):
        if args.match in name:
            lines.append(adhesive_row(name, *case))
            print(lines[-1], flush=True)
    print(f"# {time.perf_counter() - start:.0f} s")
    if args.markdown:
        with open(args.markdown, "a" if args.append else "w") as f:
            f.write(
                f"{chr(10) if args.append else ''}Adhesive scenes, {args.grid}^2 "
                "(`benchmarks/stability.py --adhesive`). Each cell: the steps converged, "
                "their contact area fractions, TAO iterations and wall time of the cycle, or "
                "the first step that did not and why (a pull-off unmarked, any other "
                "**FAIL**).\n\n" + "\n".join(lines) + "\n"
            )


def main() -> None:
    args = parse_args()
    _petsc.init([])
    if args.adhesive:
        adhesive_main(args)
        return
    cases: list[tuple] = []
    if args.scenes:
        cases = [*scenes(args.grid), *layer_scenes(args.grid), *hardness_scenes(args.grid)]
    cases += [(f"grid {n}, p0=1e-3", rough(n), 1.0, 1.0, 1e-3) for n in args.grids]
    cases = [case for case in cases if args.match in case[0]]
    lines = [
        "| scene | " + " | ".join(args.solvers) + " |",
        "| --- |" + " --- |" * len(args.solvers),
    ]
    start = time.perf_counter()
    for name, *case in cases:
        lines.append(row(name, tuple(case), args))
        print(lines[-1], flush=True)
    print(f"# {time.perf_counter() - start:.0f} s")
    if args.markdown:
        write_markdown(lines, args)


if __name__ == "__main__":
    main()
