"""Projected wall time of the ``rggpso-rq1`` plan at paper scale, from a stratified sample, beside
the same projection for a reference revision measured in the same run.

Runs ``--scenes`` scenes per obstacle-count setting (10 settings) x ``--runs`` runs x the six
methods at paper settings (100 particles, 200 iterations) with the local process executor on
``--workers`` workers, and prints each method's mean run time (the run's own compute, Numba
compilation left out), the sample's throughput and two projections of the whole plan (60,000
runs) on the same workers: from the runs' own compute (each method's mean x 10,000 runs /
workers: what the full sweep takes while the runner's overhead stays at its measured 1-2 %) and
from the sample's wall clock (which also pays for starting the workers: an upper bound).

With ``--reference REV`` the same sample runs, alternately with this tree, on the source of
revision ``REV`` of this repository (``git archive``, imported through ``PYTHONPATH``; its
Numba kernels compiled by a short warm-up sweep first): the previous implementation measured
on the same machine at the same time. ``--rounds`` alternations; each tree's best round is
kept. The issue's target: <= 10 minutes on this 2-core machine.

    python benchmarks/rggpso_sweep.py [--scenes 2] [--runs 1] [--workers 2]
        [--reference c5ba4fb] [--rounds 2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from typing import Any

from _rq1_sample import measure, sample_plan

HERE = Path(__file__).resolve().parent


def _child(a: argparse.Namespace) -> None:
    """Measure in this process's tree and print one JSON line (the parent reads it)."""
    if a.warm:
        plan, _ = sample_plan(1, 1, iterations=2)
        measure(plan, "process", a.workers)
        return
    plan, n_paper = sample_plan(a.scenes, a.runs)
    out = measure(plan, "process", a.workers)
    out["n_paper"] = n_paper
    print(json.dumps(out))


def _extract(rev: str, dest: Path) -> Path:
    """The ``src`` folder of revision ``rev`` of this repository, under ``dest``."""
    blob = subprocess.run(["git", "-C", str(HERE.parent), "archive", rev, "src"], check=True,
                          capture_output=True).stdout  # fmt: skip
    archive = dest / "src.tar"
    archive.write_bytes(blob)
    with tarfile.open(archive) as t:
        t.extractall(dest, filter="data")
    return dest / "src"


def _run(a: argparse.Namespace, src: Path | None, warm: bool = False) -> dict[str, Any] | None:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    args = [sys.executable, str(Path(__file__).resolve()), "--child", "--scenes", str(a.scenes),
            "--runs", str(a.runs), "--workers", str(a.workers)]  # fmt: skip
    if warm:
        args.append("--warm")
    proc = subprocess.run(args, env=env, capture_output=True, text=True, check=True)
    return None if warm else json.loads(proc.stdout.strip().splitlines()[-1])


def _report(name: str, r: dict[str, Any], workers: int) -> float:
    per = r["per_algorithm"]
    n_paper = r["n_paper"]
    compute = sum(per.values()) * n_paper / len(per) / workers
    by_wall = n_paper / (r["runs"] / r["wall"])
    print(f"{name}: {r['runs']} runs in {r['wall']:.1f} s ({r['runs'] / r['wall']:.2f} runs/s), "
          f"errors {r['errors']}")  # fmt: skip
    for alg, t in sorted(per.items(), key=lambda kv: kv[1]):
        print(f"  {alg:9s} {t:.3f} s per run")
    print(f"  projected rggpso-rq1 at paper scale ({n_paper:,} runs) on {workers} workers: "
          f"{compute / 60:.1f} min from the runs' compute, {by_wall / 60:.1f} min from the "
          "sample's wall clock (target <= 10 min)")  # fmt: skip
    return compute


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=2, help="scenes per obstacle-count setting")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--reference", default=None, help="a revision to measure beside this tree")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        _child(a)
        return
    with tempfile.TemporaryDirectory() as tmp:
        trees: list[tuple[str, Path | None]] = [("this tree", None)]
        if a.reference:
            trees.append((f"reference {a.reference}", _extract(a.reference, Path(tmp))))
        for _, src in trees:
            _run(a, src, warm=True)  # compiles (or loads) the tree's kernels
        best: dict[str, dict[str, Any]] = {}
        for _ in range(a.rounds):
            for name, src in trees:
                r = _run(a, src)
                assert r is not None
                if name not in best or r["wall"] < best[name]["wall"]:
                    best[name] = r
    projected = {name: _report(name, r, a.workers) for name, r in best.items()}
    if a.reference:
        ref, this = projected[f"reference {a.reference}"], projected["this tree"]
        print(f"this tree / reference, projected from the runs' compute: {this / ref:.2f} "
              f"({ref / this:.2f}x faster)")  # fmt: skip


if __name__ == "__main__":
    main()
