"""Fig. 2: the finite-size prefactors 1/theta0, 1/theta1 and 1/theta against H (theory only)."""

import argparse

import numpy as np

from petsc_contact.paper import figures
from petsc_contact.physics import theory


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--output", default="fig2", help="prefix of the PNG and HDF5 files")
    args = ap.parse_args(argv)
    h = np.linspace(0.02, 1.0, 99)
    inv0, inv1 = theory.inverse_theta_parts(h)
    figures.save(
        f"{args.output}.h5",
        {"hurst": h, "inverse_theta0": inv0, "inverse_theta1": inv1, "theta": theory.theta(h)},
        gamma=theory.GAMMA,
        nayak_beta=theory.NAYAK_BETA,
        kappa0=theory.KAPPA0,
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.8), constrained_layout=True)
    ax.plot(h, inv0, label=r"$1/\theta_0$ (Hertz mesoasperity)")
    ax.plot(h, inv1, label=r"$1/\theta_1$ (microroughness)")
    ax.plot(h, inv0 + inv1, "k", label=r"$1/\theta$")
    title = "the paper's Fig. 5: $1/\\theta(H)$ (App. B)"
    ax.set(xlabel="Hurst exponent $H$", ylabel="prefactor", title=title)
    ax.legend()
    ax.grid(alpha=0.3)
    fig.savefig(f"{args.output}.png", dpi=120)
    for hh in (0.3, 0.5, 0.7, 0.8):
        print(f"H = {hh}: theta = {float(theory.theta(hh)):.4f}")
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
