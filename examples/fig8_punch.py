"""The rough punch settled: K h_rms/p against p for periodic faces and faces cut from a larger
surface, L_p/lambda_r = 1 and 8, several seeds; K from springs in series (paper Eq. 2) and
-dp/du_bar over the face beside it; the periodic cell of Fig. 1 for reference."""

import argparse

import numpy as np

from petsc_contact.geometries.punch import flat_punch_stiffness, interfacial_stiffness
from petsc_contact.physics import theory
from petsc_contact.workflows import scenes
from petsc_contact.workflows.paper_study import CUT_FROM, PUNCH_RATIOS, piece_files

HURST = 0.7
FACES = ("periodic", "cut")
TOLERANCES = (0.05, 0.1)  # K/p within +-5% or +-10%: the linear regime


def linear_width(p: np.ndarray, ratio: np.ndarray, tolerance: float) -> tuple:
    """The widest run of consecutive loads over which ``K/p`` stays within ``1 +- tolerance``
    of its geometric middle (``max/min <= (1 + tol)/(1 - tol)``): its width in decades of
    load and its first and last load (0 and NaN without two such loads)."""
    good = np.isfinite(ratio) & (ratio > 0)
    best = (0.0, float("nan"), float("nan"))
    limit = (1 + tolerance) / (1 - tolerance)
    for i in np.flatnonzero(good):
        for j in range(i + 1, p.size):
            if not good[j]:
                break
            window = ratio[i : j + 1]
            if window.max() / window.min() > limit:
                break
            width = float(np.log10(p[j] / p[i]))
            if width > best[0]:
                best = (width, float(p[i]), float(p[j]))
    return best


def linearity(p: np.ndarray, k: np.ndarray, resolved: np.ndarray) -> str:
    """How far ``K ~ p`` holds over the ``resolved`` loads (at least 16 contact pixels): the
    widest windows of :func:`linear_width` at each of :data:`TOLERANCES`, and the smallest
    ``K/p``'s load."""
    ratio = np.where(resolved, k / p, np.nan)
    parts = [f"K/p smallest at p/E* {p[np.nanargmin(ratio)]:.2g}"]
    for tolerance in TOLERANCES:
        width, low, high = linear_width(p, ratio, tolerance)
        parts.append(f"K/p within {tolerance:.0%} over {width:.2f} decades ({low:.2g}-{high:.2g})")
    return ", ".join(parts)


