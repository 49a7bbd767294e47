"""Conventions every layer shares, each written once: input checks, length units, the grid
(its wavevectors, the ``q = 0`` mode, the row-slab layout over MPI ranks) and the FFT
normalisation with its backends.  Imports nothing else of the package."""
