"""Cost per segment against the number of obstacles (issue 18 item 2's figure): the fused
cylinder pass (``uavplan.world.geometry.cylinder_threat_batch``, PPSwarm's threat cost, what
``PathProblem`` uses) on 200 paths x 20 points in a 10 km square, with J = 10 ... 10,000
cylinders of radius 20-60 m placed uniformly, the same paths at every J.

Run: ``python benchmarks/obstacle_scaling.py [--repeats N]`` (``NUMBA_NUM_THREADS=1`` on a
shared machine). Prints ns per segment at each J and the ratio to its value at J = 50: today
every segment is tested against every cylinder, so the ratio grows linearly with J; the
issue's target with an obstacle index is at most 3 at J = 10,000.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from uavplan.world.geometry import cylinder_threat


def best_time(fn, repeats: int) -> float:  # type: ignore[no-untyped-def]
    fn()
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    side, P, N = 10_000.0, 200, 20
    start = np.array([side / 2, side / 2, 100.0])
    paths = start + np.cumsum(rng.normal(0.0, 150.0, (P, N, 3)), axis=1)
    segments = P * (N - 1)
    base = None
    print(f"{P} paths x {N} points ({segments:,} segments) in a {side / 1000:.0f} km square")
    print(f"{'cylinders':>9} {'ns/segment':>11} {'vs J=50':>8}")
    for J in (10, 50, 100, 500, 1_000, 5_000, 10_000):
        centers = rng.uniform(0.0, side, (J, 2))
        R = rng.uniform(20.0, 60.0, J)
        lo, hi = np.full(J, -np.inf), rng.uniform(150.0, 400.0, J)

        def cost() -> object:
            return cylinder_threat(paths, centers, lo, hi, R, R + 50.0, False)  # noqa: B023

        t = best_time(cost, a.repeats)
        ns = t / segments * 1e9
        base = ns if J == 50 else base
        ratio = f"{ns / base:8.1f}" if base else f"{'-':>8}"
        print(f"{J:>9,} {ns:>11.1f} {ratio}", flush=True)


if __name__ == "__main__":
    main()
