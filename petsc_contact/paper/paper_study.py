"""The paper's study as a list of runs: which surfaces, loads and grids each figure needs.

Each :class:`Piece` is one periodic or punch :class:`~petsc_contact.workflows.description.Run`
and the file it writes, ``DATA/figN/NAME.h5``; ``petsc-contact study`` runs them in resumable
pieces and the figure scripts read them back (:func:`piece_files`).
"""

from __future__ import annotations

import argparse
import os
import shlex
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any, TypeVar

import numpy as np

from ..conventions.validation import log_range
from ..io.atomic import storage
from ..io.lock import OutputBusy
from ..io.names import partial_path
from ..io.partial import committed_steps
from ..io.results import trusted
from ..io.store import tidy
from ..physics.surface import psd_shape
from ..workflows.description import Run
from ..workflows.options import DEFAULT_DATA

T = TypeVar("T")

PAPER_GRID = 8192
RMS_SLOPE = 0.1
HURSTS = (0.3, 0.5, 0.7)
SEEDS = (1, 2, 3, 4)
# Fig. 2 at eight seeds per H: intervals over seeds that can tell alpha = 0.72 from 0.77 (seeds
# 5-8 after the paper's four, each piece a 25-load sweep of 8192^2)
FIG2_SEEDS = tuple(range(1, 9))
FIG3_RATIOS = (512, 768, 2048, 4096)  # lambda_r/lambda_1, L = lambda_r
# Figs. 2 and 3: four loads per decade from below the smallest resolved contact, so that at
# least four resolved points lie below the crossover p_c (4e-6 E* on 1024^2, the paper's recipe)
FINITE_SIZE_SWEEP = (25, 1e-8, 1e-2)
FIG1_SWEEP = (16, 1e-7, 3e-1)
# Datasets beyond the paper's figures: the Hertz regime (lambda_1 of 16, 32 and 64
# pixels on 512^2, four loads per decade from below single-patch contact), the seed
# distribution (Fig. 3's lambda_r/lambda_1 = 512 over 64 seeds) and the punch settled (eight
# seeds of periodic and cut faces at L_p/lambda_r = 1 and 8)
HERTZ_GRID = 512
HERTZ_PIXELS = (16, 32, 64)  # lambda_1 in pixels
HERTZ_SWEEP = (29, 1e-9, 1e-2)
MAX_SHRINK = HERTZ_GRID // 4  # --shrink: the smallest grid, the Hertz regime's, keeps 4 pixels
DISTRIBUTION_RATIO = 512
DISTRIBUTION_SEEDS = tuple(range(1, 65))
PUNCH_SEEDS = tuple(range(1, 9))
PUNCH_RATIOS = (1, 8)  # L_p/lambda_r
# (face, L_p/lambda_r), those Fig. 1's punch (a periodic face at 1) leaves untested first
PUNCH_VARIANTS = (("cut", 1), ("periodic", 8), ("cut", 8), ("periodic", 1))
CUT_FROM = 4  # a cut face: the central patch of a periodic surface of 4 L_p
# approaches from below 1e-7 E* to past 20% area, in the face's expected rms heights (the
# parent surface's for a cut face), by L_p/lambda_r: the smoother faces of L_p/lambda_r = 8
# need the longer travel (on 256^2 trial faces 20 rms heights gave 62-76% area at 1 and 31% at
# 8, and 2048^2 faces have about half the area of 256^2 ones at the same approach)
PUNCH_APPROACHES = {1: (0.03, 20.0, 16), 8: (0.03, 40.0, 16)}
# the punch's periodic faces as periodic cells: loads 0.05 decades apart through 1-10% contact
# area (the 2048^2 faces reach 1% near 5e-4 E* and 10% near 5e-3 E*, Fig. 1's table), so that
# the punch and the cell of the same face are read by one linearity criterion, and u0 rests on
# more than six loads of the window
CELL_SWEEP = (30, 10**-3.5, 10**-2.05)
# and the same faces as punches again, their approaches through 1-10% contact area (1.5-7.3
# and 2.9-14.4 expected rms heights beyond first touch over the 8 seeds of punch/ at
# L_p/lambda_r = 1 and 8), the loads then about 0.05 decades apart as the cells'
CELL_PUNCH_APPROACHES = {1: (1.45, 7.4, 32), 8: (2.9, 14.5, 24)}