def punch_rows(paths: list[str]) -> dict:
    """A punch piece's columns (NaN where a step did not converge), its face's realised
    ``h_rms`` and seed, ``-dp/du_bar`` by finite differences where ``mean_gap`` is kept, and
    ``K`` from Eq. 2 with Pharr's analytic flat punch, as the paper took it (negative where
    the discretised punch is already stiffer than Pharr's flat one)."""
    import h5py

    rows = []
    for path in paths:
        with h5py.File(path, "r", locking=False) as f:
            ok = f["converged"][:].astype(bool)
            keys = (
                "nominal_pressure",
                "area_fraction",
                "interfacial_stiffness",
                "total_stiffness",
                "mean_gap",  # recorded by punch runs of 0.2.0 on
                "contact_patches",
            )
            row = {k: np.where(ok, f[k][:], np.nan) for k in keys if k in f}
            area = float(np.prod(f.attrs["lengths"]))
            pharr = flat_punch_stiffness(float(f.attrs["modulus"]), area)
            row |= {
                "pharr_stiffness": np.array(
                    [interfacial_stiffness(k, pharr) for k in row["total_stiffness"]]
                )
                / area,
                "h_rms": float(f.attrs["rms_height"]),
                "pixels": int(np.prod(np.atleast_1d(f.attrs["grid"])[[0, -1]])),  # n x n
                "seed": int(f.attrs["seed"]),
                "converged": ok,
            }
        if "mean_gap" in row:
            good = ok & (row["nominal_pressure"] > 0)
            row["mean_gap_stiffness"] = np.full(ok.size, np.nan)
            if good.sum() >= 3:
                row["mean_gap_stiffness"][good] = scenes.sweep_stiffness(
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
    """Fig. 1's periodic cell at this ``L/lambda_r`` (8192^2, ``L/lambda_1 = 4096``), if
    computed."""
    paths = piece_files(data, "fig1", rolloff_ratio=f"{ratio:g}")
    if not paths:
        return None
    c = scenes.curves_from_files(paths)
    return {k: v[0] for k, v in c.items() if k != "h_rms"} | {"h_rms": float(c["h_rms"][0])}


def _draw(args: argparse.Namespace, variants: dict, references: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True, constrained_layout=True)
    for ax, ratio in zip(axes, PUNCH_RATIOS, strict=True):
        ref = references.get(ratio)
        if ref is not None:
            ok = scenes.resolved(ref["area_fraction"], 8192) & np.isfinite(ref["stiffness"])
            p = ref["nominal_pressure"]
            ax.loglog(
                p[ok],
                (ref["stiffness"] * ref["h_rms"] / p)[ok],
                "-",
                color="0.6",
                lw=2,
                label=f"periodic cell, $L/\\lambda_r$ = {ratio} (Fig. 1)",
            )
        for face, color, marker in (("periodic", "C0", "o"), ("cut", "C3", "s")):
            rows = variants.get((face, ratio), [])
            for n, row in enumerate(rows):
                p = row["nominal_pressure"]
                k = row["interfacial_stiffness"] * row["h_rms"] / p
                ok = scenes.contact_resolved(row["area_fraction"], row["pixels"])
                count = f"{len(rows)} seed{'s' if len(rows) > 1 else ''}"
                label = f"{face} face, Eq. 2 ({count})" if n == 0 else None
                ax.loglog(p, k, "-", color=color, lw=0.8)
                ax.loglog(p[ok], k[ok], marker, color=color, mfc="none", ms=4, label=label)
                ax.loglog(p[~ok], k[~ok], ".", color=color, ms=3)
                kp = row["pharr_stiffness"] * row["h_rms"] / p
                label = f"{face} face, Eq. 2 with Pharr's flat punch" if n == 0 else None
                ax.loglog(p, np.where(kp > 0, kp, np.nan), ":", color=color, lw=1, label=label)
                if "mean_gap_stiffness" in row:
                    kg = row["mean_gap_stiffness"] * row["h_rms"] / p
                    label = rf"{face} face, $-dp/d\bar u$" if n == 0 else None
                    ax.loglog(p, kg, "x", color=color, ms=4, label=label)
        for row in references.get(("fig1 punch", ratio), []):
            p = row["nominal_pressure"]
            ax.loglog(
                p,
                row["interfacial_stiffness"] * row["h_rms"] / p,
                "s",
                color="0.4",
                ms=3,
                label="Fig. 1's punch (periodic face, seed 1)",
            )
        ax.plot([], [], ".", color="gray", ms=3, label="< 16 contact pixels")
        ax.axhline(1 / theory.GAMMA, color="k", ls="--", lw=0.8, label=r"$1/\gamma$")
        ax.set(
            xlabel="$p/E^*$",
            title=f"$L_p/\\lambda_r$ = {ratio}, $L_p/\\lambda_1$ = 1024, 2048$^2$",
            xlim=(1e-8, 0.1),
        )
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set(ylabel=r"$K h_\mathrm{rms}/p$ (flat: linear regime)", ylim=(0.5, 300))
    fig.suptitle(
        f"Rough punch, H = {HURST}, rms slope 0.1: periodic faces and faces cut from a "
        f"{CUT_FROM}x larger surface ($h_\\mathrm{{rms}}$: the face's own)"
    )
    fig.savefig(f"{args.output}.png", dpi=120)


def report(face: str, ratio: int, rows: list) -> list[str]:
    """Per seed: the loads reached, the linear regime's width (Eq. 2 and ``-dp/du_bar``)."""
    lines = []
    for row in rows:
        p = row["nominal_pressure"]
        ok = row["converged"] & scenes.contact_resolved(row["area_fraction"], row["pixels"])
        text = (
            f"{face} face, L_p/lambda_r = {ratio}, seed {row['seed']}: "
            f"{row['converged'].sum()}/{ok.size} converged ({ok.sum()} resolved), p/E* "
            f"{np.nanmin(p[p > 0]):.2g}-{np.nanmax(p):.2g}, area up to "
            f"{np.nanmax(row['area_fraction']):.1%}; Eq. 2: "
            f"{linearity(p, row['interfacial_stiffness'], ok)}"
        )
        pharr = row["pharr_stiffness"] / row["interfacial_stiffness"]
        top = np.nanargmax(row["area_fraction"])
        text += (
            f"; Eq. 2 with Pharr's flat punch {pharr[top]:.2f} x at the top load, "
            f"{np.nanmax(np.where(row['area_fraction'] < 0.2, pharr, np.nan)):.2f} x below 20% "
            "area"
        )
        if "mean_gap_stiffness" in row:
            ratio_k = row["mean_gap_stiffness"] / row["interfacial_stiffness"]
            mid = (row["area_fraction"] > 1e-3) & (row["area_fraction"] < 0.2)
            text += (
                f"; -dp/du_bar: {linearity(p, row['mean_gap_stiffness'], ok)}, "
                f"{np.nanmin(ratio_k[mid]):.2f}-{np.nanmax(ratio_k[mid]):.2f} x Eq. 2 at "
                "0.1-20% area"
            )
        lines.append(text)
    return lines


def _arguments() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument(
        "--data",
        metavar="DIR",
        required=True,
        help="the study's files (petsc-contact study --figure punch), e.g. data/paper",
    )
    ap.add_argument(
        "--with-partial", action="store_true", help="also read the pieces still computing"
    )
    ap.add_argument("--output", default="fig8", help="prefix of the PNG and HDF5 files")
    return ap.parse_args()


def main() -> None:
    args = _arguments()
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
            ok = scenes.resolved(ref["area_fraction"], 8192)
            print(f"periodic cell (Fig. 1), L/lambda_r = {ratio}: {linearity(p, k, ok)}")
    scenes.save(f"{args.output}.h5", data, hurst=HURST, cut_from=CUT_FROM, study_data=args.data)
    _draw(args, variants, references)
    print(f"wrote {args.output}.png and {args.output}.h5")


if __name__ == "__main__":
    main()
