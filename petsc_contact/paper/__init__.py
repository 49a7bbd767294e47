"""The paper's theory for a map, its study piece by piece, and its figures: what the paper
computes, on top of the runs of :mod:`petsc_contact.workflows`."""