@dataclass(frozen=True)
class Piece:
    """One run of the study: its figure, its file name and its description."""

    figure: str  # "fig1", "fig2", "fig3", "hertz", "seeds", "punch" or "cells": its folder
    name: str
    run: Run
    used_by: tuple[str, ...] = ()  # further figures drawn from the same file

    @property
    def grid(self) -> int:
        """The run's grid size, the measure of its cost."""
        return int(self.run.grid)  # type: ignore[arg-type]

    @property
    def steps(self) -> int:
        """The run's load steps: its sweep count or its list of loads."""
        if self.run.sweep is not None:
            return int(self.run.sweep[0])
        return len(self.run.approaches or self.run.pressures or ())

    def path(self, data: str) -> str:
        return os.path.join(data, self.figure, f"{self.name}.h5")

    def to_run(self, data: str, minutes: float | None = None) -> Run:
        """The run that computes (or goes on with) this piece into ``data``: the exact
        stiffness, scalars only, resumed, paused after ``minutes``."""
        return self.run.with_(
            stiffness=True,
            scalars_only=True,
            output=self.path(data),
            resume=True,
            stop_after=minutes,
        )


def _surface(grid: int, hurst: float, rolloff: float, cutoff: float, seed: int) -> dict[str, Any]:
    return {
        "grid": grid,
        "hurst": hurst,
        "rms_slope": RMS_SLOPE,
        "rolloff_ratio": float(rolloff),
        "cutoff_ratio": float(cutoff),
        "seed": seed,
    }


def rms_height_per_slope(hurst: float, rolloff_ratio: float, cutoff_ratio: float) -> float:
    """``h_rms / h'_rms`` of paper Eq. 5's continuum spectrum on a unit cell (the expected
    ratio of a generated surface)."""
    q0 = 2 * np.pi
    q = np.geomspace(q0, q0 * cutoff_ratio, 4000)
    c = psd_shape(q, q0, q0 * rolloff_ratio, q0 * cutoff_ratio * (1 + 1e-12), hurst)
    return float(np.sqrt(np.trapezoid(q * c, q) / np.trapezoid(q**3 * c, q)))


def check_shrink(shrink: int) -> None:
    """``ValueError`` (one line) unless ``shrink`` is a whole number from 1 to
    :data:`MAX_SHRINK`."""
    if not 1 <= shrink <= MAX_SHRINK:
        raise ValueError(
            f"--shrink must be a whole number from 1 to {MAX_SHRINK} (every grid keeps "
            f"{HERTZ_GRID // MAX_SHRINK} pixels a side), got {shrink}"
        )


