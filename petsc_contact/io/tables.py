"""Small tables: numbers read from text (a measured squeeze test, ``petsc-contact
experiment``), and names with their values drawn as HTML (what a notebook shows of a result)."""

from __future__ import annotations

import html
import re
from collections.abc import Mapping
from typing import Any

import numpy as np


def html_table(caption: str, values: Mapping[str, Any]) -> str:
    """``values`` as a two-column HTML table (name, value) under ``caption``: a notebook's
    display of a description or a result (``_repr_html_``)."""
    rows = "".join(
        f"<tr><th style='text-align:left'>{html.escape(str(name))}</th>"
        f"<td style='text-align:left'>{html.escape(_shown(value))}</td></tr>"
        for name, value in values.items()
    )
    return f"<table><caption>{html.escape(caption)}</caption>{rows}</table>"


def _shown(value: Any) -> str:
    """A value as a table shows it: numbers to 6 significant digits, lists item by item."""
    if isinstance(value, (float, np.floating)):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return ", ".join(_shown(v) for v in value)
    return str(value)


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
