"""Cost per segment against the number of obstacles (issue 18 item 2's figure): the fused
cylinder pass (``uavplan.world.geometry.cylinder_threat_batch``, PPSwarm's threat cost, what
``PathProblem`` uses) on 200 paths x 20 points, with J = 10 ... 10,000 cylinders of radius
20-60 m placed uniformly at one density (100 per 10 km square: the map grows with J, as maps of
more no-fly zones cover more ground), the same path shapes at every J.

Run: ``python benchmarks/obstacle_scaling.py [--repeats N]`` (``NUMBA_NUM_THREADS=1`` on a
shared machine). Prints ns per segment at each J and the ratio to its value at J = 50, for the
production path (from ``GRID_MIN_CYLINDERS`` cylinders on, a uniform grid picks the cylinders
near each segment; the grid is built once per world and kept) and for the every-pair kernel
measured in the same run; then the same for the cylinder check (``cylinder_hits``, which the
validator's check and graded violation use) against its every-pair kernel. The issue's target:
at most 3 times the value at J = 50 at J = 10,000.
"""

from __future__ import annotations

import argparse

import numpy as np

from _timing import best_time
from uavplan.world.geometry import (
    cylinder_hits,
    cylinder_overlap,
    cylinder_threat,
    cylinder_threat_batch,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    P, N = 200, 20
    steps = np.cumsum(rng.normal(0.0, 150.0, (P, N, 3)), axis=1)
    segments = P * (N - 1)
    base = None
    print(f"{P} paths x {N} points ({segments:,} segments), 100 cylinders per 10 km square")
    print("threat cost; cylinder check (hits and metres inside), ns per segment:")
    print(f"{'cylinders':>9} {'threat':>8} {'vs J=50':>8} {'every pair':>11} {'vs J=50':>8}"
          f" {'check':>8} {'every pair':>11}")  # fmt: skip
    base_all = None
    for J in (10, 50, 100, 500, 1_000, 5_000, 10_000):
        side = 10_000.0 * np.sqrt(J / 100.0)
        centers = rng.uniform(0.0, side, (J, 2))
        paths = np.ascontiguousarray(steps + np.array([side / 2, side / 2, 100.0]))
        R = rng.uniform(20.0, 60.0, J)
        lo, hi = np.full(J, -np.inf), rng.uniform(150.0, 400.0, J)

        cx, cy = np.ascontiguousarray(centers[:, 0]), np.ascontiguousarray(centers[:, 1])

        def cost() -> object:
            return cylinder_threat(paths, centers, lo, hi, R, R + 50.0, False)  # noqa: B023

        def every_pair() -> object:
            return cylinder_threat_batch(paths, cx, cy, lo, hi, R, R + 50.0, False)  # noqa: B023

        def check() -> object:
            return cylinder_hits(paths, centers, lo, hi, R)  # noqa: B023

        def check_every_pair() -> object:
            return cylinder_overlap(paths, centers, lo, hi, R)  # noqa: B023

        np.testing.assert_allclose(cost(), every_pair(), rtol=1e-12)
        hit_ref = check_every_pair()[1] < 0  # type: ignore[index]
        assert np.array_equal(check()[1], hit_ref)  # type: ignore[index]
        ns = best_time(cost, a.repeats) / segments * 1e9
        ns_all = best_time(every_pair, a.repeats) / segments * 1e9
        base = ns if J == 50 else base
        base_all = ns_all if J == 50 else base_all
        ratio = f"{ns / base:8.1f}" if base else f"{'-':>8}"
        ratio_all = f"{ns_all / base_all:8.1f}" if base_all else f"{'-':>8}"
        ns_c = best_time(check, a.repeats) / segments * 1e9
        ns_c_all = best_time(check_every_pair, a.repeats) / segments * 1e9
        row = f"{J:>9,} {ns:>8.1f} {ratio} {ns_all:>11.1f} {ratio_all}"
        print(f"{row} {ns_c:>8.1f} {ns_c_all:>11.1f}", flush=True)

    validator_case(a.repeats)


def validator_case(repeats: int) -> None:
    """The motion validator end to end (``paths_valid``: the fused 3-D static kernel for bounds,
    terrain and band, then the cylinders) on the SPSO terrain with J small cylinders, against
    the same validator with the grid turned off (every pair inside the fused kernel)."""
    import dataclasses

    from uavplan.problems.validity import MotionValidator
    from uavplan.scenarios import resolve
    from uavplan.world import Cylinder
    from uavplan.world import geometry as G

    sc0 = resolve("spso")
    rng = np.random.default_rng(1)
    lo, hi = np.asarray(sc0.bounds.lo), np.asarray(sc0.bounds.hi)
    start = rng.uniform(lo[:2], hi[:2], (300, 1, 2))
    xy = start + np.cumsum(rng.normal(0.0, 5.0, (300, 8, 2)), axis=1)
    z = sc0.ground(xy[..., 0], xy[..., 1]) + 150.0
    paths = np.ascontiguousarray(np.concatenate([xy, z[..., None]], axis=-1))
    print("\nmotion validator on the SPSO terrain, 300 paths x 8 points, ns per segment:")
    print(f"{'cylinders':>9} {'grid':>9} {'every pair':>11} {'valid':>6}")
    default = G.GRID_MIN_CYLINDERS
    for J in (50, 1_000, 10_000):
        cyl = tuple(
            Cylinder(tuple(c), float(r))
            for c, r in zip(
                rng.uniform(lo[:2], hi[:2], (J, 2)), rng.uniform(0.5, 2.0, J), strict=True
            )
        )
        sc = dataclasses.replace(sc0, cylinders=cyl)
        times, verdicts = [], []
        for threshold in (default, 10**9):
            G.GRID_MIN_CYLINDERS = threshold
            v = MotionValidator(sc, sc.tasks[0])
            verdicts.append(v.paths_valid(paths))
            times.append(best_time(lambda: v.paths_valid(paths), repeats) / paths[:, 1:].size * 3e9)  # noqa: B023
        G.GRID_MIN_CYLINDERS = default
        assert np.array_equal(verdicts[0], verdicts[1])
        print(f"{J:>9,} {times[0]:>9.1f} {times[1]:>11.1f} {int(verdicts[0].sum()):>6}", flush=True)


if __name__ == "__main__":
    main()
