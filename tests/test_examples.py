"""The figure scripts run end to end at toy size and write their PNG and HDF5 files.

The scripts run in this process (their ``main(argv)``, reported as a process would be:
:func:`script`), and so do the studies whose files they redraw (:func:`conftest.cli`): what
is checked is what they compute and print, not a process. One script runs as a user starts
it, a process of its own (``test_example_runs``' ``fig2_theta.py``)."""

import functools
import importlib.util
import os
import subprocess
import sys
from types import ModuleType

import h5py
import pytest
from conftest import ROOT, cli, cli_in_process, in_process


@functools.cache
def example(name: str) -> ModuleType:
    """The script ``examples/NAME`` as a module (loaded once), its ``main(argv)`` to call."""
    spec = importlib.util.spec_from_file_location(f"examples_{name[:-3]}", ROOT / "examples" / name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def script(name: str, *args: str) -> subprocess.CompletedProcess:
    """``python examples/NAME ARGS`` run in this process (its ``main(ARGS)``), reported as the
    process would be (:func:`conftest.in_process`: the exit status, what it printed); the
    figures it left open closed."""
    import matplotlib.pyplot as plt

    module = example(name)
    argv = [sys.executable, str(ROOT / "examples" / name), *args]
    try:
        return in_process(argv, lambda: module.main(list(args)))
    finally:
        plt.close("all")


@pytest.mark.parametrize(
    "name, args",
    [
        ("fig2_theta.py", []),
        ("fig5_spectrum.py", ["--grid", "64"]),
        (
            "fig4_alpha_extrapolation.py",
            "--grid 64 --ratios 8 16 32 --seeds 2 --pressures 1e-4 3e-2 8 --fit-points 3".split(),
        ),
        ("fig1_stiffness.py", ["--grid", "64", "--pressures", "1e-5", "1e-2", "6"]),
        ("fig6_hertz.py", "--grid 64 --pixels 8 16 --seeds 2 --pressures 1e-6 1e-3 7".split()),
        ("fig7_seed_distribution.py", "--grid 32 --seeds 4 --pressures 1e-4 1e-1 7".split()),
        (
            "fig3_finite_size.py",
            [
                "--grid",
                "64",
                "--hursts",
                "0.7",
                "--seeds",
                "2",
                "--pressures",
                "1e-4",
                "3e-2",
                "8",
                "--fit-points",
                "3",
            ],
        ),
    ],
)
def test_example_runs(tmp_path, name, args):
    """Each figure script at a toy size (grids of 32^2 and 64^2, a few seeds and loads: enough
    for its fits to have points) writes its picture and its numbers; ``fig2_theta.py`` (the
    quickest, theory only) as a process of its own, as a user starts it."""
    out = str(tmp_path / "fig")
    if name == "fig2_theta.py":
        r = subprocess.run(
            [sys.executable, str(ROOT / "examples" / name), *args, "--output", out],
            capture_output=True,
            text=True,
            timeout=600,
            env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        )
    else:
        r = script(name, *args, "--output", out)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "fig.png").stat().st_size > 1000
    with h5py.File(tmp_path / "fig.h5") as f:
        assert len(f.keys()) > 0


def test_figure_1_redraws_from_study_files(tmp_path):
    """Fig. 1 from the study's two sweeps and punch at a toy size (grids divided by 128, the
    most the study allows: 64^2 cells, a 16^2 punch), every step converged."""
    data = str(tmp_path / "paper")
    r = cli("study", "--figure", "1", "--shrink", "128", "--data", data, "--quiet")
    assert r.returncode == 0, r.stderr
    r = script("fig1_stiffness.py", "--data", data, "--output", str(tmp_path / "f1"))
    assert r.returncode == 0, r.stderr
    assert "64^2: 16/16 converged" in r.stdout and "punch 16^2: 16/16" in r.stdout
    with h5py.File(tmp_path / "f1.h5") as f:
        assert f["ratio8"]["stiffness"].shape == (16,) and f["punch"]["force"].shape == (16,)


