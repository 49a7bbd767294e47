"""Eq. 12's factor traced: the finite-size regime's contact fields against the assumptions of
the paper's scaling theory (Appendix B), at the loads where Eq. 12 is compared with the data.

Appendix B builds ``K`` (paper Eq. 12) from the elastic energy through ``p = K dU_el/dF``
(paper Eq. 6): one Hertz-like mesoasperity of radius ``R = chi r0^(2-H)`` (the mean summit
curvature of the heights cut at ``pi/r0``, Eqs. B6-B10) touched over a disc of radius ``r0``
(Eq. B12) stores ``U0 = 2/5 F delta`` (Eqs. B14-B16); the microroughness inside it stores
``U1 = gamma h_rms^meso F`` (Eqs. B17-B22).  For each H (``L = lambda_r``,
``L/lambda_1 = grid/2``) and seed this script solves the periodic contact with its fields,
and at the fitted loads (the four lowest with 16 contact pixels in every seed below ``p_c``,
as ``examples/fig3_finite_size.py`` fits) measures from them: the contact clusters and the
force the largest carries; the contact's radius ``r0`` (the force's second moment, and the
radius that holds half the force, each read as a Hertz disc's) and the force within
``lambda_r/4`` of its centroid; the mesoasperity's radius ``R`` (the heights cut at
``pi/r0``, their curvature at their highest pixel within ``r0`` of the centroid); the
elastic energy and its split at ``pi/r0`` and in the ``q0`` modes.  The simulated ``K``
over Eq. 12's is then the product of three measured factors: the theory's energy over the
stored one, the exponents ``dln U/dln F`` (theory over fit) and ``K`` over
``p^2/(U dln U/dln F)`` (the identity Eq. 6 on the fields).  Each seed's measurements are kept in
``OUTPUT_H<H>_seed<S>.npz`` with the settings they were solved for.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import numpy as np

from petsc_contact.conventions.grid import fft_order
from petsc_contact.geometries.step import Step
from petsc_contact.paper import figures
from petsc_contact.paper.paper_study import add_pressures_option, log_pressures
from petsc_contact.physics import theory
from petsc_contact.workflows.periodic_sweep import periodic_contact

HURSTS = (0.3, 0.5, 0.7)
ROLLOFF_WAVEVECTOR = 2 * np.pi  # q_r = 2 pi/lambda_r with L = lambda_r = 1 (Eq. 12's reading)
DISC = 0.25  # the disc of the mesoasperity: radius lambda_r/4 (diameter lambda_r/2)
HERTZ_MOMENT = 0.4  # <r^2> over a Hertz pressure disc of radius a is 2/5 a^2
HERTZ_HALF = np.sqrt(1 - 0.5 ** (2 / 3))  # half a Hertz disc's force lies within 0.608 a


def mesoasperity_theory(pressure: np.ndarray, h_rms: float, hurst: float) -> dict[str, np.ndarray]:
    """Appendix B's mesoasperity at the loads ``pressure`` (``E* = L = lambda_r = 1``, so
    ``s = 1``): ``r0`` (Eq. B12), ``R`` (Eq. B10), the energies ``U0`` (Eq. B16) and ``U1``
    (Eq. B22) per area, and ``K = p/(dU/dF)`` (Eqs. B25-B26, which are Eq. 12)."""
    q_r, beta, e = ROLLOFF_WAVEVECTOR, theory.NAYAK_BETA, 1 / (1 + hurst)
    chi = np.sqrt((2 - hurst) / hurst) * np.pi ** (hurst - 2) / (beta * q_r * h_rms)  # Eq. B9
    force = np.asarray(pressure, dtype=float) * q_r**2  # F q_r^2/E* with F = p L^2
    r0 = (0.75 * chi * force) ** e
    scale = 4 / 3 * chi**-e * (0.75 * force) ** ((1 + 2 * hurst) * e) / q_r**3
    u0 = theory.KAPPA0 * scale
    u1 = float(theory.kappa1(hurst)) * scale
    exponent = (1 + 2 * hurst) * e  # dln U/dln F
    return {
        "r0": r0 / q_r,
        "R": chi * r0 ** (2 - hurst) / q_r,
        "u0": u0,
        "u1": u1,
        "exponent": np.full(force.shape, exponent),
        "K": pressure**2 / (exponent * (u0 + u1)),
    }


def _offsets(n: int, centre: float) -> np.ndarray:
    """Signed periodic offsets (pixels) of ``0..n-1`` from ``centre``: the nearest image."""
    return (np.arange(n) - centre + n / 2) % n - n / 2


def force_centre(pressure: np.ndarray) -> tuple[float, float]:
    """The force's centroid (pixels) on the periodic cell: the circular mean of each axis."""
    angle = 2 * np.pi * np.arange(pressure.shape[0]) / pressure.shape[0]
    total = pressure.sum()
    rows, cols = pressure.sum(axis=1) / total, pressure.sum(axis=0) / total
    x, y = (np.angle(np.sum(w * np.exp(1j * angle))) % (2 * np.pi) for w in (rows, cols))
    return float(x / angle[1]), float(y / angle[1])


