"""``python -m petsc_contact.cli``: the same as ``petsc-contact``."""

import sys

from .main import main

sys.exit(main())
