"""Figures of results: load sweeps (periodic: area and mean gap; punch: force and stiffness),
ensembles, theory, an experiment, maps of fields.

Every helper returns its matplotlib ``Figure`` (made without pyplot: no global state, no
backend switched, shown as it is in a notebook) and writes it to ``path`` when one is given.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np


def plot_file(path: str, option: str = "--plot") -> str:
    """The file a figure saved as ``path`` becomes (``X`` without an extension: ``X.png``);
    ``ValueError`` naming ``option`` when matplotlib cannot write its format (``X.h5``)."""
    from matplotlib.backend_bases import FigureCanvasBase

    extension = os.path.splitext(path)[1][1:]
    if not extension:
        return f"{path}.png"
    formats = FigureCanvasBase.get_supported_filetypes()
    if extension.lower() not in formats:
        raise ValueError(
            f"{option} '{path}': a figure cannot be written as '.{extension}' (the extension "
            f"names the format: {', '.join(sorted(formats))})"
        )
    return path


P0_LABEL = "nominal pressure $p_0/E^*$"  # every load plot's x axis, without units
AREA_LABEL = "$A/A_0$"
PERSSON_AREA = r"Persson, $\mathrm{erf}(\sqrt{2}\,p_0/(E^* h'_\mathrm{rms}))$"
GAP_LABEL = r"$\bar u/h_\mathrm{rms}$"
STIFFNESS_LABEL = r"$K h_\mathrm{rms}/E^*$"
APPROACH_LABEL = r"approach $\delta/h_\mathrm{rms}$"  # a punch's, without units
LOAD_AXES = {  # a load plot's quantities: (its name with a unit, its dimensionless label)
    "p0": ("nominal pressure $p_0$", P0_LABEL),
    "gap": (r"mean gap $\bar u$", GAP_LABEL),
    "stiffness": ("stiffness per area $K$", STIFFNESS_LABEL),
}


def load_axis(
    kind: str, values: Any, units: dict[str, str] | None, modulus: float, h_rms: float
) -> tuple[float, str]:
    """The factor and label of a load plot's axis ``kind`` (``p0``, ``gap`` or ``stiffness``)
    drawing ``values``: in the run's ``units`` (``pressure``, ``length``) with the prefix
    that suits their typical size (``MPa``, ``nm``, ``MPa/µm``) where the run has the units
    the quantity needs; dimensionless (``p0/E*``, ``u_bar/h_rms``, ``K h_rms/E*``) only where
    it has none."""
    from ..conventions.units import display_scale, typeset, typical_magnitude

    pressure, length = (units or {}).get("pressure", ""), (units or {}).get("length", "")
    per_length = f"{pressure}/{length}" if pressure and length else ""
    unit = {"p0": pressure, "gap": length, "stiffness": per_length}[kind]
    name, dimensionless = LOAD_AXES[kind]
    if unit:
        factor, shown = display_scale(typical_magnitude(values), unit)
        return factor, f"{name} ({typeset(shown)})"
    if kind == "p0":
        return 1 / modulus, dimensionless
    if h_rms > 0:
        return (1 / h_rms if kind == "gap" else h_rms / modulus), dimensionless
    # a flat map (h_rms = 0): lengths in the map's own numbers, a stiffness in E* per them
    return (1.0, f"{name} (map's units)") if kind == "gap" else (1 / modulus, f"{name}$/E^*$")


def plot_sweep(
    path: str | None,
    steps: Sequence[dict[str, Any]],
    modulus: float,
    h_rms: float,
    units: dict[str, str] | None = None,
) -> Any:
    """Against the nominal pressure on a log axis: ``A/A0`` (log), the mean gap (linear) and,
    when the steps have it, the exact stiffness per area (log), each in the run's ``units``
    (``pressure``, ``length``) where it has them, else as ``p0/E*``, ``u_bar/h_rms`` and
    ``K h_rms/E*`` (:func:`load_axis`), as :func:`plot_theory` draws them.

    Steps that did not converge are drawn as red crosses.
    """
    panels = [("contact area", "area_fraction", "log"), ("mean gap", "mean_gap", "linear")]
    if all("stiffness" in s for s in steps):
        panels.append(("interfacial stiffness", "stiffness", "log"))
    table = {k: np.array([s[k] for s in steps], dtype=float)
             for k in ("nominal_pressure", *(name for _, name, _ in panels))}  # fmt: skip
    ok = np.array([bool(s["converged"]) for s in steps])
    px, xlabel = load_axis("p0", table["nominal_pressure"], units, modulus, h_rms)
    fig = _figure(figsize=(4.4 * len(panels), 3.8), layout="constrained")
    axes = fig.subplots(1, len(panels))
    for ax, (title, name, yscale) in zip(axes, panels, strict=True):
        kind = {"mean_gap": "gap", "stiffness": "stiffness"}.get(name)
        factor, label = (1.0, AREA_LABEL)
        if kind:
            factor, label = load_axis(kind, table[name], units, modulus, h_rms)
        _draw_steps(ax, table["nominal_pressure"] * px, table[name] * factor, ok)
        ax.set(xscale="log", yscale=yscale, xlabel=xlabel, ylabel=label, title=title)
    return _finish(fig, axes, path)


def _draw_steps(ax: Any, x: np.ndarray, y: np.ndarray, ok: np.ndarray) -> None:
    """The converged steps as a line of dots, the others as red crosses with a legend."""
    ax.plot(x[ok], y[ok], "o-")
    if (~ok).any():
        ax.plot(x[~ok], y[~ok], "rx", ms=10, label="NOT converged")
        ax.legend()


def plot_punch(
    path: str | None,
    steps: Sequence[dict[str, Any]],
    units: dict[str, str] | None = None,
    modulus: float = 1.0,
    h_rms: float = 0.0,
) -> Any:
    """Force against approach, and the interfacial stiffness per area (paper Eq. 2) against
    the nominal pressure ``F/L_p^2``, log-log (values that are not positive are left out),
    in the run's ``units`` (``length``, ``pressure``, ``force``) with SI prefixes (``um``,
    ``mN``, ``MPa/um``) where it has them; a run without units is drawn dimensionless as
    the periodic load plot is (:func:`load_axis`): ``p0/E*`` against ``delta/h_rms``."""
    from ..conventions.units import display_scale, typeset, typical_magnitude

    u = {"length": "", "pressure": "", "force": ""} | (units or {})
    ok = np.array([bool(s["converged"]) for s in steps])
    d, f, p, k = (
        np.array([s[name] for s in steps], dtype=float)
        for name in ("approach", "force", "nominal_pressure", "interfacial_stiffness")
    )
    scale, length = display_scale(typical_magnitude(d), u["length"])
    if not length:
        scale, length = 1 / (h_rms if h_rms > 0 else 1.0), ""
    px, xlabel = load_axis("p0", p, u, modulus, h_rms)
    left, fy, ylabel, title = p, px, xlabel, "load against approach"  # no force unit: p0
    if u["force"]:
        fy, shown = display_scale(typical_magnitude(f), u["force"])
        left, ylabel, title = f, f"force $F$ ({typeset(shown)})", "force against approach"
    kx, klabel = load_axis("stiffness", k, u, modulus, h_rms)
    fig = _figure(figsize=(9, 3.8), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    _draw_steps(ax1, d * scale, left * fy, ok)
    _draw_steps(ax2, p * px, k * kx, ok)
    approach = rf"approach $\delta$ ({typeset(length)})" if length else APPROACH_LABEL
    if not length and not h_rms > 0:  # a flat punch: no h_rms to scale by
        approach = r"approach $\delta$ (map's units)"
    ax1.set(xscale="log", yscale="log", xlabel=approach, ylabel=ylabel, title=title)
    ax2.set(xscale="log", yscale="log", xlabel=xlabel, ylabel=klabel,
            title="interfacial stiffness (paper Eq. 2)")  # fmt: skip
    return _finish(fig, (ax1, ax2), path)


def _in(unit: str, symbolic: str) -> str:
    """An axis label's unit: `` (GPa)``, or the symbolic one (`` (units of E*)``)."""
    return f" ({unit})" if unit else f" (units of {symbolic})"