def _wavenumbers(n: int) -> np.ndarray:
    """``|q|/q0`` of an ``n x n`` map's DFT modes."""
    k = fft_order(n)
    return np.hypot(k[:, None], k[None, :])


def curvature_radii(heights: np.ndarray, cut: float, near: np.ndarray) -> tuple[float, ...]:
    """The heights cut at ``|q|/q0 < cut`` (Eq. B6's ``pi/r0``): their Hertz-equivalent radius
    ``1/sqrt(k1 k2)`` at their highest pixel where ``near`` (the mesoasperity's summit; ``nan``
    where that is no summit but the mask's edge), and the theory's
    ``1/(beta rms(lap h))`` of the same cut spectrum (Nayak's mean summit curvature, Eq. B6,
    without Eq. B8's asymptotic step)."""
    n = heights.shape[0]
    q = 2 * np.pi * fft_order(n)  # L = 1
    spectrum = np.where(_wavenumbers(n) < cut, np.fft.fft2(heights), 0)
    qx, qy = q[:, None], q[None, :]
    cut_heights = np.where(near, np.real(np.fft.ifft2(spectrum)), -np.inf)
    at = np.unravel_index(np.argmax(cut_heights), heights.shape)
    hessian = [
        np.real(np.fft.ifft2(-a * b * spectrum))[at] for a, b in ((qx, qx), (qx, qy), (qy, qy))
    ]
    k1, k2 = -np.linalg.eigvalsh(np.array([[hessian[0], hessian[1]], [hessian[1], hessian[2]]]))
    laplacian = np.real(np.fft.ifft2(-(qx**2 + qy**2) * spectrum))
    rms = float(np.sqrt(np.mean(laplacian**2)))
    summit = 1 / np.sqrt(k1 * k2) if k1 > 0 and k2 > 0 else np.nan
    return float(summit), 1 / (theory.NAYAK_BETA * rms)


def _energy_terms(displacement: np.ndarray, load: np.ndarray) -> np.ndarray:
    """Each DFT mode's share of the elastic energy per area ``1/2 <u (p - p0)>`` (Parseval)."""
    n = displacement.shape[0]
    terms = np.real(np.fft.fft2(displacement) * np.conj(np.fft.fft2(load - load.mean())))
    return terms * 0.5 / n**4


def energy_split(displacement: np.ndarray, load: np.ndarray, cut: float) -> tuple[float, ...]:
    """The elastic energy per area ``1/2 <u (p - p0)>`` (Parseval) in the modes with
    ``|q|/q0 < cut``, in the ``q0`` modes (``|q| = q0``) and in all."""
    terms, k = _energy_terms(displacement, load), _wavenumbers(displacement.shape[0])
    return float(terms[k < cut].sum()), float(terms[k == 1].sum()), float(terms.sum())


def clusters(contact: np.ndarray, pressure: np.ndarray, centre: tuple[float, float]) -> np.ndarray:
    """Each cluster's share of the force: the 4-connected clusters of the map rolled to put
    the force's centroid in the middle (clusters cut by the cell's edges lie far from it and
    are counted in pieces; their number is the sweep's periodic count)."""
    from scipy import ndimage

    n = contact.shape[0]
    shift = tuple(int(round(n / 2 - c)) for c in centre)
    labels, count = ndimage.label(np.roll(contact, shift, axis=(0, 1)))
    forces = ndimage.sum(np.roll(pressure, shift, axis=(0, 1)), labels, np.arange(1, count + 1))
    return np.asarray(forces) / np.sum(forces)


