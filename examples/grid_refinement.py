"""Grid convergence of K(p): the same band-limited surface (paper Eq. 5) solved on grids 1, 2
and 4 times finer (2, 4 and 8 pixels per lambda_1 by default), K at each load against the
finest grid's, by how many contact pixels the coarsest grid resolves there.

The surface of each seed is generated on the coarsest grid and interpolated exactly to the
finer ones (its spectrum padded with zeros, ``figures.refined``): only the discretisation
changes.  Each seed's curves are kept in ``OUTPUT_seedK.npz`` as they finish, so that an
interrupted run goes on where it stopped.
"""

import argparse
import os

import numpy as np

from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import add_pressures_option, log_pressures

BINS = (1, 6, 16, 21, 100, 1000, np.inf)  # contact pixels on the coarsest grid


def _settings(args: argparse.Namespace, seed: int) -> np.ndarray:
    """What a seed's curves depend on, kept with them: grid, pixels per lambda_1, H, seed,
    the grids' factors and the loads."""
    head = [args.grid, args.pixels, args.hurst, seed, len(args.factors), *args.factors]
    return np.array([*head, *log_pressures(args)], dtype=float)


def solve_seed(args: argparse.Namespace, seed: int) -> dict[str, np.ndarray]:
    """One seed's ``K`` and contact area on each grid (cached in ``OUTPUT_seedK.npz``, with
    the settings they were solved for)."""
    path, settings = f"{args.output}_seed{seed}.npz", _settings(args, seed)
    try:
        kept = figures.kept_seed(path, settings, "curves (other grid, loads, H or factors)")
    except ValueError as exc:
        raise SystemExit(str(exc)) from None
    if kept is not None:
        return kept
    h, _ = figures.surface(args.grid, args.hurst, 1.0, args.grid / args.pixels, seed)
    p = log_pressures(args)
    out: dict[str, np.ndarray] = {"nominal_pressure": p, "settings": settings}
    for factor in args.factors:
        curve = figures.stiffness_curve(figures.refined(h, factor), p)
        out[f"stiffness_{factor}"] = curve["stiffness"]
        out[f"area_{factor}"] = curve["area_fraction"]
        print(f"# seed {seed}: {args.grid * factor}^2 solved", flush=True)
    np.savez(f"{path}.tmp.npz", **out)
    os.replace(f"{path}.tmp.npz", path)
    return out


def table(args: argparse.Namespace, runs: list[dict[str, np.ndarray]]) -> list[str]:
    """Per bin of contact pixels on the coarsest grid: the loads, and the median and range of
    ``K`` on each coarser grid over the finest's."""
    finest = max(args.factors)
    pixels = np.concatenate([r[f"area_{min(args.factors)}"] for r in runs]) * args.grid**2
    lines = [
        "| contact pixels (coarsest grid) | loads | "
        + " | ".join(
            f"K at {args.pixels * f} px / {args.pixels * finest} px" for f in args.factors[:-1]
        )
        + " |",
        "| --- | --- | " + " | ".join("---" for _ in args.factors[:-1]) + " |",
    ]
    for low, high in zip(BINS[:-1], BINS[1:], strict=True):
        inside = (pixels >= low) & (pixels < high)
        if not inside.any():
            continue
        cells = []
        for factor in args.factors[:-1]:
            ratio = np.concatenate(
                [r[f"stiffness_{factor}"] / r[f"stiffness_{finest}"] for r in runs]
            )
            ratio = ratio[inside & np.isfinite(ratio)]
            cells.append(f"{np.median(ratio):.3f} ({ratio.min():.2f}-{ratio.max():.2f})")
        span = f"{low:g}-{high - 1:g}" if np.isfinite(high) else f">= {low:g}"
        lines.append(f"| {span} | {int(inside.sum())} | " + " | ".join(cells) + " |")
    return lines


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=256, help="the coarsest grid (default 256)")
    ap.add_argument("--pixels", type=int, default=2, help="lambda_1 in its pixels (default 2)")
    ap.add_argument("--factors", type=int, nargs="+", default=[1, 2, 4],
                    help="the grids, times the coarsest (default 1 2 4)")  # fmt: skip
    ap.add_argument("--hurst", type=float, default=0.7, help="H (default 0.7)")
    ap.add_argument("--seeds", type=int, default=4, help="seeds 1..N (default 4)")
    ap.add_argument("--output", default="refinement", help="prefix of the files written")
    add_pressures_option(ap, 1e-7, 1e-2, 16)
    args = ap.parse_args(argv)
    runs = [solve_seed(args, seed) for seed in range(1, args.seeds + 1)]
    print("\n".join(table(args, runs)))


if __name__ == "__main__":
    main()
