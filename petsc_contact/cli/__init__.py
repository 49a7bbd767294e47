"""``petsc-contact``: the command line, a thin layer over the Python API.

Options with two dashes (``--grid 512``) are the package's; options with one dash
(``-tao_type bncg``, ``-tao_monitor``, ``-options_file f``, ``-log_view``) go to PETSc
unchanged.  Exit status: 0 all steps converged; 1 some step did not converge or is not
accurate (the output flags it); 2 bad input; 130 interrupted (finished steps kept in
``OUT.h5.partial``).
"""

from .main import main

__all__ = ["main"]