def pieces(shrink: int = 1) -> list[Piece]:
    """The study at the paper's parameters (grids divided by ``shrink`` for a quick look;
    ``ValueError`` unless :func:`check_shrink` accepts it)."""
    check_shrink(shrink)
    n = PAPER_GRID // shrink
    out = [
        Piece("fig1", f"periodic_r{r}", Run(**_surface(n, 0.7, r, n / 2, 1), sweep=FIG1_SWEEP))
        for r in (1, 8)
    ]
    punch_n = n // 4  # L_p/lambda_1 = 1024 at the paper's size: roughness down to two pixels
    # displacement control (one solve a step; load control costs several Newton solves),
    # from 0.01 to 10 rms heights beyond first touch: to well over 10% contact area
    h_rms = RMS_SLOPE * rms_height_per_slope(0.7, 1, punch_n / 2)
    approaches = tuple(float(f"{d:.4g}") for d in np.geomspace(1e-2, 10.0, 16) * h_rms)
    surface = _surface(punch_n, 0.7, 1, punch_n / 2, 1)
    out.append(Piece("fig1", "punch", Run(geometry="punch", **surface, approaches=approaches)))
    out += [
        Piece("fig2", f"H{h}_seed{k}", Run(**_surface(n, h, 1, n / 2, k), sweep=FINITE_SIZE_SWEEP))
        for k in FIG2_SEEDS
        for h in HURSTS
    ]
    for ratio in FIG3_RATIOS:
        m = max(2 * ratio // shrink, 16)  # roughness down to two pixels: n = 2 L/lambda_1
        out += [
            Piece(
                "fig3",
                f"ratio{ratio}_seed{k}",
                Run(**_surface(m, 0.3, 1, m / 2, k), sweep=FINITE_SIZE_SWEEP),
            )
            for k in SEEDS
        ]
    beyond = hertz_pieces(shrink) + distribution_pieces(shrink) + punch_pieces(shrink)
    return _once(out + beyond + cell_pieces(shrink))


def hertz_pieces(shrink: int = 1) -> list[Piece]:
    """The Hertz regime (``hertz/lambda{P}_seed{k}``): ``lambda_1`` of :data:`HERTZ_PIXELS`
    pixels on :data:`HERTZ_GRID`^2, ``H = 0.7``, ``L = lambda_r``, four seeds."""
    n = HERTZ_GRID // shrink
    return [
        Piece(
            "hertz",
            f"lambda{px}_seed{k}",
            Run(**_surface(n, 0.7, 1, HERTZ_GRID / px, k), sweep=HERTZ_SWEEP),
        )
        for px in HERTZ_PIXELS
        for k in SEEDS
    ]


def distribution_pieces(shrink: int = 1) -> list[Piece]:
    """The seed distribution (``seeds/ratio512_seed{k}``): Fig. 3's pieces at
    ``lambda_r/lambda_1 = 512`` over :data:`DISTRIBUTION_SEEDS` (seeds 1-4 are Fig. 3's own
    files, :func:`_once`)."""
    m = max(2 * DISTRIBUTION_RATIO // shrink, 16)
    return [
        Piece(
            "seeds",
            f"ratio{DISTRIBUTION_RATIO}_seed{k}",
            Run(**_surface(m, 0.3, 1, m / 2, k), sweep=FINITE_SIZE_SWEEP),
        )
        for k in DISTRIBUTION_SEEDS
    ]


def punch_approaches(rolloff_ratio: float, cutoff_ratio: float, cut_from: int) -> tuple[float, ...]:
    """:data:`PUNCH_APPROACHES` in the expected rms height of the face (of its parent surface,
    ``cut_from`` times the sides, for a cut face) at the study's rms slope."""
    low, high, count = PUNCH_APPROACHES[int(rolloff_ratio)]
    ratios = cut_from * rolloff_ratio, cut_from * cutoff_ratio  # the parent's, of sides cut_from
    h_rms = RMS_SLOPE * cut_from * rms_height_per_slope(0.7, *ratios)
    return tuple(float(f"{d:.4g}") for d in np.geomspace(low, high, int(count)) * h_rms)


def punch_pieces(shrink: int = 1) -> list[Piece]:
    """The punch settled (``punch/{face}_r{R}_seed{k}``): ``L_p/lambda_1 = 1024`` on 2048^2,
    ``H = 0.7``, ``L_p/lambda_r = R`` of :data:`PUNCH_RATIOS`, faces ``periodic`` (a periodic
    surface) and ``cut`` (cut from one of :data:`CUT_FROM` times the sides), by approaches;
    seed by seed in the order of :data:`PUNCH_VARIANTS`, so that every variant has its
    first seeds early."""
    n = PAPER_GRID // 4 // shrink
    out = []
    for k in PUNCH_SEEDS:
        for face, r in PUNCH_VARIANTS:
            m = CUT_FROM if face == "cut" else 1
            surface = _surface(n, 0.7, r, n / 2, k)
            run = Run(
                geometry="punch", **surface, cut_from=m, approaches=punch_approaches(r, n / 2, m)
            )
            out.append(Piece("punch", f"{face}_r{r}_seed{k}", run))
    return out


def cell_pieces(shrink: int = 1) -> list[Piece]:
    """The punch's periodic faces as periodic cells (``cells/periodic_r{R}_seed{k}``): the
    surfaces of :func:`punch_pieces`' ``periodic`` faces (the same grid, spectrum and seed, so
    the same heights), loaded by :data:`CELL_SWEEP`; then the same faces as punches
    (``cells/punch_r{R}_seed{k}``), by the approaches of :data:`CELL_PUNCH_APPROACHES`."""
    n = PAPER_GRID // 4 // shrink
    cells, punches = [], []
    for k in PUNCH_SEEDS:
        for r in PUNCH_RATIOS:
            surface = _surface(n, 0.7, r, n / 2, k)
            cells.append(Piece("cells", f"periodic_r{r}_seed{k}", Run(**surface, sweep=CELL_SWEEP)))
            low, high, count = CELL_PUNCH_APPROACHES[r]
            h_rms = RMS_SLOPE * rms_height_per_slope(0.7, r, n / 2)
            approaches = tuple(float(f"{d:.4g}") for d in np.geomspace(low, high, count) * h_rms)
            run = Run(geometry="punch", **surface, approaches=approaches)
            punches.append(Piece("cells", f"punch_r{r}_seed{k}", run))
    return cells + punches


def _once(todo: list[Piece]) -> list[Piece]:
    """Each distinct run once: a piece whose command line an earlier piece already has (Fig. 3's
    largest ratio is Fig. 2's H = 0.3) is that earlier piece, now used by both figures."""
    first: dict[tuple[str, ...], Piece] = {}
    for piece in todo:
        key = tuple(piece.run.arguments())
        seen = first.setdefault(key, piece)
        if seen is not piece:
            first[key] = replace(seen, used_by=(*seen.used_by, piece.figure))
    return list(first.values())


def complete(path: str) -> bool:
    """Whether a piece's file exists and says it is complete (``ValueError`` naming it when it
    cannot be read)."""
    if not os.path.exists(path):
        return False
    with _piece(path) as f:
        return bool(f.attrs.get("complete", False))


def check_piece(path: str, run: Run) -> None:
    """``ValueError`` (one line) unless the piece's file ``path`` (complete, or its
    ``.partial``) was written by ``run`` (:func:`~petsc_contact.workflows.seeds.check_kept`):
    a folder of another study (another ``--shrink``) is never joined."""
    from ..workflows.seeds import check_kept

    try:
        check_kept(path, run)
    except ValueError as exc:
        raise ValueError(
            f"{exc}, not this study's piece: remove it, or give this study a --data folder of "
            "its own"
        ) from None


def converged(path: str) -> bool:
    """Whether every step of a complete piece's file converged and is accurate."""
    with _piece(path) as f:
        return bool(np.all(trusted(f)))


@contextmanager
def _piece(path: str) -> Iterator[Any]:
    """A piece's file, open for reading; ``ValueError`` naming it when it is damaged."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            yield f
    except (OSError, KeyError) as exc:
        raise ValueError(
            f"the study's piece '{path}' cannot be read ({exc}): remove it, and the study "
            "computes it again"
        ) from None


def finished_steps(path: str) -> int | None:
    """The steps kept so far in a piece's unfinished file ``path + '.partial'`` (None when
    there is none, or it cannot be read while a run writes it)."""
    partial = partial_path(path)
    if not os.path.exists(partial):
        return None
    try:
        return committed_steps(partial, locking=False)
    except (OSError, KeyError):
        return None


def study_pieces(data: str, figure: str = "all", shrink: int = 1) -> list[Piece]:
    """The pieces of ``figure`` (``1``, ``fig1``, ``hertz``, ...; all of them for ``all``),
    the smaller grids first (``ValueError`` for an empty ``data``, one not a folder, a bad
    ``shrink``)."""
    if not data:
        raise ValueError("give a data folder (--data is empty)")
    if os.path.exists(data) and not os.path.isdir(data):
        raise ValueError(f"--data '{data}' is not a folder")
    name = f"fig{figure}" if figure.isdigit() else figure
    todo = [p for p in pieces(shrink) if figure == "all" or name in (p.figure, *p.used_by)]
    return sorted(todo, key=lambda p: p.grid)


def study_data(data: str | None) -> str:
    """The folder of a study's pieces: ``data``, or when none is given :data:`DEFAULT_DATA`,
    which must exist (``ValueError``, one line): run elsewhere than the repository's root,
    a study would start the whole study afresh."""
    if data is not None:
        return data
    if not os.path.isdir(DEFAULT_DATA):
        raise ValueError(
            f"no {DEFAULT_DATA} in {os.getcwd()}: run the study in the repository's root, "
            "where the paper's data are, or name a folder with --data (a new one starts "
            "the study afresh)"
        )
    return DEFAULT_DATA


def study_plan(todo: Sequence[Piece], data: str) -> list[str]:
    """One line per piece: its state (``done``, ``todo``, or the steps an unfinished piece
    has kept, ``13/25``), its file and the command line that computes it (or goes on with
    it) alone, as the study does (:meth:`Piece.to_run`)."""
    lines = []
    for piece in todo:
        path = piece.path(data)
        if complete(path):
            state = "done"
        else:
            kept = finished_steps(path)
            state = "todo" if kept is None else f"{kept}/{piece.steps}"
        command = shlex.join(["petsc-contact", *piece.to_run(data).arguments()])
        folder = os.path.dirname(path)
        if not os.path.isdir(folder):  # the study makes it; a command run alone needs it
            command = f"mkdir -p {shlex.quote(folder)} && {command}"
        lines.append(f"{state:>5}  {shlex.quote(path)}  {command}")
    return lines


PIECE_ENDS = ("complete", "unconverged", "paused", "interrupted")
"""How a piece's run ends, and so a study's (:func:`run_pieces`): every step converged, some
did not, paused by its time limit, interrupted by a signal."""


def run_pieces(
    todo: Sequence[Piece],
    data: str,
    minutes: float,
    run_piece: Callable[[Run], str],
    say: Callable[[str], None],
) -> str:
    """Run the pieces ``todo`` into the folder ``data`` in order within ``minutes``; how the
    study ends, one of :data:`PIECE_ENDS`.

    ``run_piece(run)`` runs one piece (its output locked already) and says how it ended;
    ``say(line)`` is given the study's progress on rank 0.  Every decision (a piece
    complete, the time left) is rank 0's, shared with the other ranks.  A piece is run
    inside its lock, taken once: a piece another run holds is left to it (the study then
    ends ``paused``, unless a piece did not converge), one that became complete before the
    lock was ours is skipped.  A file of the pieces that is not this study's is refused
    (``ValueError``) before anything is computed."""
    with storage(data):
        os.makedirs(data, exist_ok=True)
    return _Study(todo, data, run_piece, say).run(minutes)


class _Study:
    """One call of a study: its pieces, and those left to other runs or not converged."""

    def __init__(
        self,
        todo: Sequence[Piece],
        data: str,
        run_piece: Callable[[Run], str],
        say: Callable[[str], None],
    ) -> None:
        from ..conventions.grid import world

        self.todo, self.data, self.run_piece, self.say = todo, data, run_piece, say
        self.comm = world()
        self.elsewhere: list[str] = []  # pieces other runs are writing
        self.unconverged: list[str] = []  # complete, with steps that failed

    def run(self, minutes: float) -> str:
        """Each piece not complete yet, until the time is up; how the study ends."""
        foreign = self.agreed(_foreign, self.data, self.todo)
        if foreign:  # before anything is computed
            raise ValueError(foreign)
        began = time.perf_counter()
        for number, piece in enumerate(self.todo, 1):
            path = piece.path(self.data)
            if self.agreed(complete, path):
                tidy(path)  # what a writer killed after its last rename left
                if not self.agreed(converged, path):
                    self.unconverged.append(path)
                continue
            left = self.agreed(lambda: minutes - (time.perf_counter() - began) / 60)
            if left <= 0:
                done = f"{number - 1} of {len(self.todo)} pieces"
                self.tell(f"# study: time is up after {done}; run it again to go on")
                return "paused"
            end = self.piece(piece, f"# study {number}/{len(self.todo)}: {path}", left)
            if end in ("paused", "interrupted"):
                return end
            if end == "unconverged":
                self.unconverged.append(path)
        return self.conclude()

    def piece(self, piece: Piece, heading: str, minutes: float) -> str:
        """Run ``piece`` within ``minutes`` under its lock: how it ended, or ``"elsewhere"``
        when another run holds it."""
        from ..workflows.runner import check_files, locked

        path = piece.path(self.data)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        run = piece.to_run(self.data, round(minutes, 3))
        check_files(run)  # before its lock is taken
        try:
            with locked(path):
                if self.agreed(complete, path):  # finished by another run meanwhile
                    return "complete"
                self.tell(heading)
                return self.run_piece(run)
        except OutputBusy as busy:
            self.tell(f"{heading} is being written by another run ({busy.holder}); left to it")
            self.elsewhere.append(path)
            return "elsewhere"

    def conclude(self) -> str:
        """The study's last lines, and how it ends."""
        count = len(self.todo)
        if self.elsewhere:
            self.tell(
                f"# study: {len(self.elsewhere)} of {count} pieces are being written by other "
                "runs; run the study again once they end to check that every piece is complete"
            )
        if self.unconverged:
            self.tell(
                f"# study: {len(self.unconverged)} of {count} pieces have steps that did not "
                f"converge (flagged converged = False): {', '.join(self.unconverged)}"
            )
            return "unconverged"
        if self.elsewhere:
            return "paused"
        self.tell(f"# study: all {count} pieces complete in {self.data}")
        return "complete"

    def agreed(self, decide: Callable[..., T], *args: Any) -> T:
        """Rank 0's ``decide(*args)``, the same on every rank."""
        if self.comm.size == 1:
            return decide(*args)
        agreed: T = self.comm.bcast(decide(*args) if self.comm.rank == 0 else None, root=0)
        return agreed

    def tell(self, line: str) -> None:
        """A line of the study's progress, from rank 0 only."""
        if self.comm.rank == 0:
            self.say(line)


