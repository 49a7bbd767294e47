"""The rough punch settled: K h_rms/p against p for periodic faces and faces cut from a larger
surface, L_p/lambda_r = 1 and 8, several seeds; K from springs in series (paper Eq. 2) with the
same grid's flat punch, beside Eq. 2 with the analytic flat punch (the square's exact 1.1523
E* L_p, and King's 1.142 E* L_p, the paper's choice) and -dp/du_bar over the face; the periodic
cell of Fig. 1 for reference."""

import argparse

import numpy as np

from petsc_contact.geometries.punch import flat_punch_stiffness, interfacial_stiffness
from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import CUT_FROM, PUNCH_RATIOS, add_data_options, piece_files
from petsc_contact.physics import theory
from petsc_contact.reference import flat_punch

HURST = 0.7
FACES = ("periodic", "cut")
TOLERANCES = (0.05, 0.1)  # K/p within +-5% or +-10%: the linear regime
ANALYTIC = {"exact": flat_punch.SQUARE_BETA, "king": flat_punch.KING_BETA}
"""The analytic flat punches of paper Eq. 2 beside the grid's: the square's exact shape factor
and King's estimate, the paper's choice (as Pharr et al. quote it)."""


def linearity(p: np.ndarray, k: np.ndarray, resolved: np.ndarray) -> str:
    """How far ``K ~ p`` holds over the ``resolved`` loads (at least 16 contact pixels): the
    widest windows of :func:`~petsc_contact.paper.figures.linear_width` at each of
    :data:`TOLERANCES`, and the smallest ``K/p``'s load."""
    ratio = np.where(resolved, k / p, np.nan)
    parts = [f"K/p smallest at p/E* {p[np.nanargmin(ratio)]:.2g}"]
    for tolerance in TOLERANCES:
        width, low, high = figures.linear_width(p, ratio, tolerance)
        parts.append(f"K/p within {tolerance:.0%} over {width:.2f} decades ({low:.2g}-{high:.2g})")
    return ", ".join(parts)


def punch_rows(paths: list[str]) -> list[dict]:
    """Each punch piece's columns (NaN where a step did not converge), its face's realised
    ``h_rms`` and seed, ``-dp/du_bar`` by finite differences where ``mean_gap`` is kept, and
    ``K`` from Eq. 2 with each analytic flat punch of :data:`ANALYTIC` (``exact_stiffness``,
    ``king_stiffness``: negative where the discretised punch is already stiffer than King's
    flat one).  An unfinished piece with no converged step yet is left out."""
    import h5py

    rows = []
    for path in paths:
        with h5py.File(path, "r", locking=False) as f:
            ok = f["converged"][:].astype(bool)
            if not ok.any():
                continue
            keys = (
                "nominal_pressure",
                "area_fraction",
                "interfacial_stiffness",
                "total_stiffness",
                "flat_punch_stiffness",
                "mean_gap",  # recorded by punch runs of 0.2.0 on
                "contact_patches",
            )
            row = {k: np.where(ok, f[k][:], np.nan) for k in keys if k in f}
            area = float(np.prod(f.attrs["lengths"]))
            for name, beta in ANALYTIC.items():
                k_flat = flat_punch_stiffness(float(f.attrs["modulus"]), area, beta)
                k = [interfacial_stiffness(k_tot, k_flat) for k_tot in row["total_stiffness"]]
                row[f"{name}_stiffness"] = np.array(k) / area
            row |= {
                "h_rms": float(f.attrs["rms_height"]),
                "pixels": int(np.prod(np.atleast_1d(f.attrs["grid"])[[0, -1]])),  # n x n
                "seed": int(f.attrs["seed"]),
                "converged": ok,
            }
        if "mean_gap" in row:
            good = ok & (row["nominal_pressure"] > 0)
            row["mean_gap_stiffness"] = np.full(ok.size, np.nan)
            if good.sum() >= 3:
                row["mean_gap_stiffness"][good] = figures.sweep_stiffness(
                    row["nominal_pressure"][good], row["mean_gap"][good]
                )
        rows.append(row)
    return rows