@pytest.mark.slow
def test_figures_redraw_from_study_files(tmp_path):
    """The study's files at a toy size (grids divided by 64: 128^2 for Fig. 2, so that every
    ratio of Fig. 3 keeps a grid of its own, 16^2 to 128^2) redraw Figs. 2 and 3 of the paper
    (scripts fig3 and fig4 with --data) without solving anything; the shared H = 0.3 run
    serves both, and the fits report how many loads lie below p_c."""
    data = str(tmp_path / "paper")
    for figure in ("2", "3"):
        r = cli("study", "--figure", figure, "--shrink", "64", "--data", data, "--quiet")
        assert r.returncode == 0, r.stderr
    redraws = (
        ("fig3_finite_size.py", "f2", []),
        ("fig4_alpha_extrapolation.py", "f3", []),
        ("fig4_alpha_extrapolation.py", "f3_any", ["--min-contact-pixels", "1"]),
    )
    for name, figure, extra in redraws:
        r = script(name, "--data", data, "--output", str(tmp_path / figure), *extra)
        assert r.returncode == 0, r.stderr
        assert "below p_c" in r.stdout or "alpha" in r.stdout
        assert name.startswith("fig3") or extra or "512: not fitted" in r.stdout
        assert (tmp_path / f"{figure}.png").stat().st_size > 1000
    with h5py.File(tmp_path / "f3.h5") as f:
        # 32^2 (lambda_r/lambda_1 = 512 shrunk) has too few resolved loads: skipped, said so
        assert list(f["ratio"][:]) == [768, 2048, 4096]
        assert f["ratio4096"]["stiffness"].shape == (4, 25)  # fig2's H = 0.3 seeds
        assert list(f["ratio4096"]["seed"][:]) == [1, 2, 3, 4]  # each file's own seed
        assert f["ratio4096"]["grid"][()] == 8192 // 64
    with h5py.File(tmp_path / "f3_any.h5") as f:
        # one contact pixel per seed counts as resolved: every ratio is fitted
        assert list(f["ratio"][:]) == [512, 768, 2048, 4096]


def test_a_ratio_with_one_seed_is_drawn_but_not_fitted():
    """The alpha extrapolation leaves out a ratio whose error lacks the seed spread: the line
    through the other three is the one it would be without that ratio."""
    import numpy as np

    fig4 = example("fig4_alpha_extrapolation.py")
    ratios = [512.0, 768.0, 2048.0, 4096.0]
    alphas, seeds = [0.70, 0.72, 0.75, 0.95], [4, 4, 4, 1]
    results = {
        f"ratio{r:g}": {"alpha": a, "alpha_error": 0.05, "stiffness": np.ones((s, 3))}
        for r, a, s in zip(ratios, alphas, seeds, strict=True)
    }
    fit = fig4.extrapolation(0.3, ratios, results)
    assert list(fit["used"]) == [True, True, True, False]
    three = fig4.extrapolation(0.3, ratios[:3], results)
    assert np.allclose(fit["coefficients"], three["coefficients"])
    assert np.isfinite(fit["extrapolated_alpha_error"])
    # 768's point 0.1 below the others, errors of 0.005: the three fitted points scatter
    # about their line by more than their errors say, and chi^2 on one degree of freedom
    # scales the error; on the line it stands
    tight = {k: v | {"alpha_error": 0.005} for k, v in results.items()}
    tight["ratio768"] = tight["ratio768"] | {"alpha": 0.62}
    scattered = fig4.extrapolation(0.3, ratios, tight)
    assert scattered["dof"] == 1 and scattered["chi2"] > 1
    scaled = scattered["extrapolated_alpha_error"] * np.sqrt(scattered["chi2"])
    assert scattered["extrapolated_alpha_scaled_error"] == pytest.approx(scaled, rel=1e-12)
    on_line = {
        k: v | {"alpha": 0.8 - 0.1 * (1 / float(k[5:])) ** (1 / 1.3)} for k, v in tight.items()
    }
    straight = fig4.extrapolation(0.3, ratios, on_line)
    assert straight["chi2"] < 1e-20
    assert straight["extrapolated_alpha_scaled_error"] == straight["extrapolated_alpha_error"]


