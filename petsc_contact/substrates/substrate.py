"""What a geometry asks of a substrate: its Green's function, on a periodic cell or on a free
surface (docs/formulation.md)."""

from __future__ import annotations

from typing import Any, Protocol, TypeVar


class PeriodicSubstrate(Protocol):
    """An elastic body under a periodic cell: its surface stiffness as a Fourier multiplier.

    Attributes
    ----------
    modulus
        The contact modulus ``E*`` (pressures are in its unit).
    name
        What the run's record calls it.
    """

    @property
    def modulus(self) -> float: ...

    @property
    def name(self) -> str: ...

    def stiffness(self, q: Any) -> Any:
        """The surface stiffness (pressure per displacement) at wavevector magnitudes ``q``
        (an array of any array module; made where it is)."""
        ...

    def mean_mode_compliance(self, q0: float, interfacial_stiffness: float) -> float:
        """The compliance a preconditioner gives the mean mode ``q = 0`` when the contact
        holds the surface with ``interfacial_stiffness`` (per area)."""
        ...


class FreeSubstrate(Protocol):
    """An elastic body with a free surface around the contact: its surface compliance as the
    pixel influence function on a zero-padded grid (Hockney 1970).

    Attributes
    ----------
    modulus, name
        As :class:`PeriodicSubstrate`'s.
    """

    @property
    def modulus(self) -> float: ...

    @property
    def name(self) -> str: ...

    def compliance_kernel(
        self, shape: tuple[int, int], spacing: tuple[float, float], rows: slice
    ) -> Any:
        """The rows ``rows`` of the displacement of the ``2nx x 2ny`` padded grid under a
        unit pressure on one pixel of sides ``spacing``."""
        ...


Given = TypeVar("Given", PeriodicSubstrate, FreeSubstrate)


def of_modulus(substrate: Given, modulus: float) -> Given:
    """``substrate``, after ``ValueError`` in one line unless its modulus is ``modulus`` (the
    geometry's, in whose unit its pressures are)."""
    if substrate.modulus != modulus:
        raise ValueError(f"the substrate's modulus is {substrate.modulus}, not {modulus}")
    return substrate