def _foreign(data: str, todo: Sequence[Piece]) -> str:
    """Why a file of the pieces ``todo`` in ``data`` (complete, or a ``.partial``) is not the
    study's (:func:`check_piece`), or ``""``."""
    for piece in todo:
        path = piece.path(data)
        for kept in (path, partial_path(path)):
            try:
                if os.path.exists(kept):
                    check_piece(kept, piece.to_run(data))
            except ValueError as exc:
                return str(exc)
    return ""


def add_redraw_options(parser: argparse.ArgumentParser, figure: int, output: str) -> None:
    """A figure script's ``--fit-points``, ``--min-contact-pixels``, ``--data DIR`` (redraw
    the paper's Fig. ``figure`` from the study's files) and ``--output`` options."""
    from .figures import MIN_CONTACT_PIXELS

    parser.add_argument(
        "--fit-points", type=int, default=4, help="the lowest resolved loads fitted (default 4)"
    )
    parser.add_argument(
        "--min-contact-pixels",
        type=int,
        default=MIN_CONTACT_PIXELS,
        metavar="N",
        help="a load is resolved, drawn as such and fitted when every seed has at least N "
        f"contact pixels (default {MIN_CONTACT_PIXELS}, the study's rule)",
    )
    add_data_options(parser, str(figure), output)


