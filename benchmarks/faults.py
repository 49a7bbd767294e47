"""The fault campaign of docs/reliability.md: kills at every point of the write path and at
random times on every command that writes steps, signals and damaged parts, the slips of a
careless user, and a list of bad inputs.

usage: .venv/bin/python benchmarks/faults.py [--random 4] [--seed 1] [--workdir DIR]

For each command (a periodic sweep and a punch with ``--fields``, an ensemble, a
comparison, the study at a toy size): an uninterrupted run, then one run killed (SIGKILL) at
each point of ``tests/kill_at.py``'s write path and ``--random`` runs killed at random
instants, each followed by ``--resume`` (the study: run again).  A fault is survived when the
resumed run exits 0 with every step equal to the uninterrupted run's: to rounding when it went
on from the saved state, else to the solver's tolerance (``kill_at.same_result``), and no
temporary file of a killed writer is left.  The sweep
and the punch are also sent SIGTERM at points of the write path (and from inside a
finaliser), which must end them with exit 130 and one note, and get a part file damaged,
which must stop the assembly with exit 74 and one line; ``--resume`` then completes them.
Each slip (the same command again without ``--resume``, a resume over another run's files, a
swapped part, loosened tolerances, a text map with a byte-order mark ...) must end as
documented, with nothing lost and nothing wrong unflagged.  Then each bad input: clean when
it exits with its documented status (2, or 74 for storage), says so in one line without a
traceback, and leaves no file behind.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from kill_at import POINTS, RTOL, same_result  # noqa: E402

ENV = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
GEN = "--grid 96 --hurst 0.7 --rms-slope 0.1 --seed 3"


def cli(*args: str, killer: str = "") -> subprocess.CompletedProcess:
    head = (
        [str(ROOT / "tests" / "kill_at.py"), killer, "--"]
        if killer
        else ["-m", "petsc_contact.cli"]
    )
    return subprocess.run(
        [sys.executable, *head, *args], capture_output=True, text=True, env=ENV, timeout=900
    )


def _same_compare(a: Path, b: Path) -> None:
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert fb.attrs["complete"] and fa.attrs["solvers"] == fb.attrs["solvers"]
        for name in json.loads(fa.attrs["solvers"]):
            assert fb[name].attrs["converged"] == fa[name].attrs["converged"]
        assert np.isclose(fa.attrs["reference_mean_gap"], fb.attrs["reference_mean_gap"])


def _same_ensemble(a: Path, b: Path) -> None:
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert np.allclose(fb["mean_gap"][...], fa["mean_gap"][...], rtol=RTOL, atol=0)


def _same_study(a: Path, b: Path) -> None:
    """Every piece, equal; a kill -9 may leave a piece's (free) lock file behind."""
    names = sorted(p.name for p in (a / "fig1").iterdir())
    assert names == sorted(p.name for p in (b / "fig1").iterdir() if p.suffix != ".lock")
    for name in names:
        if name.endswith(".h5"):
            same_result(a / "fig1" / name, b / "fig1" / name, fields=False)
        else:  # the step table beside each file: as many rows
            rows = [len((x / "fig1" / name).read_text().splitlines()) for x in (a, b)]
            assert rows[0] == rows[1], f"{name}: {rows[1]} rows, not {rows[0]}"


Scenario = tuple[str, str, Callable[[Path, Path], None]]
SCENARIOS: list[Scenario] = [
    ("periodic", f"periodic {GEN} --sweep 6,1e-4,1e-2 --stiffness --fields",
     lambda a, b: same_result(a, b, True)),
    ("punch", f"punch {GEN} --forces 1e-4,1e-3,3e-3 --fields",
     lambda a, b: same_result(a, b, True)),
    ("ensemble", f"ensemble {GEN.replace('--seed 3', '')} --seeds 0-2 --pressures 1e-3,1e-2",
     _same_ensemble),
    ("compare", f"compare {GEN} --pressures 1e-3 --solvers cg,pk,bnls", _same_compare),
    ("study", "study --figure 1 --shrink 128 --minutes 30", _same_study),
]  # fmt: skip


def _target(kind: str, folder: Path, name: str) -> tuple[list[str], Path]:
    """The arguments that put a run's output in ``folder``, and what to compare."""
    if kind == "study":
        return ["--data", str(folder / name)], folder / name
    out = folder / f"{name}.h5"
    return ["--output", str(out)], out


