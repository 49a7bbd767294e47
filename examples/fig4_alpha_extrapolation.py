"""Fig. 4: the exponent alpha against (lambda_1/lambda_r)^0.77, extrapolated to lambda_1 -> 0."""

import argparse

import numpy as np

from petsc_contact import scenes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=512)
    ap.add_argument("--hurst", type=float, default=0.7)
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
    x = (1.0 / np.array(ratios)) ** 0.77
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

    fig, ax = plt.subplots(figsize=(5, 3.8), constrained_layout=True)
    ax.errorbar(x, alpha, error, fmt="o", label="simulations")
    xs = np.linspace(0, x.max() * 1.05, 50)
    ax.plot(xs, np.polyval(coef, xs), "--", label=f"linear fit: {a0:.3f} $\\pm$ {a0_err:.3f}")
    ax.plot([0], [1 / (1 + args.hurst)], "ks", label="theory 1/(1+H)")
    ax.set(
        xlabel=r"$(\lambda_1/\lambda_r)^{0.77}$",
        ylabel=r"$\alpha$",
        title=f"Fig. 4, H = {args.hurst}, {args.grid}$^2$",
    )
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.savefig(f"{args.output}.png", dpi=120)
    for r, a, e in zip(ratios, alpha, error, strict=True):
        print(f"lambda_r/lambda_1 = {r:g}: alpha = {a:.3f} +- {e:.3f}")
    print(f"extrapolated alpha = {a0:.3f} +- {a0_err:.3f}; 1/(1+H) = {1 / (1 + args.hurst):.3f}")
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
