"""PNG summary of a load sweep: contact area and mean gap against nominal pressure."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np


def plot_sweep(path: str, steps: Sequence[dict[str, Any]], modulus: float, h_rms: float) -> None:
    """Two panels: ``A/A0`` vs ``p0/E*`` (log-log) and ``p0/E*`` vs ``u_bar/h_rms`` (semi-log).

    Steps that did not converge are drawn as red crosses.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
    fig.savefig(path, dpi=110)
    plt.close(fig)