def campaign(folder: Path, randoms: int, rng: random.Random) -> tuple[int, int, list[str]]:
    tried = survived = 0
    failures: list[str] = []
    for kind, command, same in SCENARIOS:
        where, whole = _target(kind, folder, f"{kind}-whole")
        assert cli(*command.split(), *where, "--quiet").returncode == 0, kind
        faults = [f"point {p}" for p in POINTS] + [f"random {k}" for k in range(randoms)]
        for fault in faults:
            name = f"{kind}-{fault.replace(' ', '-').replace(':', '-')}"
            where, out = _target(kind, folder, name)
            args = [*command.split(), *where, "--quiet"]
            if fault.startswith("point"):
                cut = cli(*args, killer=fault.split()[1])
                if cut.returncode != -signal.SIGKILL:
                    continue  # this command never passes that point (compare has no fields)
            else:
                process = subprocess.Popen(
                    [sys.executable, "-m", "petsc_contact.cli", *args], env=ENV,
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                )  # fmt: skip
                time.sleep(rng.uniform(0.5, 6.0))
                process.send_signal(signal.SIGKILL)
                process.wait()
            tried += 1
            resume = [] if kind == "study" else ["--resume"]
            survived += _kept(name, partial(_resumed, args + resume, whole, out, same), failures)
    return tried, survived, failures


def _kept(what: str, check: Callable[[], None], failures: list[str]) -> bool:
    """Whether ``check`` passes; when it fails, ``what`` and its assertion join ``failures``."""
    try:
        check()
        return True
    except AssertionError as exc:
        failures.append(f"{what}: {str(exc).strip()[:200]}")
        return False


def _resumed(args: list[str], whole: Path, out: Path, same: Callable[[Path, Path], None]) -> None:
    """Run ``args`` (a resume) and assert that it ends ``out`` equal to ``whole``, with no
    temporary file of a killed writer left beside it."""
    again = cli(*args)
    assert again.returncode == 0, again.stderr
    same(whole, out)
    left = sorted(p.name for p in out.parent.glob(f"{out.stem}.*.tmp"))
    assert not left, f"left behind: {left}"


SIGNALS = ["before:commit:3:TERM", "after:commit:2:TERM", "after:state:2:TERM",
           "before:final:1:TERM", "after:step:2:FINALIZER"]  # fmt: skip
DAMAGES = ["damage:heights:1", "damage:step:2"]


def _stopped_then_resumed(
    cut: subprocess.CompletedProcess,
    said: tuple[int, str],
    args: list[str],
    whole: Path,
    out: Path,
    same: Callable[[Path, Path], None],
) -> None:
    """Assert that ``cut`` ended with status and one line as ``said`` (the status, a word of
    the line), and that the resume ``args`` ends ``out`` equal to ``whole``."""
    lines = cut.stderr.strip().splitlines()
    status, word = said
    assert cut.returncode == status and len(lines) == 1 and word in lines[0], (
        cut.returncode, lines[-3:])  # fmt: skip
    _resumed(args, whole, out, same)


def signals_and_damage(folder: Path) -> tuple[int, int, list[str]]:
    """SIGTERM (exit 130, one note) and damaged parts (exit 74, one line) on the sweep and
    the punch, each completed by ``--resume``."""
    tried = survived = 0
    failures: list[str] = []
    for kind, command, same in SCENARIOS[:2]:
        whole = folder / f"{kind}-whole.h5"
        assert cli(*command.split(), "--output", str(whole), "--quiet").returncode == 0, kind
        for spec in SIGNALS + DAMAGES:
            out = folder / f"{kind}-{spec.replace(':', '-')}.h5"
            args = [*command.split(), "--output", str(out), "--quiet"]
            cut = cli(*args, killer=spec)
            tried += 1
            said = (74, "--resume") if spec in DAMAGES else (130, "interrupted")
            check = partial(_stopped_then_resumed, cut, said, [*args, "--resume"], whole, out, same)
            survived += _kept(f"{kind} {spec}", check, failures)
    return tried, survived, failures


def _steps(partial: Path) -> int:
    with h5py.File(partial) as f:
        return int(f["converged"].shape[0])