@pytest.mark.parametrize(
    "bad", [["0", "1e-3", "16"], ["1e-3", "1e-8", "16"], ["1e-8", "1e-3", "1.5"]]
)
def test_figure_scripts_refuse_loads_that_are_not_log_spaced(bad, capsys):
    """``--pressures PMIN PMAX N`` of the figure scripts: a zero or reversed range or a
    fractional count is a usage error naming the option, not a traceback from numpy."""
    import argparse

    from petsc_contact.paper.paper_study import add_pressures_option, log_pressures

    parser = argparse.ArgumentParser()
    add_pressures_option(parser, 1e-8, 1e-3, 16)
    assert list(log_pressures(parser.parse_args(["--pressures", "1e-6", "1e-2", "5"]))) == (
        pytest.approx([1e-6, 1e-5, 1e-4, 1e-3, 1e-2])
    )
    with pytest.raises(SystemExit) as stop:
        parser.parse_args(["--pressures", *bad])
    assert stop.value.code == 2 and "error: --pressures needs " in capsys.readouterr().err


def _sweep_file(path, seed, loads, complete):
    """A Fig. 2 piece's scalars for ``K = p^0.6`` (64^2, every load resolved and below
    ``p_c``), as the study writes them: all loads when complete, the first ones when not."""
    import numpy as np

    p = np.geomspace(1e-8, 1e-6, 6)[:loads]
    with h5py.File(path, "w") as f:
        f.attrs.update(complete=complete, seed=seed, grid=64, cutoff_ratio=16.0, rms_height=8e-4)
        f["converged"] = np.ones(p.size, dtype=bool)
        f["nominal_pressure"], f["mean_gap"] = p, np.full(p.size, 1e-3)
        f["area_fraction"], f["stiffness"] = 0.01 * (p / 1e-8) ** 0.5, (1 + seed / 10) * p**0.6
        f["contact_patches"] = np.full(p.size, 3)


def test_an_unfinished_study_is_read_over_the_loads_every_seed_has(tmp_path):
    """``--with-partial``: a piece still computing (``.partial``, 4 of 6 loads) joins the
    three complete seeds; the script fits them over the 4 loads all four have and says so.
    Without the option, and for a piece that has kept no step, only complete files count."""
    from petsc_contact.paper.figures import curves_from_files
    from petsc_contact.paper.paper_study import piece_files

    fig2 = tmp_path / "paper" / "fig2"
    fig2.mkdir(parents=True)
    for seed in (1, 2, 3):
        _sweep_file(fig2 / f"H0.7_seed{seed}.h5", seed, 6, True)
    _sweep_file(fig2 / "H0.7_seed4.h5.partial", 4, 4, False)
    _sweep_file(fig2 / "H0.5_seed1.h5.partial", 1, 0, False)
    data = str(tmp_path / "paper")
    assert len(piece_files(data, "fig2", hurst="0.7")) == 3
    paths = piece_files(data, "fig2", partial=True, hurst="0.7")
    assert paths[-1].endswith("H0.7_seed4.h5.partial") and len(paths) == 4
    assert piece_files(data, "fig2", partial=True, hurst="0.5") == []
    assert curves_from_files(paths)["stiffness"].shape == (4, 4)
    _sweep_file(tmp_path / "unfinished.h5", 1, 4, False)  # not complete, and not a .partial
    with pytest.raises(ValueError, match="not complete"):
        curves_from_files([str(tmp_path / "unfinished.h5")])
    _sweep_file(tmp_path / "shorter.h5", 1, 5, True)  # complete, but one load fewer
    with pytest.raises(ValueError, match="same loads"):
        curves_from_files([paths[0], str(tmp_path / "shorter.h5")])
    r = script("fig3_finite_size.py", "--data", data, "--with-partial", "--output",
               str(tmp_path / "f2"))  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "H = 0.7: unfinished pieces read, 4 loads; 4 fitted below p_c" in r.stdout
    with h5py.File(tmp_path / "f2.h5") as f:
        assert f["H0.7"]["stiffness"].shape == (4, 4)
        assert f["H0.7"]["alpha"][()] == pytest.approx(0.6, abs=1e-9)


