"""Throughput of Dubins CSC smoothing: ``smooth_path`` on random 12-waypoint paths.

Run: ``python benchmarks/dubins_throughput.py [--paths N] [--repeats N]``

Random waypoints in a 1,000 m x 1,000 m x 200 m box, the paper's 20 m turning radius (PPSwarm
Sect. 5.1) and the default 5 m sampling step; prints paths/s and Dubins curves/s (best of
``--repeats`` runs, one core), and the compiled ``smooth_path`` against its Python reference
``smooth_path_reference`` measured in the same run (the ratio is the figure: absolute rates
move with the machine).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from uavplan.smoothing import dubins_csc, smooth_path
from uavplan.smoothing.dubins import smooth_path_reference


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=200)
    ap.add_argument("--waypoints", type=int, default=12)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1000.0, 1000.0, 200.0])
    paths = rng.uniform(lo, hi, size=(args.paths, args.waypoints, 3))

    smooth_path(paths[0], 20.0, step=5.0)  # the kernel compiled (or loaded) first
    rates = {}
    for f in (smooth_path, smooth_path_reference):
        best = math.inf
        n_points = 0
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            n_points = sum(f(p, 20.0, step=5.0).points.shape[0] for p in paths)
            best = min(best, time.perf_counter() - t0)
        rates[f.__name__] = args.paths / best
        print(
            f"{f.__name__}: {args.paths / best:,.0f} paths/s ({args.waypoints} waypoints, "
            f"{n_points / args.paths:.0f} points per path, {1e3 * best / args.paths:.3f} ms/path)"
        )
    print(
        f"compiled / Python reference: {rates['smooth_path'] / rates['smooth_path_reference']:.1f}x"
    )

    poses = rng.uniform([0, 0, -math.pi], [1000, 1000, math.pi], size=(2000, 2, 3))
    best = math.inf
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        for q0, q1 in poses:
            dubins_csc(q0, q1, 20.0)
        best = min(best, time.perf_counter() - t0)
    print(f"dubins_csc:  {len(poses) / best:,.0f} curves/s (all four CSC words each)")


if __name__ == "__main__":
    main()