def plot_experiment(
    path: str | None, pressure: np.ndarray, k_star: np.ndarray, k: np.ndarray
) -> Any:
    """``K`` (paper Eq. C3) and the measured ``K* = dp/ds`` against pressure, log-log."""
    fig = _figure(figsize=(5, 3.8), layout="constrained")
    ax = fig.subplots()
    ax.loglog(pressure, k_star, "s", mfc="none", label="$K^* = dp/ds$")
    ax.loglog(pressure, k, "o-", label="$K = K^*/(1 - K^* d/E')$")
    ax.set(xlabel="$p$", ylabel="stiffness per area", title="experiment (paper Eq. C3)")
    ax.legend()
    return _finish(fig, (ax,), path)


def plot_ensemble(
    path: str | None,
    summary: dict[str, np.ndarray],
    modulus: float,
    h_rms: float | Sequence[float] | np.ndarray | None = None,
    units: dict[str, str] | None = None,
) -> Any:
    """The mean over seeds with its standard error (a band and error bars) and every seed
    (grey) against the nominal pressure, log-log: the area fraction and, when computed, the
    stiffness per area.  In a run with ``units`` (``pressure``, ``length``) the pressures and
    stiffnesses are in them (:func:`load_axis`); otherwise ``p0/E*`` and ``K h_rms/E*``, each
    seed's stiffness scaled by its own rms height (``h_rms``: one per seed, or one for all;
    without it ``K/E*``, per unit of length), the mean and its error over the scaled seeds."""
    from .results import ensemble_statistics

    p = np.asarray(summary["nominal_pressure"])
    px, xlabel = load_axis("p0", p, units, modulus, 1.0)
    panels: list[tuple[str, Any, str, str]] = [("area_fraction", 1.0, "contact area", AREA_LABEL)]
    if "stiffness" in summary:
        seeds = np.atleast_2d(summary["stiffness"])
        kx, label = load_axis("stiffness", seeds, units, modulus, 1.0)
        factor: float | np.ndarray = kx
        title = "interfacial stiffness"
        if label == STIFFNESS_LABEL:  # dimensionless: each seed by its own rms height
            given = h_rms is not None
            own = np.broadcast_to(np.asarray(h_rms if given else 1.0, float), seeds.shape[:1])
            factor, label = own[:, None] / modulus, label if given else "$K/E^*$ (1/length)"
            title += r", each seed by its own $h_\mathrm{rms}$" if given else ""
        panels.append(("stiffness", factor, title, label))
    fig = _figure(figsize=(4.8 * len(panels), 4.0), layout="constrained")
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (name, factor, title, label) in zip(axes, panels, strict=True):
        rows = np.atleast_2d(summary[name]) * factor
        _draw_ensemble(ax, p * px, rows, ensemble_statistics(rows))
        ax.set(xscale="log", yscale="log", xlabel=xlabel, ylabel=label, title=title)
    axes[0].legend(fontsize=8)
    seeds_count = len(np.atleast_1d(summary["seeds"]))
    fig.suptitle(f"ensemble of {seeds_count} seeds: mean and its standard error")
    return _finish(fig, axes, path)