def _text_maps(folder: Path) -> list[tuple[str, Path]]:
    """One 16 x 16 map written plainly and as a careless export would write it."""
    h = np.random.default_rng(5).standard_normal((16, 16))
    plain = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in h) + "\n"
    variants = {
        "plain": plain.encode(),
        "a UTF-8 byte-order mark": b"\xef\xbb\xbf" + plain.encode(),
        "UTF-16 with a mark": plain.encode("utf-16"),
        "CRLF line ends": plain.replace("\n", "\r\n").encode(),
        "tabs": plain.replace(" ", "\t").encode(),
        "trailing blank lines": (plain + "\n\n  \n").encode(),
    }
    out: list[tuple[str, Path]] = []
    for what, data in variants.items():
        path = folder / f"map-{len(out)}.txt"
        path.write_bytes(data)
        out.append((what, path))
    return out


def slips(folder: Path) -> tuple[int, int, list[str]]:
    """What a careless user does: each must end as documented, nothing lost, nothing wrong
    unflagged."""
    g = GEN.split()
    sweep = ["periodic", *g, "--sweep", "4,1e-4,1e-2", "--fields", "--quiet"]
    checks: list[tuple[str, Callable[[], None]]] = []

    def again_without_resume() -> None:
        out = folder / "again.h5"
        cli(*sweep, "--output", str(out), killer="after:commit:3")
        kept = _steps(Path(f"{out}.partial"))
        r = cli(*sweep, "--output", str(out))
        assert r.returncode == 2 and "--overwrite" in r.stderr, r.stderr
        assert _steps(Path(f"{out}.partial")) == kept == 2, kept  # the first commit has none

    def swapped_part() -> None:
        out = folder / "swapped.h5"
        cli(*sweep, "--output", str(out), killer="after:commit:3")
        parts = Path(f"{out}.parts")
        shutil.copy(parts / "step-000001.h5", parts / "step-000002.h5")
        assert cli(*sweep, "--output", str(out), "--resume").returncode == 0
        same_result(folder / "sweep-whole.h5", out, fields=True)

    def parts_as_a_file() -> None:
        out = folder / "plain-parts.h5"
        cli(*sweep, "--output", str(out), killer="after:commit:3")
        parts = Path(f"{out}.parts")
        shutil.rmtree(parts)
        parts.write_text("not a folder")
        assert cli(*sweep, "--output", str(out), "--resume").returncode == 0
        same_result(folder / "sweep-whole.h5", out, fields=True)

    def ensemble_of_another_hurst() -> None:
        base = ["ensemble", *GEN.replace("--seed 3", "").split(), "--seeds", "0-1",
                "--pressures", "1e-3", "--quiet", "--output", str(folder / "ens.h5")]  # fmt: skip
        assert cli(*base).returncode == 0
        before = (folder / "ens_seed0.h5").read_bytes()
        r = cli(*[v if v != "0.7" else "0.3" for v in base], "--resume")
        assert r.returncode == 2 and (folder / "ens_seed0.h5").read_bytes() == before, r.stderr

    def ensemble_moved_with_its_seeds() -> None:  # after ensemble_of_another_hurst
        moved = folder / "moved"
        moved.mkdir(exist_ok=True)
        for p in folder.glob("ens*.h5"):
            shutil.copy(p, moved / p.name)
        shutil.copy(folder / "ens_seed1.h5", folder / "ens_seed0.h5")  # the originals changed
        assert cli("plot", str(moved / "ens.h5")).returncode == 0
        r = cli("plot", str(folder / "ens.h5"))
        assert r.returncode == 2 and "is not the run of seed 0" in r.stderr, r.stderr

    def compare_at_another_pressure() -> None:
        out = folder / "cmp.h5"
        args = ["compare", *g, "--pressures", "1e-3", "--solvers", "cg,pk,bnls", "--quiet"]
        cli(*args, "--output", str(out), killer="after:commit:2")
        before = Path(f"{out}.partial").read_bytes()
        r = cli(*[v if v != "1e-3" else "2e-3" for v in args], "--output", str(out), "--resume")
        assert r.returncode == 2 and Path(f"{out}.partial").read_bytes() == before, r.stderr

    def loosened(option: list[str], geometry: str = "periodic") -> Callable[[], None]:
        def check() -> None:
            out = folder / f"loose-{len(option)}-{option[0]}-{geometry}.h5"
            loads = ["--pressures", "1e-2"] if geometry == "periodic" else ["--forces", "1e-3"]
            r = cli(geometry, *g, *loads, "--stiffness", "--quiet", "--output", str(out), *option)
            with h5py.File(out) as f:
                flagged = not (np.all(f["converged"][:]) and np.all(f["accurate"][:]))
            assert r.returncode == 1 and flagged, (r.returncode, r.stderr[-300:])

        return check

    def same_map(path: Path, plain: Path) -> Callable[[], None]:
        def check() -> None:
            outs = [folder / f"{p.stem}.h5" for p in (plain, path)]
            for p, out in zip((plain, path), outs, strict=True):
                r = cli("periodic", "--heights", str(p), "--length", "1", "--pressures", "1e-3",
                        "--quiet", "--overwrite", "--output", str(out))  # fmt: skip
                assert r.returncode == 0, r.stderr
            with h5py.File(outs[0]) as a, h5py.File(outs[1]) as b:
                assert np.array_equal(a["heights"][...], b["heights"][...])

        return check

    def map_changed_at_resume() -> None:
        h = np.random.default_rng(7).standard_normal((64, 64)) * 1e-2
        np.save(folder / "h.npy", h)
        out = folder / "changed.h5"
        args = ["periodic", "--heights", str(folder / "h.npy"), "--length", "1", "--sweep",
                "4,1e-4,1e-2", "--quiet", "--output", str(out)]  # fmt: skip
        assert cli(*args, "--stop-after", "0").returncode == 75
        before = Path(f"{out}.partial").read_bytes()
        np.save(folder / "h.npy", 2 * h)
        r = cli(*args, "--resume")
        assert r.returncode == 2 and "--overwrite" in r.stderr, (r.returncode, r.stderr[-300:])
        assert Path(f"{out}.partial").read_bytes() == before and not out.exists()

    def compare_map_changed_at_resume() -> None:
        h = np.random.default_rng(8).standard_normal((64, 64)) * 1e-2
        np.save(folder / "hc.npy", h)
        out = folder / "cmp-map.h5"
        args = ["compare", "--heights", str(folder / "hc.npy"), "--length", "1", "--pressures",
                "1e-3", "--solvers", "cg,pk,bnls", "--quiet", "--output", str(out)]  # fmt: skip
        cli(*args, killer="after:commit:2")
        np.save(folder / "hc.npy", 2 * h)
        r = cli(*args, "--resume")
        assert r.returncode == 2 and "--overwrite" in r.stderr, (r.returncode, r.stderr[-300:])

    def compare_options_changed_at_resume() -> None:
        out = folder / "cmp-opts.h5"
        args = ["compare", *g, "--pressures", "1e-3", "--solvers", "cg,bncg", "--quiet",
                "--output", str(out)]  # fmt: skip
        assert cli(*args, "-bncg_tao_max_it", "5").returncode in (0, 1)
        r = cli(*args, "-bncg_tao_max_it", "500", "--resume")
        assert r.returncode == 0 and "never used" not in r.stderr, (r.returncode, r.stderr)
        with h5py.File(out) as f:
            assert f["bncg"].attrs["converged"], "bncg kept its 5-iteration result"

    def header_map_with_sides_as_written() -> None:
        rows = np.random.default_rng(1).standard_normal((16, 32))
        text = "x y z\n" + "\n".join(" ".join(f"{v:.6f}" for v in row) for row in rows)
        (folder / "header.txt").write_text(text + "\n")
        args = ["periodic", "--heights", str(folder / "header.txt"), "--pressures", "1e-3",
                "--quiet", "--output", str(folder / "header.h5")]  # fmt: skip
        r = cli(*args, "--length", "1,2")  # the rows as written: refused, the header said
        assert r.returncode == 2 and "--length 2,1" in r.stderr and "header" in r.stderr, r.stderr
        assert not (folder / "header.h5").exists()
        assert cli(*args, "--length", "2,1").returncode == 0

    def pressure_beyond_full_contact() -> None:
        out = folder / "full.h5"
        r = cli("periodic", *g, "--pressures", "1e-2,1", "--stiffness", "--output", str(out))
        assert r.returncode == 0 and "<-- FULL CONTACT" in r.stdout, (r.returncode, r.stdout)
        assert "at or beyond full contact" in r.stderr, r.stderr
        with h5py.File(out) as f:
            assert f["full_contact"][:].tolist() == [False, True] and np.isnan(f["stiffness"][1])

    def periodic_sweep_made_a_punch() -> None:
        code = (
            "import warnings; from petsc_contact import Run\n"
            "with warnings.catch_warnings(record=True) as w:\n"
            "    warnings.simplefilter('always')\n"
            "    punch = Run(sweep=(6, 1e4, 1e6)).with_(geometry='punch')\n"
            "assert punch.sweep is None and punch.pressures[-1] == 1e6, punch\n"
            "assert 'nominal pressures over its face' in str(w[0].message)\n"
        )
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV)
        assert r.returncode == 0, r.stderr

    checks += [
        ("a header map's --length for its rows as written", header_map_with_sides_as_written),
        ("--pressures beyond full contact", pressure_beyond_full_contact),
        ("a periodic run's sweep handed to the punch", periodic_sweep_made_a_punch),
        ("the same command again without --resume", again_without_resume),
        ("the heights file changed before --resume", map_changed_at_resume),
        ("compare's heights changed before --resume", compare_map_changed_at_resume),
        ("compare --resume with a solver's options changed", compare_options_changed_at_resume),
        ("step 2's part replaced by step 1's", swapped_part),
        ("the parts folder a plain file", parts_as_a_file),
        ("ensemble --resume over another H's seeds", ensemble_of_another_hurst),
        ("the ensemble's folder moved, its seed files changed", ensemble_moved_with_its_seeds),
        ("compare --resume at another pressure", compare_at_another_pressure),
        ("-tao_grtol 0.5", loosened(["-tao_grtol", "0.5"])),
        ("-tao_gatol 1e-2", loosened(["-tao_gatol", "1e-2"])),
        ("-stiffness_ksp_rtol 0.5", loosened(["-stiffness_ksp_rtol", "0.5"])),
        ("-stiffness_ksp_max_it 1", loosened(["-stiffness_ksp_max_it", "1"])),
        ("punch -tao_gatol 1e-2", loosened(["-tao_gatol", "1e-2"], "punch")),
    ]
    maps = _text_maps(folder)
    checks += [(f"a text map with {what}", same_map(path, maps[0][1])) for what, path in maps[1:]]
    cli(*sweep, "--output", str(folder / "sweep-whole.h5"))
    failures: list[str] = []
    survived = sum(_kept(what, check, failures) for what, check in checks)
    return len(checks), survived, failures


