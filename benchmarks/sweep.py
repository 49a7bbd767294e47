"""A whole load sweep with the exact stiffness, this checkout against an earlier commit, in one run.

usage: .venv/bin/python benchmarks/sweep.py [--grid 2048] [--hurst 0.7] [--rolloff-ratio 1]
       [--baseline 2fc6848] [--sweep 12,1e-7,1e-1 | --pressures P1,...] [--repeat 1]
       [-- PETSc options]
Both runs are the command line a user types, ``petsc-contact periodic --grid N --hurst H
--rms-slope 0.1 --rolloff-ratio R --cutoff-ratio N/2 --seed 1 --sweep ... --stiffness``
(paper bandwidth: roughness down to two pixels), each in its own process: the baseline from a
temporary ``git worktree`` of ``--baseline``, this checkout from its own tree, alternated
``--repeat`` times (the machine's speed drifts). Prints, per step and run, the iterations,
the contact solve's time, the stiffness solve's iterations and time (NaN for a commit that
does not record it); per run, the wall time and the peak resident memory of the process; and
the ratios of the medians (this checkout over the baseline). The mean gaps and stiffnesses
of the two are compared step by step: a mismatch beyond the tolerances' reach (5e-7
relative in the mean gap, 1e-6 in the stiffness) is printed as MISMATCH and makes the exit
status 1.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
COLUMNS = (
    "nominal_pressure",
    "iterations",
    "solve_time",
    "stiffness_iterations",
    "mean_gap",
    "stiffness",
    "area_fraction",
    "converged",
)
OPTIONAL = ("stiffness_time",)  # not written by earlier commits: NaN there


def run(tree: str, arguments: list[str], output: str) -> dict:
    """Run ``petsc-contact periodic`` from ``tree``; its per-step columns, wall time and peak
    memory (GiB)."""
    env = dict(os.environ, PYTHONPATH=tree)
    command = [
        sys.executable,
        "-m",
        "petsc_contact.cli",
        "periodic",
        *arguments,
        "--output",
        output,
        "--quiet",
    ]
    start = time.perf_counter()
    process = subprocess.Popen(command, env=env, cwd=tree)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        raise SystemExit(f"{tree}: petsc-contact exited with status {status}")
    with h5py.File(output) as f:
        columns = {k: np.asarray(f[k]) for k in COLUMNS}
        for k in OPTIONAL:
            columns[k] = (
                np.asarray(f[k]) if k in f else np.full(columns["iterations"].shape, np.nan)
            )
    return {"wall": wall, "memory": usage.ru_maxrss / 2**20, **columns}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=2048)
    ap.add_argument("--hurst", type=float, default=0.7)
    ap.add_argument("--rolloff-ratio", type=float, default=1.0, help="L/lambda_r")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--sweep", default="12,1e-7,1e-1", help="N,PMIN,PMAX as for the CLI")
    ap.add_argument(
        "--pressures",
        default=None,
        help="P1,... as for the CLI, instead of --sweep (one load: from first touch)",
    )
    ap.add_argument("--baseline", default="2fc6848", help="commit to compare with")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each, alternated")
    args, petsc = ap.parse_known_args()
    surface = [
        "--grid",
        str(args.grid),
        "--hurst",
        str(args.hurst),
        "--rms-slope",
        "0.1",
        "--rolloff-ratio",
        str(args.rolloff_ratio),
        "--cutoff-ratio",
        str(args.grid // 2),
        "--seed",
        str(args.seed),
        *(["--pressures", args.pressures] if args.pressures else ["--sweep", args.sweep]),
        "--stiffness",
        *[a for a in petsc if a != "--"],
    ]
    print("# petsc-contact periodic " + " ".join(surface))
    with tempfile.TemporaryDirectory() as tmp:
        base_tree = os.path.join(tmp, "baseline")
        subprocess.run(
            ["git", "-C", REPO, "worktree", "add", "--detach", "-q", base_tree, args.baseline],
            check=True,
        )
        try:
            runs: dict[str, list[dict]] = {"baseline": [], "this": []}
            for i in range(args.repeat):
                for name, tree in (("baseline", base_tree), ("this", REPO)):
                    out = run(tree, surface, os.path.join(tmp, f"{name}{i}.h5"))
                    runs[name].append(out)
                    print(
                        f"# {name} run {i + 1}: {out['wall']:.1f} s wall, "
                        f"{out['memory']:.2f} GiB peak",
                        flush=True,
                    )
        finally:
            subprocess.run(
                ["git", "-C", REPO, "worktree", "remove", "--force", base_tree], check=False
            )
    return report(runs, args.baseline)


def report(runs: dict[str, list[dict]], baseline: str) -> int:
    """Print the per-step table and the ratios; 1 if the two disagree or a step failed."""
    base, this = runs["baseline"][0], runs["this"][0]
    print(
        f"{'step':>4} {'p0':>9} {'area':>7} | {'its':>4} {'solve_s':>7} {'K its':>5} {'K_s':>5} | "
        f"{'its':>4} {'solve_s':>7} {'K its':>5} {'K_s':>5} | {'d mean_gap':>10} {'d K':>8}  "
        f"(baseline {baseline} | this checkout)"
    )
    status = 0
    for i, p0 in enumerate(this["nominal_pressure"]):
        du = abs(this["mean_gap"][i] / base["mean_gap"][i] - 1)
        dk = (
            abs(this["stiffness"][i] / base["stiffness"][i] - 1)
            if np.isfinite(base["stiffness"][i])
            else 0.0
        )
        flag = ""
        if du > 5e-7 or dk > 1e-6 or not (this["converged"][i] and base["converged"][i]):
            flag, status = "  MISMATCH", 1
        print(
            f"{i + 1:>4} {p0:>9.3e} {this['area_fraction'][i]:>7.4f} | "
            f"{base['iterations'][i]:>4} {base['solve_time'][i]:>7.2f} "
            f"{base['stiffness_iterations'][i]:>5} {base['stiffness_time'][i]:>5.2f} | "
            f"{this['iterations'][i]:>4} {this['solve_time'][i]:>7.2f} "
            f"{this['stiffness_iterations'][i]:>5} {this['stiffness_time'][i]:>5.2f} | "
            f"{du:>10.1e} {dk:>8.1e}{flag}"
        )
    for name in ("baseline", "this"):
        its = runs[name][0]["iterations"]
        warm = f", median of the warm-started steps {np.median(its[1:]):g}" if its.size > 1 else ""
        k_its = runs[name][0]["stiffness_iterations"]
        print(
            f"# {name}: iterations {int(its.sum())} in all, first step {its[0]}{warm}; "
            f"stiffness iterations {int(k_its.sum())} in all"
        )
    wall = {k: float(np.median([r["wall"] for r in v])) for k, v in runs.items()}
    solve = {k: float(np.median([r["solve_time"].sum() for r in v])) for k, v in runs.items()}
    memory = {k: max(r["memory"] for r in v) for k, v in runs.items()}
    print(
        f"# wall: {wall['baseline']:.1f} s -> {wall['this']:.1f} s, ratio "
        f"{wall['this'] / wall['baseline']:.3f}; contact solves: {solve['baseline']:.1f} s -> "
        f"{solve['this']:.1f} s, ratio {solve['this'] / solve['baseline']:.3f}; peak memory "
        f"{memory['baseline']:.2f} -> {memory['this']:.2f} GiB"
    )
    return status


if __name__ == "__main__":
    sys.exit(main())
