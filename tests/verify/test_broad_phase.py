"""The verifier's broad phase (the obstacle grid, from ``INDEX_MIN`` obstacles of a kind on)
against every obstacle tested against every segment: the same violations, in the same order,
on random worlds of cylinders, circles and polygons (convex, non-convex, with margins, some
larger than a grid cell) and trajectories that cross, touch and skirt them."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.verify import Trajectory
from uavplan.verify import obstacles as VO
from uavplan.world import Circle, Cylinder, Polygon


def _world(rng: np.random.Generator, n: int, size: float) -> dict[str, list[Any]]:
    def radius() -> float:
        return float(rng.uniform(0.5, 4.0) * rng.choice([1.0, 1.0, 10.0]))

    def center() -> tuple[float, float]:
        x, y = rng.uniform(0, size, 2)
        return float(x), float(y)

    cyl = []
    for _ in range(n):
        lo, hi, m = rng.uniform(0, 50), rng.uniform(60, 200), rng.choice([0.0, 1.0])
        cyl.append(Cylinder(center(), radius(), float(lo), float(hi), float(m)))
    circ = [Circle(center(), radius(), float(rng.choice([0.0, 0.5]))) for _ in range(n)]
    polys = []
    for _ in range(n):
        k = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k)) + rng.uniform(0, 1e-3, k)
        rad = radius() * rng.uniform(0.4, 1.0, k)
        v = rng.uniform(0, size, 2) + np.c_[rad * np.cos(ang), rad * np.sin(ang)]
        try:
            polys.append(Polygon(tuple(map(tuple, v)), float(rng.choice([0.0, 0.0, 1.5]))))
        except ValueError:
            continue  # a degenerate draw
    return {"cylinders": cyl, "circles": circ, "polygons": polys}


def _trajectory(rng: np.random.Generator, size: float, world: dict[str, list[Any]]) -> Trajectory:
    n = int(rng.integers(2, 60))
    p = np.cumsum(rng.normal(0, 0.03 * size, (n, 3)), axis=0) + np.array([0.5, 0.5, 0.0]) * size
    p[:, 2] = rng.uniform(0, 220, n)
    # waypoints on obstacles: a circle's edge, a polygon's vertex, a cylinder's axis
    if n > 4:
        c = world["circles"][0]
        p[1, :2] = np.asarray(c.center) + np.array([c.effective_radius, 0.0])
        if world["polygons"]:
            p[2, :2] = world["polygons"][0].vertices[0]
        p[3, :2] = world["cylinders"][0].center
        p[4] = p[3]  # a zero-length segment
    return Trajectory("u", np.ascontiguousarray(p), np.arange(n, dtype=np.float64))


CHECKS = (
    (VO.check_cylinders, "cylinders"),
    (VO.check_circles, "circles"),
    (VO.check_polygons, "polygons"),
)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(VO.INDEX_MIN, 3 * VO.INDEX_MIN))
def test_the_grid_finds_every_violation_every_pair_finds(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    size = 400.0
    world = _world(rng, n, size)
    found = 0
    for _ in range(4):
        traj = _trajectory(rng, size, world)
        for check, kind in CHECKS:
            obstacles = tuple(world[kind])
            with pytest.MonkeyPatch.context() as mp:
                mp.setattr(VO, "INDEX_MIN", 10**9)
                want = check(traj, obstacles)
            got = check(traj, obstacles)
            assert got == want
            found += len(want)
    assert found > 0  # the case has violations to find
    assert len(VO._GRIDS) <= 8


def test_near_segments_prunes_and_keeps_order() -> None:
    rng = np.random.default_rng(3)
    world = _world(rng, 200, 4000.0)
    circles = tuple(world["circles"])
    a = rng.uniform(0, 4000, (50, 2))
    b = a + rng.normal(0, 20, (50, 2))
    near = VO.near_segments(a, b, circles, VO._disc_boxes)
    assert [i for i, _ in near] == sorted({i for i, _ in near})
    assert sum(len(rows) for _, rows in near) < 0.1 * 50 * len(circles)
    for _, rows in near:
        assert np.all(np.diff(rows) > 0)
    bad = a.copy()
    bad[0, 0] = np.nan  # not finite: every obstacle, every segment
    every = VO.near_segments(bad, b, circles, VO._disc_boxes)
    assert len(every) == len(circles) and all(len(r) == 50 for _, r in every)
