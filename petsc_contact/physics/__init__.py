"""The physics in pure numpy: elastic kernels, paper Eq. 5 surfaces, the theories the paper
compares with, what a load step measures, the load path, and preparing a measured map.
Functions take arrays and return arrays or typed results; nothing here touches PETSc."""
