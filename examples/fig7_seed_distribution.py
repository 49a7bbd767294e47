"""The distribution over seeds of K h_rms/E* at fixed load and of the crossover p_c, against
the finite-size theory (paper Eqs. 12-13) evaluated with each seed's own h_rms."""

import argparse

import numpy as np

from petsc_contact.paper import figures
from petsc_contact.paper.fits import power_law_fit
from petsc_contact.paper.paper_study import (
    DISTRIBUTION_RATIO,
    add_data_options,
    add_pressures_option,
    log_pressures,
    piece_files,
)
from petsc_contact.physics import theory

HURST = 0.3


def linear_crossover(prefactor: float, exponent: float, u0: float) -> float:
    """Where ``K = prefactor p^exponent`` meets the linear law ``K = p/u0`` (paper Eq. 1), for
    ``E* = 1``: ``p_c = (prefactor u0)^(1/(1 - exponent))``.  Paper Eq. 12's power law met
    with ``u0 = gamma h_rms`` is paper Eq. 13 as printed."""
    return float((prefactor * u0) ** (1 / (1 - exponent)))


def theory_per_seed(h_rms: float, rolloff_ratio: float) -> tuple[float, float]:
    """Paper Eq. 12's ``K`` at ``p = E*`` (``L = E* = 1``: the power law's prefactor) and
    its crossover with ``K = p/(gamma h_rms)`` (Eq. 13), for one surface's own ``h_rms``."""
    prefactor = float(theory.finite_size_stiffness(1.0, 1.0, h_rms, HURST, 1.0, rolloff_ratio))
    return prefactor, linear_crossover(prefactor, 1 / (1 + HURST), theory.GAMMA * h_rms)


LINEAR_AREA = (0.01, 0.1)  # the contact areas where a seed's own u0 = p/K is read


def own_linear_law(p: np.ndarray, k: np.ndarray, area: np.ndarray) -> float:
    """A seed's ``u0``: the median of ``p/K`` at 1-10% contact area (as Fig. 1's crossover),
    NaN without such a load."""
    linear = np.isfinite(k) & (k > 0) & (area > LINEAR_AREA[0]) & (area < LINEAR_AREA[1])
    return float(np.median(p[linear] / k[linear])) if linear.any() else float("nan")


def simulated_crossover(
    p: np.ndarray, k: np.ndarray, area: np.ndarray, fitted: np.ndarray, alpha: float
) -> tuple[float, float]:
    """One seed's ``p_c`` and ``u0``: the ensemble's power law ``K = c p^alpha`` with this
    seed's prefactor ``c`` (the geometric mean of ``K/p^alpha`` over the ``fitted`` loads)
    met with its own linear law ``K = p/u0`` (:func:`own_linear_law`).

    The exponent is the ensemble's: a seed's own four-point fit over a quarter of a decade
    scatters so much (its ``alpha`` reaches 1) that ``(c u0)^(1/(1 - alpha))`` is no
    reading of anything."""
    u0 = own_linear_law(p, k, area)
    c = float(np.exp(np.mean(np.log(k[fitted]) - alpha * np.log(p[fitted]))))
    return linear_crossover(c, alpha, u0), u0


def knee(p: np.ndarray, k: np.ndarray, resolved: np.ndarray, alpha: float) -> float:
    """A seed's ``p_c`` read off its own curve: the load at which the local slope
    ``d ln K/d ln p`` between neighbouring resolved loads reaches ``(alpha + 1)/2``, halfway
    from the power law to the linear law, to stay there for the next pair of loads too (a
    single steep pair among a few contacts is not the crossover); log-interpolated between
    the pairs' midpoints, NaN where it never does.  Unlike :func:`simulated_crossover` it
    extrapolates neither law."""
    ok = np.flatnonzero(resolved & np.isfinite(k) & (k > 0))
    x, y = np.log(p[ok]), np.log(k[ok])
    slope, middle = np.diff(y) / np.diff(x), 0.5 * (x[1:] + x[:-1])
    target = 0.5 * (alpha + 1)
    steep = slope >= target
    lasting = np.flatnonzero(steep[:-1] & steep[1:])
    if not lasting.size:
        return float("nan")
    j = lasting[0]
    if j == 0:
        return float(np.exp(middle[0]))
    t = (target - slope[j - 1]) / (slope[j] - slope[j - 1])
    return float(np.exp(middle[j - 1] + t * (middle[j] - middle[j - 1])))


