"""The motion validator's yes/no question (``MotionValidator.passing``) with the fused
static-world kernel against the same checks run one by one (the reference), in one run.

    python benchmarks/validity_fused.py

Batches: RRT*-like (6 short edges per call) and optimizer-like (300 paths of 12 waypoints) on
``ppswarm2`` (terrain, 10 cylinders, a band above ground checked along segments). Prints the
time per call of each and the ratio; the verdicts are asserted equal.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np

from uavplan.problems.validity import MotionValidator
from uavplan.scenarios import resolve


def batches(sc, rng):  # type: ignore[no-untyped-def]
    t = sc.tasks[0]
    start = np.asarray(t.start)
    short = np.stack([start + rng.normal(0, 20, (6, 3)), start + rng.normal(0, 20, (6, 3))], 1)
    line = np.linspace(t.start, t.goal, 12)
    opt = np.repeat(line[None], 300, axis=0)
    opt[:, 1:-1, :2] += rng.normal(0, 25, (300, 10, 2))
    xy = opt[:, 1:-1, :2]
    opt[:, 1:-1, 2] = sc.ground(xy[..., 0], xy[..., 1]) + rng.uniform(110, 190, (300, 10))
    return {"6 edges (RRT*)": short, "300 paths x 12 (PSO)": opt}


def timed(fn, n):  # type: ignore[no-untyped-def]
    fn()
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n


def main() -> None:
    sc = resolve("ppswarm2")
    fused = MotionValidator(sc, sc.tasks[0], strict_altitude=True)
    ref = MotionValidator(sc, sc.tasks[0], strict_altitude=True)
    ref.__dict__["_static_args"] = None  # the checks one by one
    rng = np.random.default_rng(0)
    print(f"{'batch':<22} {'fused us':>10} {'one by one us':>14} {'ratio':>6} {'pass':>6}")
    for name, paths in batches(sc, rng).items():
        b1, b2 = fused.batch(paths), ref.batch(paths)
        a, r = fused.passing(b1), ref.passing(b2)
        assert np.array_equal(a, r)
        n = 2000 if len(paths) < 10 else 200
        tf = timed(lambda p=paths: fused.passing(fused.batch(p)), n)
        tr = timed(lambda p=paths: ref.passing(ref.batch(p)), n)
        print(f"{name:<22} {tf * 1e6:>10.1f} {tr * 1e6:>14.1f} {tr / tf:>5.1f}x "
              f"{len(a):>3}/{len(paths)}")  # fmt: skip


if __name__ == "__main__":
    main()
