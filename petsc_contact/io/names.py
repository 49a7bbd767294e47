"""The names of a run's files beside its output ``OUT.h5`` (:mod:`petsc_contact.io.store`
describes what each holds)."""

from __future__ import annotations

PARTIAL = ".partial"  # a run's file until it ends: OUT.h5.partial, replaced by OUT.h5 at the end
STATE = ".state.npz"
PARTS = ".parts"
LOCK = ".lock"
HEIGHTS_PART = "heights.h5"  # the part with the heights (and a measured map's filled mask)


def partial_path(path: str) -> str:
    """The file a run with output ``path`` commits its finished steps to until it ends."""
    return path + PARTIAL


def is_partial(path: str) -> bool:
    """Whether ``path`` names an unfinished run's file (see :func:`partial_path`)."""
    return path.endswith(PARTIAL)


def state_path(path: str) -> str:
    """Where an unfinished run keeps the state it resumes from: beside ``path``."""
    return path + STATE


def csv_path(path: str) -> str:
    """The step table beside a run's results: ``OUT.csv`` for ``OUT.h5``."""
    return path.removesuffix(".h5") + ".csv"


def parts_path(path: str) -> str:
    """The folder of an unfinished run's bulky arrays (heights, fields)."""
    return path + PARTS


def step_part(step: int) -> str:
    """The name of the part with step ``step``'s fields (counted from 1): ``step-000001.h5``."""
    return f"step-{step:06d}.h5"
