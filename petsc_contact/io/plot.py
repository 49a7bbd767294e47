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


def plot_sweep(
    path: str | None, steps: Sequence[dict[str, Any]], modulus: float, h_rms: float
) -> Any:
    """``A/A0`` against ``p0/E*`` (log-log), ``p0/E*`` against ``u_bar/h_rms`` (semi-log) and,
    when the steps have it, the exact stiffness ``K h_rms/E*`` against ``p0/E*`` (log-log).

    Steps that did not converge are drawn as red crosses.
    """
    p = np.array([s["nominal_pressure"] for s in steps]) / modulus
    area = np.array([s["area_fraction"] for s in steps])
    scale = h_rms if h_rms > 0 else 1.0
    gap = np.array([s["mean_gap"] for s in steps]) / scale
    ok = np.array([bool(s["converged"]) for s in steps])
    stiffness = all("stiffness" in s for s in steps)
    fig = _figure(figsize=(13 if stiffness else 9, 3.8), layout="constrained")
    axes = fig.subplots(1, 3 if stiffness else 2)
    panels = [(axes[0], area, "loglog"), (axes[1], None, "semilogy")]
    if stiffness:
        k = np.array([s["stiffness"] for s in steps]) * scale / modulus
        panels.append((axes[2], k, "loglog"))
    for ax, y, kind in panels:
        xs, ys = (gap, p) if y is None else (p, y)
        getattr(ax, kind)(xs[ok], ys[ok], "o-", label="converged")
        if (~ok).any():
            getattr(ax, kind)(xs[~ok], np.abs(ys[~ok]) + 1e-300, "rx", ms=10, label="NOT converged")
            ax.legend()
    axes[0].set(xlabel="$p_0/E^*$", ylabel="$A/A_0$", title="contact area")
    axes[1].set(xlabel=r"$\bar u/h_\mathrm{rms}$", ylabel="$p_0/E^*$", title="mean gap")
    if stiffness:
        axes[2].set(
            xlabel="$p_0/E^*$", ylabel=r"$K h_\mathrm{rms}/E^*$", title="interfacial stiffness"
        )
    return _finish(fig, axes, path)