def _draw_ensemble(ax: Any, p: np.ndarray, rows: np.ndarray, stats: dict[str, Any]) -> None:
    """Every seed's line (``rows``: seeds x steps), and their mean with its standard error
    (``stats``: :func:`~petsc_contact.io.results.ensemble_statistics` of the rows)."""
    for i, row in enumerate(rows):
        ax.plot(p, row, "-", color="0.6", lw=0.8, label="each seed" if i == 0 else None)
    mean, sem = stats["mean"], stats["sem"]
    ax.fill_between(p, mean - sem, mean + sem, color="C0", alpha=0.25, lw=0)
    ax.errorbar(p, mean, yerr=sem, fmt="o-", color="C0", capsize=4, label="mean, +- s.e.m.")


def plot_theory(
    path: str | None,
    result: Any,
    modulus: float,
    runs: Sequence[tuple[str, dict[str, np.ndarray]]] = (),
    units: dict[str, str] | None = None,
) -> Any:
    """The map's spectrum with its fitted power law, and Persson's mean gap ``u_bar(p)``,
    stiffness ``K(p)`` with the finite-size crossover ``p_c`` marked, as printed (paper
    Eq. 13) and in the recipe of the paper's quoted values (``crossover_pressure_paper``),
    where it lies among the pressures drawn (the legend names only what is in view), and
    contact area ``A(p)/A0`` (``result.area_fraction``; ``None``, as in a theory file
    written before it was computed: a row of three panels without it).

    ``runs`` are simulations to draw beside the theory, in its units: ``(label, table)``
    with the arrays ``nominal_pressure``, ``mean_gap`` and, if computed, ``stiffness`` and
    ``area_fraction``.  ``units`` (``length``, ``pressure``) label the axes as
    :func:`load_axis` does: in them where the theory has them, dimensionless where it has
    none.
    """
    h = result.rms_height
    area = result.area_fraction is not None
    fig = _figure(figsize=(10, 7.4) if area else (13, 3.8), layout="constrained")
    axes = list(fig.subplots(2, 2).ravel() if area else fig.subplots(1, 3))
    ax1, ax2, ax3 = axes[:3]
    _draw_spectrum(ax1, result, (units or {}).get("length", ""))
    scales = {kind: load_axis(kind, values, units, modulus, h)
              for kind, values in (("p0", result.nominal_pressure), ("gap", result.mean_gap),
                                   ("stiffness", result.stiffness))}  # fmt: skip
    (px, xlabel), (gx, glabel), (kx, klabel) = scales.values()
    panels = [(ax2, "mean_gap", result.mean_gap * gx, "linear", glabel, "mean gap", "Persson"),
              (ax3, "stiffness", result.stiffness * kx, "log", klabel, "interfacial stiffness",
               "Persson")]  # fmt: skip
    if area:
        panels.append((axes[3], "area_fraction", result.area_fraction, "log", AREA_LABEL,
                       "contact area", PERSSON_AREA))  # fmt: skip
    factors = {"mean_gap": gx, "stiffness": kx, "area_fraction": 1.0}
    for ax, name, values, yscale, ylabel, title, label in panels:
        ax.set(xscale="log", yscale=yscale, xlabel=xlabel, ylabel=ylabel, title=title)
        ax.plot(result.nominal_pressure * px, values, "-", label=label)
        _draw_runs(ax, runs, name, px, factors[name])
    _mark_crossovers(ax3, result, px)
    for ax in axes[1:]:
        ax.legend(fontsize=8)
    return _finish(fig, axes, path)


