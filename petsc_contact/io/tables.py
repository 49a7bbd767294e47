"""Small numeric tables read from text: a measured squeeze test (``petsc-contact experiment``)."""

from __future__ import annotations

import re

import numpy as np


def load_table(path: str, columns: int) -> np.ndarray:
    """A small numeric table: comma- or whitespace-separated, ``#`` comments, and at most one
    header line (a first row that is not numbers).  Raises ``ValueError`` with the line."""
    rows: list[list[float]] = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            fields = [v for v in re.split(r"[,\s]+", text) if v]
            try:
                rows.append([float(v) for v in fields])
            except ValueError:
                if rows:  # only the first row may be a header
                    raise ValueError(f"'{path}' line {number} is not {columns} numbers") from None
                rows.append([])  # the header
                continue
            if len(fields) != columns:
                raise ValueError(f"'{path}' line {number} has {len(fields)} columns, not {columns}")
    table = np.array([r for r in rows if r], dtype=float).reshape(-1, columns)
    if not table.size or not np.all(np.isfinite(table)):
        raise ValueError(f"'{path}' must hold rows of {columns} finite numbers")
    return table