def plot_punch(
    path: str | None, steps: Sequence[dict[str, Any]], units: dict[str, str] | None = None
) -> Any:
    """Force against approach, and the interfacial stiffness per area against the nominal
    pressure; ``units`` (``length``, ``pressure``, ``force``) label the axes."""
    from ..conventions.units import METRES, PASCALS, display_force, display_unit

    u = {"length": "", "pressure": "", "force": ""} | (units or {})
    ok = np.array([bool(s["converged"]) for s in steps])
    d = np.array([s["approach"] for s in steps])
    f = np.array([s["force"] for s in steps])
    p = np.array([s["nominal_pressure"] for s in steps])
    k = np.array([s["interfacial_stiffness"] for s in steps])
    if u["length"] and u["pressure"]:  # in newtons and lengths with SI prefixes: mN, um
        f, u["force"] = display_force(f * PASCALS[u["pressure"]] * METRES[u["length"]] ** 2)
        scale, u["length"] = display_unit(float(np.max(np.abs(d), initial=0.0)), u["length"])
        d, k = d * scale, k / scale
    fig = _figure(figsize=(9, 3.8), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(d[ok], f[ok], "o-")
    ax2.loglog(p[ok & (p > 0)], k[ok & (p > 0)], "o-")
    if (~ok).any():
        ax1.plot(d[~ok], f[~ok], "rx", ms=10, label="NOT converged")
        ax1.legend()
    per = f"{u['pressure']}/{u['length']}" if u["pressure"] and u["length"] else ""
    ax1.set(
        xlabel=rf"approach $\delta${_in(u['length'], 'length')}",
        ylabel=f"force $F${_in(u['force'], 'E* length^2')}",
        title="punch",
    )
    ax2.set(
        xlabel=f"$F/L_p^2${_in(u['pressure'], 'E*')}",
        ylabel=f"$K${_in(per, 'E*/length')}",
        title="interfacial stiffness, Eq. 2",
    )
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


def plot_ensemble(path: str | None, summary: dict[str, np.ndarray], modulus: float) -> Any:
    """Mean over seeds with its standard error against ``p0/E*``: the area fraction and, when
    computed, the stiffness per area (log-log)."""
    p = np.asarray(summary["nominal_pressure"]) / modulus
    names = [q for q in ("area_fraction", "stiffness") if f"{q}_mean" in summary]
    fig = _figure(figsize=(4.5 * len(names), 3.8))
    axes = fig.subplots(1, len(names), squeeze=False)
    for ax, q in zip(axes[0], names, strict=True):
        mean, sem = summary[f"{q}_mean"], summary[f"{q}_sem"]
        ax.errorbar(p, mean, yerr=sem, fmt="o-", capsize=2)
        ax.set(xscale="log", yscale="log", xlabel="$p_0/E^*$", ylabel=q.replace("_", " "))
        ax.set_title(f"mean over {int(np.max(summary[f'{q}_count']))} seeds, +- s.e.m.")
    fig.set_layout_engine("constrained")
    return _finish(fig, list(axes[0]), path)


def plot_theory(
    path: str | None,
    result: Any,
    modulus: float,
    runs: Sequence[tuple[str, dict[str, np.ndarray]]] = (),
    units: dict[str, str] | None = None,
) -> Any:
    """The map's spectrum with its fitted power law, and Persson's mean gap ``u_bar(p)`` and
    stiffness ``K(p)`` with the finite-size crossover ``p_c`` marked, as printed (paper
    Eq. 13) and in the recipe of the paper's quoted values (``crossover_pressure_paper``).

    ``runs`` are simulations to draw beside the theory: ``(label, table)`` with the arrays
    ``nominal_pressure``, ``mean_gap`` and, if computed, ``stiffness`` (a run's file).
    ``units`` (``length``) label the spectrum's axes.
    """
    length = (units or {}).get("length", "")
    h = result.rms_height if result.rms_height > 0 else 1.0
    fig = _figure(figsize=(13, 3.8), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(1, 3)
    ax1.loglog(result.wavevector, result.psd, ".", ms=3, label="map")
    lo, hi = result.fit_range
    q = np.geomspace(lo, hi, 20)
    inside = (result.wavevector >= lo) & (result.wavevector <= hi)
    slope = 2 + 2 * result.hurst_fit
    anchor = np.exp(np.mean(np.log(result.psd[inside] * result.wavevector[inside] ** slope)))
    ax1.loglog(q, anchor * q**-slope, "k-", label=f"H = {result.hurst_fit:.2f}")
    ax1.set(
        xlabel=f"$q${_in(f'1/{length}' if length else '', '1/length')}",
        ylabel=f"$C(q)${_in(f'{length}^4' if length else '', 'length^4')}",
        title="spectrum",
    )
    ax1.legend()
    p = result.nominal_pressure / modulus
    ax2.semilogx(p, result.mean_gap / h, "-", label="Persson")
    ax3.loglog(p, result.stiffness * h / modulus, "-", label="Persson")
    for label, table in runs:
        sim_p = np.asarray(table["nominal_pressure"]) / modulus
        ax2.semilogx(sim_p, np.asarray(table["mean_gap"]) / h, "o", mfc="none", label=label)
        if "stiffness" in table:
            sim_k = np.asarray(table["stiffness"]) * h / modulus
            ax3.loglog(sim_p, sim_k, "o", mfc="none", label=label)
    for value, style, name in (
        (result.crossover_pressure, "--", "$p_c$ (Eq. 13 as printed)"),
        (result.crossover_pressure_paper, ":", r"$p_c$ (the paper's recipe)"),
    ):
        ax3.axvline(value / modulus, color="k", ls=style, label=name)
    ax2.set(xlabel="$p_0/E^*$", ylabel=r"$\bar u/h_\mathrm{rms}$", title="mean gap")
    ax3.set(xlabel="$p_0/E^*$", ylabel=r"$K h_\mathrm{rms}/E^*$", title="interfacial stiffness")
    ax2.legend(fontsize=8)
    ax3.legend(fontsize=8)
    return _finish(fig, (ax1, ax2, ax3), path)


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
    from matplotlib.colors import ListedColormap, LogNorm, Normalize
    from matplotlib.patches import Patch

    from ..conventions.units import display_unit

    lx, ly = lengths
    factor, unit = display_unit(max(lx, ly), length_unit or None)
    fig = _figure(figsize=(5.8, 4.8), layout="constrained")
    ax = fig.subplots()
    extent = (0.0, lx * factor, 0.0, ly * factor)
    show = dict(origin="lower", extent=extent, interpolation="nearest", aspect="equal")
    if kind in MASKS:
        (off, off_colour), (on, on_colour) = MASKS[kind]
        ax.imshow(values.T.astype(float), cmap=ListedColormap([off_colour, on_colour]),
                  vmin=0, vmax=1, **show)  # fmt: skip
        share = float(np.mean(values))
        handles = [
            Patch(color=off_colour, label=off),
            Patch(color=on_colour, label=f"{on}, {100 * share:.3g}%"),
        ]
        ax.legend(handles=handles, loc="upper right", framealpha=0.9, fontsize=8)
    else:
        data = np.asarray(values, dtype=float)
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
            norm: Any = LogNorm(vmin=low, vmax=vmax if vmax is not None else positive.max())
            data = np.ma.masked_less_equal(data, 0)
        elif kind == "heights":  # centred on the mean plane, robust to a few spikes
            bound = float(np.max(np.abs(np.percentile(data, [0.5, 99.5]))))
            norm = Normalize(
                vmin=-bound if vmin is None else vmin, vmax=bound if vmax is None else vmax
            )
        else:  # a gap: from zero (contact) to its 99.5th percentile, robust to a few spikes
            top = float(np.percentile(data, 99.5)) if vmax is None else vmax
            norm = Normalize(vmin=vmin if vmin is not None else min(0.0, data.min()), vmax=top)
        cmap = _colour_map("RdBu_r" if kind == "heights" else "viridis")
        cmap.set_bad("#d9d9d9")
        image = ax.imshow(data.T, cmap=cmap, norm=norm, **show)
        slack = 1e-9 * float(np.ptp(data.compressed() if np.ma.isMA(data) else data))
        low_cut = norm.vmin is not None and data.min() < norm.vmin - slack
        high_cut = norm.vmax is not None and data.max() > norm.vmax + slack
        fig.colorbar(
            image,
            ax=ax,
            label=label + (" (log scale)" if use_log else ""),
            shrink=0.9,
            extend={(True, True): "both", (True, False): "min", (False, True): "max"}.get(
                (low_cut, high_cut), "neither"
            ),
        )
    suffix = f" ({unit})" if unit else " (unit of --length)"
    ax.set(xlabel="x" + suffix, ylabel="y" + suffix, title=title)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def _colour_map(name: str) -> Any:
    import matplotlib

    return matplotlib.colormaps[name].copy()


def plot_compare(path: str | None, trajectories: Sequence[Any], reference: dict[str, Any]) -> Any:
    """Pressure error and natural residual against wall time, log-log, one line per solver
    (:class:`~petsc_contact.workflows.compare.Trajectory`)."""
    fig = _figure(figsize=(10, 4), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    for t in trajectories:
        tm = np.maximum(np.asarray(t.time), 1e-4)
        style = "-" if t.converged else ":"
        ax1.loglog(tm, np.maximum(t.pressure_error, 1e-17), style, label=t.name)
        ax2.loglog(tm, np.maximum(t.natural_residual, 1e-17), style, label=t.name)
    ax1.axhline(reference["natural_residual"], color="gray", lw=0.8)
    ax1.set(
        xlabel="wall time (s)",
        ylabel=r"$\|p - p_\mathrm{ref}\| / \|p_\mathrm{ref}\|$",
        title="pressure error (dotted: not converged)",
    )
    ax2.set(xlabel="wall time (s)", ylabel=r"rms$(\min(k g, p))/p_0$", title="natural residual")
    ax2.legend(fontsize=8)
    return _finish(fig, (ax1, ax2), path)


def _figure(**options: Any) -> Any:
    """A figure of its own (matplotlib's object interface: no pyplot state)."""
    from matplotlib.figure import Figure

    return Figure(**options)


def _finish(fig: Any, axes: Sequence[Any], path: str | None) -> Any:
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig
