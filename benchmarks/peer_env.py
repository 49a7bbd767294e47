"""Which Python runs the peers (Tamaas, ContactMechanics) for the comparisons.

The package's own venv when both import there (``.venv/bin/pip install -e '.[peers]'``: they
need numpy 2, as the package does); else a venv of their own at ``benchmarks/peers/.venv``
(``python3 -m venv benchmarks/peers/.venv && benchmarks/peers/.venv/bin/pip install tamaas
contactmechanics``); else none, and the comparisons are skipped.
"""

from __future__ import annotations

import importlib.util
import os
import sys

OWN_VENV = os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "peers", ".venv", "bin", "python"
)


def peer_python() -> str | None:
    """The interpreter that runs the peers' scripts, or ``None`` when neither has them."""
    if all(importlib.util.find_spec(m) is not None for m in ("tamaas", "ContactMechanics")):
        return sys.executable
    return OWN_VENV if os.path.exists(OWN_VENV) else None