def _variant_files(data: str, face: str, ratio: int, partial: bool) -> list[str]:
    cut = str(CUT_FROM if face == "cut" else 1)
    return piece_files(
        data, "punch", "punch", partial=partial, rolloff_ratio=f"{ratio:g}", cut_from=cut
    )


def periodic_reference(data: str, ratio: int) -> dict | None:
    """Fig. 1's periodic cell at this ``L/lambda_r`` (8192^2 at the study's size), if
    computed, with its grid size ``n`` and its ``K h_rms/p`` over its resolved loads."""
    import h5py

    paths = piece_files(data, "fig1", rolloff_ratio=f"{ratio:g}")
    if not paths:
        return None
    c = figures.curves_from_files(paths)
    with h5py.File(paths[0], "r", locking=False) as f:
        n = int(np.atleast_1d(f.attrs["grid"])[0])
    ref = {k: v[0] for k, v in c.items() if k != "h_rms"} | {"h_rms": float(c["h_rms"][0])}
    p = ref["nominal_pressure"]
    ok = figures.resolved(ref["area_fraction"], n) & np.isfinite(ref["stiffness"])
    return ref | {"n": n, "resolved": ok, "normalised": ref["stiffness"] * ref["h_rms"] / p}


def normalised(row: dict, key: str = "interfacial_stiffness") -> np.ndarray:
    """``K h_rms/p`` of a punch piece over its resolved loads (``nan`` elsewhere): constant
    in a linear regime."""
    ok = figures.contact_resolved(row["area_fraction"], row["pixels"])
    return np.where(ok, row[key] * row["h_rms"] / row["nominal_pressure"], np.nan)


def against_cell(row: dict, ref: dict | None) -> np.ndarray:
    """The punch's ``K h_rms/p`` over the periodic cell's at the same ``p/E*`` (log-log
    interpolated between the cell's resolved loads), per step."""
    if ref is None:
        return np.full(row["nominal_pressure"].shape, np.nan)
    cell = np.where(ref["resolved"], ref["normalised"], np.nan)
    return normalised(row) / figures.log_interp(
        row["nominal_pressure"], ref["nominal_pressure"], cell
    )