def measure(step: Step, heights: np.ndarray, r0_theory: float, exponent: float) -> dict[str, float]:
    """One load step's fields against Appendix B's mesoasperity (see the module docstring);
    the energy is also split at ``pi/r0`` of B12's ``r0_theory``, and the clusters' force
    shares ``f`` give ``sum f^exponent``: what Appendix B's ``U ~ F^exponent`` stores in
    independent clusters, over one contact's."""
    n, gap, load, contact = heights.shape[0], step.gap, step.pressure, step.contact
    assert gap is not None and load is not None and contact is not None, "solved with fields"
    pressure = np.where(contact, load, 0.0)
    centre = force_centre(pressure)
    shares = clusters(contact, pressure, centre)
    dx, dy = _offsets(n, centre[0])[:, None] / n, _offsets(n, centre[1])[None, :] / n
    distance2 = dx**2 + dy**2
    force = pressure.sum()
    moment = np.sum(pressure * distance2) / force / HERTZ_MOMENT
    r0 = max(float(np.sqrt(moment)), 0.5 / n)  # one pixel: half a pixel
    order = np.argsort(distance2, axis=None)
    half = np.searchsorted(np.cumsum(pressure.ravel()[order]), force / 2)
    r_half = float(np.sqrt(distance2.ravel()[order[half]]))
    cut = 1 / (2 * r0)  # pi/r0 in units of q0 = 2 pi
    summit, mean_summit = curvature_radii(heights, cut, distance2 <= r0**2)
    long, q0_modes, total = energy_split(gap + heights, load, cut)
    long_theory = energy_split(gap + heights, load, 1 / (2 * r0_theory))[0]
    return {
        "patches": float(step.scalars["contact_patches"]),
        "largest_share": float(shares.max()),
        "independent": float(np.sum(shares**exponent)),
        "disc_share": float(pressure[distance2 <= DISC**2].sum() / force),
        "r0": r0,
        "r0_half": r_half / HERTZ_HALF,
        "R": summit,
        "R_spectrum": mean_summit,
        "u": total,
        "u_long": long,
        "u_q0": q0_modes,
        "u_long_B": long_theory,
    }


MEASURED = (
    "patches",
    "largest_share",
    "disc_share",
    "r0",
    "r0_half",
    "R",
    "R_spectrum",
    "u",
    "u_long",
    "u_q0",
    "u_long_B",
    "independent",
)


def _settings(args: argparse.Namespace, hurst: float, seed: int) -> np.ndarray:
    """What a seed's measurements depend on, kept with them: grid, H, seed and the loads."""
    return np.array([args.grid, hurst, seed, *log_pressures(args)], dtype=float)


def solve_seed(args: argparse.Namespace, hurst: float, seed: int) -> dict[str, np.ndarray]:
    """One seed's sweep with its fields, measured at every load (:func:`measure`); kept in
    ``OUTPUT_H<H>_seed<S>.npz`` with the settings it was solved for."""
    path, settings = f"{args.output}_H{hurst}_seed{seed}.npz", _settings(args, hurst, seed)
    try:
        kept = figures.kept_seed(path, settings, "measurements (other grid, loads or H)")
    except ValueError as exc:
        raise SystemExit(str(exc)) from None
    if kept is not None:
        return kept
    heights, h_rms = figures.surface(args.grid, hurst, 1.0, args.grid / 2, seed)
    p = log_pressures(args)
    rows: dict[str, list[float]] = {k: [] for k in (*MEASURED, "stiffness", "area_fraction")}
    theory_at = mesoasperity_theory(p, h_rms, hurst)
    r0_theory, exponent = theory_at["r0"], float(theory_at["exponent"][0])
    steps = periodic_contact(heights, length=1.0, pressures=p.tolist(), fields=True, stiffness=True)
    for step, r0 in zip(steps, r0_theory, strict=True):
        done = step.converged
        found = measure(step, heights, r0, exponent) if done else dict.fromkeys(MEASURED, np.nan)
        for key in ("stiffness", "area_fraction"):
            found[key] = float(step.scalars[key]) if done else np.nan
        for key, value in found.items():
            rows[key].append(value)
    out: dict[str, Any] = {k: np.array(v) for k, v in rows.items()}
    out |= {"nominal_pressure": p, "h_rms": np.array(h_rms), "settings": settings}
    np.savez(f"{path}.tmp.npz", **out)
    os.replace(f"{path}.tmp.npz", path)
    print(f"# H = {hurst}, seed {seed}: solved", flush=True)
    return out


