"""The punch against the periodic cell of its own face, and u0 from the cells' loads.

Each periodic punch face of ``petsc-contact study --figure punch`` (2048^2, H = 0.7,
``L_p/lambda_1 = 1024``, ``L_p/lambda_r`` 1 and 8, 8 seeds) is also solved as a periodic cell
(``--figure cells``: the same heights, loads 0.05 decades apart from 3.2e-4 to 8.9e-3 E*), and
as a punch again by approaches about 0.05 decades of load apart through 1-10% contact area
(read in place of ``punch/``'s where complete).
Both are read by one linearity criterion: the exponent ``m`` of ``K ~ p^m`` fitted over the
resolved steps at 1-10% contact area (``m = 1``: the linear regime of paper Eq. 1), and the
widest window of loads over which ``K/p`` stays within 10%. The cells also give ``u0`` of
Persson's exponential law (paper Eq. 3) from every load in the 1-10% window, two ways: the
median of ``p/K`` and the slope ``-du_bar/d ln p`` of the mean gap, each with a 68% interval
over seeds and loads resampled, beside Persson's closed form for the face's spectrum.
"""

import argparse
import functools
from collections.abc import Callable

import numpy as np

from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import PUNCH_RATIOS, RMS_SLOPE, add_data_options, piece_files
from petsc_contact.physics import theory

HURST = 0.7
WINDOW = (0.01, 0.1)  # the contact areas where the linear regime is read
TOLERANCE = 0.1  # K/p within +-10%: the linear window's width
AREAS = (0.01, 0.05, 0.1)  # where the punch is divided by its cell
SAME_FACE = 1e-9  # the punch's and the cell's h_rms agree to this: one face
KEYS = ("nominal_pressure", "area_fraction", "mean_gap")


def read(path: str) -> dict:
    """A piece's columns (``nan`` where a step did not converge), its stiffness ``K`` (the
    cell's exact one, the punch's paper Eq. 2 with the grid's flat punch), its face's realised
    ``h_rms``, seed, pixel count and which steps are resolved (at least 16 contact pixels);
    ``ValueError`` (one line, naming it) for a file that cannot be read."""
    import h5py

    try:
        with h5py.File(path, "r", locking=False) as f:
            ok = f["converged"][:].astype(bool)
            stiffness = "interfacial_stiffness" if "interfacial_stiffness" in f else "stiffness"
            row = {k: np.where(ok, f[k][:], np.nan) for k in (*KEYS, stiffness)}
            row["K"] = row.pop(stiffness)
            grid = np.atleast_1d(f.attrs["grid"])
            row |= {"h_rms": float(f.attrs["rms_height"]), "seed": int(f.attrs["seed"])}
    except (OSError, KeyError) as exc:
        raise ValueError(f"'{path}' cannot be read ({exc}): not compared") from None
    pixels, row["n"] = int(grid[0] * grid[-1]), int(grid[0])
    row["resolved"] = ok & figures.contact_resolved(row["area_fraction"], pixels)
    return row


def pairs(data: str, ratio: int) -> list[tuple[dict, dict]]:
    """The (punch, cell) of every seed with both complete at this ``L_p/lambda_r`` (the punch
    of ``cells/`` by approaches through 1-10% area where it is complete, else ``punch/``'s);
    ``SystemExit`` (one line) where a cell's face is not its punch's (another ``h_rms``)."""
    where = {"rolloff_ratio": f"{ratio:g}"}
    faces = piece_files(data, "punch", "punch", cut_from="1", **where)  # periodic faces
    faces += piece_files(data, "cells", "punch", **where)  # their denser approaches, if done
    punches = {r["seed"]: r for r in map(read, faces)}  # the denser ones where both are
    out = []
    for cell in map(read, piece_files(data, "cells", **where)):
        punch = punches.get(cell["seed"])
        if punch is None:
            continue
        if abs(punch["h_rms"] / cell["h_rms"] - 1) > SAME_FACE:
            raise SystemExit(
                f"cells: seed {cell['seed']} at L/lambda_r = {ratio} has h_rms "
                f"{cell['h_rms']:.9g}, its punch face {punch['h_rms']:.9g}: not the same face, "
                "not compared"
            )
        out.append((punch, cell))
    return out


def in_window(row: dict) -> np.ndarray:
    """The resolved steps at :data:`WINDOW` contact area."""
    area = row["area_fraction"]
    return row["resolved"] & (area >= WINDOW[0]) & (area <= WINDOW[1])


def exponent(row: dict) -> float:
    """``m`` of ``K ~ p^m`` by least squares over :func:`in_window` (NaN under 3 steps)."""
    mid = in_window(row)
    if mid.sum() < 3:
        return float("nan")
    return float(np.polyfit(np.log(row["nominal_pressure"][mid]), np.log(row["K"][mid]), 1)[0])


def width(row: dict) -> float:
    """The widest window (decades of load) over which ``K/p`` stays within :data:`TOLERANCE`
    (resolved steps only)."""
    ratio = np.where(row["resolved"], row["K"] / row["nominal_pressure"], np.nan)
    return figures.linear_width(row["nominal_pressure"], ratio, TOLERANCE)[0]


