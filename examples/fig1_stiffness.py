"""Fig. 1: K(p) for L/lambda_r = 1 and 8 with Persson theory, K = p/u0 and the punch; inset p(u).

The punch's K is paper Eq. 2 with the same grid's flat punch, drawn beside Eq. 2 with the
analytic flat punch: the square's exact 1.1523 E* L_p and King's 1.142 E* L_p (the paper's,
through Pharr et al.); the punch's table against the periodic curves is printed.
"""

import argparse

import numpy as np

from petsc_contact.geometries.punch import flat_punch_stiffness, interfacial_stiffness
from petsc_contact.paper import figures
from petsc_contact.paper.fits import power_law_fit
from petsc_contact.paper.paper_study import (
    RMS_SLOPE,
    add_data_options,
    add_pressures_option,
    log_pressures,
    piece_files,
)
from petsc_contact.physics import theory
from petsc_contact.reference import flat_punch


def crossover_from_simulation(
    p: np.ndarray, k: np.ndarray, area: np.ndarray, points: int = 4
) -> tuple[float, float]:
    """Where the low-load power law meets K = p/u0 fitted at 1-10% contact area (NaN when
    fewer than ``points`` resolved steps are left to fit)."""
    mid = (area > 0.01) & (area < 0.1) & np.isfinite(k)
    u0 = float(np.median(p[mid] / k[mid])) if mid.any() else float("nan")
    if np.count_nonzero(np.isfinite(k) & (k > 0)) < points:
        return float("nan"), u0
    fit = power_law_fit(p, k, points)
    return (fit.prefactor * u0) ** (1 / (1 - fit.alpha)), u0


def _solved(
    args: argparse.Namespace, ratio: float, p: np.ndarray, cutoff: float
) -> tuple[dict, float, int, float]:
    h, h_rms = figures.surface(args.grid, args.hurst, ratio, cutoff, args.seed, RMS_SLOPE)
    return figures.stiffness_curve(h, p), h_rms, args.grid, cutoff


def _read(
    args: argparse.Namespace, ratio: float, p: np.ndarray, cutoff: float
) -> tuple[dict, float, int, float]:
    """The study's sweep of this roll-off (its own loads, grid and cut-off)."""
    import h5py

    paths = piece_files(args.data, "fig1", rolloff_ratio=f"{ratio:g}")
    if not paths:
        raise FileNotFoundError(f"no complete Fig. 1 sweep for L/lambda_r = {ratio:g}")
    with h5py.File(paths[0]) as f:
        n, cutoff = int(f.attrs["grid"]), float(f.attrs["cutoff_ratio"])
    curves = figures.curves_from_files(paths)
    curve = {k: v[0] for k, v in curves.items() if k != "h_rms"}
    return figures.with_sweep_stiffness(curve), float(curves["h_rms"][0]), n, cutoff


def _solved_punch(args: argparse.Namespace) -> tuple[dict, float, int]:
    n = args.punch_grid or args.grid // 2
    hp, hp_rms = figures.surface(n, args.hurst, 1.0, n / 4, args.seed)
    approaches = np.geomspace(1e-2, 30.0, 18) * hp_rms  # to well over 10% contact area
    punch = figures.punch_curve(hp, approaches)
    k_tot, k_int = punch["total_stiffness"], punch["interfacial_stiffness"]
    with np.errstate(divide="ignore", invalid="ignore"):  # the grid's flat punch, from Eq. 2
        punch["flat_punch_stiffness"] = 1 / (1 / k_tot - 1 / k_int)
    return with_analytic_references(punch, 1.0, 1.0), hp_rms, n


def _read_punch(args: argparse.Namespace) -> tuple[dict, float, int]:
    import h5py

    paths = piece_files(args.data, "fig1", command="punch")
    if not paths:
        raise SystemExit(f"no complete Fig. 1 punch in {args.data}")
    with h5py.File(paths[0]) as f:
        keys = (
            "approach force nominal_pressure area_fraction interfacial_stiffness "
            "total_stiffness flat_punch_stiffness"
        ).split()
        punch = {k: f[k][:] for k in keys} | {"converged": f["converged"][:].astype(bool)}
        area, modulus = float(np.prod(f.attrs["lengths"])), float(f.attrs["modulus"])
        punch = with_analytic_references(punch, modulus, area)
        return punch, float(f.attrs["rms_height"]), int(f.attrs["grid"])


