"""Spectra: Eq. 5 against a realisation, (a) without and (b) with roll-off; q0, qr, q1 marked.

The prescribed line is Eq. 5 with the ``C0`` of the rms slope the surface was drawn for (the
surfaces' target, as in every figure's Persson curve), not rescaled to the realisation: where
the two differ, the realisation scatters.  Each panel gives the realised rms slope beside the
target, and the realised ``h_rms`` against the spectrum's.
"""

import argparse

import numpy as np
from mpi4py import MPI

from petsc_contact.conventions.grid import Grid, fundamental_wavevector
from petsc_contact.devices.fft import make_fft
from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import RMS_SLOPE
from petsc_contact.physics.surface import radial_psd, rms_of


def spectra(grid_n: int, hurst: float, ratio: float, cutoff: float, seed: int) -> dict:
    """The realised radial PSD of one surface and the prescribed spectrum it was drawn from
    (Eq. 5 at the rms slope :data:`RMS_SLOPE`), with the realised and prescribed rms slope and
    ``h_rms``."""
    h, h_rms = figures.surface(grid_n, hurst, ratio, cutoff, seed, RMS_SLOPE)
    grid = Grid(grid_n, 1.0, MPI.COMM_SELF)
    fft = make_fft(grid)
    q, c = radial_psd(grid, fft, h)
    qi, ci = figures.ideal_spectrum(1.0, hurst, ratio, cutoff, rms_slope=RMS_SLOPE)
    return {
        "q": q,
        "psd": c,
        "q_prescribed": qi,
        "psd_prescribed": ci,
        "h_rms": h_rms,
        "h_rms_prescribed": np.sqrt(2 * np.pi * np.trapezoid(qi * ci, qi)),
        "rms_slope": rms_of(grid, fft, h, slope=True),
    }


def panel(ax, data: dict, ratio: float, cutoff: float, title: str) -> None:
    q, c = data["q"], data["psd"]
    ok = c > 1e-20 * c.max()  # beyond q1 only FFT rounding is left
    ax.loglog(q[ok], c[ok], ".", ms=3, label="realised (radial average)")
    ax.loglog(
        data["q_prescribed"],
        data["psd_prescribed"],
        "k-",
        label=f"prescribed, Eq. 5 at rms slope {RMS_SLOPE:g}",
    )
    ax.text(
        0.03,
        0.03,
        f"rms slope: realised {data['rms_slope']:.4f}, target {RMS_SLOPE:g}\n"
        f"$h_\\mathrm{{rms}}$: realised / prescribed = "
        f"{data['h_rms'] / data['h_rms_prescribed']:.2f}",
        transform=ax.transAxes,
        fontsize=8,
        va="bottom",
    )
    q0 = fundamental_wavevector(1.0)
    marks = {"$q_0$": q0, "$q_1$": cutoff * q0}
    if ratio > 1:
        marks["$q_r$"] = ratio * q0
    for label, value in marks.items():
        ax.axvline(value, color="0.5", lw=0.8, ls="--")
        ax.text(value, 0.97, label, transform=ax.get_xaxis_transform(), ha="center", va="top")
    ax.set(xlabel="$q$ (in $1/L$, $L$ the cell's side)", ylabel="$C(q)$", title=title)
    ax.grid(alpha=0.3, which="both")


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=1024, help="pixels per side (default 1024)")
    ap.add_argument("--hurst", type=float, default=0.7, help="Hurst exponent H (default 0.7)")
    ap.add_argument("--rolloff-ratio", type=float, default=8.0, help="L/lambda_r of panel (b)")
    ap.add_argument("--cutoff-ratio", type=float, default=None, help="default grid/4")
    ap.add_argument("--seed", type=int, default=1, help="surface seed (default 1)")
    ap.add_argument("--output", default="fig5", help="prefix of the PNG and HDF5 files")
    args = ap.parse_args(argv)
    cutoff = args.cutoff_ratio or args.grid / 4
    ratios = {"a": 1.0, "b": args.rolloff_ratio}
    data = {k: spectra(args.grid, args.hurst, r, cutoff, args.seed) for k, r in ratios.items()}
    figures.save(
        f"{args.output}.h5",
        {k: {n: v for n, v in d.items() if n != "h_rms"} for k, d in data.items()},
        rms_slope_target=RMS_SLOPE,
        hurst=args.hurst,
        rolloff_ratios=[ratios["a"], ratios["b"]],
        cutoff_ratio=cutoff,
        seed=args.seed,
        grid=args.grid,
        h_rms=[float(data["a"]["h_rms"]), float(data["b"]["h_rms"])],
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True, sharey=False)
    for ax, (key, ratio) in zip(axes, ratios.items(), strict=True):
        roll = "without roll-off" if ratio <= 1 else f"with roll-off, $L/\\lambda_r$ = {ratio:g}"
        panel(ax, data[key], ratio, cutoff, f"({key}) H = {args.hurst}, {roll}")
    axes[0].legend(loc="upper right", bbox_to_anchor=(1.0, 0.92))  # below the q marks
    fig.suptitle(f"the paper's Fig. 4 (Eq. 5's spectrum), one {args.grid}$^2$ realisation")
    fig.savefig(f"{args.output}.png", dpi=120)
    for key, d in data.items():
        print(
            f"({key}) h_rms = {d['h_rms']:.6g} (prescribed {d['h_rms_prescribed']:.6g}, ratio "
            f"{d['h_rms'] / d['h_rms_prescribed']:.3f}), rms slope = {d['rms_slope']:.4f} "
            f"(target {RMS_SLOPE:g})"
        )
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
