"""Deprecated alias of :mod:`petsc_contact.numerics.kernels` (moved in 0.2.0; removed in 0.3.0)."""

import warnings

from ..numerics.kernels import *  # noqa: F403

warnings.warn(
    "petsc_contact.backend.kernels is deprecated: import "
    "petsc_contact.numerics.kernels (removed in 0.3.0)",
    DeprecationWarning,
    stacklevel=2,
)
