"""The paper's Fig. 2: finite-size K(p) for H = 0.3, 0.5, 0.7 (L = lambda_r), alpha fitted,
with the theory's K(p) (paper Eq. 12) and its ratio to the simulation."""

import argparse

import numpy as np

from petsc_contact.io.store import is_partial
from petsc_contact.paper import figures
from petsc_contact.paper.fits import ensemble_statistics
from petsc_contact.paper.paper_study import (
    add_pressures_option,
    add_redraw_options,
    log_pressures,
    piece_files,
)
from petsc_contact.physics import theory

PAPER_ALPHA = {0.3: 0.72, 0.5: 0.66, 0.7: 0.59}


def _computed(args: argparse.Namespace) -> tuple[np.ndarray, dict]:
    """Run the sweeps here (``--grid``, ``--cutoff-ratio``, ``--hursts``, ``--seeds``)."""
    cutoff = args.cutoff_ratio = args.cutoff_ratio or args.grid / 4
    p = log_pressures(args)
    results = {
        f"H{h}": figures.ensemble_curves(
            args.grid,
            h,
            1.0,
            cutoff,
            range(args.seeds),
            p,
            points=args.fit_points,
            min_contact_pixels=args.min_contact_pixels,
        )
        for h in args.hursts
    }
    return p, results


def _from_data(args: argparse.Namespace) -> tuple[np.ndarray, dict]:
    """Read the study's complete pieces of every H present (no solve), with
    ``--with-partial`` also those still computing."""
    import h5py

    results = {}
    for h in list(args.hursts):
        paths = piece_files(args.data, "fig2", partial=args.with_partial, hurst=f"{h}")
        if not paths:
            print(f"# H = {h}: no complete piece in {args.data} yet")
            args.hursts.remove(h)
            continue
        with h5py.File(paths[0], "r", locking=False) as f:
            n, args.cutoff_ratio = int(f.attrs["grid"]), float(f.attrs["cutoff_ratio"])
        curves = figures.curves_from_files(paths)
        p_c = figures.crossover(curves["h_rms"], h, 1.0)
        fit = figures.finite_size_fit(curves, n * n, p_c, args.fit_points, args.min_contact_pixels)
        if any(map(is_partial, paths)):
            loads, below = curves["stiffness"].shape[1], fit["below_crossover"]
            print(f"# H = {h}: unfinished pieces read, {loads} loads; {below} fitted below p_c")
        results[f"H{h}"], args.grid = curves | fit, n
    if not results:
        raise SystemExit(f"no complete Fig. 2 piece in {args.data}")
    return next(iter(results.values()))["nominal_pressure"][0], results


def eq12_ratios(r: dict, hurst: float) -> tuple[float, np.ndarray, np.ndarray]:
    """The simulated ``K`` over paper Eq. 12's at the fitted loads (geometric mean): of the
    seed-averaged ``K`` against Eq. 12 with the seeds' mean ``h_rms``, of each seed's ``K``
    against Eq. 12 with its own ``h_rms``, and the first's 68% interval over the seeds
    resampled with replacement (``figures.seed_bootstrap``)."""
    p = r["nominal_pressure"][0][r["fitted"]]

    def ratio(k: np.ndarray, h_rms: np.ndarray) -> np.ndarray:  # per row of k, its own h_rms
        eq12 = theory.finite_size_stiffness(p, 1.0, h_rms[..., None], hurst, 1.0, 1.0)
        return np.exp(np.mean(np.log(k[..., r["fitted"]] / eq12), axis=-1))

    def resampled(rows: np.ndarray) -> np.ndarray:  # every resample (a row of seeds) at once
        k = np.nanmean(r["stiffness"][rows.T], axis=0)
        return ratio(k, r["h_rms"][rows].mean(axis=1))

    seeds = ratio(r["stiffness"], r["h_rms"])
    interval = figures.seed_bootstrap(len(seeds), resampled, batched=True)
    return float(ratio(r["stiffness_mean"], r["h_rms"].mean())), seeds, interval


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=512, help="pixels per side (default 512)")
    ap.add_argument("--cutoff-ratio", type=float, default=None, help="L/lambda_1 (default grid/4)")
    ap.add_argument(
        "--hursts",
        type=float,
        nargs="+",
        default=[0.3, 0.5, 0.7],
        help="Hurst exponents (default 0.3 0.5 0.7)",
    )
    ap.add_argument("--seeds", type=int, default=4, help="surfaces per H (default 4)")
    add_pressures_option(ap, 1e-8, 1e-3, 16)
    add_redraw_options(ap, 2, "fig3")
    return ap.parse_args(argv)