def seed_median(rows: list, x_key: str, y: list[np.ndarray], x: np.ndarray) -> np.ndarray:
    """The median over seeds of ``y`` (one array per seed, against its ``x_key`` column) at
    ``x``, where at least half of the seeds (and two) reach it."""
    at = np.array([figures.log_interp(x, r[x_key], v) for r, v in zip(rows, y, strict=True)])
    enough = np.sum(np.isfinite(at), axis=0) >= max(2, (len(rows) + 1) // 2)
    middle = np.full(x.shape, np.nan)
    middle[enough] = np.nanmedian(at[:, enough], axis=0)
    return middle


AREAS = (0.01, 0.05, 0.1, 0.2)  # contact area fractions the summary compares at
SCATTER_LOADS = (1e-6, 1e-4, 1e-3)  # p/E* at which the seed-to-seed scatter is given


def _range(values: np.ndarray, digits: int = 2) -> str:
    """``median [min-max]`` of the finite values, with ``(n/N)`` when only ``n`` of the
    ``N`` seeds have one."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return "-"
    text = f"{np.median(v):.{digits}f} [{v.min():.{digits}f}-{v.max():.{digits}f}]"
    return text if v.size == np.size(values) else f"{text} ({v.size}/{np.size(values)})"


def summary(face: str, ratio: int, rows: list, ref: dict | None) -> str:
    """A variant over its seeds, as a Markdown table row.  As ``median [min-max]`` over the
    seeds: the punch over the cell at 1, 5, 10 and 20% area; ``K h_rms/p`` at the step
    nearest 20% area with the grid's, the exact analytic and King's flat punch (negative
    where the punch is stiffer than King's flat one); the widest window within 10% (decades);
    the area at which the total stiffness is half the flat punch's (the edges' share).  Then
    the range of ``-dp/du_bar`` over Eq. 2 over every step from 0.1% to 10% area of every
    seed, and the scatter between seeds at fixed loads, the standard deviation (ddof 1) of
    ``ln(K h_rms)``."""
    areas = np.array(AREAS)
    half = np.array(
        [
            figures.log_interp(
                0.5, r["total_stiffness"] / r["flat_punch_stiffness"], r["area_fraction"]
            )
            for r in rows
        ]
    )
    vs_cell = np.array(
        [figures.log_interp(areas, r["area_fraction"], against_cell(r, ref)) for r in rows]
    )
    near = [int(np.nanargmin(np.abs(np.log(r["area_fraction"] / 0.2)))) for r in rows]
    top = np.array([normalised(r)[i] for r, i in zip(rows, near, strict=True)])
    exact, king = (
        np.array([normalised(r, key)[i] for r, i in zip(rows, near, strict=True)])
        for key in ("exact_stiffness", "king_stiffness")
    )
    reached = np.array([r["area_fraction"][i] for r, i in zip(rows, near, strict=True)])
    widths = []
    for r in rows:
        ok = figures.contact_resolved(r["area_fraction"], r["pixels"])
        ratio_k = np.where(ok, r["interfacial_stiffness"] / r["nominal_pressure"], np.nan)
        widths.append(figures.linear_width(r["nominal_pressure"], ratio_k, 0.1)[0])
    gap = []
    for r in rows:
        mid = (r["area_fraction"] >= 1e-3) & (r["area_fraction"] <= 0.1)
        if "mean_gap_stiffness" in r:
            gap.extend((r["mean_gap_stiffness"] / r["interfacial_stiffness"])[mid])
    gap_text = f"{np.nanmin(gap):.2f}-{np.nanmax(gap):.2f}" if np.isfinite(gap).any() else "-"
    loads = np.array(SCATTER_LOADS)
    at = np.array([figures.log_interp(loads, r["nominal_pressure"], normalised(r)) for r in rows])
    scatter = []
    for column in at.T:
        column = column[np.isfinite(column)]
        scatter.append(f"{np.std(np.log(column), ddof=1):.2f}" if column.size >= 3 else "-")
    cells = [
        f"{face} face, `L_p/lambda_r = {ratio}`",
        str(len(rows)),
        *(_range(vs_cell[:, i]) for i in range(areas.size)),
        f"{_range(top)} at {reached.min():.0%}-{reached.max():.0%}",
        _range(exact),
        _range(king),
        _range(np.array(widths)),
        gap_text,
        _range(100 * half, 1),
        " / ".join(scatter),
    ]
    return "| " + " | ".join(cells) + " |"


SUMMARY_HEADER = (
    "| punch | seeds | punch / cell at 1% area | 5% | 10% | 20% | `K h_rms/p` near 20%, Eq. 2 "
    "with the grid's flat punch | with the exact analytic | with King's "
    "| within 10% (decades) | `-dp/du_bar` / Eq. 2, 0.1-10% area | area (%) at `K_tot = "
    "K_flat/2` | std of `ln(K h_rms)` at "
    + ", ".join(f"{p:.0e}" for p in SCATTER_LOADS)
    + " E* |\n"
    + "| --- " * 13
    + "|"
)


MEDIAN = {"ls": "-", "ms": 3.5, "mfc": "none", "lw": 1.6, "markevery": 4}  # median over seeds


REFERENCE_STYLES = (
    ({"ls": (0, (3, 3)), "lw": 0.8}, "Eq. 2 with the exact flat square (median, in black)"),
    (
        {"ls": ":", "lw": 1.3},
        "Eq. 2 with King's flat square, the paper's (median, to a seed's < 0)",
    ),
    ({"ls": "none", "marker": "x", "ms": 4}, r"$-dp/d\bar u$ (median)"),
)
"""How :func:`_draw_references` draws Eq. 2 with the analytic flat punches and ``-dp/du_bar``."""


def _draw_references(ax: object, rows: list, p: np.ndarray, color: str) -> None:
    """A variant's medians over its seeds at ``p`` of Eq. 2 with the exact and with King's
    flat punch (the latter up to the last load before a seed's turns negative) and of
    ``-dp/du_bar`` (every third load), in the face's ``color`` (the exact one in black, on
    top of the grid's, from which it differs by at most a few percent)."""
    (exact_style, _), (king_style, _), (gap_style, _) = REFERENCE_STYLES
    exact = [normalised(r, "exact_stiffness") for r in rows]
    ax.loglog(p, seed_median(rows, "nominal_pressure", exact, p), color="k", **exact_style)
    king = [normalised(r, "king_stiffness") for r in rows]
    ends = []  # the last load before a seed's Eq. 2 with King's turns negative
    for r, v in zip(rows, king, strict=True):
        with np.errstate(invalid="ignore"):
            turned = np.flatnonzero(v <= 0)
        ends.append(r["nominal_pressure"][turned[0] - 1] if turned.size else np.inf)
    shown = p <= min(ends)
    median = seed_median(rows, "nominal_pressure", king, p)
    ax.loglog(p[shown], median[shown], color=color, **king_style)
    if all("mean_gap_stiffness" in r for r in rows):
        gap = [normalised(r, "mean_gap_stiffness") for r in rows]
        median = seed_median(rows, "nominal_pressure", gap, p)
        ax.loglog(p[::3], median[::3], color=color, **gap_style)


def _draw(args: argparse.Namespace, variants: dict, references: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(
        2,
        2,
        figsize=(12, 8.4),
        sharex="row",
        sharey="row",
        height_ratios=(3, 2),
        constrained_layout=True,
    )
    for column, ratio in enumerate(PUNCH_RATIOS):
        ax, below = axes[0, column], axes[1, column]
        ref = references.get(ratio)
        if ref is not None:
            ok = ref["resolved"]
            ax.loglog(
                ref["nominal_pressure"][ok],
                ref["normalised"][ok],
                "-",
                color="0.55",
                lw=2.5,
                label=f"periodic cell, $L/\\lambda_r$ = {ratio} (Fig. 1, {ref['n']}$^2$)",
            )
        for face, color, marker in (("periodic", "C0", "o"), ("cut", "C3", "s")):
            rows = variants.get((face, ratio), [])
            if not rows:
                continue
            for row in rows:
                ax.loglog(
                    row["nominal_pressure"], normalised(row), "-", color=color, lw=0.6, alpha=0.35
                )
                below.semilogx(
                    row["area_fraction"],
                    against_cell(row, ref),
                    "-",
                    color=color,
                    lw=0.6,
                    alpha=0.35,
                )
            lo = min(
                np.nanmin(np.where(r["nominal_pressure"] > 0, r["nominal_pressure"], np.nan))
                for r in rows
            )
            hi = max(np.nanmax(r["nominal_pressure"]) for r in rows)
            p = np.geomspace(lo, hi, 60)
            n = len(rows)
            eq2 = seed_median(rows, "nominal_pressure", [normalised(r) for r in rows], p)
            label = f"{face} face, Eq. 2: median of {n} seeds (thin: each)"
            ax.loglog(p, eq2, marker, color=color, label=label, **MEDIAN)
            _draw_references(ax, rows, p, color)
            a = np.geomspace(1e-4, 0.5, 60)
            cell = seed_median(rows, "area_fraction", [against_cell(r, ref) for r in rows], a)
            label = f"{face} face: median (thin: each seed)"
            below.semilogx(a, cell, marker, color=color, label=label, **MEDIAN)
        for row in references.get(("fig1 punch", ratio), []):
            p = row["nominal_pressure"]
            ax.loglog(
                p,
                normalised(row),
                "^",
                color="0.3",
                ms=3.5,
                label="Fig. 1's punch (periodic face, seed 1)",
            )
        for style, label in REFERENCE_STYLES:  # one entry per style, both faces' colours
            ax.plot([], [], color="0.3", label=label, **style)
        ax.axhline(1 / theory.GAMMA, color="k", ls="--", lw=0.8, label=r"$1/\gamma$")
        ax.set(
            title=f"$L_p/\\lambda_r$ = {ratio}, $L_p/\\lambda_1$ = 1024, 2048$^2$",
            xlim=(1e-8, 0.1),
            xlabel="$p/E^*$",
        )
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.45, 1.0))
        below.axhline(1, color="k", lw=0.8)
        below.set(xlabel="contact area fraction", xlim=(1e-4, 0.6), yscale="log")
        below.grid(alpha=0.3, which="both")
        below.legend(fontsize=7, loc="lower left")
    axes[0, 0].set(ylabel=r"$K h_\mathrm{rms}/p$ (flat: linear regime)", ylim=(0.5, 1500))
    axes[1, 0].set(ylabel="punch / periodic cell at the same $p$", ylim=(0.3, 3))
    ticks = (0.3, 0.5, 0.7, 1, 1.5, 2, 3)
    axes[1, 0].set_yticks(ticks, [f"{t:g}" for t in ticks])
    axes[1, 0].yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    fig.suptitle(
        f"Rough punch, H = {HURST}, rms slope 0.1: periodic faces and faces cut from a "
        f"{CUT_FROM}x larger surface ($h_\\mathrm{{rms}}$: the face's own; resolved loads)"
    )
    fig.savefig(f"{args.output}.png", dpi=120)


def report(face: str, ratio: int, rows: list) -> list[str]:
    """Per seed: the loads reached, the linear regime's width (Eq. 2 and ``-dp/du_bar``)."""
    lines = []
    for row in rows:
        p = row["nominal_pressure"]
        ok = row["converged"] & figures.contact_resolved(row["area_fraction"], row["pixels"])
        text = (
            f"{face} face, L_p/lambda_r = {ratio}, seed {row['seed']}: "
            f"{row['converged'].sum()}/{ok.size} converged ({ok.sum()} resolved), p/E* "
            f"{np.nanmin(p[p > 0]):.2g}-{np.nanmax(p):.2g}, area up to "
            f"{np.nanmax(row['area_fraction']):.1%}; Eq. 2: "
            f"{linearity(p, row['interfacial_stiffness'], ok)}"
        )
        top = np.nanargmax(row["area_fraction"])
        for name, key in (("the exact", "exact_stiffness"), ("King's", "king_stiffness")):
            over = row[key] / row["interfacial_stiffness"]
            below = np.where(row["area_fraction"] < 0.2, over, np.nan)
            text += (
                f"; Eq. 2 with {name} flat punch {over[top]:.3f} x at the top load, "
                f"{np.nanmin(below):.3f}-{np.nanmax(below):.3f} x below 20% area"
            )
        if "mean_gap_stiffness" in row:
            ratio_k = row["mean_gap_stiffness"] / row["interfacial_stiffness"]
            mid = (row["area_fraction"] >= 1e-3) & (row["area_fraction"] <= 0.1)
            text += (
                f"; -dp/du_bar: {linearity(p, row['mean_gap_stiffness'], ok)}, "
                f"{np.nanmin(ratio_k[mid]):.2f}-{np.nanmax(ratio_k[mid]):.2f} x Eq. 2 at "
                "0.1-10% area"
            )
        lines.append(text)
    return lines


def _arguments(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    add_data_options(ap, "punch", "fig8", required=True)
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    args = _arguments(argv)
    variants, references, data = {}, {}, {}
    references[("fig1 punch", 1)] = punch_rows(piece_files(args.data, "fig1", "punch"))
    for ratio in PUNCH_RATIOS:
        references[ratio] = periodic_reference(args.data, ratio)
        for face in FACES:
            rows = punch_rows(_variant_files(args.data, face, ratio, args.with_partial))
            if not rows:
                print(f"# no {face} face at L_p/lambda_r = {ratio} in {args.data} yet")
                continue
            variants[(face, ratio)] = rows
            data[f"{face}_r{ratio}"] = {f"seed{r['seed']}": r for r in rows}
            for line in report(face, ratio, rows):
                print(line)
    if not variants:
        raise SystemExit(f"no complete punch piece in {args.data}")
    for line in report("Fig. 1's periodic", 1, references[("fig1 punch", 1)]):
        print(line)
    for ratio in PUNCH_RATIOS:
        ref = references[ratio]
        if ref is not None:
            p, k = ref["nominal_pressure"], ref["stiffness"]
            print(
                f"periodic cell (Fig. 1), L/lambda_r = {ratio}: {linearity(p, k, ref['resolved'])}"
            )
    print(SUMMARY_HEADER)
    for (face, ratio), rows in sorted(variants.items(), key=lambda v: (v[0][1], v[0][0])):
        print(summary(face, ratio, rows, references[ratio]))
    figures.save(f"{args.output}.h5", data, hurst=HURST, cut_from=CUT_FROM, study_data=args.data)
    _draw(args, variants, references)
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
