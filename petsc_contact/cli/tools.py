"""``plot`` and ``experiment``: maps of stored fields and load plots drawn again from a
results file, and a measured squeeze test."""

from __future__ import annotations

import argparse


def run_plot(args: argparse.Namespace) -> int:
    """``petsc-contact plot``: one field of one step as a map or, with ``--sweep`` (a theory
    or ensemble file always), the file's load plot drawn again as ``OUT_redrawn.png``."""
    from ..paper.redraw import draw_map, draws_load_plot, field_map, map_file, redraw

    if draws_load_plot(args.file, args.sweep):
        print(f"# wrote {redraw(args.file, args.output)}")
        return 0
    found = field_map(args.file, args.field, args.step)
    out = args.output or map_file(args.file, args.field, found.step)
    draw_map(found, out, args.file, args.scale, args.vmin, args.vmax)
    print(f"# wrote {out}")
    return 0


def run_experiment(args: argparse.Namespace) -> int:
    """``petsc-contact experiment``: Eq. C3 on a measured ``p(s)`` table."""
    from ..workflows.experiment import squeeze_test

    found = squeeze_test(args.table, args.modulus, args.thickness, args.output, args.plot)
    if not args.quiet:
        print(f"{'p':>12} {'s':>12} {'K*':>12} {'K':>12}")
        rows = (found.pressure, found.displacement, found.measured_stiffness, found.stiffness)
        for row in zip(*rows, strict=True):
            print(" ".join(f"{v:>12.5g}" for v in row))
        print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return 0
