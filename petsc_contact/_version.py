"""The package's version, defined once (the ground floor: it imports nothing)."""

__version__ = "0.2.0"
