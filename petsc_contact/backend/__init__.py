"""The PETSc edge: options scoping, FFT operators as shell ``Mat``/``PC`` contexts, the TAO
driver, the package's own TAO types (constrained CG), the periodic contact's preconditioner
with its exact Schur and two-level forms, and the held-set ``KSP`` stiffness solves.  The
only layer that touches petsc4py objects."""