@pytest.mark.slow
def test_the_gallery_draws_every_picture(tmp_path):
    """examples/gallery.py at 64^2 (each map still has pixels in and out of contact): every
    command of docs/gallery.md runs and draws, each in this process
    (:func:`conftest.cli_in_process`) in the gallery's folder, as the script runs it."""
    gallery = example("gallery.py")

    def in_this_process(words: list[str], folder: str) -> None:
        here = os.getcwd()
        os.chdir(folder)
        try:
            r = cli_in_process(*words)
        finally:
            os.chdir(here)
        assert r.returncode == 0, r.stderr

    gallery.draw(str(tmp_path), 64, run=in_this_process)
    drawn = sorted(p.name for p in tmp_path.iterdir())
    documented = (ROOT / "docs" / "gallery.md").read_text()
    assert drawn and all(f"gallery/{name}" in documented for name in drawn), drawn
    assert all((tmp_path / name).stat().st_size > 5000 for name in drawn)


@pytest.mark.slow
def test_punch_figure_redraws_from_study_files(tmp_path):
    """The punch pieces at a toy size (grids divided by 128, the most the study allows: 16^2
    faces, the cut ones from 64^2) draw the punch figure: every variant has its 8 seeds,
    -dp/du_bar stands beside Eq. 2, and each variant's summary over its seeds is one table
    row."""
    data = tmp_path / "paper"
    r = cli("study", "--figure", "punch", "--shrink", "128", "--data", str(data), "--quiet")
    assert r.returncode == 0, r.stderr
    out = tmp_path / "f8"
    r = script("fig8_punch.py", "--data", str(data), "--output", str(out))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert sum(", seed " in line and "-dp/du_bar" in line for line in lines) == 32
    summary = [line for line in lines if line.startswith("| ") and " face, " in line]
    assert len(summary) == 4 and all(line.split(" | ")[1] == "8" for line in summary), summary
    with h5py.File(f"{out}.h5") as f:
        assert sorted(f) == ["cut_r1", "cut_r8", "periodic_r1", "periodic_r8"]
        assert all(len(f[v]) == 8 for v in f)
    _punch_against_its_own_cell(data, tmp_path)


def _punch_against_its_own_cell(data, tmp_path):
    """The cells of the punch's periodic faces: each seed's punch is compared with the cell
    of its own face (one row per ``L_p/lambda_r``, 8 seeds), and a cell whose face is not its
    punch's is refused in one line."""
    r = cli("study", "--figure", "cells", "--shrink", "128", "--data", str(data), "--quiet")
    assert r.returncode == 0, r.stderr
    r = script("punch_own_cell.py", "--data", str(data), "--output", str(tmp_path / "own"))
    assert r.returncode == 0, r.stderr
    rows = [line for line in r.stdout.splitlines() if line.startswith("| `L")]
    assert len(rows) == 4 and all(line.split(" | ")[1] == "8" for line in rows), rows
    assert (tmp_path / "own.png").stat().st_size > 5000
    with h5py.File(data / "cells" / "periodic_r8_seed3.h5", "r+") as f:  # another face
        f.attrs["rms_height"] = 1.01 * f.attrs["rms_height"]
    r = script("punch_own_cell.py", "--data", str(data), "--output", str(tmp_path / "own2"))
    assert r.returncode == 1 and "not the same face" in r.stderr and "seed 3" in r.stderr
    damaged = data / "cells" / "periodic_r1_seed2.h5"
    damaged.write_bytes(bytes(range(256)) * 16)  # bad bytes: named in one line
    r = script("punch_own_cell.py", "--data", str(data), "--output", str(tmp_path / "own3"))
    assert r.returncode == 1 and str(damaged) in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_sweeps_whose_loads_differ_by_rounding_are_one_sweep(tmp_path):
    """numpy 1 and 2 round ``geomspace`` a unit in the last place apart: files of the same
    sweep written under each are read together; loads apart by more are refused."""
    import numpy as np

    from petsc_contact.paper.figures import curves_from_files

    for name, scale in (("a.h5", 1.0), ("b.h5", 1 + 2e-16), ("c.h5", 1 + 1e-9)):
        _sweep_file(tmp_path / name, 1, 6, True)
        with h5py.File(tmp_path / name, "r+") as f:
            f["nominal_pressure"][...] = f["nominal_pressure"][:] * scale
    same = curves_from_files([str(tmp_path / "a.h5"), str(tmp_path / "b.h5")])
    assert same["stiffness"].shape == (2, 6) and np.isfinite(same["stiffness"]).all()
    with pytest.raises(ValueError, match="same loads"):
        curves_from_files([str(tmp_path / "a.h5"), str(tmp_path / "c.h5")])


