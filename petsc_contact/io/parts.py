"""The checksums of a run's parts (``OUT.h5.parts/``): what an interrupted run's parts can
still give, checked against the SHA-256 each commit recorded."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .atomic import _reason
from .names import HEIGHTS_PART, parts_path, step_part
from .provenance import file_digest

if TYPE_CHECKING:
    from .store import Finished


@dataclass
class PartsCheck:
    """What the part files of an interrupted run can give (:func:`check_parts`)."""

    steps: int  # the finished steps whose parts are sound: the steps after are computed again
    maps: bool  # heights.h5 is missing or damaged: it is written again
    problem: str = ""  # what is wrong and what is done about it, in words ("" when nothing)


def check_parts(path: str, finished: Finished, maps: bool, fields: bool) -> PartsCheck:
    """Check the parts of an interrupted run on output ``path`` against the checksums their
    commits recorded: ``heights.h5`` where the run stores ``maps``, each finished step's
    where it stores ``fields`` (up to the first that is missing or damaged); nothing when no
    step is finished (the run starts afresh).

    A part of a ``.partial`` of an earlier version, which records no checksums, is accepted
    when every dataset in it can be read."""
    folder, digests, steps = parts_path(path), finished.parts, finished.steps
    if not steps:  # the run starts afresh
        return PartsCheck(0, False)
    said = []
    heights = part_problem(folder, HEIGHTS_PART, digests) if maps else ""
    if heights:
        said.append(f"{heights}: it is written again from the run's heights")
    for k in range(1, finished.steps + 1) if fields else ():
        wrong = part_problem(folder, step_part(k), digests)
        if wrong:
            said.append(f"{wrong}: computing {_steps(k, steps)} again")
            steps = k - 1
            break
    return PartsCheck(steps, bool(heights), "; ".join(said))


def _steps(first: int, last: int) -> str:
    """``step 4`` or ``steps 2 to 4``."""
    return f"step {first}" if first == last else f"steps {first} to {last}"


def part_problem(folder: str, name: str, digests: dict[str, str]) -> str:
    """What is wrong with part ``name`` of ``folder`` ("" when nothing): missing, unreadable,
    or its bytes are not those its commit recorded in ``digests`` (damaged, or another
    step's).  Without a recorded checksum every dataset in it must be readable."""
    path = os.path.join(folder, name)
    if not os.path.isfile(path):
        return f"{path} is missing"
    try:
        if name not in digests:
            _read_whole(path)
        elif file_digest(path) != digests[name]:
            return f"{path} does not match the checksum its commit recorded (damaged or replaced)"
    except Exception as exc:  # a truncated or foreign file: any reader failure
        return f"{path} cannot be read ({_reason(exc)})"
    return ""


def _read_whole(path: str) -> None:
    """Read every dataset of an HDF5 file: an error when one cannot be read."""
    import h5py

    with h5py.File(path, "r") as f:
        for name in f:
            np.asarray(f[name])
