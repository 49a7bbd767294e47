"""Analytic contact solutions the package is tested against (pure numpy).

- :mod:`~petsc_contact.reference.westergaard`: a periodic sinusoidal wave;
- :mod:`~petsc_contact.reference.johnson_wavy`: the same wave with adhesion, in the JKR limit;
- :mod:`~petsc_contact.reference.hertz`: a sphere on a half-space;
- :mod:`~petsc_contact.reference.flat_punch`: flat circular and square punches.
"""

from . import flat_punch, hertz, johnson_wavy, westergaard

__all__ = ["flat_punch", "hertz", "johnson_wavy", "westergaard"]
