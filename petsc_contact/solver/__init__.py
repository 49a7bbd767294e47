"""The package's own solver on arrays of any device (no PETSc, no CuPy import here): the
constrained CG, the held-set linear solve, and the driver of the array path."""