def test_the_grid_refinement_reuses_what_it_solved(tmp_path):
    """``examples/grid_refinement.py``: a table of K on the coarser grids over the finest's,
    binned by contact pixels; each seed's curves kept, so that a second run solves nothing.
    32^2 to 128^2, two seeds, five loads: the table has rows and each seed a file."""
    import numpy as np

    args = ["--grid", "32", "--seeds", "2", "--pressures", "1e-4", "3e-2", "5",
            "--output", str(tmp_path / "r")]  # fmt: skip
    first = script("grid_refinement.py", *args)
    assert first.returncode == 0, first.stderr
    assert first.stdout.count("solved") == 6 and "| contact pixels" in first.stdout
    again = script("grid_refinement.py", *args)
    assert "solved" not in again.stdout
    assert again.stdout.splitlines()[-3:] == first.stdout.splitlines()[-3:]
    with np.load(tmp_path / "r_seed1.npz") as kept:
        assert kept["stiffness_4"].shape == (5,) and np.isfinite(kept["stiffness_4"]).all()
    # other loads with the same files: refused in one line, not a table of the old curves
    other = [*args[:-5], "1e-4", "1e-2", "5", *args[-2:]]
    refused = script("grid_refinement.py", *other)
    assert refused.returncode == 1 and "holds another run's curves" in refused.stderr
    (tmp_path / "r_seed2.npz").write_bytes(b"not a numpy file")  # bad bytes
    damaged = script("grid_refinement.py", *args)
    assert damaged.returncode == 1 and "r_seed2.npz is damaged" in damaged.stderr


def test_the_knee_of_a_curve_is_its_crossover():
    """``fig7``'s second ``p_c``: on ``c p^0.77`` and ``p/u0`` joined smoothly the local
    slope reaches (0.77 + 1)/2 at the laws' crossing within a quarter of a decade; one steep
    pair among the low loads is not taken for it, and a curve that never steepens has none."""
    import numpy as np

    fig7 = example("fig7_seed_distribution.py")
    p = np.geomspace(1e-8, 1e-2, 25)
    crossing = 1e-5  # c p^0.77 = p/u0 there, with u0 = 1
    k = np.hypot(crossing**0.23 * p**0.77, p)  # the two laws joined smoothly
    resolved = np.ones(p.size, bool)
    assert abs(np.log10(fig7.knee(p, k, resolved, 0.77) / crossing)) < 0.25
    bumped = k.copy()
    bumped[3] *= 2.0  # one steep pair at a few contacts, then back on the power law
    assert abs(np.log10(fig7.knee(p, bumped, resolved, 0.77) / crossing)) < 0.25
    assert np.isnan(fig7.knee(p, p**0.77, resolved, 0.77))


def test_the_eq12_trace_tabulates_and_reuses_what_it_solved(tmp_path):
    """``examples/eq12_trace.py``: the fields' measurements against Appendix B in two tables;
    Appendix B's energy gives Eq. 12 back; each seed kept (a second run with ``--figure``
    solves only the figure's loads), another run's file refused. 64^2, two seeds, eight
    loads: a few contact clusters at the lowest loads, a fit over several loads."""
    args = ["--grid", "64", "--seeds", "2", "--hursts", "0.7",
            "--pressures", "1e-4", "3e-2", "8", "--output", str(tmp_path / "t")]  # fmt: skip
    first = script("eq12_trace.py", *args)
    assert first.returncode == 0, first.stderr
    assert first.stdout.count("solved") == 2 and "K over Eq. 12 1.0000" in first.stdout
    assert "| H | clusters |" in first.stdout and "| 0.7 |" in first.stdout
    again = script("eq12_trace.py", *args, "--figure")
    assert again.returncode == 0, again.stderr
    assert "solved" not in again.stdout
    assert again.stdout.splitlines()[-5:-1] == first.stdout.splitlines()[-4:]
    assert (tmp_path / "t.png").stat().st_size > 5000
    other = [*args[:-5], "1e-4", "1e-2", "8", *args[-2:]]
    refused = script("eq12_trace.py", *other)
    assert refused.returncode == 1 and "holds another run's measurements" in refused.stderr