def over_cell(punch: dict, cell: dict) -> np.ndarray:
    """The punch's ``K`` over its cell's at the same load (log-log interpolated between the
    cell's resolved loads), at :data:`AREAS` of the punch's contact area."""
    cell_k = np.where(cell["resolved"], cell["K"], np.nan)
    ratio = np.where(
        punch["resolved"],
        punch["K"]
        / figures.log_interp(punch["nominal_pressure"], cell["nominal_pressure"], cell_k),
        np.nan,
    )
    return figures.log_interp(np.array(AREAS), punch["area_fraction"], ratio)


def _range(values: np.ndarray, digits: int = 2) -> str:
    """``median [min-max]`` of the finite values, ``-`` without any."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return "-"
    return f"{np.median(v):.{digits}f} [{v.min():.{digits}f}-{v.max():.{digits}f}]"


def comparison_row(ratio: int, rows: list[tuple[dict, dict]]) -> str:
    """A variant over its seeds as a Markdown table row (:data:`COMPARISON_HEADER`)."""
    vs = np.array([over_cell(p, c) for p, c in rows])
    cells = [
        f"`L_p/lambda_r = {ratio}`",
        str(len(rows)),
        *(_range(vs[:, i]) for i in range(len(AREAS))),
        _range(np.array([exponent(p) for p, _ in rows])),
        _range(np.array([exponent(c) for _, c in rows])),
        str(int(np.median([in_window(p).sum() for p, _ in rows]))),
        str(int(np.median([in_window(c).sum() for _, c in rows]))),
        _range(np.array([width(p) for p, _ in rows])),
        _range(np.array([width(c) for _, c in rows])),
    ]
    return "| " + " | ".join(cells) + " |"


COMPARISON_HEADER = (
    "| face | seeds | punch / own cell at 1% area | 5% | 10% | `m` of `K ~ p^m` at 1-10% "
    "area, punch | own cell | steps in the window, punch | own cell | `K/p` within 10% "
    "(decades), punch | own cell |\n" + "| --- " * 11 + "|"
)


def u0_by_stiffness(p: np.ndarray, k: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """``u0 = p/K`` (paper Eq. 1), the median over the loads given (the last axis: one value
    per row of resampled loads)."""
    return np.median(p / k, axis=-1)


def u0_by_gap(p: np.ndarray, k: np.ndarray, gap: np.ndarray) -> np.ndarray:
    """``u0 = -du_bar/d ln p`` (paper Eq. 3), the least-squares line's slope in closed form
    over the loads given (the last axis; NaN where they are under 2 distinct loads)."""
    x = np.log(p)
    dx = x - x.mean(axis=-1, keepdims=True)
    dy = gap - gap.mean(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = (dx * dy).sum(axis=-1) / (dx * dx).sum(axis=-1)
    return np.where(np.ptp(p, axis=-1) > 0, -slope, np.nan)


@functools.cache
def resampled(sizes: tuple[int, ...]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The bootstrap's draws over seeds whose windows hold ``sizes`` loads: for each seed,
    the loads of every resample that drew it (a row each) and where each lands among the
    :data:`~petsc_contact.paper.figures.BOOTSTRAP_RESAMPLES` x seeds slots. Drawn one
    resample at a time from a fixed stream (the seeds, then each seed drawn's loads), so
    the same sizes give the same draws: made once, shared by both estimators."""
    rng = np.random.default_rng(figures.BOOTSTRAP_SEED)
    count = len(sizes)
    drawn: list[list[np.ndarray]] = [[] for _ in sizes]
    where: list[list[int]] = [[] for _ in sizes]
    for resample in range(figures.BOOTSTRAP_RESAMPLES):
        for slot, i in enumerate(rng.integers(0, count, count)):
            drawn[i].append(rng.integers(0, sizes[i], sizes[i]))
            where[i].append(resample * count + slot)
    return [
        (np.array(d, dtype=int).reshape(len(d), n), np.array(w, dtype=int))
        for d, w, n in zip(drawn, where, sizes, strict=True)
    ]


def seeds_and_loads(
    windows: list[tuple[np.ndarray, ...]], estimator: Callable[..., np.ndarray]
) -> np.ndarray:
    """The 68% percentile interval of the median over seeds of ``estimator(p, K, u_bar)``,
    seeds resampled and, within each seed drawn, its window's loads resampled
    (:func:`resampled`); the estimator runs once per seed, over every resample of its loads."""
    count = len(windows)
    values = np.full(figures.BOOTSTRAP_RESAMPLES * count, np.nan)
    draws = resampled(tuple(w[0].size for w in windows))
    for window, (rows, slots) in zip(windows, draws, strict=True):
        if slots.size:
            values[slots] = estimator(*(column[rows] for column in window))
    medians = np.nanmedian(values.reshape(figures.BOOTSTRAP_RESAMPLES, count), axis=1)
    return np.percentile(medians, [16, 84])


