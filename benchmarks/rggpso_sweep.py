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

``--cpu`` (with ``--reference``) measures on a shared machine instead: one process per tree
runs the sample's runs one at a time, the two trees alternating run by run, and each run's
thread CPU time is taken (the least of ``--rounds``), so that load from other work inflates
both alike; the projection is then each method's mean CPU time x 10,000 runs / workers, what
the plan would take with every worker on a core of its own.

    python benchmarks/rggpso_sweep.py [--scenes 2] [--runs 1] [--workers 2]
        [--reference c5ba4fb] [--rounds 2] [--cpu]
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


def _serve(a: argparse.Namespace) -> None:
    """Run the sample's runs by index, as the parent asks on stdin; print each one's method
    and thread CPU time."""
    import time

    from uavplan.bench.execute import execute_run, limit_threads, warm_up

    limit_threads()
    warm_up()
    plan, n_paper = sample_plan(a.scenes, a.runs)
    specs = plan.runs("sample")
    for s in specs[: len(plan.algorithms)]:
        execute_run(s)  # the first runs load each method's code
    print(len(specs), n_paper, flush=True)
    for line in sys.stdin:
        s = specs[int(line)]
        t0 = time.thread_time()
        row = execute_run(s)
        print(s.algorithm, time.thread_time() - t0, row["status"], flush=True)


def _cpu(a: argparse.Namespace, trees: list[tuple[str, Path | None]]) -> dict[str, Any]:
    """Alternate the trees run by run; per tree the least CPU time of each run over the
    rounds, averaged per method (see the module)."""
    procs = {}
    for name, src in trees:
        env = dict(os.environ, NUMBA_NUM_THREADS="1")
        if src is not None:
            env["PYTHONPATH"] = str(src)
        args = [sys.executable, str(Path(__file__).resolve()), "--serve", "--scenes",
                str(a.scenes), "--runs", str(a.runs)]  # fmt: skip
        procs[name] = subprocess.Popen(args, env=env, stdin=subprocess.PIPE,
                                       stdout=subprocess.PIPE, text=True)  # fmt: skip
    sizes = {name: p.stdout.readline().split() for name, p in procs.items()}
    n, n_paper = (int(v) for v in sizes["this tree"])
    best: dict[str, dict[int, tuple[str, float]]] = {name: {} for name in procs}
    errors = dict.fromkeys(procs, 0)
    for r in range(a.rounds):
        for i in range(n):
            order = list(procs) if (i + r) % 2 == 0 else list(procs)[::-1]
            for name in order:
                p = procs[name]
                p.stdin.write(f"{i}\n")
                p.stdin.flush()
                alg, t, status = p.stdout.readline().split()
                errors[name] += status != "ok"
                if i not in best[name] or float(t) < best[name][i][1]:
                    best[name][i] = (alg, float(t))
    for p in procs.values():
        p.stdin.close()
        p.wait()
    out = {}
    for name, runs in best.items():
        per: dict[str, list[float]] = {}
        for alg, t in runs.values():
            per.setdefault(alg, []).append(t)
        out[name] = {"per_algorithm": {k: sum(v) / len(v) for k, v in per.items()},
                     "n_paper": n_paper, "runs": n, "errors": errors[name]}  # fmt: skip
    return out


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
    what = "CPU time" if "wall" not in r else "run time"
    if "wall" in r:
        print(f"{name}: {r['runs']} runs in {r['wall']:.1f} s "
              f"({r['runs'] / r['wall']:.2f} runs/s), errors {r['errors']}")  # fmt: skip
    else:
        print(f"{name}: {r['runs']} runs, one at a time, errors {r['errors']}")
    for alg, t in sorted(per.items(), key=lambda kv: kv[1]):
        print(f"  {alg:9s} {t:.3f} s {what} per run")
    line = (f"  projected rggpso-rq1 at paper scale ({n_paper:,} runs) on {workers} workers: "
            f"{compute / 60:.1f} min from the runs' {what}")  # fmt: skip
    if "wall" in r:
        line += f", {n_paper / (r['runs'] / r['wall']) / 60:.1f} min from the sample's wall clock"
    print(line + " (target <= 10 min)")
    return compute


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=2, help="scenes per obstacle-count setting")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--reference", default=None, help="a revision to measure beside this tree")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--cpu", action="store_true", help="CPU time per run, trees alternating")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        _child(a)
        return
    if a.serve:
        _serve(a)
        return
    with tempfile.TemporaryDirectory() as tmp:
        trees: list[tuple[str, Path | None]] = [("this tree", None)]
        if a.reference:
            trees.append((f"reference {a.reference}", _extract(a.reference, Path(tmp))))
        for _, src in trees:
            _run(a, src, warm=True)  # compiles (or loads) the tree's kernels
        best: dict[str, dict[str, Any]] = {}
        if a.cpu:
            best = _cpu(a, trees)
        for _ in range(0 if a.cpu else a.rounds):
            for name, src in trees:
                r = _run(a, src)
                assert r is not None
                if name not in best or r["wall"] < best[name]["wall"]:
                    best[name] = r
    projected = {name: _report(name, r, a.workers) for name, r in best.items()}
    if a.reference:
        ref, this = projected[f"reference {a.reference}"], projected["this tree"]
        print(f"this tree / reference, projected: {this / ref:.2f} ({ref / this:.2f}x faster)")


if __name__ == "__main__":
    main()