ANALYTIC = {"exact": flat_punch.SQUARE_BETA, "king": flat_punch.KING_BETA}
"""The analytic flat punches of paper Eq. 2 beside the grid's: the square's exact shape factor
and King's estimate, the paper's choice (as Pharr et al. quote it)."""


def with_analytic_references(punch: dict, modulus: float, area: float) -> dict:
    """The punch's columns with ``exact_stiffness`` and ``king_stiffness``: its interfacial
    stiffness per area from paper Eq. 2 with each analytic flat punch of :data:`ANALYTIC`
    (``inf`` or negative where the total stiffness reaches or passes King's)."""
    out = dict(punch)
    for name, beta in ANALYTIC.items():
        k_flat = flat_punch_stiffness(modulus, area, beta)
        k = [interfacial_stiffness(k_tot, k_flat) for k_tot in punch["total_stiffness"]]
        out[f"{name}_stiffness"] = np.array(k) / area
    return out


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=512, help="pixels per side (default 512)")
    ap.add_argument("--hurst", type=float, default=0.7, help="Hurst exponent H (default 0.7)")
    ap.add_argument(
        "--rolloff-ratios",
        type=float,
        nargs="+",
        default=[1.0, 8.0],
        help="L/lambda_r values (default 1 8)",
    )
    ap.add_argument("--cutoff-ratio", type=float, default=None, help="default grid/4")
    ap.add_argument("--seed", type=int, default=1, help="surface seed (default 1)")
    add_pressures_option(ap, 1e-7, 5e-2, 16)
    ap.add_argument("--punch-grid", type=int, default=None, help="default grid/2")
    add_data_options(ap, "1", "fig1", partial=False)
    return ap.parse_args(argv)


def _periodic_curves(args: argparse.Namespace) -> tuple[dict, int]:
    """Each roll-off's K(p) with Persson's theory (on paper Eq. 5 at the surfaces' prescribed
    rms slope), the resolution mask, both crossovers and the Hertz slope at its lowest
    resolved loads."""
    cutoff = args.cutoff_ratio or args.grid / 4
    p = log_pressures(args)
    data, n = {}, args.grid
    for ratio in list(args.rolloff_ratios):
        try:
            curve, h_rms, n, cutoff = (_read if args.data else _solved)(args, ratio, p, cutoff)
        except FileNotFoundError as missing:  # the study has not computed it yet
            print(f"# {missing} in {args.data} yet")
            args.rolloff_ratios.remove(ratio)
            continue
        p = curve["nominal_pressure"]
        q, c = figures.ideal_spectrum(1.0, args.hurst, ratio, cutoff, rms_slope=RMS_SLOPE)
        curve["persson_stiffness"] = theory.persson_stiffness(p, q, c, 1.0)
        curve["persson_mean_gap"] = theory.persson_mean_gap(p, q, c, 1.0)
        pc_formula = theory.crossover_pressure(
            1.0, h_rms, args.hurst, 1.0, ratio, convention="paper"
        )
        curve["resolved"] = ok = figures.resolved(curve["area_fraction"], n)
        pc_sim, u0 = crossover_from_simulation(
            p[ok], curve["stiffness"][ok], curve["area_fraction"][ok]
        )
        curve.update(
            h_rms=h_rms,
            pc_formula=pc_formula,
            pc_simulation=pc_sim,
            u0=u0,
            lowest_slope=lowest_slope(p[ok], curve["stiffness"][ok]),
        )
        data[f"ratio{ratio:g}"] = curve
        print(
            f"# L/lambda_r = {ratio:g}, {n}^2: {int(curve['converged'].sum())}/{p.size} converged",
            flush=True,
        )
    if not args.rolloff_ratios:
        raise SystemExit(f"no complete Fig. 1 sweep in {args.data}")
    data["nominal_pressure"] = p
    return data, n


def lowest_slope(p: np.ndarray, k: np.ndarray) -> float:
    """``d ln K/d ln p`` between the two lowest loads given (Hertz: 1/3)."""
    good = np.isfinite(k) & (k > 0)
    if np.count_nonzero(good) < 2:
        return float("nan")
    (p0, p1), (k0, k1) = p[good][:2], k[good][:2]
    return float(np.log(k1 / k0) / np.log(p1 / p0))


