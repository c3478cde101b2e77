"""Throughput of the batched path cost: segment-cylinder tests per second, ours vs references.

Run: ``python benchmarks/cost_throughput.py [--repeats N]``

Sizes (issue 2): the SPSO size (500 paths x 12 points x 6 cylinders + the SPSO DEM) and a large
size (1,000 paths x 50 points x 100 cylinders). For each it prints, measured in this one run:

* the Numba kernel (parallel over the population, all cores) in segment-cylinder tests/s;
* the same kernel's plain NumPy reference (one core) and a plain per-path Python loop, with
  our speed-up over each (the Python loop is timed on a slice and scaled per test);
* for the SPSO size, the whole SPSO cost of a population (``PathProblem.cost``) and the whole
  evaluation with feasibility (``PathProblem.evaluate``: exact terrain, obstacles), in ms.

Timings are the best of ``--repeats`` runs (the machine is shared; the best is the least noisy).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Callable

import numpy as np

from uavplan.problems import CartesianEncoding, PathProblem
from uavplan.scenarios import load_builtin
from uavplan.world.geometry import (
    segment_cylinder_distance,
    segment_cylinder_distance_reference,
)


def best_time(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm-up (JIT compile, caches)
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def python_loop(paths: np.ndarray, centers: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> list:
    """Per-path, per-segment, per-cylinder loop in plain Python (the naive implementation)."""
    out = []
    for path in paths.tolist():
        rows = []
        for s in range(len(path) - 1):
            ax, ay, az = path[s]
            bx, by, bz = path[s + 1]
            row = []
            for (cx, cy), zl, zh in zip(centers.tolist(), lo.tolist(), hi.tolist(), strict=True):
                dz = bz - az
                t0, t1 = 0.0, 1.0
                if dz != 0.0:
                    ta, tb = sorted(((zl - az) / dz, (zh - az) / dz))
                    t0, t1 = max(t0, ta), min(t1, tb)
                elif not zl <= az <= zh:
                    t1 = -1.0
                if t0 > t1:
                    row.append(math.inf)
                    continue
                px, py = ax + t0 * (bx - ax), ay + t0 * (by - ay)
                qx, qy = ax + t1 * (bx - ax), ay + t1 * (by - ay)
                ex, ey = qx - px, qy - py
                den = ex * ex + ey * ey
                t = 0.0 if den == 0 else min(max(((cx - px) * ex + (cy - py) * ey) / den, 0.0), 1.0)
                row.append(math.hypot(cx - px - t * ex, cy - py - t * ey))
            rows.append(row)
        out.append(rows)
    return out


def kernel_case(name: str, pop: int, n: int, J: int, repeats: int, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    paths = rng.uniform([0, 0, 0], [1000, 1000, 300], (pop, n, 3))
    centers = rng.uniform(0, 1000, (J, 2))
    lo = np.where(rng.random(J) < 0.5, -np.inf, 0.0)
    hi = np.where(rng.random(J) < 0.5, np.inf, rng.uniform(50, 300, J))
    tests = pop * (n - 1) * J
    t_numba = best_time(lambda: segment_cylinder_distance(paths, centers, lo, hi), repeats)
    t_numpy = best_time(
        lambda: segment_cylinder_distance_reference(paths, centers, lo, hi), max(1, repeats // 2)
    )
    k = max(1, min(pop, 20_000 // max(1, (n - 1) * J)))
    t_py = best_time(lambda: python_loop(paths[:k], centers, lo, hi), 1) * pop / k
    assert np.allclose(
        segment_cylinder_distance(paths, centers, lo, hi),
        segment_cylinder_distance_reference(paths, centers, lo, hi),
    )
    print(f"\n{name}: {pop} paths x {n} points x {J} cylinders = {tests:,} segment-cylinder tests")
    print(
        f"  numba kernel ({os.cpu_count()} cores) {t_numba * 1e3:9.2f} ms  "
        f"{tests / t_numba / 1e6:9.1f} M tests/s"
    )
    print(
        f"  numpy reference (1 core)   {t_numpy * 1e3:9.2f} ms  "
        f"{tests / t_numpy / 1e6:9.1f} M tests/s"
        f"  -> ours x{t_numpy / t_numba:.1f}"
    )
    print(
        f"  python per-path loop       {t_py * 1e3:9.1f} ms  {tests / t_py / 1e6:9.3f} M tests/s"
        f"  -> ours x{t_py / t_numba:.0f}"
    )


def spso_cost_case(repeats: int) -> None:
    sc = load_builtin("spso")
    problem = PathProblem(sc)
    enc = CartesianEncoding(problem)
    rng = np.random.default_rng(1)
    X = enc.lower + rng.random((500, enc.dim)) * (enc.upper - enc.lower)
    paths = enc.decode(X)
    t_cost = best_time(lambda: problem.cost(paths), repeats)
    t_dec = best_time(lambda: enc.evaluate(X), repeats)
    t_eval = best_time(lambda: problem.evaluate(paths), repeats)
    t_loop = best_time(lambda: [problem.cost(paths[i : i + 1]) for i in range(50)], 1) * 10
    print("\nSPSO scenario, population of 500 paths x 12 points (6 cylinders, 1045 x 879 DEM):")
    print(f"  SPSO cost (PathProblem.cost)              {t_cost * 1e3:7.3f} ms per population")
    print(f"  genes -> paths -> cost (encoding.evaluate) {t_dec * 1e3:7.3f} ms per population")
    print(f"  cost + feasibility (exact terrain etc.)  {t_eval * 1e3:7.3f} ms per population")
    print(
        f"  same cost, one path per call (loop)      {t_loop * 1e3:7.1f} ms per population"
        f"  -> batched x{t_loop / t_cost:.0f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    kernel_case("SPSO size", 500, 12, 6, args.repeats)
    kernel_case("large size", 1000, 50, 100, args.repeats)
    spso_cost_case(args.repeats)


if __name__ == "__main__":
    main()
