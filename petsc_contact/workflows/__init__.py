"""The runs on the core: a run described and prepared, load sweeps of both geometries, the
one runner, solver comparison, ensembles over seeds and the squeeze test."""
