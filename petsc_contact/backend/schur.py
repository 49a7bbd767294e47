"""Deprecated alias of :mod:`petsc_contact.numerics.schur` (moved in 0.2.0; removed in 0.3.0)."""

import warnings

from ..numerics.schur import *  # noqa: F403

warnings.warn(
    "petsc_contact.backend.schur is deprecated: import "
    "petsc_contact.numerics.schur (removed in 0.3.0)",
    DeprecationWarning,
    stacklevel=2,
)
