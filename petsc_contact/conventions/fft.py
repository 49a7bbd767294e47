"""Deprecated alias of :mod:`petsc_contact.numerics.fft` (moved in 0.2.0; removed in 0.3.0)."""

import warnings

from ..numerics.fft import *  # noqa: F403

warnings.warn(
    "petsc_contact.conventions.fft is deprecated: import "
    "petsc_contact.numerics.fft (removed in 0.3.0)",
    DeprecationWarning,
    stacklevel=2,
)