def _draw(args: argparse.Namespace, results: dict) -> None:
    """The figure, and the fitted alphas against the paper's and 1/(1+H) on stdout."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.8, 4.2), constrained_layout=True)
    print(
        f"{'H':>4} {'alpha (fit)':>16} {'paper (sim.)':>12} {'1/(1+H)':>8}  "
        "K/K_Eq.12 at the fitted loads: seed-averaged (seeds)"
    )
    for h in args.hursts:
        r = results[f"H{h}"]
        p = r["nominal_pressure"][0]  # each H its own loads (fewer while a piece computes)
        h_rms = r["h_rms"].mean()
        k = r["stiffness_mean"] * h_rms
        ok = r["resolved"]  # at least --min-contact-pixels in every seed
        seeds = len(r["stiffness"])
        label = f"H = {h} ({seeds} seed{'s' if seeds > 1 else ''})"
        (line,) = ax.loglog(p[ok], k[ok], "o", mfc="none", label=label)
        spread = ensemble_statistics(r["stiffness"] * r["h_rms"][:, None])["std"]  # NaN: 1 seed
        ax.fill_between(
            p[ok], (k - spread)[ok], (k + spread)[ok], color=line.get_color(), alpha=0.2
        )
        ax.loglog(p[~ok], k[~ok], ".", color=line.get_color(), alpha=0.5)
        low = p[r["fitted"]]
        ax.loglog(
            low,
            r["prefactor"] * low ** r["alpha"] * h_rms,
            "-",
            color=line.get_color(),
            label=rf"$\alpha$ = {r['alpha']:.2f} $\pm$ {r['alpha_error']:.2f}",
        )
        ax.axvline(r["crossover"], color=line.get_color(), ls=":", lw=1)
        below = p[p <= r["crossover"]]  # Eq. 12 up to the crossover
        eq12 = theory.finite_size_stiffness(below, 1.0, h_rms, h, 1.0, 1.0) * h_rms
        ax.loglog(below, eq12, "--", color=line.get_color(), lw=1)
        paper = PAPER_ALPHA.get(h, float("nan"))
        print(
            f"{h:>4} {r['alpha']:>9.3f} +- {r['alpha_error']:.3f} {paper:>12} {1 / (1 + h):>8.3f}"
            f"  {r['eq12_ratio']:.2f} ({', '.join(f'{x:.2f}' for x in r['eq12_ratios'])})"
        )
    ax.plot(
        [], [], ".", color="gray", label=f"< {args.min_contact_pixels} contact pixels (not fitted)"
    )
    ax.fill_between([], [], [], color="gray", alpha=0.2, label="spread over seeds (std)")
    ax.plot([], [], "--", color="gray", label="theory, paper Eq. 12 (mean $h_\\mathrm{rms}$)")
    ax.plot([], [], ":", color="gray", label="$p_c$, Eq. 13 (the paper's recipe)")
    ax.set(
        xlabel="$p_0/E^*$",
        ylabel=r"$K h_\mathrm{rms}/E^*$",
        title=f"paper Fig. 2: L = $\\lambda_r$, {args.grid}$^2$"
        if args.data
        else f"quick look at {args.grid}$^2$ (the paper's Fig. 2: 8192$^2$)",
    )
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1))  # beside: no data hidden
    ax.grid(alpha=0.3, which="both")
    fig.savefig(f"{args.output}.png", dpi=120)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    p, results = (_from_data if args.data else _computed)(args)
    for h in args.hursts:
        r = results[f"H{h}"]
        r["eq12_ratio"], r["eq12_ratios"], r["eq12_ratio_interval"] = eq12_ratios(r, h)
        low, high = r["alpha_interval"]
        k_low, k_high = r["eq12_ratio_interval"]
        print(
            f"H = {h}: alpha = {r['alpha']:.3f} +- {r['alpha_error']:.3f} (68% over the seeds "
            f"resampled: {low:.3f}-{high:.3f}); K/Eq. 12 = {r['eq12_ratio']:.2f} "
            f"({k_low:.2f}-{k_high:.2f}); fitted loads below p_c: {r['below_crossover']}"
        )
    figures.save(
        f"{args.output}.h5",
        {"nominal_pressure": p, **results},
        grid=args.grid,
        cutoff_ratio=args.cutoff_ratio,
        rolloff_ratio=1.0,
        rms_slope=0.1,
        **({"study_data": args.data} if args.data else {"seeds": list(range(args.seeds))}),
        fit_points=args.fit_points,
    )
    _draw(args, results)
    print("theta(H): " + ", ".join(f"{h}: {float(theory.theta(h)):.3f}" for h in args.hursts))
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
