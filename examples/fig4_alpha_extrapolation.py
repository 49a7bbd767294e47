"""Paper Fig. 3: alpha against (lambda_1/lambda_r)^(1/(1+H)) with L = lambda_r, and a K(p) inset.

The paper's run: ``--grid 8192 --hurst 0.3 --ratios 512 768 2048 4096`` (the exponent
1/(1+H) is the paper's 0.77 at H = 0.3); the defaults are a quick look at 512^2.
"""

import argparse

import numpy as np

from petsc_contact.io.store import is_partial
from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import (
    FIG3_RATIOS,
    add_pressures_option,
    add_redraw_options,
    log_pressures,
    piece_files,
)


def _computed(args: argparse.Namespace) -> tuple[list[float], np.ndarray, dict]:
    """Run the sweeps here (``--grid``, ``--ratios``, ``--seeds``)."""
    ratios = args.ratios or [args.grid / 32, args.grid / 16, args.grid / 8, args.grid / 4]
    p = log_pressures(args)
    results = {
        f"ratio{r:g}": figures.ensemble_curves(
            args.grid,
            args.hurst,
            1.0,
            r,
            range(args.seeds),
            p,
            points=args.fit_points,
            min_contact_pixels=args.min_contact_pixels,
        )
        for r in ratios
    }
    return ratios, p, results


def _from_data(args: argparse.Namespace) -> tuple[list[float], np.ndarray, dict]:
    """Read the study's complete pieces of every ratio present (no solve), with
    ``--with-partial`` also those still computing."""
    import h5py

    ratios, results = [], {}
    for r in FIG3_RATIOS:
        paths = piece_files(args.data, "fig3", partial=args.with_partial, cutoff_ratio=f"{r:g}")
        if not paths:
            print(f"# lambda_r/lambda_1 = {r}: no complete piece in {args.data} yet")
            continue
        with h5py.File(paths[0], "r", locking=False) as f:
            n, hurst = int(f.attrs["grid"]), float(f.attrs["hurst"])
        if hurst != args.hurst:
            raise SystemExit(f"the study's Fig. 3 pieces have H = {hurst}, not {args.hurst}")
        curves = figures.curves_from_files(paths)
        if any(map(is_partial, paths)):
            loads = curves["stiffness"].shape[1]
            print(f"# lambda_r/lambda_1 = {r}: unfinished pieces read, {loads} loads")
        p_c = figures.crossover(curves["h_rms"], hurst, 1.0)
        try:
            fit = figures.finite_size_fit(
                curves, n * n, p_c, args.fit_points, args.min_contact_pixels
            )
        except ValueError as exc:
            print(f"# lambda_r/lambda_1 = {r}: not fitted ({exc})")
            continue
        results[f"ratio{r:g}"] = curves | fit | {"grid": n}
        ratios.append(float(r))
        alone = " (one seed: the error is the fit's alone)" if len(paths) == 1 else ""
        print(f"# lambda_r/lambda_1 = {r}: {len(paths)} seeds on {n}^2{alone}")
    if not ratios:
        raise SystemExit(f"no complete Fig. 3 piece in {args.data}")
    return ratios, results[f"ratio{ratios[0]:g}"]["nominal_pressure"][0], results


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=512, help="pixels per side (default 512)")
    ap.add_argument("--hurst", type=float, default=0.3, help="Hurst exponent H (default 0.3)")
    ap.add_argument(
        "--ratios",
        type=float,
        nargs="+",
        default=None,
        help="lambda_r/lambda_1 values (default grid/32 ... grid/4; L = lambda_r)",
    )
    ap.add_argument("--seeds", type=int, default=4, help="surfaces per ratio (default 4)")
    add_pressures_option(ap, 1e-8, 1e-3, 16)
    add_redraw_options(ap, 3, "fig4")
    return ap.parse_args(argv)


def extrapolation(hurst: float, ratios: list[float], results: dict) -> dict:
    """``alpha`` against ``x = (lambda_1/lambda_r)^(1/(1+H))``, weighted by its errors, and
    the straight line through them to ``x = 0`` (``alpha_0`` with an error from three
    ratios on).  A ratio with one seed so far has no seed spread in its error: it is drawn
    but left out of the line (``used``).

    The fit's error assumes the points scatter about the line as their errors say; where
    they scatter more (``chi^2`` above its degrees of freedom) the error is scaled by
    ``sqrt(chi^2/dof)`` (Birge's ratio; the Particle Data Group's rule), which
    ``extrapolated_alpha_scaled_error`` gives."""
    alpha = np.array([results[f"ratio{r:g}"]["alpha"] for r in ratios])
    error = np.array([results[f"ratio{r:g}"]["alpha_error"] for r in ratios])
    used = np.array([len(results[f"ratio{r:g}"]["stiffness"]) > 1 for r in ratios])
    exponent = 1 / (1 + hurst)  # the paper's 0.77 at H = 0.3
    x = (1.0 / np.array(ratios)) ** exponent
    w = 1.0 / np.maximum(error[used], 1e-3) ** 2
    coef, cov = (
        np.polyfit(x[used], alpha[used], 1, w=np.sqrt(w), cov="unscaled")
        if used.sum() > 2
        else (np.polyfit(x[used], alpha[used], 1), np.full((2, 2), np.nan))
    )
    residual = alpha[used] - np.polyval(coef, x[used])
    chi2, dof = float(np.sum(w * residual**2)), int(used.sum()) - 2
    birge = max(1.0, np.sqrt(chi2 / dof)) if dof > 0 else np.nan
    return {
        "used": used,
        "x": x,
        "alpha": alpha,
        "alpha_error": error,
        "exponent": exponent,
        "coefficients": coef,
        "extrapolated_alpha": coef[1],
        "extrapolated_alpha_error": float(np.sqrt(cov[1, 1])),
        "extrapolated_alpha_scaled_error": float(birge * np.sqrt(cov[1, 1])),
        "chi2": chi2,
        "dof": dof,
    }


