"""Input checks shared by every module: one wording for every rejected number."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

if TYPE_CHECKING:
    from .grid import Grid


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


def log_range(name: str, count: float, bounds: tuple[float, float] | None = None) -> None:
    """``ValueError`` unless ``count`` log-spaced values (from ``bounds = (low, high)``, when
    given) exist: a whole ``count >= 2`` and ``0 < low < high``."""
    if not (count >= 2 and count == int(count)):
        raise ValueError(f"{name} needs a whole N >= 2, got {count:g}")
    if bounds is not None and not (0 < bounds[0] < bounds[1] < np.inf):
        raise ValueError(f"{name} needs 0 < PMIN < PMAX, got {bounds[0]:g} and {bounds[1]:g}")


def per_axis(value: Any, name: str) -> tuple[Any, Any]:
    """``(v, v)`` for one value, ``(x, y)`` for a pair: a grid or pixel size given once for a
    square or per axis for a rectangle."""
    if isinstance(value, (tuple, list, np.ndarray)):
        if len(value) != 2:
            raise ValueError(f"{name} needs one value or two (x, y), got {tuple(value)}")
        return value[0], value[1]
    return value, value


def check_finite(grid: Grid, h: np.ndarray, what: str = "heights") -> None:
    """Raise ``ValueError`` if any rank's slab has NaN or inf."""
    bad = grid.sum(np.count_nonzero(~np.isfinite(h)))[0]
    if bad:
        raise ValueError(f"{what} contain {int(bad)} NaN or infinite values")


Function = TypeVar("Function", bound=Callable[..., Any])


def keywords_after_first(*former: str) -> Callable[[Function], Function]:
    """Make a function's parameters after the first keyword-only, while calls that pass them
    by position go on working for one release (until 0.3.0): ``former`` names the parameters
    those positions used to fill, in order, and such a call warns (``DeprecationWarning``)
    with the keywords to write instead."""

    def decorate(function: Function) -> Function:
        @functools.wraps(function)
        def wrapper(first: Any, *args: Any, **kwargs: Any) -> Any:
            if args:
                if len(args) > len(former):
                    raise TypeError(
                        f"{function.__name__}() takes 1 positional argument, then keywords"
                    )
                names = former[: len(args)]
                twice = [n for n in names if n in kwargs]
                if twice:
                    raise TypeError(f"{function.__name__}() got two values for '{twice[0]}'")
                warnings.warn(
                    f"{function.__name__}(): pass {', '.join(f'{n}=' for n in names)} by "
                    "keyword; arguments after the first given by position are deprecated and "
                    "refused from 0.3.0",
                    DeprecationWarning,
                    stacklevel=2,
                )
                kwargs.update(zip(names, args, strict=True))
            return function(first, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate
