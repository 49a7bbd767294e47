"""The Hertz regime: K(p) while one asperity carries the load, for lambda_1 of several pixel
counts and seeds, against Hertz's K ~ p^(1/3) with the highest summit's own curvature."""

import argparse

import numpy as np

from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import (
    add_data_options,
    add_pressures_option,
    log_pressures,
    piece_files,
)
from petsc_contact.physics import theory

HURST = 0.7


def _spectral_derivatives(spectrum: np.ndarray, q: np.ndarray, x: np.ndarray) -> tuple:
    """Height, gradient and Hessian of the band-limited surface whose ``fft2`` is
    ``spectrum`` (wavevectors ``q`` per axis) at the point ``x`` (any, not only a pixel)."""
    qx, qy = q[:, None], q[None, :]
    e = spectrum * np.exp(1j * (qx * x[0] + qy * x[1])) / spectrum.size
    gradient = np.array([np.real(1j * qx * e).sum(), np.real(1j * qy * e).sum()])
    xy = np.real(-qx * qy * e).sum()
    hessian = np.array([[np.real(-qx * qx * e).sum(), xy], [xy, np.real(-qy * qy * e).sum()]])
    return float(np.real(e.sum())), gradient, hessian


def summit_radius(heights: np.ndarray, length: float = 1.0, subpixel: bool = True) -> float:
    """The equivalent radius ``1/sqrt(kappa_1 kappa_2)`` of the highest summit.

    The curvatures are the eigenvalues of ``-grad grad h`` from exact spectral derivatives
    of the band-limited surface (paper Eq. 5), at the summit itself (Newton's steps on the
    gradient from the highest pixel; ``subpixel``) or at the highest pixel, up to half a
    pixel away.  An elliptical Hertz contact of principal radii ``R_1, R_2`` has, to 3% for
    ``R_1/R_2 <= 4.2``, the stiffness of the sphere of radius ``sqrt(R_1 R_2)`` (Johnson,
    Contact Mechanics, 1985, sec. 4.2, with its elliptic integrals).
    """
    n = heights.shape[0]
    q = 2 * np.pi * np.fft.fftfreq(n, d=length / n)
    spectrum = np.fft.fft2(heights)
    x = np.array(np.unravel_index(np.argmax(heights), heights.shape), dtype=float) * length / n
    _, gradient, hessian = _spectral_derivatives(spectrum, q, x)
    for _ in range(20 if subpixel else 0):
        step = np.linalg.solve(hessian, -gradient)
        x += step
        _, gradient, hessian = _spectral_derivatives(spectrum, q, x)
        if np.abs(step).max() < 1e-9 * length:
            break
    k1, k2 = -np.linalg.eigvalsh(hessian)
    if not (k1 > 0 and k2 > 0):
        return float("nan")  # not a summit: no Hertz contact to compare with
    return float(1 / np.sqrt(k1 * k2))


