"""Interactions: what happens at the surface between the bodies (its bounds and its energy),
one part of a contact model beside its substrate (:mod:`petsc_contact.substrates`)."""
