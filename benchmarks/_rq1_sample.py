"""A stratified sample of the ``rggpso-rq1`` plan at paper settings (the sweep benchmarks'
workload; imported by the scripts beside it, which run as ``python benchmarks/NAME.py``)."""

from __future__ import annotations

import dataclasses
import tempfile
import time
from typing import Any

from uavplan.bench.catalog import get_plan
from uavplan.bench.plans import ExperimentPlan, Scale
from uavplan.bench.runner import run_sweep
from uavplan.bench.store import ResultStore
from uavplan.scenarios.names import SETTINGS


def sample_plan(
    scenes: int, runs: int, iterations: int | None = None
) -> tuple[ExperimentPlan, int]:
    """``rggpso-rq1`` on ``scenes`` scenes per obstacle-count setting (spread over the 100
    indices) x ``runs`` runs x its six methods, at paper settings (``iterations`` to shorten
    them), as the scale ``"sample"``; and the run count of the whole plan at paper scale."""
    plan = get_plan("rggpso-rq1")
    paper = plan.scales["paper"]
    picked = tuple(
        f"rgg-n{n:02d}-i{i:03d}" for n in SETTINGS for i in range(0, 100, 100 // scenes)
    )[: scenes * len(SETTINGS)]
    scale = Scale(
        runs=runs,
        iterations=iterations or paper.iterations,
        pop_size=paper.pop_size,
        scenarios=picked,
    )
    n_paper = len(paper.scenarios or ()) * paper.runs * len(plan.algorithms)
    return dataclasses.replace(plan, scales={"sample": scale}), n_paper


def measure(plan: ExperimentPlan, executor: str, workers: int, **kw: Any) -> dict[str, Any]:
    """Run the sample in a fresh folder: its wall time, runs, errors, and each method's mean
    run time (the run's own compute, compilation left out) in seconds."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        summary = run_sweep(plan, tmp, scale="sample", executor=executor, workers=workers, **kw)
        wall = time.perf_counter() - t0
        df = ResultStore(tmp).read(["algorithm", "wall_time", "status"])
    per = df.groupby("algorithm")["wall_time"].mean()
    return {
        "wall": wall,
        "runs": len(df),
        "errors": int(summary.failed),
        "per_algorithm": {str(a): float(t) for a, t in per.items()},
    }
