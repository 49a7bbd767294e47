"""Substrates: what the elastic body is, given by its surface Green's function (arrays only).

A contact model is composed of a substrate (here), an interaction at the surface
(:mod:`petsc_contact.interactions`), a solver backend (:mod:`petsc_contact.solver.backends`)
and a device (:mod:`petsc_contact.devices.device`).  The geometries
(:mod:`petsc_contact.geometries`) put them together.
"""