def _windows(rows: list[tuple[dict, dict]], unit: list[float]) -> list[tuple[np.ndarray, ...]]:
    """Each cell's ``(p, K, u_bar)`` at its :func:`in_window` loads, lengths in ``unit`` (one
    per seed), so that the estimators give ``u0`` in that unit."""
    out = []
    for (_, cell), scale in zip(rows, unit, strict=True):
        mid = in_window(cell)
        p, k, gap = cell["nominal_pressure"][mid], cell["K"][mid], cell["mean_gap"][mid]
        out.append((p, k * scale, gap / scale))
    return out


def _estimates(windows: list[tuple[np.ndarray, ...]]) -> list[str]:
    """``median [68% interval]`` of both estimators over seeds (and loads), ``-`` without a
    seed of two loads in the window."""
    windows = [w for w in windows if w[0].size >= 2]  # a slope needs two loads
    if not windows:
        return ["-", "-"]
    text = []
    for estimator in (u0_by_stiffness, u0_by_gap):
        median = np.median([estimator(*w) for w in windows])
        low, high = seeds_and_loads(windows, estimator)
        text.append(f"{median:.3f} [{low:.3f}-{high:.3f}]")
    return text


def u0_row(ratio: int, rows: list[tuple[dict, dict]]) -> str:
    """The cells' ``u0`` at this ``L/lambda_r`` by both estimators, median over seeds [68%
    interval over seeds and loads]: in each face's realised ``h_rms``, and over Persson's
    closed form on the prescribed spectrum (the same length unit); beside it Persson's in the
    spectrum's ``h_rms``, as a Markdown table row."""
    n = rows[0][1]["n"]  # the paper bandwidth: L/lambda_1 = n/2
    q, c = figures.ideal_spectrum(1.0, HURST, ratio, n / 2, rms_slope=RMS_SLOPE)
    spectrum_h = float(np.sqrt(2 * np.pi * np.trapezoid(q * c, q)))
    persson = theory.persson_exponential(q, c)[1]
    realised = [cell["h_rms"] for _, cell in rows]
    windows = _windows(rows, realised)
    text = [f"`L/lambda_r = {ratio}`", str(len(rows)), str(min(w[0].size for w in windows))]
    text += _estimates(windows) + _estimates(_windows(rows, [persson] * len(rows)))
    text.append(f"{persson / spectrum_h:.3f}")
    text.append(f"{np.median(realised) / spectrum_h:.3f}")
    return "| " + " | ".join(text) + " |"


U0_HEADER = (
    "| cell | seeds | loads in the window (fewest) | `u0/h_rms` = `p/K` | `-du_bar/d ln p` "
    "| `u0/u0_Persson` = `p/K` | `-du_bar/d ln p` | Persson's `u0/h_rms` (the spectrum's) "
    "| realised / spectrum's `h_rms` |\n" + "| --- " * 9 + "|"
)


def draw(output: str, variants: dict) -> None:
    """``K h_rms/p`` against contact area, each seed's cell (line) and punch (markers), one
    panel per ``L_p/lambda_r``, the 1-10% window shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(variants), figsize=(5.2 * len(variants), 4.2), sharey=True)
    for ax, (ratio, rows) in zip(np.atleast_1d(axes), variants.items(), strict=True):
        for i, (punch, cell) in enumerate(rows):
            colour = plt.cm.viridis(i / max(len(rows) - 1, 1))
            for row, style in ((cell, {"ls": "-", "lw": 1}), (punch, {"ls": "--", "marker": "o"})):
                ok = row["resolved"]
                y = row["K"][ok] * row["h_rms"] / row["nominal_pressure"][ok]
                ax.loglog(row["area_fraction"][ok], y, color=colour, ms=3, **style)
        ax.axvspan(*WINDOW, color="0.9", zorder=0)
        ax.set(
            xlabel="contact area fraction",
            title=f"$L_p/\\lambda_r = {ratio}$: punch (o, dashed) and its own cell (line)",
            xlim=(1e-3, 0.6),
        )
    np.atleast_1d(axes)[0].set_ylabel(r"$K h_\mathrm{rms}/p$ (each seed a colour)")
    fig.tight_layout()
    fig.savefig(f"{output}.png", dpi=120)


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(description=__doc__)
    add_data_options(ap, "cells", "punch_own_cell", required=True, partial=False)
    args = ap.parse_args(argv)
    try:
        variants = {r: rows for r in PUNCH_RATIOS if (rows := pairs(args.data, r))}
    except ValueError as exc:  # a damaged piece: named, never compared
        raise SystemExit(str(exc)) from None
    if not variants:
        raise SystemExit(f"no seed with both its punch and its cell complete in {args.data}")
    print(COMPARISON_HEADER)
    for ratio, rows in variants.items():
        print(comparison_row(ratio, rows))
    print()
    print(U0_HEADER)
    for ratio, rows in variants.items():
        print(u0_row(ratio, rows))
    draw(args.output, variants)
    kept = {
        f"r{r}": {f"seed{c['seed']}": {"punch": p, "cell": c} for p, c in rows}
        for r, rows in variants.items()
    }
    figures.save(f"{args.output}.h5", kept)


if __name__ == "__main__":
    main()
