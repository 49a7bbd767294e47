"""Run ``petsc-contact ARGS`` and SIGKILL it at a chosen point of its write path.

    python tests/kill_at.py WHEN:TARGET:N[:HOW] -- ARGS...

``TARGET`` is the file a rename puts in place: ``heights`` and ``step`` (the part files),
``commit`` (the ``.partial`` file, a comparison's too), ``state`` (the resume state),
``table`` (``OUT.csv``), ``final`` (``OUT.h5``).  ``WHEN`` is ``before`` the ``N``-th such rename,
``after`` it, or ``during`` the writing of the file it renames (the process dies with the
temporary file half written).  ``HOW`` is ``KILL`` (the default: ``SIGKILL``), ``TERM``
(``SIGTERM``, which the package handles) or ``FINALIZER`` (``SIGTERM`` sent from inside a
finaliser, where Python drops the exception its handler raises).  ``WHEN`` may also be
``damage``: after the ``N``-th rename, 64 bytes in the middle of the file are inverted, and
the run goes on.  Nothing of the package is changed: the runner wraps
``os.replace`` from outside.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
import weakref
from pathlib import Path

import h5py
import numpy as np

from petsc_contact.cli import main

POINTS = [  # every point of the write path a kill is tried at
    "before:heights:1",
    "during:heights:1",
    "before:step:2",
    "during:step:2",
    "after:step:2",
    "before:commit:3",
    "during:commit:3",
    "after:commit:3",
    "before:state:2",
    "during:state:2",
    "after:state:2",
    "during:table:1",
    "after:table:1",
    "before:final:1",
    "during:final:1",
    "after:final:1",
]
RTOL = 1e-6  # a step resumed from first touch starts elsewhere: within the solver's tolerance
# (1e-8 p0 rms; 1.8e-10 in mean gap and 3.7e-9 of the largest pressure at 64^2: docs/reliability.md)
EXACT = 1e-10  # resumed from the saved state and what the sweep held: the same steps, apart
# from rounding (1e-16) amplified by the operator's condition number (about 1e4 here), x 100
SCALARS = ("mean_gap", "area_fraction", "stiffness", "force", "approach", "nominal_pressure")


def resumed_from_state(f: h5py.File) -> bool:
    """Whether a results file was resumed, each time from its saved state (not first touch)."""
    segments = json.loads(str(f.attrs.get("resumed", "[]")) or "[]")
    return bool(segments) and all(s["from_saved_state"] for s in segments)


def same_result(a: Path, b: Path, fields: bool) -> None:
    """Assert that run ``b`` (cut and resumed) holds every step of run ``a``: equal to
    rounding (:data:`EXACT`, the same iterations) when every resume went on from the saved
    state, else to the solver's tolerance (:data:`RTOL`)."""
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert fb.attrs["complete"] and fb["converged"].shape == fa["converged"].shape
        assert np.all(fb["converged"][:])
        rtol = EXACT if resumed_from_state(fb) else RTOL
        if rtol == EXACT:
            assert np.array_equal(fb["iterations"][:], fa["iterations"][:])
        for name in SCALARS:
            if name in fa:
                same = np.allclose(fb[name][:], fa[name][:], rtol=rtol, atol=0, equal_nan=True)
                assert same, name  # NaN: a stiffness at full contact, NaN in both
        if fields:
            for name in ("gap", "pressure"):
                scale = np.abs(fa[name][...]).max()
                assert np.allclose(fb[name][...], fa[name][...], rtol=0, atol=rtol * scale), name
            assert np.mean(fb["contact"][...] != fa["contact"][...]) < 1e-3
            h = fa["heights"][...]  # generated on other FFT layouts: equal to rounding
            assert np.allclose(fb["heights"][...], h, rtol=0, atol=1e-12 * np.abs(h).max())


RANK = r"(\.\d+of\d+)?"  # on several ranks each writes its own: heights.2of4.h5, .state.2of4.npz


def _target(path: str) -> str:
    path = str(path)
    for name, found in (
        (
            "heights",
            ".parts" in path and bool(re.search(rf"{re.escape(os.sep)}heights{RANK}\.h5", path)),
        ),
        ("step", f"{os.sep}step-" in path and ".parts" in path),
        ("state", bool(re.search(rf"\.state{RANK}\.npz", path))),
        ("commit", path.endswith(".partial")),
        ("table", path.endswith(".csv")),
        ("final", path.endswith(".h5")),
    ):
        if found:
            return name
    return ""


def _signal(how: str) -> None:
    """Send this process ``SIGKILL``, ``SIGTERM``, or ``SIGTERM`` from inside a finaliser."""
    if how != "FINALIZER":
        os.kill(os.getpid(), signal.SIGKILL if how == "KILL" else signal.SIGTERM)
        return

    class Dropped:
        pass

    dropped = Dropped()
    weakref.finalize(dropped, os.kill, os.getpid(), signal.SIGTERM)
    del dropped  # the finaliser runs here; the KeyboardInterrupt it raises is dropped


def _damage(path: str) -> None:
    """Invert 64 bytes in the middle of ``path`` (zeros written there might change nothing)."""
    middle = os.path.getsize(path) // 2
    with open(path, "r+b") as f:
        f.seek(middle)
        inverted = bytes(255 - b for b in f.read(64))
        f.seek(middle)
        f.write(inverted)


def _install(when: str, target: str, nth: int, how: str = "KILL") -> None:
    seen = {"count": 0}
    replace = os.replace

    def counted(path: str) -> bool:
        if _target(path) != target:
            return False
        seen["count"] += 1
        return seen["count"] == nth

    def killing_replace(src: str, dst: str) -> None:
        hit = counted(dst)
        if hit and when == "during":  # the temporary file half written when the process dies
            os.truncate(src, max(os.path.getsize(src) // 2, 1))
        if hit and when in ("before", "during"):
            _signal(how)
        replace(src, dst)
        if hit and when == "after":
            _signal(how)
        if hit and when == "damage":
            _damage(dst)

    os.replace = killing_replace  # type: ignore[assignment]


if __name__ == "__main__":
    spec, separator, *args = sys.argv[1:]
    assert separator == "--", "usage: kill_at.py WHEN:TARGET:N[:HOW] -- ARGS..."
    when, target, nth, *how = spec.split(":")
    _install(when, target, int(nth), *how)
    sys.exit(main(args))