def add_data_options(
    parser: argparse.ArgumentParser,
    figure: str,
    output: str,
    required: bool = False,
    partial: bool = True,
) -> None:
    """A figure script's ``--data DIR`` (the files of ``petsc-contact study --figure
    figure``; ``required`` for scripts that only redraw), ``--with-partial`` (for scripts
    that read unfinished pieces: ``partial``) and ``--output`` options."""
    parser.add_argument(
        "--data",
        metavar="DIR",
        required=required,
        help=f"redraw from the study's files (petsc-contact study --figure {figure}), "
        "e.g. data/paper",
    )
    if partial:
        parser.add_argument(
            "--with-partial",
            action="store_true",
            help="also read the pieces still computing (NAME.h5.partial), over the loads "
            "every seed has so far: a look at an unfinished study, not its result",
        )
    parser.add_argument(
        "--output", default=output, help=f"prefix of the PNG and HDF5 files (default {output})"
    )


class _LogSpacedPressures(argparse.Action):
    """``--pressures PMIN PMAX N``, refused unless ``0 < PMIN < PMAX`` and ``N >= 2`` is whole."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        try:
            log_range(str(option_string), values[2], (values[0], values[1]))
        except ValueError as bad:
            parser.error(str(bad))
        setattr(namespace, self.dest, values)


def add_pressures_option(parser: argparse.ArgumentParser, low: float, high: float, n: int) -> None:
    """A figure script's ``--pressures PMIN PMAX N`` option: ``N`` log-spaced ``p0/E*``,
    read back with :func:`log_pressures`."""
    parser.add_argument(
        "--pressures",
        type=float,
        nargs=3,
        action=_LogSpacedPressures,
        default=[low, high, n],
        metavar=("PMIN", "PMAX", "N"),
        help=f"log-spaced p0/E* (default {low:g} {high:g} {n})".replace("e-0", "e-"),
    )


def log_pressures(args: argparse.Namespace) -> np.ndarray:
    """The loads ``p0/E*`` of :func:`add_pressures_option`'s ``--pressures``."""
    low, high, n = args.pressures
    return np.geomspace(low, high, int(n))


def _text(value: Any) -> str:
    """A description's value as the command line writes it (``0.3``, ``512``)."""
    return f"{value:g}" if isinstance(value, float) else str(value)


def piece_files(
    data: str, figure: str, command: str = "periodic", *, partial: bool = False, **where: str
) -> list[str]:
    """The complete files of ``figure``'s ``command`` pieces whose command line has every
    ``--option value`` of ``where`` (``hurst="0.3"``, ``cutoff_ratio="512"``).  With
    ``partial``, an unfinished piece's ``NAME.h5.partial`` stands in for it once it has kept
    a step."""
    out = []
    for piece in pieces():
        if figure not in (piece.figure, *piece.used_by) or piece.run.geometry != command:
            continue
        if all(_text(getattr(piece.run, k)) == v for k, v in where.items()):
            path = piece.path(data)
            if complete(path):
                out.append(path)
            elif partial and (finished_steps(path) or 0) > 0:
                out.append(partial_path(path))
    return out
