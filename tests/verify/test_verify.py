"""The independent fleet verifier (``uavplan.verify.core``) and ``uavplan verify``.

References are brute force: dense sampling of positions in time and of the bilinear terrain
along segments (``Terrain.height``, the plain lookup), never the planner's geometry kernels.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import parse_plan
from uavplan.verify import KINDS, PlanFormatError, Trajectory, verify_plan
from uavplan.verify.obstacles import check_circles, check_cylinders, check_polygons
from uavplan.verify.separation import (
    candidate_pairs,
    check_moving,
    check_separation,
    pair_min_distance,
)
from uavplan.verify.terrain import bilinear_height, check_terrain, terrain_clearance_extrema
from uavplan.verify.timing import check_bounds, check_speed, check_times
from uavplan.world import (
    UAV,
    AltitudeBand,
    Bounds,
    Circle,
    Cylinder,
    MovingObstacle,
    Polygon,
    Scenario,
    Task,
    Terrain,
)

runner = CliRunner()


def traj(uid: str, points: Any, times: Any) -> Trajectory:
    return Trajectory(uid, np.asarray(points, dtype=float), np.asarray(times, dtype=float))


def uav(uid: str, points: Any, times: Any, **extra: Any) -> dict[str, Any]:
    return {"id": uid, "waypoints": points, "times": times, "feasible": True, **extra}


def flat_scenario(n_tasks: int = 2, s2: float = 10.0, speed: float = 50.0, **kw: Any) -> Scenario:
    tasks = tuple(Task(f"u{k}", (0.0, 0.0, 10.0), (1.0, 0.0, 10.0)) for k in range(n_tasks))
    return Scenario(
        "flat",
        Bounds((-200.0, -200.0, 0.0), (200.0, 200.0, 200.0)),
        tasks,
        uav=UAV(speed=speed, s2=s2),
        **kw,
    )


def ridge_terrain() -> Terrain:
    """A 5 x 5 grid (10 m cells, x and y from 0 to 40 m) with a 50 m north-south ridge at x = 20."""
    h = np.zeros((5, 5))
    h[:, 2] = 50.0
    return Terrain(h, x0=0.0, y0=0.0, dx=10.0, dy=10.0, name="ridge")


def sampled_min_distance(a: Trajectory, b: Trajectory, n: int = 20001) -> float:
    t0 = max(a.times[0], b.times[0])
    t1 = min(a.times[-1], b.times[-1])
    if t0 > t1:
        return math.inf
    t = np.unique(np.concatenate([np.linspace(t0, t1, n), a.times, b.times]))
    t = t[(t >= t0) & (t <= t1)]
    pa = np.stack([np.interp(t, a.times, a.points[:, k]) for k in range(a.dim)], 1)
    pb = np.stack([np.interp(t, b.times, b.points[:, k]) for k in range(b.dim)], 1)
    return float(np.linalg.norm(pa - pb, axis=1).min())


# ---------------------------------------------------------------------------- separation
def test_swap_between_samples_is_caught() -> None:
    # Head-on on the same line, sampled every second: 20 m apart at t = 2 and t = 3 (S2 = 10),
    # but they pass through each other at t = 2.5.
    t = [0, 1, 2, 3, 4, 5]
    a = traj("a", [[x, 0, 10] for x in (0, 20, 40, 60, 80, 100)], t)
    b = traj("b", [[x, 0, 10] for x in (100, 80, 60, 40, 20, 0)], t)
    sampled = np.linalg.norm(a.points - b.points, axis=1)
    assert sampled.min() == pytest.approx(20.0)  # a sampled-instant check sees no conflict
    d, tm = pair_min_distance(a, b)
    assert d == pytest.approx(0.0, abs=1e-9)
    assert tm == pytest.approx(2.5)
    res = check_separation([a, b], 10.0)
    assert len(res.violations) == 1
    v = res.violations[0]
    assert v.kind == "separation" and v.uavs == ("a", "b")
    assert v.time == pytest.approx(2.5) and v.value == pytest.approx(0.0, abs=1e-9)
    assert v.where[0] == pytest.approx((50.0, 0.0, 10.0))
    assert v.where[1] == pytest.approx((50.0, 0.0, 10.0))
    assert "from t=2.250 to 2.750 s" in v.message  # closing at 40 m/s: 10 m takes 0.25 s


def test_different_breakpoints_crossing() -> None:
    # Breakpoints of a and b never coincide; they cross at right angles between them.
    a = traj("a", [[-50, 0, 0], [-10, 0, 0], [50, 0, 0]], [0, 4, 10])
    b = traj("b", [[0, -50, 0], [0, 30, 0], [0, 50, 0]], [0.0, 8.0, 10.0])
    d, tm = pair_min_distance(a, b)
    assert d <= sampled_min_distance(a, b) + 1e-9
    pa, pb = a.position(tm), b.position(tm)
    assert float(np.linalg.norm(pa - pb)) == pytest.approx(d, abs=1e-9)
    assert check_separation([a, b], 10.0).violations


def test_near_miss_exactly_at_s2_passes() -> None:
    a = traj("a", [[0, 0, 0], [100, 0, 0]], [0, 5])
    b = traj("b", [[100, 10, 0], [0, 10, 0]], [0, 5])
    res = check_separation([a, b], 10.0)
    assert res.violations == []
    assert res.min_distance == pytest.approx(10.0)
    assert res.min_pair == ("a", "b") and res.min_time == pytest.approx(2.5)
    closer = traj("b", [[100, 9.99, 0], [0, 9.99, 0]], [0, 5])
    assert len(check_separation([a, closer], 10.0).violations) == 1


def test_only_in_the_air_between_first_and_last_time() -> None:
    # b takes off from the point where a is at t = 2.5, but only at t = 10, after a landed.
    a = traj("a", [[0, 0, 0], [100, 0, 0]], [0, 5])
    b = traj("b", [[50, 0, 0], [50, 100, 0]], [10, 15])
    assert pair_min_distance(a, b)[0] == math.inf
    assert check_separation([a, b], 10.0).violations == []
    # landing at the instant the other takes off, at the same place, is a conflict
    c = traj("c", [[100, 0, 0], [100, 100, 0]], [5, 10])
    assert pair_min_distance(a, c) == (pytest.approx(0.0), pytest.approx(5.0))


def test_jump_at_landing_is_swept() -> None:
    # b lands at t = 5 with a jump onto a's parked position: caught (and a speed violation)
    a = traj("a", [[0, 0, 0], [0, 0, 0]], [0, 5])
    b = traj("b", [[50, 0, 0], [30, 0, 0], [0, 0, 0]], [0, 5, 5])
    assert pair_min_distance(a, b) == (pytest.approx(0.0), pytest.approx(5.0))
    assert [v.value for v in check_speed(b, 20.0)] == [math.inf]


def test_two_encounters_of_one_pair_are_reported_separately() -> None:
    a = traj("a", [[0, 0, 0], [100, 0, 0], [0, 0, 0]], [0, 10, 20])
    b = traj("b", [[50, 50, 0], [50, -50, 0], [50, 50, 0]], [0, 10, 20])
    vs = check_separation([a, b], 10.0).violations
    assert [v.time for v in vs] == [pytest.approx(5.0), pytest.approx(15.0)]


def test_pruning_never_drops_a_close_pair() -> None:
    rng = np.random.default_rng(3)
    trajs = []
    for k in range(60):
        pts = rng.uniform(0, 200, (6, 3))
        dt = np.linalg.norm(np.diff(pts, axis=0), axis=1) / 20.0
        trajs.append(
            Trajectory(f"u{k}", pts, rng.uniform(0, 30) + np.concatenate([[0], np.cumsum(dt)]))
        )
    pruned = check_separation(trajs, 15.0)
    full = check_separation(trajs, 15.0, prune=False)
    assert pruned.pairs_checked < full.pairs_checked
    key = [(v.uavs, round(v.time or 0, 9)) for v in pruned.violations]
    assert key == [(v.uavs, round(v.time or 0, 9)) for v in full.violations]
    assert key  # the fleet does have conflicts
    kept = {tuple(p) for p in candidate_pairs(trajs, 15.0).tolist()}
    for i in range(len(trajs)):
        for j in range(i + 1, len(trajs)):
            if (i, j) not in kept:
                assert pair_min_distance(trajs[i], trajs[j])[0] > 15.0


_coord = st.floats(-100, 100, allow_nan=False, allow_infinity=False)


@st.composite
def timed_paths(draw: Any) -> Trajectory:
    n = draw(st.integers(2, 5))
    pts = [[draw(_coord) for _ in range(3)] for _ in range(n)]
    t0 = draw(st.floats(0, 10))
    # a step is 0 (a jump) or at least 1 ms; some flight time overall (a flight that lasts no
    # time at all, or a subnormal one, is not a trajectory the planner can write)
    steps = [draw(st.one_of(st.just(0.0), st.floats(1e-3, 5.0))) for _ in range(n - 1)]
    if sum(steps) == 0.0:
        steps[-1] = 1.0
    times = t0 + np.concatenate([[0.0], np.cumsum(steps)])
    return traj("x", pts, times)


@settings(max_examples=150, deadline=None)
@given(timed_paths(), timed_paths())
def test_min_separation_matches_dense_sampling(a: Trajectory, b: Trajectory) -> None:
    d, tm = pair_min_distance(a, b)
    ref = sampled_min_distance(a, b)
    if ref == math.inf:
        assert d == math.inf
        return
    # exact is never above what sampling sees ...
    assert d <= ref + 1e-7
    # ... and sampling gets within its resolution of it (a jump is not sampled by np.interp)
    if np.all(np.diff(a.times) > 1e-3) and np.all(np.diff(b.times) > 1e-3):
        span = min(a.times[-1], b.times[-1]) - max(a.times[0], b.times[0])
        vmax = sum(
            float(np.max(np.linalg.norm(np.diff(p.points, axis=0), axis=1) / np.diff(p.times)))
            for p in (a, b)
        )
        assert ref - d <= vmax * span / 20000 + 1e-7
        # and it is attained at the reported time
        gap = float(np.linalg.norm(a.position(tm) - b.position(tm)))
        assert gap == pytest.approx(d, abs=1e-6)


# ---------------------------------------------------------------------------- obstacles
def test_cylinder_crossing_and_clearing() -> None:
    cyl = Cylinder((50.0, 0.0), 10.0, z_min=0.0, z_max=100.0, margin=1.0)
    through = traj("a", [[0, 0, 50], [100, 0, 50]], [0, 5])
    vs = check_cylinders(through, [cyl])
    assert len(vs) == 1 and vs[0].kind == "cylinder"
    assert vs[0].value == pytest.approx(0.0) and vs[0].required == pytest.approx(11.0)
    assert vs[0].where[0] == pytest.approx((50.0, 0.0, 50.0)) and vs[0].time == pytest.approx(2.5)
    # tangent to the grown radius: allowed; just inside: not
    assert check_cylinders(traj("a", [[0, 11, 50], [100, 11, 50]], [0, 5]), [cyl]) == []
    assert check_cylinders(traj("a", [[0, 10.99, 50], [100, 10.99, 50]], [0, 5]), [cyl])
    # over the top (z_max + margin = 101): allowed; climbing through the top: caught
    assert check_cylinders(traj("a", [[0, 0, 101.5], [100, 0, 101.5]], [0, 5]), [cyl]) == []
    climb = traj("a", [[0, 0, 150], [100, 0, 50]], [0, 5])
    vs = check_cylinders(climb, [cyl])
    assert len(vs) == 1 and vs[0].value == pytest.approx(0.0)
    # descending, the segment enters the z range only at x = 55 (z = 101): 5 m from the axis
    high = traj("a", [[0, 0, 200], [100, 0, 20]], [0, 5])
    vs = check_cylinders(high, [cyl])
    assert vs[0].value == pytest.approx(5.0, abs=1e-9)
    assert vs[0].where[0] == pytest.approx((55.0, 0.0, 101.0))


def test_circles_and_polygons_are_prisms() -> None:
    circ = Circle((50.0, 0.0), 5.0, margin=1.0)
    assert check_circles(traj("a", [[0, 0, 500], [100, 0, 500]], [0, 5]), [circ])
    assert check_circles(traj("a", [[0, 6, 500], [100, 6, 500]], [0, 5]), [circ]) == []
    # an L-shaped (non-convex) polygon
    ell = Polygon(((0, 0), (40, 0), (40, 10), (10, 10), (10, 40), (0, 40)))
    # through the notch: outside the polygon, though inside its convex hull
    notch = traj("a", [[15, 45, 9], [45, 15, 9]], [0, 5])
    assert check_polygons(notch, [ell]) == []
    vs = check_polygons(traj("a", [[-5, 5, 9], [45, 5, 9]], [0, 5]), [ell])
    assert len(vs) == 1 and vs[0].value < 0 and "enters polygon 0" in vs[0].message
    # along an edge (touching, no margin): allowed; with a 2 m margin: not
    edge = traj("a", [[-10, 0, 9], [50, 0, 9]], [0, 5])
    assert check_polygons(edge, [ell]) == []
    grown = Polygon(ell.vertices, margin=2.0)
    vs = check_polygons(traj("a", [[-10, -1, 9], [50, -1, 9]], [0, 5]), [grown])
    assert len(vs) == 1 and vs[0].value == pytest.approx(1.0) and vs[0].required == 2.0
    # wholly inside
    vs = check_polygons(traj("a", [[2, 2, 9], [5, 30, 9]], [0, 5]), [ell])
    assert len(vs) == 1 and vs[0].value < 0


def test_moving_obstacle() -> None:
    obs = MovingObstacle(5.0, np.array([0.0, 10.0]), np.array([[50, -50, 10], [50, 50, 10]]))
    a = traj("a", [[0, 0, 10], [100, 0, 10]], [0, 10])
    vs = check_moving(a, [obs])
    assert len(vs) == 1 and vs[0].time == pytest.approx(5.0) and vs[0].value == pytest.approx(0)
    late = traj("a", [[0, 0, 10], [100, 0, 10]], [20, 30])  # the obstacle waits at (50, 50)
    assert check_moving(late, [obs]) == []


# ---------------------------------------------------------------------------- terrain and band
def test_terrain_crossing_between_waypoints_above_ground() -> None:
    ter = ridge_terrain()
    a = traj("a", [[0, 20, 30], [40, 20, 30]], [0, 4])  # both ends 30 m above flat ground
    assert np.all(a.points[:, 2] - bilinear_height(ter, a.points[:, 0], a.points[:, 1]) > 0)
    vs = check_terrain(a, ter)
    assert len(vs) == 1 and vs[0].kind == "terrain"
    assert vs[0].value == pytest.approx(-20.0)
    assert vs[0].where[0] == pytest.approx((20.0, 20.0, 30.0)) and vs[0].time == pytest.approx(2)
    assert check_terrain(traj("a", [[0, 20, 50], [40, 20, 50]], [0, 4]), ter) == []  # grazing


def test_terrain_outside_the_grid_uses_the_nearest_edge() -> None:
    ter = ridge_terrain()  # the ridge extends north and south beyond the grid
    a = traj("a", [[0, 100, 30], [40, 100, 30]], [0, 4])
    vs = check_terrain(a, ter)
    assert len(vs) == 1 and vs[0].value == pytest.approx(-20.0)


def test_band_violations_mid_segment() -> None:
    band = AltitudeBand(20.0, 60.0, "ground")
    ter = ridge_terrain()
    # ends 50 m above ground, over the ridge only 0 m: below the band (and touching terrain)
    low = traj("a", [[0, 20, 50], [40, 20, 50]], [0, 4])
    vs = check_terrain(low, ter, band)
    assert [v.kind for v in vs] == ["altitude"]
    assert vs[0].value == pytest.approx(0.0) and vs[0].required == 20.0
    assert vs[0].where[0][0] == pytest.approx(20.0)
    # a valley: ends on 50 m plateaus at 30 m above ground, the middle 80 m above ground
    h = np.full((5, 5), 50.0)
    h[:, 2] = 0.0
    valley = Terrain(h, dx=10.0, dy=10.0)
    high = traj("a", [[0, 20, 80], [40, 20, 80]], [0, 4])
    vs = check_terrain(high, valley, band)
    assert len(vs) == 1 and vs[0].value == pytest.approx(80.0) and vs[0].required == 60.0
    assert "above the band" in vs[0].message
    # absolute band: the waypoints decide
    absolute = AltitudeBand(20.0, 60.0, "absolute")
    vs = check_terrain(traj("a", [[0, 0, 30], [10, 0, 70]], [0, 1]), None, absolute)
    assert len(vs) == 1 and vs[0].value == 70.0 and vs[0].required == 60.0


@st.composite
def terrain_and_segment(draw: Any) -> tuple[Terrain, np.ndarray, np.ndarray]:
    ny, nx = draw(st.integers(2, 6)), draw(st.integers(2, 6))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    ter = Terrain(rng.uniform(0, 30, (ny, nx)), x0=-3.0, y0=2.0, dx=2.5, dy=4.0)
    a = np.array([rng.uniform(-12, 20), rng.uniform(-8, 32), rng.uniform(-5, 40)])
    b = np.array([rng.uniform(-12, 20), rng.uniform(-8, 32), rng.uniform(-5, 40)])
    if draw(st.booleans()):  # axis-aligned and along grid lines too
        b[draw(st.integers(0, 1))] = a[draw(st.integers(0, 1))]
    return ter, a, b


@settings(max_examples=150, deadline=None)
@given(terrain_and_segment())
def test_terrain_extrema_are_exact(case: tuple[Terrain, np.ndarray, np.ndarray]) -> None:
    ter, a, b = case
    ext = terrain_clearance_extrema(a[None], b[None], ter)[0]
    s = np.linspace(0, 1, 40001)
    p = a + s[:, None] * (b - a)
    c = p[:, 2] - ter.height(p[:, 0], p[:, 1])  # the plain bilinear lookup as reference
    assert ext[0] <= c.min() + 1e-9 and ext[2] >= c.max() - 1e-9
    for col in (0, 2):  # attained where reported
        q = a + ext[col + 1] * (b - a)
        assert q[2] - float(ter.height(q[0], q[1])) == pytest.approx(ext[col], abs=1e-9)


def test_own_bilinear_matches_terrain_height() -> None:
    rng = np.random.default_rng(0)
    ter = Terrain(rng.uniform(0, 10, (4, 7)), x0=1.0, y0=-2.0, dx=3.0, dy=2.0)
    x, y = rng.uniform(-5, 30, 500), rng.uniform(-10, 15, 500)
    assert np.allclose(bilinear_height(ter, x, y), ter.height(x, y), atol=1e-12)


# ---------------------------------------------------------------------------- timing, bounds
def test_times_speed_and_bounds() -> None:
    back = traj("a", [[0, 0, 0], [10, 0, 0], [20, 0, 0]], [0, 2, 1])
    assert [v.kind for v in check_times(back)] == ["times"]
    fast = traj("a", [[0, 0, 0], [100, 0, 0], [110, 0, 0], [120, 0, 0]], [0, 1, 1, 2])
    vs = check_speed(fast, 20.0)
    assert [v.value for v in vs] == [pytest.approx(100.0), math.inf]
    assert check_speed(traj("a", [[0, 0, 0], [20, 0, 0]], [0, 1]), 20.0) == []
    # rounding of plan files (6 decimals) is tolerated
    assert check_speed(traj("a", [[0, 0, 0], [2.000001, 0, 0]], [0, 0.1]), 20.0) == []
    out = traj("a", [[0, 0, 0], [250, 0, 10]], [0, 20])
    vs = check_bounds(out, (-200, -200, 0), (200, 200, 200))
    assert len(vs) == 1 and vs[0].value == pytest.approx(50.0) and "along x" in vs[0].message


# ---------------------------------------------------------------------------- whole plans
def clean_plan() -> dict[str, Any]:
    return {
        "format": "uavplan.plan/1",
        "scenario": "flat",
        "uavs": [
            uav(f"u{k}", [[0, 20 * k, 10], [50, 20 * k, 20], [100, 20 * k, 10]], [0, 2, 4])
            for k in range(3)
        ],
    }


def test_clean_fleet_passes() -> None:
    report = verify_plan(clean_plan(), flat_scenario(3))
    assert report.ok and report.violations == []
    assert report.counts == dict.fromkeys(KINDS, 0)
    assert report.pairs_total == 3 and report.pairs_checked == 0  # all farther than S2
    assert report.min_separation == pytest.approx(20.0)  # found by widening the pruning
    assert report.min_separation_pair == ("u0", "u1")
    d = report.to_dict()
    assert d["ok"] is True and json.loads(json.dumps(d))["min_separation"] == pytest.approx(20)


def test_plan_with_every_kind_of_world() -> None:
    ter = ridge_terrain()
    sc = Scenario(
        "world",
        Bounds((-10.0, -10.0, 0.0), (50.0, 50.0, 200.0)),
        (Task("a", (0.0, 5.0, 60.0), (40.0, 5.0, 60.0)), Task("b", (0.0, 35.0, 60.0), (0, 0, 0))),
        terrain=ter,
        cylinders=(Cylinder((30.0, 35.0), 3.0),),
        altitude=AltitudeBand(5.0, 100.0, "ground"),
        uav=UAV(speed=20.0, s2=10.0),
    )
    plan = {
        "scenario": "other",
        "uavs": [
            uav("a", [[0, 5, 60], [40, 5, 60]], [0, 2]),
            uav("b", [[0, 35, 60], [40, 35, 60]], [0, 2]),
            uav("c", [[20, -5, 30], [20, 45, 30]], [0, 2.5]),
            uav("d", [[40, 5, 60], [0, 5, 60]], [0, 2]),
        ],
    }
    report = verify_plan(plan, sc)
    counts = report.counts
    assert counts["cylinder"] == 1  # b through the cylinder
    assert counts["terrain"] == 1  # c under the ridge
    assert counts["separation"] == 1  # a and d head-on (c is 30 m below them)
    assert counts["altitude"] == 1  # c below the band
    assert sum(counts.values()) == 4
    assert {v.uavs for v in report.violations if v.kind == "separation"} == {("a", "d")}
    assert any("scenario 'other'" in w for w in report.warnings)
    assert any("b: path goal" in w for w in report.warnings)
    assert any("c: the plan calls it feasible" in w for w in report.warnings)


def test_two_dimensional_plan() -> None:
    sc = Scenario(
        "flat2d",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("p", (0.0, 50.0), (100.0, 50.0)),),
        circles=(Circle((50.0, 80.0), 5.0),),
        uav=UAV(speed=20.0, s2=5.0),
    )
    plan = {
        "uavs": [
            uav("p", [[0, 50], [100, 50]], [0, 5]),
            uav("q", [[50, 0], [50, 100]], [0, 5]),
        ]
    }
    report = verify_plan(plan, sc)
    assert report.counts["separation"] == 1 and report.counts["circle"] == 1
    with pytest.raises(PlanFormatError, match=r"expected a point of 2 coordinates"):
        verify_plan({"uavs": [uav("p", [[0, 50, 1], [100, 50, 1]], [0, 5])]}, sc)


def test_smoothed_paths() -> None:
    plan = clean_plan()
    with pytest.raises(PlanFormatError, match=r"uavs\[0\] \(u0\): no smoothed path"):
        verify_plan(plan, flat_scenario(3), smoothed=True)
    for u in plan["uavs"]:
        y = u["waypoints"][0][1]
        u["smoothed"] = {"points": [[0, y, 10], [100, 0, 10]], "times": [0, 5]}
    report = verify_plan(plan, flat_scenario(3), smoothed=True)
    assert report.smoothed and report.counts["separation"] == 3  # they all meet at (100, 0)
    assert verify_plan(plan, flat_scenario(3)).ok


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda p: p.pop("uavs"), "uavs: missing"),
        (lambda p: p["uavs"][1].pop("times"), r"uavs\[1\]\.times: missing"),
        (lambda p: p["uavs"][1]["times"].pop(), r"uavs\[1\]\.times: 2 values but waypoints has 3"),
        (lambda p: p["uavs"][0]["waypoints"][1].pop(), r"uavs\[0\]\.waypoints\[1\]: expected a"),
        (lambda p: p["uavs"][2]["times"].__setitem__(1, "x"), r"times\[1\]: 'x' is not a number"),
        (lambda p: p["uavs"][2]["times"].__setitem__(1, "inf"), "is not a finite number"),
        (lambda p: p["uavs"][2].__setitem__("id", "u0"), "'u0' appears twice"),
        (lambda p: p.__setitem__("format", "other/2"), "format: 'other/2' is not one of"),
    ],
)
def test_bad_plans(mutate: Any, message: str) -> None:
    plan = clean_plan()
    mutate(plan)
    with pytest.raises(PlanFormatError, match=message):
        parse_plan(plan, 3, source="plan.json").trajectories()


# ------------------------------------------------------------- per-axis separation (box)
BOX = (50.0, 50.0, 20.0)  # the RSCDWOA paper, Sect. 5: minimal distance [50, 50, 20] m


def sampled_box_measure(a: Trajectory, b: Trajectory, n: int = 20001) -> float:
    t0, t1 = max(a.times[0], b.times[0]), min(a.times[-1], b.times[-1])
    t = np.unique(np.concatenate([np.linspace(t0, t1, n), a.times, b.times]))
    t = t[(t >= t0) & (t <= t1)]
    pa = np.stack([np.interp(t, a.times, a.points[:, k]) for k in range(3)], 1)
    pb = np.stack([np.interp(t, b.times, b.points[:, k]) for k in range(3)], 1)
    return float(50.0 * np.min(np.max(np.abs(pa - pb) / np.asarray(BOX), axis=1)))


def test_box_separation_is_per_axis() -> None:
    a = traj("a", [[0, 0, 100], [200, 0, 100]], [0, 10])
    above = traj("b", [[0, 0, 130], [200, 0, 130]], [0, 10])  # 30 m over: clear of 20 m in z
    res = check_separation([a, above], 10.0, axes=BOX)
    assert res.violations == [] and res.min_distance == pytest.approx(75.0)  # 50 * 30 / 20
    assert check_separation([a, above], 50.0).violations  # a 50 m sphere would reject it
    beside = traj("b", [[40, 0, 110], [240, 0, 110]], [0, 10])  # 40 m in x, 10 m in z
    assert not check_separation([a, beside], 10.0).violations  # a 10 m sphere accepts it
    res = check_separation([a, beside], 10.0, axes=BOX)
    assert len(res.violations) == 1
    v = res.violations[0]
    assert v.value == pytest.approx(40.0) and "within the box 50/50/20 m" in v.message


def test_box_crossing_found_between_breakpoints() -> None:
    # crossing at right angles 15 m apart in z: inside the box from t = 7.5 to 12.5 s
    a = traj("a", [[0, 200, 50], [400, 200, 50]], [0, 20])
    b = traj("b", [[200, 0, 65], [200, 400, 65]], [0, 20])
    res = check_separation([a, b], 0.0, axes=BOX)
    assert len(res.violations) == 1
    assert res.min_distance == pytest.approx(37.5)
    assert "closer from t=7.500 to 12.500 s" in res.violations[0].message


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_box_measure_matches_sampling_and_the_reservation_table(seed: int) -> None:
    """The verifier's bisection against dense sampling, and against the planner's reservation
    table (which enumerates the kinks instead): two methods, one answer."""
    from uavplan.world.reservations import ReservationTable

    rng = np.random.default_rng(seed)
    pa = rng.uniform([0, 0, 0], [300, 300, 60], (4, 3))
    pb = rng.uniform([0, 0, 0], [300, 300, 60], (5, 3))
    ta = np.concatenate([[0.0], np.cumsum(rng.uniform(1, 4, 3))])
    t0 = rng.uniform(0, 2)  # one take-off time: the times must not decrease
    tb = np.concatenate([[t0], t0 + np.cumsum(rng.uniform(1, 4, 4))])
    a, b = traj("a", pa, ta), traj("b", pb, tb)
    d, tm = pair_min_distance(a, b, axes=BOX)
    if not math.isfinite(d):
        return
    assert d <= sampled_box_measure(a, b) + 1e-9
    assert sampled_box_measure(a, b) - d < 0.5
    off = np.abs(b.position(tm) - a.position(tm))
    assert 50.0 * np.max(off / np.asarray(BOX)) == pytest.approx(d, abs=1e-6)
    table = ReservationTable(np.zeros(3), np.array([300.0, 300.0, 60.0]), BOX, dt=1.0)
    table.add("a", pa, ta)
    assert table.min_distance_reference(pb, tb) == pytest.approx(d, abs=1e-7)


@pytest.mark.parametrize("seed", range(4))
def test_box_minimum_skipping_far_intervals_equals_every_interval_s(seed: int) -> None:
    """The box measure's walk skips the intervals whose per-axis bound cannot beat the best
    so far (the level's bisection is 80 steps): its minimum and time equal those of the walk
    that records every interval (nothing skipped), on long random flights."""
    from uavplan.verify.separation import _metric, _pack, _walk

    rng = np.random.default_rng(seed)
    n = 300
    pa = np.cumsum(rng.normal(0, 40, (n, 3)), axis=0)
    pb = pa[::-1] + rng.normal(0, 60, (n, 3))
    ta = np.concatenate([[0.0], np.cumsum(rng.uniform(1, 4, n - 1))])
    tb = np.concatenate([[0.5], 0.5 + np.cumsum(rng.uniform(1, 4, n - 1))])
    a, b = traj("a", pa, ta), traj("b", pb, tb)
    d, tm = pair_min_distance(a, b, axes=BOX)
    P, T, off = _pack([a, b])
    box, S = _metric(BOX)
    rec = np.empty((2 * n + 2, 16))
    _, m = _walk(P, T, off[0], off[1], off[1], off[2], rec, True, box, S)
    k = int(np.argmin(rec[:m, 2]))
    assert d == rec[k, 2] and tm == rec[k, 3]


def test_verify_plan_uses_the_uav_box() -> None:
    tasks = (Task("u0", (0, 0, 100), (200, 0, 100)), Task("u1", (40, 0, 110), (240, 0, 110)))
    sc = Scenario(
        "box", Bounds((-300.0, -300.0, 0.0), (300.0, 300.0, 300.0)), tasks,
        uav=UAV(speed=50.0, s2_axes=BOX),
    )  # fmt: skip
    plan = {
        "uavs": [
            uav("u0", [[0, 0, 100], [200, 0, 100]], [0, 4]),
            uav("u1", [[40, 0, 110], [240, 0, 110]], [0, 4]),
        ]
    }
    rep = verify_plan(plan, sc)
    assert rep.s2 == 50.0 and rep.s2_axes == BOX
    assert rep.counts["separation"] == 1 and not rep.ok
    plan["uavs"][1]["waypoints"] = [[40, 0, 125], [240, 0, 125]]  # 25 m above: clear
    rep = verify_plan(plan, sc)
    assert rep.ok, [v.message for v in rep.violations]
    assert rep.to_dict()["s2_axes"] == list(BOX)


# ---------------------------------------------------------------------------- CLI
def _scenario_file(d: Path) -> Path:
    data = {
        "name": "flat",
        "bounds": {"lower": [-200, -200, 0], "upper": [200, 200, 200]},
        "uav": {"speed": 50, "s2": 10},
        "tasks": [
            {"id": f"u{k}", "start": [0, 20 * k, 10], "goal": [100, 20 * k, 10]} for k in range(3)
        ],
    }
    p = d / "flat.json"
    p.write_text(json.dumps(data))
    return p


def _invoke(*args: str) -> Any:
    result = runner.invoke(app, ["verify", *args])
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result


def test_cli_clean_and_violating(tmp_path: Path) -> None:
    sc = _scenario_file(tmp_path)
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(clean_plan()))
    r = _invoke(str(plan), str(sc))
    assert r.exit_code == 0, r.output
    assert "violations: none" in r.output and "min separation: 20 m between u0 and u1" in r.output
    assert _invoke(str(tmp_path), str(sc)).exit_code == 0  # the folder holding plan.json
    bad = clean_plan()
    bad["uavs"][1]["waypoints"] = [[100, 0, 10], [50, 0, 20], [0, 0, 10]]  # u0 head-on
    plan.write_text(json.dumps(bad))
    report = tmp_path / "report.json"
    r = _invoke(str(plan), str(sc), "--json", str(report))
    assert r.exit_code == 1
    assert "separation: u0 and u1 0.000 m apart at t=2.000 s" in r.output
    assert "violations: 1 (separation 1)" in r.output and "FAILED" in r.output
    assert json.loads(report.read_text())["counts"]["separation"] == 1


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (None, "no such plan file"),
        ("{not json", "invalid JSON: Expecting property name enclosed in double quotes at line 1"),
        ('{"uavs": []}', "uavs: expected a non-empty list, got []"),
        ('{"uavs": [{"id": "u0", "waypoints": [[0, 0, 10], [1, 0, 10]], "times": [0]}]}',
         "uavs[0].times: 1 values but waypoints has 2 points"),
        ('{"uavs": [{"id": "u0", "waypoints": [[0, 0], [1, 0]], "times": [0, 1]}]}',
         "uavs[0].waypoints[0]: expected a point of 3 coordinates, got [0, 0]"),
    ],
)  # fmt: skip
def test_cli_bad_input(tmp_path: Path, content: str | None, expected: str) -> None:
    sc = _scenario_file(tmp_path)
    plan = tmp_path / "plan.json"
    if content is not None:
        plan.write_text(content)
    r = _invoke(str(plan), str(sc))
    assert r.exit_code == 2
    assert expected in r.output
    assert len(r.output.strip().splitlines()) == 1


def test_cli_bad_scenario_and_missing_smoothed(tmp_path: Path) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(clean_plan()))
    r = _invoke(str(plan), str(tmp_path / "nope.yaml"))
    assert r.exit_code == 2 and "no such scenario file" in r.output
    r = _invoke(str(plan), str(_scenario_file(tmp_path)), "--smoothed")
    assert r.exit_code == 2 and "uavs[0] (u0): no smoothed path" in r.output
