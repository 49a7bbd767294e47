"""The state a run resumes from: ``OUT.h5.state.npz``, one slab per rank.

After each committed step, every rank saves its rows of the solution the next step starts
from, and of the fields the sweep holds beside it, to its slab (``OUT.h5.state.npz`` on one
rank, ``OUT.h5.state.RofP.npz`` on ``P``; ``after_step`` says which step it ends, ``slab``
which rank wrote it).  A resume on any rank count reads each rank's rows only, and each rank
checks only the slabs that hold them (the ranks agree on the verdict); one that finds the
state missing, damaged or stale starts the next step from first touch.
"""

from __future__ import annotations

import os
import zipfile
from contextlib import suppress
from typing import TYPE_CHECKING, Any

import numpy as np

from ..conventions.grid import block_rows
from ..physics.continuation import Held
from .atomic import _reason, on_every, replaced, storage
from .names import state_path
from .parts import SlabRows, mapped, slab_name, slab_of

if TYPE_CHECKING:
    from ..conventions.grid import Grid, RowSource


def write_state(path: str, comm: Any, state: np.ndarray, held: Held | None, step: int) -> None:
    """Every rank of ``comm`` saves its rows of the state after ``step`` and of the fields
    ``held`` beside it: its slab of output ``path``'s ``OUT.h5.state.npz`` (collective)."""
    kept: dict[str, Any] = {}
    if held is not None:
        kept["held"] = np.asarray(held.scalars, dtype=float)
        kept.update({f"held_field_{i}": slab for i, slab in enumerate(held.fields)})
    where = slab_name(state_path(path), comm.rank, comm.size)
    writer = np.array([comm.rank, comm.size])  # a swapped slab is known by it

    def save() -> None:
        with storage(where), replaced(where) as tmp, open(tmp, "wb") as f:
            np.savez(f, **kept, state=state, after_step=step - 1, slab=writer)

    on_every(comm, save)


def saved_state(path: str, steps: int, grid: Grid) -> tuple[RowSource | None, Held | None, str]:
    """The state after step ``steps`` and what the sweep held beside it (``None`` in a state
    file of an earlier version), as row sources whose rows are read when a rank of ``grid``
    asks for them, or ``None`` and why not.  Of the sets of slabs left by runs on different
    rank counts (a run killed before it removed the older set), the newest sound one; every
    rank of ``grid`` goes through the sets rank 0 found and reaches the same verdict on each
    (collective)."""
    where = state_path(path)
    if not steps:
        return None, None, ""
    comm = grid.comm
    sets = comm.bcast(_state_sets(where) if comm.rank == 0 else None, root=0)
    problem = f"{where} is missing"
    for i, files in enumerate(sets):
        try:
            after, slabs_of = _read_slabs(files, grid)
        except _Damaged as exc:
            problem = str(exc) if i == 0 else problem
            continue
        if after + 1 == steps:
            rows = grid.shape[0]
            state = SlabRows(slabs_of.pop("state"), rows)
            held = None
            if "held" in slabs_of:
                scalars = slabs_of.pop("held")[0][1]
                fields: tuple[Any, ...] = tuple(
                    SlabRows(slabs_of[f"held_field_{k}"], rows) for k in range(len(slabs_of))
                )  # row sources: each rank reads its rows of each (grid.scatter)
                held = Held(np.asarray(scalars), fields)
            return state, held, ""
        problem = f"{files[0]} is of step {after + 1}, not {steps}" if i == 0 else problem
    return None, None, problem


class _Damaged(Exception):
    """A state slab that cannot be used: missing, truncated, foreign or failing its CRC."""


def _state_sets(where: str) -> list[list[str]]:
    """The files of every set of state slabs beside ``where`` (``OUT.h5.state.npz``), one
    list per rank count, in rank order, the newest set first."""
    folder, name = os.path.split(where)
    times: dict[int, int] = {}  # each rank count's newest slab
    for entry in os.listdir(folder or "."):
        found = slab_of(name, entry)
        if found is not None:
            time = os.stat(os.path.join(folder, entry)).st_mtime_ns
            times[found[1]] = max(times.get(found[1], 0), time)
    newest = sorted(times, key=lambda size: -times[size])
    return [[os.path.join(folder, slab_name(name, r, p)) for r in range(p)] for p in newest]


