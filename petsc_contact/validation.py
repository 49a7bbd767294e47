"""Input checks shared by every module: one wording for every rejected number."""

from __future__ import annotations

import numpy as np


def positive(name: str, value: float) -> float:
    """``value`` as a float; ``ValueError`` unless it is positive and finite."""
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be positive and finite, got {value}")
    return v


def non_negative(name: str, value: float) -> float:
    """``value`` as a float; ``ValueError`` unless it is non-negative and finite."""
    v = float(value)
    if not (np.isfinite(v) and v >= 0):
        raise ValueError(f"{name} must be non-negative and finite, got {value}")
    return v
