"""Paper Fig. 3: alpha against (lambda_1/lambda_r)^(1/(1+H)) with L = lambda_r, and a K(p) inset.

The paper's run: ``--grid 8192 --hurst 0.3 --ratios 512 768 2048 4096`` (the exponent
1/(1+H) is the paper's 0.77 at H = 0.3); the defaults are a quick look at 512^2.
"""

import argparse

import numpy as np

from petsc_contact import scenes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=512)
    ap.add_argument("--hurst", type=float, default=0.3)
    ap.add_argument(
        "--ratios",
        type=float,
        nargs="+",
        default=None,
        help="lambda_r/lambda_1 values (default grid/32 ... grid/4; L = lambda_r)",
    )
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument(
        "--pressures", type=float, nargs=3, default=[1e-8, 1e-3, 16], metavar=("PMIN", "PMAX", "N")
    )
    ap.add_argument("--fit-points", type=int, default=4)
    ap.add_argument("--output", default="fig4")
    args = ap.parse_args()
    ratios = args.ratios or [args.grid / 32, args.grid / 16, args.grid / 8, args.grid / 4]
    p = np.geomspace(args.pressures[0], args.pressures[1], int(args.pressures[2]))
    results, alpha, error = {}, [], []
    for r in ratios:
        res = scenes.ensemble_curves(
            args.grid, args.hurst, 1.0, r, range(args.seeds), p, points=args.fit_points
        )
        results[f"ratio{r:g}"] = res
        alpha.append(res["alpha"])
        error.append(res["alpha_error"])
    exponent = 1 / (1 + args.hurst)  # the paper's 0.77 at H = 0.3
    x = (1.0 / np.array(ratios)) ** exponent
    alpha, error = np.array(alpha), np.array(error)
    w = 1.0 / np.maximum(error, 1e-3) ** 2
    coef, cov = (
        np.polyfit(x, alpha, 1, w=np.sqrt(w), cov="unscaled")
        if len(x) > 2
        else (np.polyfit(x, alpha, 1), np.full((2, 2), np.nan))
    )
    a0, a0_err = coef[1], float(np.sqrt(cov[1, 1]))
    scenes.save(
        f"{args.output}.h5",
        {
            "nominal_pressure": p,
            "ratio": np.array(ratios),
            "x": x,
            "alpha": alpha,
            "alpha_error": error,
            **results,
        },
        hurst=args.hurst,
        grid=args.grid,
        extrapolated_alpha=a0,
        extrapolated_alpha_error=a0_err,
        theory_alpha=1 / (1 + args.hurst),
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2), constrained_layout=True)
    ax.errorbar(x, alpha, error, fmt="o", label="simulations")
    xs = np.linspace(0, x.max() * 1.05, 50)
    ax.plot(xs, np.polyval(coef, xs), "--", label=f"linear fit: {a0:.3f} $\\pm$ {a0_err:.3f}")
    ax.plot([0], [exponent], "ks", label="theory 1/(1+H)")
    ax.set(
        xlabel=rf"$(\lambda_1/\lambda_r)^{{{exponent:.2f}}}$",
        ylabel=r"$\alpha$",
        title=f"H = {args.hurst}, {args.grid}$^2$, $L = \\lambda_r$",
    )
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    inset = ax.inset_axes([0.6, 0.58, 0.37, 0.37])
    for r in ratios:
        res = results[f"ratio{r:g}"]
        k = np.nanmean(res["stiffness"] * res["h_rms"][:, None], axis=0)
        fitted = res["fitted"]
        line = inset.loglog(p[fitted], k[fitted], "o-", ms=2, lw=0.8, label=f"{r:g}")
        inset.loglog(p[~fitted], k[~fitted], "x", ms=3, color=line[0].get_color())
    inset.set_xlabel("$p/E^*$", fontsize=7)
    inset.set_ylabel(r"$K h_\mathrm{rms}/E^*$", fontsize=7)
    inset.tick_params(labelsize=6)
    inset.legend(fontsize=5, title=r"$\lambda_r/\lambda_1$", title_fontsize=5)
    fig.savefig(f"{args.output}.png", dpi=120)
    for r, a, e in zip(ratios, alpha, error, strict=True):
        print(f"lambda_r/lambda_1 = {r:g}: alpha = {a:.3f} +- {e:.3f}")
    print(f"extrapolated alpha = {a0:.3f} +- {a0_err:.3f}; 1/(1+H) = {1 / (1 + args.hurst):.3f}")
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