def log_spread(values: np.ndarray) -> float:
    """The standard deviation of ``ln(values)`` over the finite ones (ddof 1): the relative
    scatter of a positive quantity."""
    v = np.log(values[np.isfinite(values) & (values > 0)])
    return float(v.std(ddof=1)) if v.size > 1 else float("nan")


def analyse(curves: dict, n: int, rolloff_ratio: float, at: list[float], points: int) -> dict:
    """Per seed: ``K h_rms/E*`` at the loads nearest ``at`` (NaN where not resolved), Eq. 12
    there, the simulated and theoretical ``p_c``; per load: the scatter of ``ln(K h_rms/E*)``
    over the seeds that resolve it."""
    p = curves["nominal_pressure"][0]
    h = curves["h_rms"]
    resolved = figures.resolved(curves["area_fraction"], n) & np.isfinite(curves["stiffness"])
    scaled = np.where(resolved, curves["stiffness"] * h[:, None], np.nan)
    index = [int(np.argmin(np.abs(np.log(p / v)))) for v in at]
    prefactors, pc_theory = np.array([theory_per_seed(v, rolloff_ratio) for v in h]).T
    every = np.all(resolved, axis=0)  # the loads every seed resolves
    fitted = np.zeros_like(every)
    fitted[np.flatnonzero(every)[:points]] = True
    mean_k = np.exp(np.mean(np.log(curves["stiffness"][:, fitted]), axis=0))
    alpha = power_law_fit(p[fitted], mean_k, points).alpha
    own = [power_law_fit(p[fitted], k[fitted], points).alpha for k in curves["stiffness"]]
    pc_sim, u0 = np.array(
        [
            simulated_crossover(
                p, curves["stiffness"][s], curves["area_fraction"][s], fitted, alpha
            )
            for s in range(h.size)
        ]
    ).T
    seen = np.count_nonzero(resolved, axis=0) == h.size
    knees = [knee(p, curves["stiffness"][s], resolved[s], alpha) for s in range(h.size)]
    return curves | {
        "pc_knee": np.array(knees),
        "loads": p[index],
        "scaled_stiffness": scaled[:, index],
        "eq12_scaled_stiffness": (prefactors * h)[:, None] * p[index] ** (1 / (1 + HURST)),
        "pc_simulation": pc_sim,
        "alpha": alpha,
        "alphas": np.array(own),
        "fitted": fitted,
        "u0": u0,
        "pc_eq13": pc_theory,
        "spread_simulation": np.array(
            [log_spread(scaled[:, j]) if seen[j] else np.nan for j in range(p.size)]
        ),
        "spread_eq12": log_spread(prefactors * h),
    }


def _solved(args: argparse.Namespace) -> tuple[dict, int]:
    p = log_pressures(args)
    rows, h_rms = [], []
    for seed in range(1, args.seeds + 1):
        h, rms = figures.surface(args.grid, HURST, 1.0, args.grid / 2, seed)
        rows.append(figures.stiffness_curve(h, p))
        h_rms.append(rms)
    curves = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    return curves | {"h_rms": np.array(h_rms), "seed": np.arange(1, args.seeds + 1)}, args.grid


def _read(args: argparse.Namespace) -> tuple[dict, int]:
    paths = piece_files(args.data, "seeds", partial=args.with_partial)
    if len(paths) < 2:
        raise SystemExit(f"fewer than two complete seed pieces in {args.data}")
    return figures.curves_from_files(paths), 2 * DISTRIBUTION_RATIO


def _histogram(ax, values: dict, xlabel: str, title: str) -> None:
    finite = np.concatenate([v[np.isfinite(v)] for v in values.values()])
    bins = np.geomspace(finite.min() / 1.05, finite.max() * 1.05, 25)
    for (label, v), color in zip(values.items(), ("C0", "C3"), strict=True):
        ax.hist(v[np.isfinite(v)], bins=bins, histtype="step", lw=1.5, color=color, label=label)
    ax.set_xscale("log")
    ax.set(xlabel=xlabel, ylabel="seeds", title=title)
    ax.legend(fontsize=7)