def _geometric(x: np.ndarray) -> float:
    """Geometric mean of the finite values."""
    x = np.asarray(x, dtype=float)
    return float(np.exp(np.mean(np.log(x[np.isfinite(x) & (x > 0)]))))


def seed_factors(run: dict[str, np.ndarray], fitted: np.ndarray, hurst: float) -> dict:
    """One seed at the fitted loads: each measurement against Appendix B's, as arrays over
    the loads (ratios ``theory/measured`` for energies, ``measured/theory`` for lengths)."""
    from petsc_contact.paper.fits import power_law_fit

    p = run["nominal_pressure"][fitted]
    m = {k: run[k][fitted] for k in (*MEASURED, "stiffness")}
    th = mesoasperity_theory(p, float(run["h_rms"]), hurst)
    radius_at_r0 = th["R"] * (m["r0"] / th["r0"]) ** (2 - hurst)  # Eq. B10 at the measured r0
    hertz_u0 = 0.4 * p * (9 * p**2 / (16 * m["R"])) ** (1 / 3)  # Eqs. B14-B15, E* = A0 = 1
    exponent = power_law_fit(p, m["u"], p.size).alpha  # dln U/dln F over the fitted loads
    eq12 = theory.finite_size_stiffness(p, 1.0, float(run["h_rms"]), hurst, 1.0, 1.0)
    return {
        "patches": m["patches"],
        "largest_share": m["largest_share"],
        "disc_share": m["disc_share"],
        "r0": m["r0"] / th["r0"],
        "r0_half": m["r0_half"] / th["r0"],
        "r0_B_lambda1": th["r0"] * run["settings"][0] / 2,
        "r0_lambda_r": m["r0_half"],
        "R": m["R"] / radius_at_r0,
        "R_spectrum": m["R_spectrum"] / radius_at_r0,
        "long_share": m["u_long"] / m["u"],
        "q0_share": m["u_q0"] / m["u"],
        "long_share_B": m["u_long_B"] / m["u"],
        "u0_B": th["u0"] / m["u_long_B"],
        "u1_B": th["u1"] / (m["u"] - m["u_long_B"]),
        "curvature": (m["R"] / radius_at_r0) ** (1 / 3),
        "size": (m["r0"] / th["r0"]) ** ((2 - hurst) / 3),
        "hertz": hertz_u0 / m["u_long"],
        "u0": th["u0"] / m["u_long"],
        "u1": th["u1"] / (m["u"] - m["u_long"]),
        "u": (th["u0"] + th["u1"]) / m["u"],
        "independent": 1 / m["independent"],
        "exponent": th["exponent"] / exponent,
        "identity": m["stiffness"] * exponent * m["u"] / p**2,
        "eq12": m["stiffness"] / eq12,
        "theory_check": th["K"] / eq12,
    }


SHARES = ("patches", "largest_share", "disc_share", "long_share", "q0_share", "long_share_B")


def _aggregate(factors: list[dict]) -> dict[str, float]:
    """:func:`seed_factors` of one or more seeds over all their loads: medians of counts and
    shares, geometric means of ratios."""
    out = {}
    for key in factors[0]:
        values = np.concatenate([s[key] for s in factors])
        out[key] = float(np.nanmedian(values)) if key in SHARES else _geometric(values)
    return out


SEED_LINE = (
    "# H = {hurst}, seed {seed}: {patches:.0f} clusters, r0 (half the force) {r0_half:.1f} "
    "B12's, U below pi/r0 {long_share:.2f}, U_B/U {u:.2f}, K/Eq. 12 {eq12:.2f}"
)


