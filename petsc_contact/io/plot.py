"""PNG summaries of load sweeps (periodic: area and mean gap; punch: force and stiffness)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def plot_sweep(path: str, steps: Sequence[dict[str, Any]], modulus: float, h_rms: float) -> None:
    """Two panels: ``A/A0`` vs ``p0/E*`` (log-log) and ``p0/E*`` vs ``u_bar/h_rms`` (semi-log).

    Steps that did not converge are drawn as red crosses.
    """
    plt = _pyplot()
    p = np.array([s["nominal_pressure"] for s in steps]) / modulus
    area = np.array([s["area_fraction"] for s in steps])
    gap = np.array([s["mean_gap"] for s in steps]) / (h_rms if h_rms > 0 else 1.0)
    ok = np.array([bool(s["converged"]) for s in steps])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), constrained_layout=True)
    ax1.loglog(p[ok], area[ok], "o-", label="converged")
    ax2.semilogy(gap[ok], p[ok], "o-")
    if (~ok).any():
        ax1.loglog(p[~ok], np.maximum(area[~ok], 1e-12), "rx", ms=10, label="NOT converged")
        ax2.semilogy(gap[~ok], p[~ok], "rx", ms=10)
        ax1.legend()
    ax1.set(xlabel="$p_0/E^*$", ylabel="$A/A_0$", title="contact area")
    ax2.set(xlabel=r"$\bar u/h_\mathrm{rms}$", ylabel="$p_0/E^*$", title="mean gap")
    _finish(fig, (ax1, ax2), path)


def plot_punch(path: str, steps: Sequence[dict[str, Any]]) -> None:
    """Two panels: force vs approach, and interfacial stiffness per area vs nominal pressure."""
    plt = _pyplot()
    ok = np.array([bool(s["converged"]) for s in steps])
    d = np.array([s["approach"] for s in steps])
    f = np.array([s["force"] for s in steps])
    p = np.array([s["nominal_pressure"] for s in steps])
    k = np.array([s["interfacial_stiffness"] for s in steps])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), constrained_layout=True)
    ax1.plot(d[ok], f[ok], "o-")
    ax2.loglog(p[ok & (p > 0)], k[ok & (p > 0)], "o-")
    if (~ok).any():
        ax1.plot(d[~ok], f[~ok], "rx", ms=10, label="NOT converged")
        ax1.legend()
    ax1.set(xlabel=r"approach $\delta$", ylabel="force $F$", title="punch")
    ax2.set(xlabel="$F/L_p^2$", ylabel="$K$ (per area)", title="interfacial stiffness, Eq. 2")
    _finish(fig, (ax1, ax2), path)


def plot_experiment(path: str, pressure: np.ndarray, k_star: np.ndarray, k: np.ndarray) -> None:
    """``K`` (paper Eq. C3) and the measured ``K* = dp/ds`` against pressure, log-log."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.8), constrained_layout=True)
    ax.loglog(pressure, k_star, "s", mfc="none", label="$K^* = dp/ds$")
    ax.loglog(pressure, k, "o-", label="$K = K^*/(1 - K^* d/E')$")
    ax.set(xlabel="$p$", ylabel="stiffness per area", title="experiment (paper Eq. C3)")
    ax.legend()
    _finish(fig, (ax,), path)


def plot_ensemble(path: str, summary: dict[str, np.ndarray], modulus: float) -> None:
    """Mean over seeds with its standard error against ``p0/E*``: the area fraction and, when
    computed, the stiffness per area (log-log)."""
    plt = _pyplot()
    p = np.asarray(summary["nominal_pressure"]) / modulus
    names = [q for q in ("area_fraction", "stiffness") if f"{q}_mean" in summary]
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.8), squeeze=False)
    for ax, q in zip(axes[0], names, strict=True):
        mean, sem = summary[f"{q}_mean"], summary[f"{q}_sem"]
        ax.errorbar(p, mean, yerr=sem, fmt="o-", capsize=2)
        ax.set(xscale="log", yscale="log", xlabel="$p_0/E^*$", ylabel=q.replace("_", " "))
        ax.set_title(f"mean over {int(np.max(summary[f'{q}_count']))} seeds, +- s.e.m.")
    fig.set_layout_engine("constrained")
    _finish(fig, list(axes[0]), path)


def plot_theory(path: str, result: Any, modulus: float) -> None:
    """Two panels: the map's spectrum with its fitted power law, and Persson's ``K(p)`` with
    the finite-size crossover ``p_c`` (both variants) marked."""
    plt = _pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), constrained_layout=True)
    ax1.loglog(result.wavevector, result.psd, ".", ms=3, label="map")
    lo, hi = result.fit_range
    q = np.geomspace(lo, hi, 20)
    inside = (result.wavevector >= lo) & (result.wavevector <= hi)
    anchor = np.exp(
        np.mean(
            np.log(result.psd[inside] * result.wavevector[inside] ** (2 + 2 * result.hurst_fit))
        )
    )
    ax1.loglog(
        q, anchor * q ** (-2 - 2 * result.hurst_fit), "k-", label=f"H = {result.hurst_fit:.2f}"
    )
    ax1.set(xlabel="$q$", ylabel="$C(q)$", title="spectrum")
    ax1.legend()
    p = result.nominal_pressure / modulus
    ax2.loglog(p, result.stiffness * result.rms_height / modulus, "-", label="Persson")
    for value, style, name in (
        (result.crossover_pressure, "--", "$p_c$ (Eq. 13)"),
        (result.crossover_pressure_appendix, ":", r"$p_c$ ($q_r \approx \pi/L$)"),
    ):
        ax2.axvline(value / modulus, color="k", ls=style, label=name)
    ax2.set(xlabel="$p_0/E^*$", ylabel=r"$K h_\mathrm{rms}/E^*$", title="interfacial stiffness")
    ax2.legend()
    _finish(fig, (ax1, ax2), path)


def plot_field(
    path: str,
    values: np.ndarray,
    lengths: float | tuple[float, float],
    title: str,
    label: str,
    contact: bool = False,
    unit: str = "",
) -> None:
    """A map of one field over the cell ``[0, Lx] x [0, Ly]`` (physical axes, equal aspect)
    with a colour bar; ``unit`` labels the axes."""
    lx, ly = lengths if isinstance(lengths, tuple) else (lengths, lengths)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.6, 4.6), constrained_layout=True)
    cmap = "Greys" if contact else "viridis"
    image = ax.imshow(
        values.T, origin="lower", extent=(0, lx, 0, ly), cmap=cmap, interpolation="nearest"
    )
    suffix = f" ({unit})" if unit else ""
    ax.set(xlabel="x" + suffix, ylabel="y" + suffix, title=title)
    fig.colorbar(image, ax=ax, label=label)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _finish(fig: Any, axes: Sequence[Any], path: str) -> None:
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    fig.savefig(path, dpi=110)
    fig.clf()
    import matplotlib.pyplot as plt

    plt.close(fig)
