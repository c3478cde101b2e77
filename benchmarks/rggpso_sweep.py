"""Projected wall time of the ``rggpso-rq1`` plan at paper scale, from a stratified sample.

Runs ``--scenes`` scenes per obstacle-count setting (10 settings) x ``--runs`` runs x the six
algorithms at paper settings (100 particles, 200 iterations) with the local process executor,
then prints runs/s, seconds per run per algorithm (summed worker time) and the projected time
of the whole plan (60,000 runs) on the same workers. The issue's target: <= 30 minutes on this
2-core machine.

    python benchmarks/rggpso_sweep.py [--scenes 2] [--runs 1] [--workers 2]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time

from uavplan.bench.catalog import get_plan
from uavplan.bench.plans import Scale
from uavplan.bench.runner import run_sweep
from uavplan.bench.store import ResultStore
from uavplan.scenarios.generators import SETTINGS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=2, help="scenes per obstacle-count setting")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    plan = get_plan("rggpso-rq1")
    paper = plan.scales["paper"]
    scenes = tuple(
        f"rgg-n{n:02d}-i{i:03d}" for n in SETTINGS for i in range(0, 100, 100 // a.scenes)
    )[: a.scenes * len(SETTINGS)]
    sample = dataclasses.replace(
        plan,
        scales={
            "sample": Scale(
                runs=a.runs,
                iterations=paper.iterations,
                pop_size=paper.pop_size,
                scenarios=scenes,
            )
        },
    )
    n_paper = len(paper.scenarios or ()) * paper.runs * len(plan.algorithms)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        summary = run_sweep(sample, tmp, scale="sample", executor="process", workers=a.workers)
        wall = time.perf_counter() - t0
        df = ResultStore(tmp).read(["algorithm", "wall_time", "status"])
    print(
        f"{len(df)} runs ({len(scenes)} scenes x {a.runs} runs x {len(plan.algorithms)} "
        f"algorithms) on {a.workers} workers in {wall:.1f} s: {len(df) / wall:.2f} runs/s"
    )
    per = df.groupby("algorithm")["wall_time"].mean().sort_values()
    for alg, t in per.items():
        print(f"  {alg:9s} {t:.3f} s per run (worker time)")
    print(f"  mean      {df['wall_time'].mean():.3f} s per run; errors: {summary.failed}")
    print(
        f"projected rggpso-rq1 paper scale ({n_paper:,} runs): "
        f"{n_paper / (len(df) / wall) / 60:.1f} min at this throughput (target <= 30 min)"
    )


if __name__ == "__main__":
    main()