def _read_slabs(
    files: list[str], grid: Grid
) -> tuple[int, dict[str, list[tuple[int, np.ndarray]]]]:
    """The step a set of state slabs ends and, of the slabs that hold this rank's rows of
    ``grid``, each array as ``(first row, array)``, memory-mapped (``held``'s whole, it is
    small).  A rank opens only those slabs (a rank without rows, the first), checks each
    member's CRC, streamed, and the ranks agree (collective): every rank raises the same
    :class:`_Damaged`, naming the first slab of the set that any rank could not use."""
    total, mine = grid.shape[0], grid.rows
    spans = [block_rows(total, len(files), k) for k in range(len(files))]  # their rows
    needed = [k for k, r in enumerate(spans) if r.start < mine.stop and r.stop > mine.start]
    problem: tuple[int, str] | None = None
    afters: set[int] = set()
    arrays: dict[str, list[tuple[int, np.ndarray]]] = {}
    for k in needed or [0]:
        try:
            after, members = _read_slab(files[k], spans[k].stop - spans[k].start, (k, len(files)))
        except _Damaged as exc:
            problem = (k, str(exc))
            break
        afters.add(after)
        for member, array in members.items():
            arrays.setdefault(member, []).append((spans[k].start, array))
    said = grid.comm.gather((problem, afters), root=0)
    verdict = None if said is None else _verdict(files, said)  # on rank 0
    verdict = grid.comm.bcast(verdict, root=0)
    if isinstance(verdict, str):
        raise _Damaged(verdict)
    return verdict, arrays


def _verdict(files: list[str], said: list[tuple[tuple[int, str] | None, set[int]]]) -> int | str:
    """The step the set of state slabs ``files`` ends, or what is wrong with it: its first
    slab that a rank found wrong (``said``, each rank's first problem and the steps its slabs
    end), or its slabs ending different steps."""
    problems = sorted(problem for problem, _ in said if problem is not None)
    if problems:
        return problems[0][1]
    afters = set().union(*(after for _, after in said))
    if len(afters) != 1:
        return f"{files[0]} and its other slabs end different steps"
    return afters.pop()


def _read_slab(where: str, rows: int, slab: tuple[int, int]) -> tuple[int, dict[str, np.ndarray]]:
    """The step the state slab ``where`` ends and its arrays, memory-mapped (``held``'s
    whole); every member's CRC checked, streamed.  :class:`_Damaged` when it is missing or
    cannot be used, its state has not ``rows`` rows, or it was written by another rank than
    ``slab`` (``(rank, size)``: the slabs swapped or renamed; a slab of an earlier version
    records none)."""
    if not os.path.exists(where):
        raise _Damaged(f"{where} is missing")
    try:
        with zipfile.ZipFile(where) as archive:
            bad = archive.testzip()
        if bad is not None:
            raise ValueError(f"{bad} fails its CRC")
        with np.load(where) as saved:
            after = int(saved["after_step"])
            writer = tuple(int(v) for v in saved["slab"]) if "slab" in saved.files else slab
            names = [m for m in saved.files if m not in ("after_step", "slab")]
            members = {"held": saved["held"]} if "held" in names else {}
        if writer != slab:
            raise ValueError(
                f"it holds the rows of rank {writer[0]} of {writer[1]}, not of rank {slab[0]} "
                "(swapped or renamed)"
            )
        members.update({m: mapped(where, m) for m in names if m != "held"})
        if len(members["state"]) != rows:
            raise ValueError(f"its state has {len(members['state'])} rows, not {rows}")
    except Exception as exc:  # a truncated or foreign file: any reader failure
        raise _Damaged(f"{where} is damaged ({_reason(exc)})") from None
    return after, members


def remove_states(path: str, keep: int) -> None:
    """Remove the state slabs of output ``path`` but those written on ``keep`` ranks."""
    folder, name = os.path.split(os.path.abspath(state_path(path)))
    for entry in os.listdir(folder):
        found = slab_of(name, entry)
        if found is not None and found[1] != keep:
            with suppress(FileNotFoundError):
                os.remove(os.path.join(folder, entry))