def summary(runs: list[dict[str, np.ndarray]], hurst: float, grid: int) -> dict[str, float]:
    """The seeds of one H at their fitted loads (``figures.finite_size_fit``, as
    ``examples/fig3_finite_size.py``; :func:`_aggregate`), each seed's line printed, and
    ``K/Eq. 12`` of the seed-averaged ``K`` (the seeds' mean ``h_rms``)."""
    curves = {k: np.array([r[k] for r in runs]) for k in ("area_fraction", "stiffness", "h_rms")}
    curves["nominal_pressure"] = runs[0]["nominal_pressure"]
    fit = figures.finite_size_fit(
        curves, grid * grid, figures.crossover(curves["h_rms"], hurst, 1.0)
    )
    fitted = fit["fitted"]
    per_seed = [seed_factors(r, fitted, hurst) for r in runs]
    for run, factors in zip(runs, per_seed, strict=True):
        seed = int(run["settings"][2])
        print(SEED_LINE.format(hurst=hurst, seed=seed, **_aggregate([factors])))
    out = _aggregate(per_seed)
    p = curves["nominal_pressure"][fitted]
    eq12 = theory.finite_size_stiffness(p, 1.0, float(curves["h_rms"].mean()), hurst, 1.0, 1.0)
    out["eq12_mean"] = _geometric(fit["stiffness_mean"][fitted] / eq12)
    out["theory_long_share"] = theory.KAPPA0 / (theory.KAPPA0 + float(theory.kappa1(hurst)))
    out["alpha"], out["low"], out["high"] = fit["alpha"], float(p[0]), float(p[-1])
    out["pixels"] = float(np.min(curves["area_fraction"][:, fitted]) * grid * grid)
    return out


GEOMETRY = (
    ("clusters", "patches", "{:.0f}"),
    ("largest cluster's force", "largest_share", "{:.2f}"),
    ("force within lambda_r/4", "disc_share", "{:.2f}"),
    ("B12's r0 / lambda_1", "r0_B_lambda1", "{:.1f}"),
    ("r0 (half the force) / lambda_r", "r0_lambda_r", "{:.3f}"),
    ("r0 / B12's", "r0", "{:.1f}"),
    ("r0 from half the force / B12's", "r0_half", "{:.1f}"),
    ("R / B10's at r0", "R", "{:.2f}"),
    ("B6's R / B10's", "R_spectrum", "{:.2f}"),
)
ENERGY = (
    ("U below pi/r0", "long_share", "{:.2f}"),
    ("B's U0/U", "theory_long_share", "{:.2f}"),
    ("U in q0", "q0_share", "{:.2f}"),
    ("U below B12's pi/r0", "long_share_B", "{:.2f}"),
    ("U0_B / U below B12's", "u0_B", "{:.2f}"),
    ("U1_B / U above B12's", "u1_B", "{:.2f}"),
    ("(R/R_B)^1/3", "curvature", "{:.2f}"),
    ("(r0/r0_B)^((2-H)/3)", "size", "{:.2f}"),
    ("Hertz(R) / U below pi/r0", "hertz", "{:.2f}"),
    ("U0_B / U below", "u0", "{:.2f}"),
    ("U1_B / U above", "u1", "{:.2f}"),
    ("U_B / U", "u", "{:.2f}"),
    ("1 / sum f^((1+2H)/(1+H))", "independent", "{:.2f}"),
    ("exponent B / fit", "exponent", "{:.2f}"),
    ("K / (p^2/(U dlnU/dlnF))", "identity", "{:.2f}"),
    ("K / Eq. 12 (seeds)", "eq12", "{:.2f}"),
    ("K / Eq. 12 (seed-averaged)", "eq12_mean", "{:.2f}"),
)


def table(rows: dict[float, dict[str, float]], columns: tuple) -> list[str]:
    """A markdown table, one row per H, of ``columns`` (header, key, format)."""
    lines = [
        "| H | " + " | ".join(c[0] for c in columns) + " |",
        "| --- |" + " --- |" * len(columns),
    ]
    for hurst, row in rows.items():
        cells = [fmt.format(row[key]) for _, key, fmt in columns]
        lines.append(f"| {hurst} | " + " | ".join(cells) + " |")
    return lines