def local_slope(p: np.ndarray, k: np.ndarray) -> np.ndarray:
    """``d ln K/d ln p`` between neighbouring loads, at their geometric mean (NaN where
    either stiffness is missing); Hertz: 1/3, the power-law regime ``1/(1+H)``, linear 1."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.diff(np.log(k), axis=-1) / np.diff(np.log(p))


def single_patch_limit(p: np.ndarray, resolved: np.ndarray, patches: np.ndarray) -> float:
    """The largest resolved load up to which every resolved load is carried by one contact
    patch (NaN: the lowest resolved load already has several)."""
    ok = np.flatnonzero(resolved)
    several = ok[patches[ok] != 1]
    last = ok[ok < several[0]] if several.size else ok
    return float(p[last[-1]]) if last.size else float("nan")


HERTZ_TOLERANCE = 0.1  # K within 10% of Hertz's: the Hertz regime


def hertz_limit(p: np.ndarray, ratio: np.ndarray, resolved: np.ndarray) -> float:
    """The largest load up to which ``K/K_Hertz`` stays within :data:`HERTZ_TOLERANCE` of 1
    from the lowest resolved load on (NaN: not even there)."""
    ok = np.flatnonzero(resolved)
    inside = np.abs(ratio[ok] - 1) <= HERTZ_TOLERANCE
    run = ok[: np.argmin(inside)] if not inside.all() else ok
    return float(p[run[-1]]) if run.size else float("nan")


def _solved(args: argparse.Namespace, pixels: int) -> dict:
    p = log_pressures(args)
    rows, h_rms = [], []
    for seed in range(1, args.seeds + 1):
        h, rms = figures.surface(args.grid, HURST, 1.0, args.grid / pixels, seed)
        rows.append(figures.stiffness_curve(h, p))
        h_rms.append(rms)
    out = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    return out | {"h_rms": np.array(h_rms), "seed": np.arange(1, args.seeds + 1), "grid": args.grid}


def _read(args: argparse.Namespace, pixels: int) -> dict:
    """The study's ``hertz`` pieces of this ``lambda_1`` (its grid, its loads)."""
    import h5py

    n = 512
    paths = piece_files(args.data, "hertz", cutoff_ratio=f"{n / pixels:g}")
    if not paths:
        raise FileNotFoundError(f"no complete Hertz piece with lambda_1 = {pixels} pixels")
    with h5py.File(paths[0]) as f:
        if int(f.attrs["grid"]) != n:
            raise ValueError(f"{paths[0]}: grid {f.attrs['grid']}, the study's is {n}")
    return figures.curves_from_files(paths) | {"grid": n}


def analyse(curves: dict, pixels: int) -> dict:
    """Each seed's summit radius, Hertz ``K``, ratio to it, local slopes and single-patch
    limit; the range of the local slope while one patch carries the load."""
    n = int(curves["grid"])
    p = curves["nominal_pressure"][0]
    radius, pixel_radius, hertz, half_space = [], [], [], []
    limit, slopes_one, hertz_end = [], [], []
    for row, seed in enumerate(curves["seed"]):
        h, _ = figures.surface(n, HURST, 1.0, n / pixels, int(seed))
        radius.append(summit_radius(h))
        pixel_radius.append(summit_radius(h, subpixel=False))
        hertz.append(theory.hertz_stiffness(p, 1.0, radius[-1], 1.0, cell=1.0))
        half_space.append(theory.hertz_stiffness(p, 1.0, pixel_radius[-1], 1.0))
        ok = figures.resolved(curves["area_fraction"][row], n) & np.isfinite(
            curves["stiffness"][row]
        )
        one = ok & (curves["contact_patches"][row] == 1)
        limit.append(single_patch_limit(p, ok, curves["contact_patches"][row]))
        hertz_end.append(hertz_limit(p, curves["stiffness"][row] / hertz[-1], ok))
        both = one[1:] & one[:-1]  # a slope between two single-patch loads
        slopes_one.extend(local_slope(p, curves["stiffness"][row])[both])
    resolved = figures.resolved(curves["area_fraction"], n)
    return curves | {
        "pixels": pixels,
        "radius": np.array(radius),
        "pixel_radius": np.array(pixel_radius),
        "hertz_stiffness": np.array(hertz),
        "half_space_hertz_stiffness": np.array(half_space),
        "resolved": resolved,
        "single_patch": resolved & (curves["contact_patches"] == 1),
        "single_patch_limit": np.array(limit),
        "hertz_limit": np.array(hertz_end),
        "single_patch_slopes": np.array(slopes_one),
    }


