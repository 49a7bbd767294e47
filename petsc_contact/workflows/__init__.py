"""What users run on the core: load sweeps of both geometries, solver comparison, ensembles
over seeds, theory for a given map, figure data and the paper's study."""
