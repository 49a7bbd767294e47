"""The fault campaign of docs/reliability.md: kills at every point of the write path and at
random times on every command that writes steps, and a list of bad inputs.

usage: .venv/bin/python benchmarks/faults.py [--random 4] [--seed 1] [--workdir DIR]

For each command (a periodic sweep and a punch with ``--fields``, an ensemble, a
comparison, the study at a toy size): an uninterrupted run, then one run killed (SIGKILL) at
each point of ``tests/kill_at.py``'s write path and ``--random`` runs killed at random
instants, each followed by ``--resume`` (the study: run again).  A fault is survived when the
resumed run exits 0 with every step equal to the uninterrupted run's to the solver's
tolerance.  Then each bad input: clean when it exits with its documented status (2, or 74
for storage), says so in one line without a traceback, and leaves no file behind.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
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
    ("compare", f"compare {GEN} --pressure 1e-3 --solvers cg,pk,bnls", _same_compare),
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
    failures = []
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
            again = cli(*args, *([] if kind == "study" else ["--resume"]))
            try:
                assert again.returncode == 0, again.stderr
                same(whole, out)
                survived += 1
            except AssertionError as exc:
                failures.append(f"{name}: {str(exc).strip()[:200]}")
    return tried, survived, failures


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
    g, out = GEN.split(), ["--output", str(folder / "out.h5")]
    run = ["periodic", *g, "--pressures", "1e-3"]
    return [
        ("--minutes nan", ["study", "--minutes", "nan", "--data", str(folder / "d")], 2),
        ("--minutes -1", ["study", "--minutes=-1", "--data", str(folder / "d")], 2),
        ("--stop-after nan", [*run, "--stop-after", "nan", *out], 2),
        ("--grid 200000", ["periodic", "--grid", "200000", "--hurst", "0.7", "--rms-slope",
                           "0.1", "--pressures", "1e-3", *out], 2),
        ("a seed of 2^70", ["periodic", *g[:-2], "--seed", str(2**70), "--pressures", "1e-3",
                            *out], 2),
        ("theory on a flat map", ["theory", "--heights", str(folder / "flat.npy"), *out], 2),
        ("compare --solvers ''", ["compare", *g, "--pressure", "1e-3", "--solvers", ",", *out], 2),
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