def single_patch_limit(curve: dict) -> float:
    """The largest load below which every resolved contact is one patch (NaN: none is)."""
    ok = curve["resolved"]
    p, patches = curve["nominal_pressure"][ok], curve["contact_patches"][ok]
    several = np.flatnonzero(patches != 1)
    last = (several[0] if several.size else p.size) - 1
    return float(p[last]) if last >= 0 else float("nan")


def _draw(args: argparse.Namespace, data: dict, n: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p, punch = data["nominal_pressure"], data["punch"]
    fig, ax = plt.subplots(figsize=(6, 4.6), constrained_layout=True)
    inset = ax.inset_axes([0.62, 0.1, 0.35, 0.33])
    hertz = False  # a Hertz guide only where the lowest resolved load rests on one patch
    for ratio in args.rolloff_ratios:
        d = data[f"ratio{ratio:g}"]
        hr, ok = d["h_rms"], d["resolved"]
        k = d["stiffness"] * hr
        (line,) = ax.loglog(
            p[ok], k[ok], "o", mfc="none", label=f"$L/\\lambda_r$ = {ratio:g} (exact)"
        )
        color = line.get_color()
        # fewer than 16 contact pixels: not resolved, drawn small and never fitted
        ax.loglog(p[~ok], k[~ok], ".", color=color, alpha=0.5)
        single = ok & (d["contact_patches"] == 1)  # one asperity carries the load
        ax.loglog(p[single], k[single], "o", color=color)
        ax.loglog(p, d["stiffness_sweep"] * hr, "x", color=color, ms=4)
        ax.loglog(p, d["persson_stiffness"] * hr, "-", color=color, lw=1)
        ax.axvline(d["pc_formula"], color=color, ls=":", lw=1)
        first = np.flatnonzero(ok & np.isfinite(k) & (k > 0))[:1]
        if first.size and single[first[0]]:  # one asperity at the lowest resolved load
            hertz = True
            ph = p[first[0]] * np.geomspace(1 / 30, 10, 8)
            ax.loglog(ph, k[first[0]] * (ph / p[first[0]]) ** (1 / 3), "-.", color=color, lw=1)
        inset.semilogy(d["mean_gap"] / hr, p, "o", ms=2, color=color)
        inset.semilogy(d["persson_mean_gap"] / hr, p, "-", lw=1, color=color)
    ax.plot([], [], "o", color="gray", label="one contact patch")
    ax.plot([], [], ".", color="gray", label="< 16 contact pixels (not fitted)")
    ax.plot([], [], "x", color="gray", ms=4, label=r"$-dp/d\bar u$ along the sweep")
    ax.plot([], [], "-", color="gray", lw=1, label=f"Persson on Eq. 5 at rms slope {RMS_SLOPE:g}")
    if hertz:
        ax.plot([], [], "-.", color="gray", label=r"Hertz, $K \propto p^{1/3}$")
    ax.plot([], [], ":", color="gray", label="$p_c$, Eq. 13 (the paper's recipe)")
    ax.loglog(p, p / theory.GAMMA, "k--", lw=1, label=r"$K = p/(\gamma h_\mathrm{rms})$")
    _draw_punch(ax, punch)
    ax.set(
        xlabel="$p_0/E^*$",
        ylabel=r"$K h_\mathrm{rms}/E^*$",
        title=("paper Fig. 1: " if args.data else "quick look at the paper's Fig. 1: ")
        + f"H = {args.hurst}, {n}$^2$",
    )
    ax.set_ylim(top=10)  # K diverges at full contact: the last loads leave the frame
    ax.legend(fontsize=6.5, loc="upper left")
    ax.grid(alpha=0.3, which="both")
    inset.set(xlabel=r"$\bar u/h_\mathrm{rms}$", ylabel="$p_0/E^*$")
    inset.tick_params(labelsize=6, labelleft=False, labelright=True)
    inset.yaxis.set_label_position("right")
    fig.savefig(f"{args.output}.png", dpi=120)


def _draw_punch(ax: object, punch: dict) -> None:
    """The punch's ``K h_rms`` from Eq. 2 with the grid's flat punch (squares), the exact
    analytic one (pluses) and King's (dotted, up to the last load before it turns negative)."""
    ok = punch["converged"] & (punch["nominal_pressure"] > 0)
    p, hp = punch["nominal_pressure"], punch["h_rms"]
    k = punch["interfacial_stiffness"]
    ax.loglog(p[ok], k[ok] * hp, "s", mfc="none", color="gray", label="punch (Eq. 2)")
    exact = punch["exact_stiffness"]
    label = "punch, Eq. 2 with the exact flat square"
    ax.loglog(p[ok], exact[ok] * hp, "+", color="k", ms=5, label=label)
    king = punch["king_stiffness"]
    with np.errstate(invalid="ignore"):
        shown = ok & np.isfinite(king) & (king > 0)
    label = "punch, Eq. 2 with King's flat square (the paper's)"
    ax.loglog(p[shown], king[shown] * hp, ":", color="k", lw=1.2, label=label)


def punch_table(data: dict) -> list[str]:
    """The punch against the periodic curves at its loads, as Markdown rows: ``p/E*``, area,
    ``K h_rms/p`` from Eq. 2 with the grid's, the exact and King's flat punch,
    ``K_tot/K_flat`` (the grid's), each periodic curve's ``K h_rms/p`` at the same load
    (log-log interpolated over its resolved loads) and the punch over the first."""
    punch = data["punch"]
    p, hp = punch["nominal_pressure"], punch["h_rms"]
    cells = {}
    for key, d in data.items():
        if key.startswith("ratio"):
            ok = d["resolved"] & np.isfinite(d["stiffness"]) & (d["stiffness"] > 0)
            x, y = np.log(d["nominal_pressure"][ok]), np.log(d["stiffness"][ok] * d["h_rms"])
            with np.errstate(divide="ignore"):
                at = np.exp(np.interp(np.log(p), x, y, left=np.nan, right=np.nan))
            cells[key] = at / p
    names = " | ".join(f"periodic `L/lambda_r = {k[5:]}`" for k in cells)
    rows = [
        "| `p/E*` | area | punch `K h_rms/p`, Eq. 2 with the grid's flat punch | the exact "
        f"analytic | King's | `K_tot/K_flat` | {names} | punch / periodic {min(cells)[5:]} |",
        "| --- " * (7 + len(cells)) + "|",
    ]
    for i in np.flatnonzero(punch["converged"] & (p > 0)):
        norm = [punch[f"{k}_stiffness"][i] * hp / p[i] for k in ("interfacial", "exact", "king")]
        periodic = [c[i] for c in cells.values()]
        if not np.isfinite(periodic).any():
            continue
        ratio = punch["total_stiffness"][i] / punch["flat_punch_stiffness"][i]
        values = [f"{v:.3g}" for v in (*norm, ratio, *periodic, norm[0] / periodic[0])]
        rows.append(
            f"| {p[i]:.1e} | {punch['area_fraction'][i]:.2g} | " + " | ".join(values) + " |"
        )
    return rows


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    data, n = _periodic_curves(args)
    punch, hp_rms, n_punch = (_read_punch if args.data else _solved_punch)(args)
    top = punch["area_fraction"][punch["converged"]].max(initial=0.0)
    print(
        f"# punch {n_punch}^2: {int(punch['converged'].sum())}/{punch['converged'].size} "
        f"converged, up to {top:.0%} of the footprint in contact",
        flush=True,
    )
    data["punch"] = punch | {"h_rms": hp_rms}
    figures.save(
        f"{args.output}.h5",
        data,
        grid=n,
        hurst=args.hurst,
        cutoff_ratio=args.cutoff_ratio or args.grid / 4,
        seed=args.seed,
        punch_grid=n_punch,
        gamma=theory.GAMMA,
    )
    _draw(args, data, n)
    for ratio in args.rolloff_ratios:
        d = data[f"ratio{ratio:g}"]
        hr = d["h_rms"]
        print(
            f"L/lambda_r = {ratio:g}: q_r h_rms = {2 * np.pi * ratio * hr:.3g}, "
            f"p_c/E* formula (paper Eq. 13, the paper's recipe) {d['pc_formula']:.2e}, simulation "
            f"crossover {d['pc_simulation']:.2e}, u0/h_rms = {d['u0'] / hr:.3f}, "
            f"d ln K/d ln p at the lowest resolved loads {d['lowest_slope']:.2f} (Hertz 1/3), "
            f"one contact patch up to p0/E* = {single_patch_limit(d):.2g} (nan: at no load)"
        )
    for row in punch_table(data):
        print(row)
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