def _draw_runs(
    ax: Any, runs: Sequence[tuple[str, dict[str, np.ndarray]]], name: str, px: float, factor: float
) -> None:
    """Each simulation's ``name`` against its nominal pressures (scaled by ``px`` and
    ``factor``) as open circles, where its table has it."""
    for label, table in runs:
        if name in table:
            x = np.asarray(table["nominal_pressure"]) * px
            ax.plot(x, np.asarray(table[name]) * factor, "o", mfc="none", label=label)


def _mark_crossovers(ax: Any, result: Any, px: float) -> None:
    """``p_c`` as printed and in the paper's recipe, each where it lies among the pressures
    drawn, the axis kept to the loads' range."""
    low, high = ax.get_xlim()
    for value, style, name in (
        (result.crossover_pressure, "--", "$p_c$ (Eq. 13 as printed)"),
        (result.crossover_pressure_paper, ":", r"$p_c$ (the paper's recipe)"),
    ):
        if low <= value * px <= high:
            ax.axvline(value * px, color="k", ls=style, label=name)
    ax.set_xlim(low, high)


def _draw_spectrum(ax: Any, result: Any, length: str) -> None:
    """The map's radial spectrum and its fitted power law, in ``length`` (``""``: unit-free)."""
    from ..conventions.units import typeset

    ax.loglog(result.wavevector, result.psd, ".", ms=3, label="map")
    lo, hi = result.fit_range
    q = np.geomspace(lo, hi, 20)
    inside = (result.wavevector >= lo) & (result.wavevector <= hi)
    slope = 2 + 2 * result.hurst_fit
    anchor = np.exp(np.mean(np.log(result.psd[inside] * result.wavevector[inside] ** slope)))
    ax.loglog(q, anchor * q**-slope, "k-", label=f"fit, H = {result.hurst_fit:.2f}")
    shown = typeset(length)
    ax.set(
        xlabel=f"wavevector $q${_in(f'1/{shown}' if length else '', '1/length')}",
        ylabel=f"$C(q)${_in(f'{shown}^4' if length else '', 'length^4')}",
        title="spectrum",
    )
    ax.legend()


MASKS = {  # two-colour maps: what 0 and 1 mean, and their colours
    "contact": (("open", "#e8e8e8"), ("in contact", "#b2182b")),
    "filled": (("measured", "#e8e8e8"), ("filled", "#2166ac")),
}
LOG_RANGE = 100.0  # ``scale="auto"`` draws pressure on a log scale past this max/min ratio