def report(d: dict) -> str:
    """One line on a ``lambda_1``: where one patch carries the load, with how many contact
    pixels, the local slope and ``K/K_Hertz`` there."""
    one, n = d["single_patch"], int(d["grid"])
    head = f"lambda_1 = {d['pixels']} px, {n}^2, {len(d['seed'])} seeds"
    slopes, ratio = d["single_patch_slopes"], (d["stiffness"] / d["hertz_stiffness"])[one]
    if not (slopes.size and ratio.size):
        return f"{head}: fewer than two resolved single-patch loads"
    pixels = np.rint(d["area_fraction"][one] * n * n)
    limits = ", ".join(f"{v:.2g}" for v in d["single_patch_limit"])
    ends = ", ".join(f"{v:.2g}" for v in d["hertz_limit"])
    radii = ", ".join(f"{r:.3g}" for r in d["radius"])
    p = d["nominal_pressure"]
    hertzian = d["single_patch"] & (p <= d["hertz_limit"][:, None])
    close = (d["stiffness"] / d["hertz_stiffness"])[hertzian]
    plain = (d["stiffness"] / d["half_space_hertz_stiffness"])[hertzian]
    seeds = "; ".join(
        f"{seed}: {r[o].min():.2f}-{r[o].max():.2f}" if o.any() else f"{seed}: -"
        for seed, r, o in zip(d["seed"], d["stiffness"] / d["hertz_stiffness"], one, strict=True)
    )
    pixel_radii = ", ".join(f"{r:.3g}" for r in d["pixel_radius"])
    return (
        f"{head}: one patch up to p0/E* = {limits} (seeds 1-4), on {pixels.min():.0f}-"
        f"{pixels.max():.0f} contact pixels, local slope there {slopes.min():.2f}-"
        f"{slopes.max():.2f} (Hertz 1/3), K/K_Hertz {ratio.min():.2f}-{ratio.max():.2f}; "
        f"K within {HERTZ_TOLERANCE:.0%} of Hertz up to p0/E* = {ends}, K/K_Hertz "
        f"{np.median(close) if close.size else np.nan:.3f} median there (half-space Hertz of "
        f"the highest pixel's radius: {np.median(plain) if plain.size else np.nan:.3f}); "
        f"K/K_Hertz over each seed's one-patch loads {seeds}; summit radius/L {radii} "
        f"(at the highest pixel: {pixel_radii})"
    )


def refinement(pixels: int, seed: int, loads: np.ndarray, factors=(1, 2, 4)) -> list[str]:
    """``K/K_Hertz`` (periodic cell, the summit's radius) at ``loads`` on the 512^2 surface
    of ``lambda_1 = pixels`` and ``seed`` solved on grids ``factors`` times finer: whether a
    deviation from Hertz is the grid's (it shrinks) or the surface's (it stays)."""
    from petsc_contact import periodic_contact

    h, _ = figures.surface(512, HURST, 1.0, 512 / pixels, seed)
    hertz = theory.hertz_stiffness(loads, 1.0, summit_radius(h), 1.0, cell=1.0)
    lines = []
    for factor in factors:
        fine = figures.refined(h, factor)
        steps = periodic_contact(fine, length=1.0, pressures=loads, stiffness=True)
        k = np.array([step.scalars["stiffness"] for step in steps])
        area = np.array([step.scalars["area_fraction"] for step in steps]) * (512 * factor) ** 2
        patches = [int(step.scalars["contact_patches"]) for step in steps]
        lines.append(
            f"lambda_1 = {pixels * factor} px ({512 * factor}^2), seed {seed}: contact pixels "
            f"{np.rint(area).astype(int).tolist()}, patches {patches}, K/K_Hertz "
            + ", ".join(f"{v:.3f}" for v in k / hertz)
        )
    return lines


