"""``plot`` and ``experiment``: maps of stored fields, and a measured squeeze test."""

from __future__ import annotations

import argparse
import os

import numpy as np

from ..conventions.validation import positive
from ..io.schema import EXPERIMENT, annotate
from ..io.store import atomic_h5
from .common import InputError


def run_plot(args: argparse.Namespace) -> int:
    """``petsc-contact plot``: one field of one step as a map."""
    import h5py

    from ..io.plot import plot_field
    from ..io.schema import ENTRIES
    from ..io.store import check_writable

    if not os.path.isfile(args.file):
        raise InputError(f"'{args.file}' does not exist")
    with h5py.File(args.file, "r") as f:
        if args.field not in f:
            hint = " (run with --fields)" if args.field != "heights" else ""
            raise InputError(f"'{args.file}' has no dataset '{args.field}'{hint}")
        data = f[args.field]
        steps = data.shape[0] if data.ndim == 3 else 1
        if not -steps <= args.step < steps:
            raise InputError(f"--step {args.step} is out of range: the file has {steps} steps")
        values = data[args.step] if data.ndim == 3 else data[...]
        side = float(f.attrs.get("length", 1.0))
        lx, ly = (float(v) for v in f.attrs.get("lengths", (side, side)))
        length_unit = str(f.attrs.get("length_unit", ""))
        step = args.step % steps
        load = f["nominal_pressure"][step] if "nominal_pressure" in f else np.nan
        per_step = data.ndim == 3
    stem = args.file[:-3] if args.file.endswith(".h5") else args.file
    out = args.output or f"{stem}_{args.field}_step{step}.png"
    check_writable(out)
    title = f"{args.field}, step {step}" + (f", p0 = {load:.3g}" if per_step else "")
    unit = {
        "length": f"({length_unit})" if length_unit else "in the unit of --length",
        "pressure": "in the unit of --modulus",
    }
    label = f"{args.field} {unit.get(ENTRIES[args.field].units, '(1: in contact)')}"
    plot_field(out, values, (lx, ly), title, label, args.field == "contact", length_unit)
    print(f"# wrote {out}")
    return 0


def run_experiment(args: argparse.Namespace) -> int:
    """``petsc-contact experiment``: Eq. C3 on a measured ``p(s)`` table."""
    from ..io.store import check_writable
    from ..io.tables import load_table
    from ..physics.theory import block_corrected_stiffness

    for name in ("modulus", "thickness"):
        positive(f"--{name}", getattr(args, name))
    if not os.path.isfile(args.table):
        raise InputError(f"table '{args.table}' does not exist")
    table = load_table(args.table, 2)
    check_writable(args.output)
    p, disp = table[:, 0], table[:, 1]
    k_star, k = block_corrected_stiffness(p, disp, args.modulus, args.thickness)

    with atomic_h5(args.output) as f:
        f["pressure"], f["displacement"] = p, disp
        f["measured_stiffness"], f["stiffness"] = k_star, k
        f.attrs.update(
            geometry="experiment",
            block_modulus=args.modulus,
            thickness=args.thickness,
            table=os.path.abspath(args.table),
            formula="K* = dp/ds (2nd-order differences), K = K*/(1 - K* d/E')",
        )
        annotate(f, EXPERIMENT.__getitem__)
    if not args.quiet:
        print(f"{'p':>12} {'s':>12} {'K*':>12} {'K':>12}")
        for row in zip(p, disp, k_star, k, strict=True):
            print(" ".join(f"{v:>12.5g}" for v in row))
    if args.plot:
        from ..io.plot import plot_experiment

        plot_experiment(args.plot, p, k_star, k)
    return 0