def plot_map(
    path: str | None,
    values: np.ndarray,
    lengths: tuple[float, float],
    length_unit: str = "",
    kind: str = "pressure",
    title: str = "",
    label: str = "",
    scale: str = "auto",
    vmin: float | None = None,
    vmax: float | None = None,
) -> Any:
    """A map of one field over the cell (physical axes with an SI prefix, equal aspect).

    Parameters
    ----------
    values
        The ``nx x ny`` field (rows are ``x``).
    lengths, length_unit
        The sides ``(Lx, Ly)`` and their unit (``""``: unit-free).
    kind
        ``pressure``, ``gap`` (from 0 to its 99.5th percentile), ``heights`` (centred on 0,
        to its 0.5th and 99.5th percentiles), or a mask: ``contact``, ``filled`` (two colours
        and a legend).  A colour bar with arrows says values lie beyond its range.
    label
        The colour bar's label (with the values' unit).
    scale
        ``linear``, ``log``, or ``auto``: log for a pressure whose positive values span more
        than :data:`LOG_RANGE` (from their first percentile; zero pressure, out of contact,
        drawn in grey).
    vmin, vmax
        The colour range (default: the values').
    """
    from matplotlib.colors import LogNorm

    from ..conventions.units import display_scale, typeset

    lx, ly = lengths
    factor, unit = display_scale(max(lx, ly), length_unit)
    fig = _figure(figsize=(5.8, 4.8), layout="constrained")
    ax = fig.subplots()
    extent = (0.0, lx * factor, 0.0, ly * factor)
    show = dict(origin="lower", extent=extent, interpolation="nearest", aspect="equal")
    if kind in MASKS:
        _draw_mask(ax, values, MASKS[kind], show)
    else:
        data, norm = _colour_range(np.asarray(values, dtype=float), kind, scale, vmin, vmax)
        cmap = _colour_map("RdBu_r" if kind == "heights" else "viridis")
        image = ax.imshow(data.T, cmap=cmap, norm=norm, **show)
        log = " (log scale)" if isinstance(norm, LogNorm) else ""
        fig.colorbar(image, ax=ax, label=label + log, shrink=0.9, extend=_beyond(data, norm))
    suffix = f" ({typeset(unit)})" if unit else " (unit of --length)"
    ax.set(xlabel="x" + suffix, ylabel="y" + suffix, title=title)
    if path is not None:
        save(fig, path)
    return fig


def _draw_mask(ax: Any, values: np.ndarray, mask: Any, show: dict[str, Any]) -> None:
    """A two-colour map (one of :data:`MASKS`) with a legend giving the share of ones."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    (off, off_colour), (on, on_colour) = mask
    cmap = ListedColormap([off_colour, on_colour])
    ax.imshow(values.T.astype(float), cmap=cmap, vmin=0, vmax=1, **show)
    share = float(np.mean(values))
    handles = [
        Patch(color=off_colour, label=off),
        Patch(color=on_colour, label=f"{on}, {100 * share:.3g}%"),
    ]
    ax.legend(handles=handles, loc="upper right", framealpha=0.9, fontsize=8)


def _colour_range(
    data: np.ndarray, kind: str, scale: str, vmin: float | None, vmax: float | None
) -> tuple[np.ndarray, Any]:
    """The values to draw and their colour normalisation (:func:`plot_map`); on a log scale
    the values that are not positive are masked (drawn grey)."""
    from matplotlib.colors import LogNorm, Normalize

    positive = data[data > 0]
    use_log = scale == "log" or (
        scale == "auto"
        and kind == "pressure"
        and positive.size > 0
        and positive.max() > LOG_RANGE * positive.min()
    )
    if use_log:
        if positive.size == 0:
            raise ValueError("a log scale needs positive values; use --scale linear")
        low = vmin if vmin is not None else float(np.percentile(positive, 1))
        norm = LogNorm(vmin=low, vmax=vmax if vmax is not None else positive.max())
        return np.ma.masked_less_equal(data, 0), norm
    if kind == "heights":  # centred on the mean plane, robust to a few spikes
        bound = float(np.max(np.abs(np.percentile(data, [0.5, 99.5]))))
        low, top = -bound, bound
    else:  # a gap: from zero (contact) to its 99.5th percentile, robust to a few spikes
        low, top = min(0.0, data.min()), float(np.percentile(data, 99.5))
    return data, Normalize(vmin=low if vmin is None else vmin, vmax=top if vmax is None else vmax)


def _beyond(data: np.ndarray, norm: Any) -> str:
    """The colour bar's ``extend``: which ends have values beyond the colour range."""
    slack = 1e-9 * float(np.ptp(data.compressed() if np.ma.isMA(data) else data))
    low = norm.vmin is not None and data.min() < norm.vmin - slack
    high = norm.vmax is not None and data.max() > norm.vmax + slack
    return {(True, True): "both", (True, False): "min", (False, True): "max"}.get(
        (low, high), "neither"
    )