def _panels(axes: tuple, hurst: float, seed: int, grid: int, load: float) -> None:
    """One H's two panels: the contact pixels about the force's centroid (coloured by their
    pressure) with B12's ``r0`` and the measured ones, and the share of the elastic energy
    below ``|q|`` against ``|q|/q0``."""
    heights, h_rms = figures.surface(grid, hurst, 1.0, grid / 2, seed)
    (step,) = periodic_contact(heights, length=1.0, pressures=[load], fields=True)
    r0_b = float(mesoasperity_theory(np.array([load]), h_rms, hurst)["r0"][0])
    found, gap, load_field = measure(step, heights, r0_b, 1.0), step.gap, step.pressure
    assert gap is not None and load_field is not None and step.contact is not None
    pressure = np.where(step.contact, load_field, 0.0)
    centre = force_centre(pressure)
    dx, dy = (_offsets(grid, c) / grid for c in centre)
    rows, cols = np.nonzero(pressure)
    level = np.log10(pressure[rows, cols] / load)
    axes[0].scatter(dx[rows], dy[cols], c=level, s=4, marker="s", cmap="viridis", linewidths=0)
    t = np.linspace(0, 2 * np.pi, 200)
    for radius, style, label in (
        (r0_b, "r-", "B12's $r_0$"),
        (found["r0_half"], "k--", "$r_0$ from half the force"),
        (found["r0"], "k-", "$r_0$ from its second moment"),
    ):
        axes[0].plot(radius * np.cos(t), radius * np.sin(t), style, lw=1, label=label)
    extent = 1.15 * max(found["r0"], 4 * r0_b)
    axes[0].set(xlim=(-extent, extent), ylim=(-extent, extent), aspect="equal")
    axes[0].set(title=f"H = {hurst}, seed {seed}, $p_0$ = {load:.2g} E*", xlabel="x / L")
    terms = _energy_terms(gap + heights, load_field)
    k = _wavenumbers(grid).ravel()
    order = np.argsort(k)
    below = np.cumsum(terms.ravel()[order]) / terms.sum()
    axes[1].semilogx(k[order][1:], below[1:], "C0-", lw=1.5, label="fields")
    axes[1].axvline(1 / (2 * found["r0"]), color="k", lw=1, label="$\\pi/r_0$ (second moment)")
    axes[1].axvline(1 / (2 * r0_b), color="r", lw=1, label="$\\pi/r_0$, B12's")
    share = theory.KAPPA0 / (theory.KAPPA0 + float(theory.kappa1(hurst)))
    axes[1].plot([1 / (2 * r0_b)], [share], "ro", label="Appendix B's $U_0/U$ at $\\pi/r_0$")
    axes[1].set(xlabel="$|q|/q_0$", ylim=(0, 1))
    axes[1].grid(alpha=0.3, which="both")


def draw(args: argparse.Namespace, rows: dict[float, dict[str, float]]) -> None:
    """``OUTPUT.png``: for each H, seed 1 at its second fitted load (:func:`_panels`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(rows), figsize=(4 * len(rows), 7.4), squeeze=False)
    p = log_pressures(args)
    for column, (hurst, row) in enumerate(rows.items()):
        load = float(p[(p >= row["low"] * (1 - 1e-9))][1])
        _panels(tuple(axes[:, column]), hurst, 1, args.grid, load)
    axes[0, 0].set_ylabel("y / L (contact pixels, colour: log$_{10}$ p/$p_0$)")
    axes[1, 0].set_ylabel("share of the elastic energy below $|q|$")
    axes[0, -1].legend(fontsize=7, loc="lower right")
    axes[1, -1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(f"{args.output}.png", dpi=110)
    print(f"wrote {args.output}.png")


def main(argv: list[str] | None = None) -> None:
    """Run the script with ``argv`` (default: the command line's)."""
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--grid", type=int, default=1024, help="pixels per side, L/lambda_1 = grid/2 (default 1024)"
    )
    ap.add_argument(
        "--hursts", type=float, nargs="+", default=list(HURSTS), help="H (default 0.3 0.5 0.7)"
    )
    ap.add_argument("--seeds", type=int, default=4, help="seeds 1..N per H (default 4)")
    ap.add_argument("--output", default="eq12_trace", help="prefix of the files written")
    ap.add_argument("--figure", action="store_true", help="draw OUTPUT.png (solves seed 1 again)")
    add_pressures_option(ap, 1e-8, 1e-5, 13)
    args = ap.parse_args(argv)
    rows = {}
    for hurst in args.hursts:
        runs = [solve_seed(args, hurst, seed) for seed in range(1, args.seeds + 1)]
        rows[hurst] = summary(runs, hurst, args.grid)
        r = rows[hurst]
        print(
            f"# H = {hurst}: fitted loads {r['low']:.2g}-{r['high']:.2g} E*, at least "
            f"{r['pixels']:.0f} contact pixels, alpha = {r['alpha']:.3f}; Appendix B's K over "
            f"Eq. 12 {r['theory_check']:.4f}"
        )
    print("\n".join(table(rows, GEOMETRY)))
    print()
    print("\n".join(table(rows, ENERGY)))
    if args.figure:
        draw(args, rows)


if __name__ == "__main__":
    main()
