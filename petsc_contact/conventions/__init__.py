"""Conventions every layer shares, each written once: input checks, length units, the grid
(its wavevectors, the ``q = 0`` mode, the row-slab layout over MPI ranks) and the memory a
run will need.  Imports nothing else of the package (``fft``, a deprecated alias of
:mod:`petsc_contact.devices.fft`, aside)."""
