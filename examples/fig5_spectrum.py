"""Fig. 5: the prescribed power spectrum (Eq. 5) against the realised one of a generated surface."""

import argparse

from mpi4py import MPI

from petsc_contact import scenes
from petsc_contact.fft import make_fft
from petsc_contact.grid import Grid
from petsc_contact.surface import radial_psd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=1024)
    ap.add_argument("--hurst", type=float, default=0.7)
    ap.add_argument("--rolloff-ratio", type=float, default=8.0)
    ap.add_argument("--cutoff-ratio", type=float, default=None, help="default grid/4")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--output", default="fig5")
    args = ap.parse_args()
    cutoff = args.cutoff_ratio or args.grid / 4
    h, h_rms = scenes.surface(args.grid, args.hurst, args.rolloff_ratio, cutoff, args.seed)
    grid = Grid(args.grid, 1.0, MPI.COMM_SELF)
    q, c = radial_psd(grid, make_fft(grid), h)
    qi, ci = scenes.ideal_spectrum(1.0, args.hurst, args.rolloff_ratio, cutoff, h_rms)
    scenes.save(
        f"{args.output}.h5",
        {"q": q, "psd": c, "q_prescribed": qi, "psd_prescribed": ci},
        hurst=args.hurst,
        rolloff_ratio=args.rolloff_ratio,
        cutoff_ratio=cutoff,
        seed=args.seed,
        grid=args.grid,
        h_rms=h_rms,
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.8), constrained_layout=True)
    ok = c > 1e-20 * c.max()  # beyond q1 only FFT rounding is left
    ax.loglog(q[ok], c[ok], ".", ms=3, label="realised (radial average)")
    ax.loglog(qi, ci, "k-", label="prescribed, Eq. 5")
    ax.set(xlabel="$q$ (1/L)", ylabel="$C(q)$", title=f"Fig. 5, H = {args.hurst}")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    fig.savefig(f"{args.output}.png", dpi=120)
    print(f"h_rms = {h_rms:.4g}; wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
