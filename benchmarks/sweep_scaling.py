"""Sweep scaling: the same sample of runs on 1 and 2 local workers, with the process executor and
with a local Dask cluster, and the parallel efficiency (issue 18 item 6).

The sample is ``rggpso-rq1`` at paper settings on ``--scenes`` scenes per obstacle-count setting
x ``--runs`` runs x its six methods (``_rq1_sample.py``; ``--iterations`` shortens the runs).
Each configuration runs the sample into a fresh folder; printed per configuration: wall time
(worker start-up included), throughput (runs/s), the runs' mean own compute (which grows when
two workers share the machine's two cores with anything else), and for 2 workers the parallel
efficiency ``throughput(2) / (2 throughput(1))`` of the same executor. The workers' Numba
kernels are loaded from this tree's cache (the first configuration compiles them if needed:
a warm-up sweep runs first and is not reported).

    python benchmarks/sweep_scaling.py [--scenes 1] [--runs 1] [--iterations N] [--repeats 1]
"""

from __future__ import annotations

import argparse

from _rq1_sample import measure, sample_plan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=1, help="scenes per obstacle-count setting")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--iterations", type=int, default=None, help="default: the paper's 200")
    ap.add_argument("--repeats", type=int, default=1, help="best of this many sweeps each")
    a = ap.parse_args()
    plan, _ = sample_plan(a.scenes, a.runs, a.iterations)
    warm, _ = sample_plan(1, 1, iterations=2)
    measure(warm, "process", 2)
    n = None
    head = ("executor", 9), ("workers", 7), ("wall s", 8), ("runs/s", 8), ("run s", 7)
    print(" ".join(f"{h:>{w}}" for h, w in head), f"{'efficiency':>10}")
    for executor in ("process", "dask"):
        throughput: dict[int, float] = {}
        for workers in (1, 2):
            best = min((measure(plan, executor, workers) for _ in range(a.repeats)),
                       key=lambda r: r["wall"])  # fmt: skip
            n = best["runs"]
            assert best["errors"] == 0, best
            throughput[workers] = best["runs"] / best["wall"]
            per = best["per_algorithm"]
            mean_run = sum(per.values()) / len(per)
            eff = f"{throughput[2] / (2 * throughput[1]):>10.2f}" if workers == 2 else f"{'':>10}"
            print(f"{executor:>9} {workers:>7} {best['wall']:>8.1f} {throughput[workers]:>8.2f} "
                  f"{mean_run:>7.3f} {eff}", flush=True)  # fmt: skip
    print(f"({n} runs each: the same seeds, so the same results on every executor)")


if __name__ == "__main__":
    main()