def _draw(args: argparse.Namespace, d: dict, n: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 8), constrained_layout=True)
    seeds, p1 = d["h_rms"].size, d["loads"][0]
    _histogram(
        axes[0, 0],
        {
            "simulation": d["scaled_stiffness"][:, 0],
            "Eq. 12, each seed's $h_\\mathrm{rms}$": d["eq12_scaled_stiffness"][:, 0],
        },
        r"$K h_\mathrm{rms}/E^*$",
        f"(a) stiffness at $p_0/E^*$ = {p1:.2g}",
    )
    _histogram(
        axes[0, 1],
        {
            "simulation (power law meets its own $p/u_0$)": d["pc_simulation"],
            "Eq. 13, each seed's $h_\\mathrm{rms}$": d["pc_eq13"],
        },
        "$p_c/E^*$",
        "(b) crossover to the linear regime",
    )
    h = d["h_rms"] / np.median(d["h_rms"])
    ax = axes[1, 0]
    for j, (load, marker) in enumerate(zip(d["loads"], ("o", "s"), strict=False)):
        ax.loglog(
            h,
            d["scaled_stiffness"][:, j],
            marker,
            mfc="none",
            ms=4,
            label=f"simulation, $p_0/E^*$ = {load:.2g}",
        )
        ax.loglog(
            h,
            d["eq12_scaled_stiffness"][:, j],
            marker,
            ms=2,
            color="C3",
            label="Eq. 12" if j == 0 else None,
        )
        ax.axhline(load / theory.GAMMA, color="k", ls="--", lw=0.7)
    ax.plot([], [], "k--", lw=0.7, label=r"$p/(\gamma E^*)$, no scatter")
    ax.set(
        xlabel=r"$h_\mathrm{rms}$ / median",
        ylabel=r"$K h_\mathrm{rms}/E^*$",
        title="(c) each seed against its $h_\\mathrm{rms}$",
    )
    ax.legend(fontsize=7)
    ax = axes[1, 1]
    p = d["nominal_pressure"][0]
    ax.semilogx(p, d["spread_simulation"], "o-", ms=3, label="simulation")
    shown = p[np.isfinite(d["spread_simulation"])]  # the loads every seed resolves
    pc = float(np.nanmedian(d["pc_eq13"]))  # Eq. 12 holds below its crossover, Eq. 13's
    eq12 = "Eq. 12 (the $h_\\mathrm{rms}$ scatter alone), below Eq. 13's $p_c$"
    if pc > shown.min():
        ax.hlines(d["spread_eq12"], shown.min(), min(pc, shown.max()), color="C3", label=eq12)
    else:
        ax.plot([], [], color="C3", label=f"{eq12} = {pc:.1g}\n(left of the axis)")
    ax.hlines(0, max(pc, shown.min()), shown.max(), color="k", ls="--", lw=0.7,
              label=r"$p/(\gamma E^*)$, above it")  # fmt: skip
    ax.axvline(
        np.nanmedian(d["pc_simulation"]), color="C0", ls=":", lw=1, label="median simulated $p_c$"
    )
    ax.set(
        xlabel="$p_0/E^*$",
        ylabel=r"std of $\ln(K h_\mathrm{rms}/E^*)$ over seeds",
        title="(d) scatter against load",
    )
    ax.set_ylim(-0.01, 1.6 * np.nanmax(d["spread_simulation"]))  # the legend above the data
    ax.legend(fontsize=7, loc="upper right")
    for a in axes.flat:
        a.grid(alpha=0.3, which="both")
    fig.suptitle(
        f"{seeds} seeds: H = {HURST}, $L = \\lambda_r$, $\\lambda_r/\\lambda_1$ = {n // 2}, "
        f"{n}$^2$, rms slope 0.1"
    )
    fig.savefig(f"{args.output}.png", dpi=120)


