"""The PETSc edge: options scoping, FFT operators as shell ``Mat``/``PC`` contexts, the TAO
driver, the package's own TAO types (constrained CG), the held-set ``KSP`` stiffness solves
and the fused numba passes they run.  The only layer that touches petsc4py objects."""
