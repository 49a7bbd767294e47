"""The numerical engine under the physics and the PETSc edge, without PETSc, on a device's
arrays (:mod:`petsc_contact.devices`): the numba kernels compiled once at set-up, the coarse
matrix's sums over aggregates, and the dense Schur algebra on small contact sets."""
