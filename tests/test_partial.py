"""The ``.partial`` file's one commit protocol and its readers (``io.partial``)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from petsc_contact.io.partial import (
    commit,
    committed_steps,
    discard,
    read_attributes,
    read_committed,
)


def _table(steps: int):
    def write(f):
        f.create_dataset("step", data=np.arange(1, steps + 1))
        f.create_dataset("converged", data=np.ones(steps, dtype=bool))
        f.create_dataset("mean_gap", data=np.linspace(1.0, 0.5, steps))

    return write


def test_a_commit_replaces_the_partial_whole_and_is_read_back(tmp_path):
    """Each commit holds the attributes given and what its writer added, nothing of the
    last; the readers see the record, the table and the steps."""
    out = str(tmp_path / "out.h5")
    record = {"parameters": {"seed": 3}, "heights_sha256": "ab", "complete": False}
    commit(out, record, _table(2))
    commit(out, {**record, "parts": {"heights.h5": "cd"}}, _table(3))
    kept = read_committed(out + ".partial")
    assert kept.parameters == {"seed": 3}
    assert kept.digest == "ab" and kept.parts == {"heights.h5": "cd"}
    assert kept.steps == 3 and list(kept.table["mean_gap"]) == list(np.linspace(1.0, 0.5, 3))
    assert committed_steps(out + ".partial") == 3
    assert not read_attributes(out + ".partial")["complete"]
    assert os.listdir(tmp_path) == ["out.h5.partial"]


def test_a_failed_commit_leaves_the_last_one(tmp_path):
    """A writer that fails mid-commit leaves the last commit and no temporary file."""
    out = str(tmp_path / "out.h5")
    commit(out, {"parameters": {}}, _table(2))

    def broken(f):
        _table(5)(f)
        raise RuntimeError("killed")

    with pytest.raises(RuntimeError):
        commit(out, {"parameters": {}}, broken)
    assert committed_steps(out + ".partial") == 2
    assert os.listdir(tmp_path) == ["out.h5.partial"]


def test_discard_removes_the_partial_if_there_is_one(tmp_path):
    """The ``.partial`` goes, and its absence is no error."""
    out = str(tmp_path / "out.h5")
    discard(out)  # none: nothing to do
    commit(out, {"parameters": {}}, _table(1))
    discard(out)
    assert os.listdir(tmp_path) == []