def report(d: dict) -> list[str]:
    """The distributions in numbers: medians and log spreads, simulation against theory."""
    lines = []
    for j, load in enumerate(d["loads"]):
        sim, eq12 = d["scaled_stiffness"][:, j], d["eq12_scaled_stiffness"][:, j]
        lines.append(
            f"p0/E* = {load:.2g}: K h_rms/E* median {np.nanmedian(sim):.3g} "
            f"(range {np.nanmin(sim):.3g}-{np.nanmax(sim):.3g}, std of ln {log_spread(sim):.3f}, "
            f"{np.count_nonzero(np.isfinite(sim))} seeds resolved); Eq. 12 median "
            f"{np.median(eq12):.3g} (std of ln {log_spread(eq12):.3f}); linear law "
            f"{load / theory.GAMMA:.3g}; correlation of ln K h_rms with ln h_rms "
            f"{_correlation(d['h_rms'], sim):.2f}"
        )
    p_fit = d["nominal_pressure"][0][d["fitted"]]
    lines.append(
        f"p_c/E*: simulation median {np.nanmedian(d['pc_simulation']):.3g} (quartiles "
        f"{_quartiles(d['pc_simulation'])}, range "
        f"{np.nanmin(d['pc_simulation']):.3g}-{np.nanmax(d['pc_simulation']):.3g}, std of ln "
        f"{log_spread(d['pc_simulation']):.3f}); Eq. 13 median {np.median(d['pc_eq13']):.3g} "
        f"(std of ln {log_spread(d['pc_eq13']):.3f}); read off each seed's curve where its "
        f"local slope reaches (alpha + 1)/2: median {np.nanmedian(d['pc_knee']):.3g} "
        f"(quartiles {_quartiles(d['pc_knee'])}, range "
        f"{np.nanmin(d['pc_knee']):.3g}-{np.nanmax(d['pc_knee']):.3g}, std of ln "
        f"{log_spread(d['pc_knee']):.3f}, {np.count_nonzero(np.isfinite(d['pc_knee']))} "
        f"seeds); alpha {d['alpha']:.3f} (the seeds' "
        f"geometric-mean K at p0/E* {p_fit.min():.2g}-{p_fit.max():.2g}; each seed's own: "
        f"{np.mean(d['alphas']):.3f} +- {np.std(d['alphas'], ddof=1):.3f}, "
        f"{d['alphas'].min():.2f}-{d['alphas'].max():.2f})"
    )
    lines.append(
        f"h_rms: std of ln {log_spread(d['h_rms']):.3f} over {d['h_rms'].size} seeds; u0/h_rms "
        f"{np.nanmedian(d['u0'] / d['h_rms']):.3f} median (gamma = {theory.GAMMA})"
    )
    return lines


def _quartiles(values: np.ndarray) -> str:
    """The first and third quartiles of the finite ``values``."""
    low, high = np.nanpercentile(values, [25, 75])
    return f"{low:.3g}-{high:.3g}"


def _correlation(h: np.ndarray, values: np.ndarray) -> float:
    ok = np.isfinite(values) & (values > 0)
    return float(np.corrcoef(np.log(h[ok]), np.log(values[ok]))[0, 1]) if ok.sum() > 2 else np.nan


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=128, help="pixels per side (default 128)")
    ap.add_argument("--seeds", type=int, default=8, help="seeds 1..N (default 8)")
    add_pressures_option(ap, 1e-6, 1e-2, 17)
    ap.add_argument(
        "--at",
        type=float,
        nargs="+",
        metavar="P",
        help="the loads p0/E* of the stiffness distributions (the nearest computed; default "
        "with --data 1e-6, below p_c, and 1e-4, above; else 1e-3 and 1e-2, resolved at 128^2)",
    )
    ap.add_argument("--fit-points", type=int, default=4, help="loads of each seed's fit (4)")
    add_data_options(ap, "seeds", "fig7")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    curves, n = (_read if args.data else _solved)(args)
    at = args.at or ([1e-6, 1e-4] if args.data else [1e-3, 1e-2])
    d = analyse(curves, n, 1.0, at, args.fit_points)
    for line in report(d):
        print(line)
    figures.save(f"{args.output}.h5", d, hurst=HURST, grid=n, study_data=args.data or "")
    _draw(args, d, n)
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