def _draw(args: argparse.Namespace, data: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.3), sharex=True, constrained_layout=True)
    for pixels, color in zip(args.pixels, ("C0", "C1", "C2"), strict=False):
        d = data.get(f"lambda{pixels}")
        if d is None:
            continue
        p = d["nominal_pressure"][0]
        for row in range(d["stiffness"].shape[0]):
            k, hr = d["stiffness"][row], d["h_rms"][row]
            ok, one = d["resolved"][row], d["single_patch"][row]
            label = f"$\\lambda_1$ = {pixels} px" if row == 0 else None
            axes[0].loglog(p[ok], k[ok] * hr, "-", color=color, lw=0.8, label=label)
            axes[0].loglog(p[~ok], k[~ok] * hr, ".", color=color, ms=3, alpha=0.5)
            axes[0].loglog(p[one], k[one] * hr, "o", color=color, ms=3)
            axes[0].loglog(p, d["hertz_stiffness"][row] * hr, ":", color=color, lw=0.8)
            ratio = k / d["hertz_stiffness"][row]
            axes[1].semilogx(p[ok], ratio[ok], "-", color=color, lw=0.8, label=label)
            axes[1].semilogx(p[one], ratio[one], "o", color=color, ms=3)
            axes[1].semilogx(p[~ok], ratio[~ok], ".", color=color, ms=3, alpha=0.5)
            slope = local_slope(p, k)
            mid = np.sqrt(p[1:] * p[:-1])
            both = ok[1:] & ok[:-1]
            axes[2].semilogx(mid[both], slope[both], "-", color=color, lw=0.8, label=label)
            single = one[1:] & one[:-1]
            axes[2].semilogx(mid[single], slope[single], "o", color=color, ms=3)
    for ax in axes:
        ax.plot([], [], "o", color="gray", ms=3, label="one contact patch")
        ax.plot([], [], ".", color="gray", ms=3, label="< 16 contact pixels")
        ax.grid(alpha=0.3, which="both")
        ax.set_xlabel("$p_0/E^*$")
    axes[0].plot([], [], ":", color="gray", label="Hertz: summit radius, periodic cell")
    axes[0].set(ylabel=r"$K h_\mathrm{rms}/E^*$", title="(a) stiffness")
    axes[1].axhline(1.0, color="k", lw=0.8)
    axes[1].set(
        ylabel=r"$K / K_\mathrm{Hertz}$", title="(b) against Hertz (summit radius, periodic cell)"
    )
    axes[1].set_ylim(0, 3)
    for value, text in ((1 / 3, "1/3 (Hertz)"), (1 / (1 + HURST), "1/(1+H)"), (1.0, "1")):
        axes[2].axhline(value, color="k", ls="--", lw=0.7)
        axes[2].annotate(
            text, (0.98, value), xycoords=("axes fraction", "data"), va="bottom", ha="right"
        )
    axes[2].set(ylabel=r"$d\,\ln K / d\,\ln p_0$", title="(c) local slope")
    axes[2].set_ylim(0, 1.5)
    axes[0].legend(fontsize=7, loc="upper left")
    axes[1].legend(fontsize=7, loc="upper left")
    n = next(iter(data.values()))["grid"]
    fig.suptitle(f"Hertz regime: H = {HURST}, $L = \\lambda_r$, {n}$^2$, rms slope 0.1")
    fig.savefig(f"{args.output}.png", dpi=120)


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=128, help="pixels per side (default 128)")
    ap.add_argument(
        "--pixels",
        type=int,
        nargs="+",
        default=[16, 32, 64],
        help="lambda_1 in pixels (default 16 32 64)",
    )
    ap.add_argument("--seeds", type=int, default=2, help="seeds 1..N (default 2)")
    ap.add_argument(
        "--refine",
        type=int,
        nargs="+",
        metavar="SEED",
        help="instead of the figure: these seeds' surfaces of each --pixels solved again on "
        "grids 2 and 4 times finer at --refine-loads, K/K_Hertz printed",
    )
    ap.add_argument(
        "--refine-loads",
        type=float,
        nargs="+",
        default=[1e-6, 1.8e-6, 3.2e-6, 5.6e-6],
        metavar="P",
        help="p0/E* of --refine (default 1e-6 1.8e-6 3.2e-6 5.6e-6)",
    )
    add_pressures_option(ap, 1e-9, 1e-2, 29)
    add_data_options(ap, "hertz", "fig6", partial=False)
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    if args.refine:
        for pixels in args.pixels:
            for seed in args.refine:
                print("\n".join(refinement(pixels, seed, np.array(args.refine_loads))))
        return
    data = {}
    for pixels in args.pixels:
        try:
            curves = (_read if args.data else _solved)(args, pixels)
        except FileNotFoundError as missing:
            print(f"# {missing} in {args.data} yet")
            continue
        data[f"lambda{pixels}"] = analyse(curves, pixels)
        print(report(data[f"lambda{pixels}"]))
    if not data:
        raise SystemExit(f"no complete Hertz piece in {args.data}")
    figures.save(f"{args.output}.h5", data, hurst=HURST, study_data=args.data or "")
    _draw(args, data)
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