def _colour_map(name: str) -> Any:
    """The colour map ``name``, grey where a value is masked (a log scale's zeros)."""
    import matplotlib

    return matplotlib.colormaps[name].with_extremes(bad="#d9d9d9")


REFERENCE = "reference solve's\nnatural residual"


def plot_compare(path: str | None, trajectories: Sequence[Any], reference: dict[str, Any]) -> Any:
    """Pressure error and natural residual against wall time, log-log, one line per solver
    (:class:`~petsc_contact.workflows.compare.Trajectory`), and in grey, on the residual's
    panel only, the natural residual of the reference they are measured against: how far
    that solve itself is from exact (its pressure error is zero by definition)."""
    fig = _figure(figsize=(11.5, 4), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    for t in trajectories:
        tm = np.maximum(np.asarray(t.time), 1e-4)
        style = "-" if t.converged else ":"
        ax1.loglog(tm, np.maximum(t.pressure_error, 1e-17), style, label=t.name)
        ax2.loglog(tm, np.maximum(t.natural_residual, 1e-17), style, label=t.name)
    ax2.axhline(reference["natural_residual"], color="gray", lw=0.8, label=REFERENCE)
    ax1.set(
        xlabel="wall time (s)",
        ylabel=r"$\|p - p_\mathrm{ref}\| / \|p_\mathrm{ref}\|$",
        title="pressure error (dotted: not converged)",
    )
    ax2.set(xlabel="wall time (s)", ylabel=r"rms$(\min(k g, p))/p_0$", title="natural residual")
    fig.legend(*ax2.get_legend_handles_labels(), loc="outside right upper", fontsize=8)
    return _finish(fig, (ax1, ax2), path)


def save(fig: Any, path: str) -> None:
    """Write ``fig`` to ``path`` (:func:`plot_file`'s: ``X`` is ``X.png``) whole
    (:func:`~petsc_contact.io.atomic.replaced`: a full disk leaves no torn figure), its
    format named by the extension; a failure to write is one
    :class:`~petsc_contact.io.atomic.StorageError`."""
    from .atomic import replaced, storage

    path = plot_file(path)
    with storage(path), replaced(path) as temporary:
        fig.savefig(temporary, dpi=110, format=os.path.splitext(path)[1][1:].lower())


def _figure(**options: Any) -> Any:
    """A figure of its own (matplotlib's object interface: no pyplot state)."""
    from matplotlib.figure import Figure

    return Figure(**options)


def _finish(fig: Any, axes: Sequence[Any], path: str | None) -> Any:
    """Grids, readable log ticks (:func:`_few_decades`), and the figure written to ``path``."""
    for ax in axes:
        _say_nothing_drawn(ax)
        ax.grid(True, which="both", alpha=0.3)
        _few_decades(ax.xaxis, ax.get_xlim())
        _few_decades(ax.yaxis, ax.get_ylim())
    if path is not None:
        save(fig, path)
    return fig


def _say_nothing_drawn(ax: Any) -> None:
    """A panel of lines with no point it can draw (every value NaN, as the stiffness at full
    contact, or not positive on a log axis) says so, on linear axes, instead of failing."""
    points = [np.column_stack([line.get_xdata(), line.get_ydata()]) for line in ax.lines]
    xy = np.concatenate(points).astype(float) if points else np.empty((0, 2))
    for k, log in enumerate((ax.get_xscale() == "log", ax.get_yscale() == "log")):
        if log:
            xy = xy[xy[:, k] > 0]
    if ax.lines and not np.isfinite(xy).all(axis=1).any():
        ax.set(xscale="linear", yscale="linear", xticks=[], yticks=[])
        ax.text(0.5, 0.5, "no value to draw\n(NaN: e.g. at full contact)", ha="center",
                va="center", transform=ax.transAxes, color="0.4")  # fmt: skip


def _few_decades(axis: Any, limits: tuple[float, float]) -> None:
    """A log axis spanning less than two decades ticked at 1, 2 and 5 times the powers of ten
    as plain numbers (``0.2``, ``50``), where matplotlib labels its minor ticks too and they
    run into each other."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    low, high = sorted(limits)
    if axis.get_scale() != "log" or low <= 0 or high > 100 * low:
        return
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())