def _draw(args: argparse.Namespace, ratios: list[float], results: dict, fit: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, exponent = fit["x"], fit["exponent"]
    a0, a0_err = fit["extrapolated_alpha"], fit["extrapolated_alpha_scaled_error"]
    fig, ax = plt.subplots(figsize=(6.4, 5.0), constrained_layout=True)
    used = fit["used"]
    ax.errorbar(x[used], fit["alpha"][used], fit["alpha_error"][used], fmt="o", label="simulations")
    if not used.all():
        ax.errorbar(
            x[~used],
            fit["alpha"][~used],
            fit["alpha_error"][~used],
            fmt="o",
            mfc="none",
            color="C0",
            label="one seed so far (not fitted)",
        )
    xs = np.linspace(0, x.max() * 1.05, 50)
    ax.plot(
        xs,
        np.polyval(fit["coefficients"], xs),
        "--",
        label=f"linear fit: {a0:.3f} $\\pm$ {a0_err:.3f}"
        + (f" ($\\chi^2$ = {fit['chi2']:.1f}, {fit['dof']} dof)" if fit["dof"] > 0 else ""),
    )
    ax.plot([0], [exponent], "ks", label="theory 1/(1+H)")
    ax.set(
        xlabel=rf"$(\lambda_1/\lambda_r)^{{{exponent:.2f}}}$",
        ylabel=r"$\alpha$",
        title=("paper Fig. 3: " if args.data else "quick look: ")
        + f"H = {args.hurst}, "
        + (r"$n = 2\lambda_r/\lambda_1$" if args.data else f"{args.grid}$^2$")
        + r", $L = \lambda_r$",
    )
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    low = min(np.nanmin(fit["alpha"] - fit["alpha_error"]), exponent) - 0.05
    high = max(np.nanmax(fit["alpha"] + fit["alpha_error"]), exponent)
    ax.set_ylim(low, high + 0.7 * (high - low))  # the top third is the inset's, above the data
    inset = ax.inset_axes([0.45, 0.64, 0.52, 0.33])
    for r in ratios:
        res = results[f"ratio{r:g}"]
        p = res["nominal_pressure"][0]  # each ratio its own loads (fewer while one computes)
        k = np.nanmean(res["stiffness"] * res["h_rms"][:, None], axis=0)
        ok, fitted = res["resolved"], res["fitted"]
        line = inset.loglog(p[ok], k[ok], "-", lw=0.8, label=f"{r:g}")
        inset.loglog(p[~ok], k[~ok], "x", ms=3, color=line[0].get_color())
        inset.loglog(p[fitted], k[fitted], "o", ms=2.5, color=line[0].get_color())
    inset.set_xlabel("$p/E^*$", fontsize=8)
    inset.set_ylabel(r"$K h_\mathrm{rms}/E^*$", fontsize=8)
    inset.tick_params(labelsize=7.5)
    inset.legend(fontsize=6.5, title=r"$\lambda_r/\lambda_1$", title_fontsize=6.5)
    fig.savefig(f"{args.output}.png", dpi=120)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    ratios, p, results = (_from_data if args.data else _computed)(args)
    fit = extrapolation(args.hurst, ratios, results)
    figures.save(
        f"{args.output}.h5",
        {
            "nominal_pressure": p,
            "ratio": np.array(ratios),
            **{k: fit[k] for k in ("x", "alpha", "alpha_error", "used")},
            **results,
        },
        hurst=args.hurst,
        **({"study_data": args.data} if args.data else {"grid": args.grid}),
        extrapolated_alpha=fit["extrapolated_alpha"],
        extrapolated_alpha_error=fit["extrapolated_alpha_error"],
        extrapolated_alpha_scaled_error=fit["extrapolated_alpha_scaled_error"],
        chi2=fit["chi2"],
        theory_alpha=fit["exponent"],
    )
    _draw(args, ratios, results, fit)
    for r, a, e in zip(ratios, fit["alpha"], fit["alpha_error"], strict=True):
        res = results[f"ratio{r:g}"]
        print(
            f"lambda_r/lambda_1 = {r:g}: alpha = {a:.3f} +- {e:.3f} "
            f"({res['below_crossover']} of {args.fit_points} fitted loads below p_c = "
            f"{res['crossover']:.2g})"
        )
    if fit["used"].sum() > 2:
        error, scaled = fit["extrapolated_alpha_error"], fit["extrapolated_alpha_scaled_error"]
        chi2 = f"chi2 = {fit['chi2']:.1f} on {fit['dof']} degrees of freedom"
        how = (
            f"the fit's error {error:.3f} scaled by sqrt(chi2/dof): {chi2}"
            if scaled > error
            else f"{chi2}: the fit's error stands"
        )
        print(
            f"extrapolated alpha = {fit['extrapolated_alpha']:.3f} +- {scaled:.3f} ({how}); "
            f"1/(1+H) = {fit['exponent']:.3f}"
        )
    else:
        print("the extrapolation needs three ratios or more (drawn, but without an error)")
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
