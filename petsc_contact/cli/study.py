"""``study``: the paper's datasets at the paper's parameters, in resumable pieces.

Each piece is one ``periodic`` or ``punch`` run with ``--stiffness --scalars-only``, written
to ``DATA/figN/NAME.h5``.  A piece already complete is skipped; an unfinished one continues
from its ``.partial`` file; the study stops cleanly after the step that ends past
``--minutes`` (exit status 75) and the next call goes on from there.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .common import EXIT_INTERRUPTED, EXIT_PAUSED

PAPER_GRID = 8192
HURSTS = (0.3, 0.5, 0.7)
SEEDS = (1, 2, 3, 4)
FIG3_RATIOS = (512, 768, 2048, 4096)  # lambda_r/lambda_1, L = lambda_r
# Figs. 2 and 3: four loads per decade from below the smallest resolved contact, so that at
# least four resolved points lie below the crossover p_c (about 2e-6 E* on 1024^2)
FINITE_SIZE_SWEEP = "25,1e-8,1e-2"


@dataclass(frozen=True)
class Piece:
    """One run of the study: its figure, its file name and its command line."""

    figure: str  # "fig1", "fig2" or "fig3": where the file is kept
    name: str
    argv: tuple[str, ...]
    used_by: tuple[str, ...] = ()  # further figures drawn from the same file

    @property
    def grid(self) -> int:
        """The run's grid size, the measure of its cost."""
        return int(self.argv[self.argv.index("--grid") + 1])

    def path(self, data: str) -> str:
        return os.path.join(data, self.figure, f"{self.name}.h5")


def _surface(grid: int, hurst: float, rolloff: float, cutoff: float, seed: int) -> list[str]:
    return [
        *f"--grid {grid} --hurst {hurst} --rms-slope 0.1 --rolloff-ratio {rolloff:g}".split(),
        *f"--cutoff-ratio {cutoff:g} --seed {seed}".split(),
    ]


def pieces(shrink: int = 1) -> list[Piece]:
    """The study at the paper's parameters (grids divided by ``shrink`` for a quick look)."""
    n = PAPER_GRID // shrink
    sweep = ["--sweep", "16,1e-7,3e-1"]
    out = [
        Piece("fig1", f"periodic_r{r}", ("periodic", *_surface(n, 0.7, r, n / 2, 1), *sweep))
        for r in (1, 8)
    ]
    punch_n = n // 4  # L_p/lambda_1 = 1024 at the paper's size: roughness down to two pixels
    forces = ",".join(f"{f:.3g}" for f in np.geomspace(1e-6, 3e-1, 16))
    out.append(
        Piece(
            "fig1",
            "punch",
            ("punch", *_surface(punch_n, 0.7, 1, punch_n / 2, 1), "--forces", forces),
        )
    )
    out += [
        Piece(
            "fig2",
            f"H{h}_seed{k}",
            ("periodic", *_surface(n, h, 1, n / 2, k), "--sweep", FINITE_SIZE_SWEEP),
        )
        for h in HURSTS
        for k in SEEDS
    ]
    for ratio in FIG3_RATIOS:
        m = max(2 * ratio // shrink, 16)  # roughness down to two pixels: n = 2 L/lambda_1
        out += [
            Piece(
                "fig3",
                f"ratio{ratio}_seed{k}",
                ("periodic", *_surface(m, 0.3, 1, m / 2, k), "--sweep", FINITE_SIZE_SWEEP),
            )
            for k in SEEDS
        ]
    return _once(out)


def _once(todo: list[Piece]) -> list[Piece]:
    """Each distinct run once: a piece whose command line an earlier piece already has (Fig. 3's
    largest ratio is Fig. 2's H = 0.3) is that earlier piece, now used by both figures."""
    first: dict[tuple[str, ...], Piece] = {}
    for piece in todo:
        seen = first.setdefault(piece.argv, piece)
        if seen is not piece:
            first[piece.argv] = replace(seen, used_by=(*seen.used_by, piece.figure))
    return list(first.values())


def chosen(args: argparse.Namespace) -> list[Piece]:
    """The pieces of ``--figure`` (all of them for ``all``), the smaller grids first."""
    figure = f"fig{args.figure}"
    todo = [
        p for p in pieces(args.shrink) if args.figure == "all" or figure in (p.figure, *p.used_by)
    ]
    return sorted(todo, key=lambda p: p.grid)


def complete(path: str) -> bool:
    """Whether a piece's file exists and says it is complete."""
    if not os.path.exists(path):
        return False
    import h5py

    with h5py.File(path, "r") as f:
        return bool(f.attrs.get("complete", False))


def run_study(args: argparse.Namespace, petsc_args: list[str]) -> int:
    """Run the pieces of the chosen figures in order within ``--minutes``."""
    from .arguments import build_parser
    from .runs import run

    todo = chosen(args)
    began = time.perf_counter()
    for number, piece in enumerate(todo, 1):
        path = piece.path(args.data)
        if complete(path):
            continue
        left = args.minutes - (time.perf_counter() - began) / 60
        if left <= 0:
            return _paused(todo, args.data, number - 1)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        argv = [*piece.argv, "--stiffness", "--scalars-only", "--output", path, "--resume"]
        argv += ["--stop-after", f"{left:.3f}"] + (["--quiet"] if args.quiet else [])
        print(f"# study {number}/{len(todo)}: {path}", flush=True)
        code = run(build_parser().parse_args(argv), ["study", *argv], petsc_args)
        if code in (EXIT_PAUSED, EXIT_INTERRUPTED):
            return code
    print(f"# study: all {len(todo)} pieces complete in {args.data}")
    return 0


def _paused(todo: Sequence[Piece], data: str, done: int) -> int:
    print(f"# study: time is up after {done} of {len(todo)} pieces; run it again to go on")
    return EXIT_PAUSED


def study_plan(args: argparse.Namespace) -> str:
    """One line per piece: its file, and whether it is complete."""
    todo = chosen(args)
    return "\n".join(
        f"{'done' if complete(p.path(args.data)) else 'todo'}  {p.path(args.data)}  "
        f"petsc-contact {' '.join(p.argv)}"
        for p in todo
    )