def bad_inputs(folder: Path) -> list[tuple[str, list[str], int]]:
    """Each bad input: what it is, its arguments, and its documented exit status."""
    rng = np.random.default_rng(0)
    np.save(folder / "huge.npy", rng.standard_normal((32, 32)) * 1e300)
    np.save(folder / "flat.npy", np.ones((32, 32)))
    np.save(folder / "nan.npy", np.full((32, 32), np.nan))
    np.save(folder / "cube.npy", np.zeros((4, 4, 4)))
    (folder / "noise.dat").write_bytes(rng.bytes(2 * 16 * 16))
    (folder / "broken.h5").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(64))
    (folder / "notes.txt").write_text("not a map\n")
    (folder / "ragged.txt").write_text("1 2 3\n4 5 6\n7 8\n")
    (folder / "worded.txt").write_text("1 2 3\n4 NA 6\n7 8 9\n")
    (folder / "noise.opts").write_bytes(rng.bytes(256))
    nul = np.random.default_rng(1).standard_normal((16, 32))
    text = bytearray(("\n".join(" ".join(f"{v:.6f}" for v in row) for row in nul) + "\n").encode())
    text[40:48] = bytes(8)  # a crash's NUL padding inside the first rows
    (folder / "nul.txt").write_bytes(bytes(text))
    (folder / "a-folder").mkdir(exist_ok=True)
    with h5py.File(folder / "bare-run.h5", "w") as f:  # a run written with modulus=1e9: no unit
        f.attrs.update(geometry="periodic", length_unit="", pressure_unit="")
        f["nominal_pressure"], f["mean_gap"] = [1e6], [1e-7]
    if not (folder / "fifo").exists():
        os.mkfifo(folder / "fifo")
    if not (folder / "full").exists() and os.geteuid() == 0:  # a device node like /dev/full
        os.mknod(folder / "full", 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    g, out = GEN.split(), ["--output", str(folder / "out.h5")]
    run = ["periodic", *g, "--pressures", "1e-3"]
    heights = ["--heights", str(folder / "flat.npy")]
    devices = [("--output a device node", [*run, "--output", str(folder / "full")], 2)] * (
        os.geteuid() == 0
    )
    return [
        *devices,
        ("--output a FIFO", [*run, "--output", str(folder / "fifo")], 2),
        ("--output a folder", [*run, "--output", str(folder / "a-folder")], 2),
        ("--output the heights file", ["periodic", *heights, "--pressures", "1e-3",
                                       "--output", str(folder / "flat.npy")], 2),
        ("--plot the --output", [*run, *out, "--plot", str(folder / "out.h5")], 2),
        ("compare --solvers cg,cg", ["compare", *g, "--pressures", "1e-3", "--solvers", "cg,cg",
                                     *out], 2),
        ("theory --compare without --plot", ["theory", *heights, "--compare",
                                             str(folder / "cut.h5.partial"), *out], 2),
        ("an options file of random bytes", [*run, *out, "-options_file",
                                             str(folder / "noise.opts")], 2),
        ("--heights a folder", ["periodic", "--heights", str(folder / "a-folder"),
                                "--pressures", "1e-3", *out], 2),
        ("--heights /dev/null", ["periodic", "--heights", "/dev/null", "--pressures", "1e-3",
                                 *out], 2),
        ("a ragged text map", ["periodic", "--heights", str(folder / "ragged.txt"),
                               "--length", "1", "--pressures", "1e-3", *out], 2),
        ("NA in a text map", ["periodic", "--heights", str(folder / "worded.txt"),
                              "--length", "1", "--pressures", "1e-3", *out], 2),
        ("study --shrink 0", ["study", "--shrink", "0", "--data", str(folder / "d")], 2),
        ("study --data ''", ["study", "--data", ""], 2),
        ("--pressures 1e-3,,2e-3", ["periodic", *g, "--pressures", "1e-3,,2e-3", *out], 2),
        ("plot of a .partial", ["plot", str(folder / "cut.h5.partial")], 2),
        ("--minutes nan", ["study", "--minutes", "nan", "--data", str(folder / "d")], 2),
        ("--minutes -1", ["study", "--minutes=-1", "--data", str(folder / "d")], 2),
        ("--stop-after nan", [*run, "--stop-after", "nan", *out], 2),
        ("--grid 200000", ["periodic", "--grid", "200000", "--hurst", "0.7", "--rms-slope",
                           "0.1", "--pressures", "1e-3", *out], 2),
        ("a seed of 2^70", ["periodic", *g[:-2], "--seed", str(2**70), "--pressures", "1e-3",
                            *out], 2),
        ("theory on a flat map", ["theory", "--heights", str(folder / "flat.npy"), *out], 2),
        ("compare --solvers ''", ["compare", *g, "--pressures", "1e-3", "--solvers", ",", *out], 2),
        ("a missing options file", [*run, *out, "-options_file", "/no/such.opts"], 2),
        ("heights x 1e300", ["periodic", "--heights", str(folder / "huge.npy"), "--pressures",
                             "1e-3", *out], 2),
        ("--pressures 1e300", ["periodic", *g, "--pressures", "1e300", *out], 2),
        ("--pressures 1e-12", ["periodic", *g, "--pressures", "1e-12", *out], 2),
        ("--pressures -1", ["periodic", *g, "--pressures=-1", *out], 2),
        ("--pressures nan", ["periodic", *g, "--pressures", "nan", *out], 2),
        ("-tao_gatol abc", [*run, *out, "-tao_gatol", "abc"], 2),
        ("-tao_type nosuch", [*run, *out, "-tao_type", "nosuch"], 2),
        ("--output ''", [*run, "--output", ""], 2),
        ("an output folder that does not exist", [*run, "--output", "/no/such/out.h5"], 74),
        ("an unknown option", [*run, *out, "--no-such"], 2),
        ("--hurst 2", ["periodic", "--grid", "32", "--hurst", "2", "--rms-slope", "0.1",
                       "--pressures", "1e-3", *out], 2),
        ("--grid 1", ["periodic", "--grid", "1", "--hurst", "0.7", "--rms-slope", "0.1",
                      "--pressures", "1e-3", *out], 2),
        ("heights all NaN", ["periodic", "--heights", str(folder / "nan.npy"), "--pressures",
                             "1e-3", *out], 2),
        ("a 3-D array", ["periodic", "--heights", str(folder / "cube.npy"), "--pressures",
                         "1e-3", *out], 2),
        ("random bytes", ["periodic", "--heights", str(folder / "noise.dat"), "--pressures",
                          "1e-3", *out], 2),
        ("a broken HDF5 file", ["periodic", "--heights", str(folder / "broken.h5"),
                                "--pressures", "1e-3", *out], 2),
        ("prose", ["periodic", "--heights", str(folder / "notes.txt"), "--pressures", "1e-3",
                   *out], 2),
        ("a missing heights file", ["periodic", "--heights", str(folder / "none.npy"),
                                    "--pressures", "1e-3", *out], 2),
        ("--channel 9", ["periodic", "--heights", str(folder / "flat.npy"), "--channel", "9",
                         "--pressures", "1e-3", *out], 2),
        ("--resume of another run", [*run, "--seed", "4", "--output", str(folder / "cut.h5"),
                                     "--resume"], 2),
        ("punch --forces 0", ["punch", *g, "--forces", "0", *out], 2),
        ("ensemble with --heights", ["ensemble", "--heights", str(folder / "flat.npy"),
                                     "--seeds", "0-1", "--pressures", "1e-3", *out], 2),
        ("NUL bytes in a text map", ["periodic", "--heights", str(folder / "nul.txt"),
                                     "--length", "1", "--pressures", "1e-3", *out], 2),
        ("--length 150um,", [*run, "--length", "150um,", *out], 2),
        ("--output x.h5/", [*run, "--output", str(folder / "x.h5") + "/"], 2),
        ("-tao_max_it abc", [*run, *out, "-tao_max_it", "abc"], 2),
        ("punch --forces 1e300", ["punch", *g, "--forces", "1e300", *out], 2),
        ("--options-prefix a_ with an unknown type", [*run, *out, "--options-prefix", "a_",
                                                      "-a_tao_type", "nosuch"], 2),
        ("theory --compare a unit-free run in GPa", ["theory", *g, "--modulus", "1GPa",
                                                     "--length", "100um", "--plot",
                                                     str(folder / "t.png"), "--compare",
                                                     str(folder / "bare-run.h5"), *out], 2),
    ]  # fmt: skip


def clean_inputs(folder: Path) -> tuple[int, list[str]]:
    cases = bad_inputs(folder)
    # the resume case needs a run of another seed cut short first
    cli("periodic", *GEN.split(), "--pressures", "1e-3,1e-2", "--stop-after", "0", "--quiet",
        "--output", str(folder / "cut.h5"))  # fmt: skip
    kept = sorted(p.name for p in folder.iterdir())
    clean, failures = 0, []
    for what, args, status in cases:
        r = cli(*args)
        lines = r.stderr.strip().splitlines()
        left = sorted(p.name for p in folder.iterdir())
        ok = (
            r.returncode == status
            and len(lines) == 1
            and lines[0].startswith("petsc-contact: error:")
            and left == kept
        )
        clean += ok
        if not ok:
            failures.append(f"{what}: exit {r.returncode}, {lines[-3:]}, left {left}")
    return clean, failures


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--random", type=int, default=4, help="random-time kills per command")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workdir", default=None)
    args = ap.parse_args()
    folder = Path(args.workdir or tempfile.mkdtemp(prefix="faults-"))
    (folder / "kills").mkdir(parents=True, exist_ok=True)
    (folder / "inputs").mkdir(exist_ok=True)
    began = time.perf_counter()
    tried, survived, failures = campaign(folder / "kills", args.random, random.Random(args.seed))
    print(f"faults: {tried} tried, {survived} survived with nothing lost")
    for line in failures:
        print(f"  {line}")
    tried, survived, failures = signals_and_damage(folder / "kills")
    print(
        f"signals and damaged parts: {tried} tried, {survived} ended as documented, resumed whole"
    )
    for line in failures:
        print(f"  {line}")
    (folder / "slips").mkdir(exist_ok=True)
    tried, survived, failures = slips(folder / "slips")
    print(f"slips: {tried} tried, {survived} ended as documented, nothing lost or unflagged")
    for line in failures:
        print(f"  {line}")
    cases = len(bad_inputs(folder / "inputs"))
    clean, failures = clean_inputs(folder / "inputs")
    print(f"bad inputs: {cases} tried, {clean} clean (status, one line, nothing left)")
    for line in failures:
        print(f"  {line}")
    print(f"# {time.perf_counter() - began:.0f} s")
    if not args.workdir:
        shutil.rmtree(folder)


if __name__ == "__main__":
    main()
