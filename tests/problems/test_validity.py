"""The motion validator: the one validity path (points, segments, timed paths, reservations)."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.problems import PathProblem
from uavplan.problems.validity import CHECKS, MotionValidator, band_repair, greedy_shortcut
from uavplan.scenarios import resolve
from uavplan.world import (
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
from uavplan.world.reservations import ReservationTable


def world3() -> Scenario:
    x = np.arange(0, 201, 10.0)
    H = np.tile(x * 0.2, (21, 1)) + 5 * np.sin(x / 30)[:, None]
    t = Terrain(H, 0.0, 0.0, 10.0, 10.0, "bumps")
    mover = MovingObstacle(8.0, np.array([0.0, 20.0]), np.array([[60.0, 20, 70], [60, 180, 70]]))
    return Scenario(
        "w3",
        Bounds((0.0, 0.0, 0.0), (200.0, 200.0, 200.0)),
        (Task("a", (10.0, 100.0, 60.0), (190.0, 100.0, 90.0)),),
        terrain=t,
        cylinders=(Cylinder((100.0, 100.0), 20.0), Cylinder((150.0, 60.0), 10.0, 0.0, 50.0)),
        polygons=(Polygon(((120.0, 140.0), (160.0, 140.0), (140.0, 170.0))),),
        moving_obstacles=(mover,),
        altitude=AltitudeBand(20.0, 80.0, "ground"),
    )


def world2() -> Scenario:
    return Scenario(
        "w2",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("a", (5.0, 50.0), (95.0, 50.0)),),
        circles=(Circle((50.0, 50.0), 10.0),),
        polygons=(Polygon(((20.0, 10.0), (40.0, 10.0), (40.0, 30.0), (30.0, 15.0), (20.0, 30.0))),),
    )


def random_segments(sc: Scenario, m: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    lo, hi = sc.bounds.lo - 5, sc.bounds.hi + 5
    a = rng.uniform(lo, hi, (m, sc.dim))
    b = a + rng.normal(0, 30, (m, sc.dim))
    if sc.dim == 3:
        a[:, 2] = sc.ground(a[:, 0], a[:, 1]) + rng.uniform(-10, 100, m)
        b[:, 2] = sc.ground(b[:, 0], b[:, 1]) + rng.uniform(-10, 100, m)
    return a, b


@pytest.mark.parametrize("make", [world2, world3], ids=["2d", "3d"])
@pytest.mark.parametrize("strict", [False, True])
def test_segments_valid_is_the_cost_free_problems_verdict(make, strict: bool) -> None:
    sc = make()
    v = MotionValidator(sc, strict_altitude=strict)
    a, b = random_segments(sc, 3000, 1)
    got = v.segments_valid(a, b)
    ref = PathProblem(sc, cost=(), strict_altitude=strict).evaluate(np.stack([a, b], 1)).feasible
    np.testing.assert_array_equal(got, ref)
    assert 0.05 < got.mean() < 0.95  # both answers happen
    # the checks that apply to each world, in report order
    assert v.checks() == tuple(c for c in CHECKS if c in v.checks())
    assert ("terrain" in v.checks()) == (sc.dim == 3)


def test_points_are_zero_length_segments_and_agree_with_point_problems() -> None:
    sc = world3()
    v = MotionValidator(sc)
    rng = np.random.default_rng(0)
    p = rng.uniform(sc.bounds.lo, sc.bounds.hi, (2000, 3))
    p[:, 2] = sc.ground(p[:, 0], p[:, 1]) + rng.uniform(-5, 90, 2000)
    ok = v.is_valid(p)
    np.testing.assert_array_equal(ok, v.segments_valid(p, p))
    # where no moving obstacle is involved, the scenario's own point check agrees
    static = MotionValidator(
        Scenario(**{**sc.__dict__, "moving_obstacles": (), "metadata": {}}),
    )
    want = np.array([not sc.__class__.point_problems(static.scenario, q) for q in p])
    np.testing.assert_array_equal(static.is_valid(p), want)


def test_timed_segments_see_moving_obstacles_and_reserved_uavs() -> None:
    sc = world3()
    table = ReservationTable(sc.bounds.lo, sc.bounds.hi, 10.0)
    table.add("b", np.array([[100.0, 20, 120], [100, 180, 120]]), np.array([0.0, 16.0]))
    v = MotionValidator(sc, reservations=table)
    assert v.checks()[-2:] == ("moving", "separation")
    # crossing b's track at 120 m: clear when we pass before it arrives, not when we meet it
    a = np.array([[90.0, 100, 120]])
    b = np.array([[110.0, 100, 120]])
    open_sky = {"altitude": None, "cylinders": (), "polygons": (), "metadata": {}}
    band = MotionValidator(Scenario(**{**sc.__dict__, **open_sky}), reservations=table)
    assert band.paths_valid(np.stack([a, b], 1))[0] != band.segments_valid(a, b, 7.5, 8.5)[0]
    assert band.segments_valid(a, b, 0.0, 1.0)[0]  # b is at y = 20..30 then
    assert not band.segments_valid(a, b, 7.5, 8.5)[0]  # b passes y = 100 at t = 8 s
    # the mover crosses x = 60 from y = 20 to y = 180 during 0..20 s
    a2, b2 = np.array([[50.0, 100, 70]]), np.array([[70.0, 100, 70]])
    ok = band.segments_valid(a2, b2, np.array([9.5]), np.array([10.5]))
    assert not ok[0]
    assert band.segments_valid(a2, b2, 30.0, 31.0)[0]  # long gone (it holds its last point)
    with pytest.raises(ValueError, match="both"):
        v.segments_valid(a, b, 0.0, None)


@pytest.mark.parametrize("make", [world2, world3], ids=["2d", "3d"])
def test_clearance_sign_matches_the_violations(make) -> None:
    sc = make()
    v = MotionValidator(sc)
    a, b = random_segments(sc, 1500, 4)
    paths = np.stack([a, b], 1)
    batch = v.batch(paths)
    viol = v.violations(batch)
    clear = v.clearance(paths)
    assert set(clear) == set(viol)
    for kind in ("bounds", "cylinders", "circles", "terrain", "moving"):
        if kind in clear:
            assert np.all(clear[kind][viol[kind]] <= 1e-9), kind
            assert np.all(~viol[kind][clear[kind] > 1e-9]), kind
    if "polygons" in clear:
        assert np.all(clear["polygons"][viol["polygons"]] <= 1e-9)
    if "altitude" in clear:  # at the waypoints (not strict)
        assert np.array_equal(clear["altitude"] < -1e-9, viol["altitude"])


def test_graded_violation_is_zero_only_where_valid() -> None:
    sc = world3()
    v = MotionValidator(sc)
    a, b = random_segments(sc, 1000, 2)
    batch = v.batch(np.stack([a, b], 1))
    viol = v.violations(batch)
    V = v.graded_violation(batch, viol)
    bad = np.zeros(len(a), dtype=bool)
    for x in viol.values():
        bad |= x
    assert np.all(V[bad] >= 100.0) and np.all(V >= 0)
    # more failed checks weigh more
    n_failed = sum(x.astype(int) for x in viol.values())
    assert np.all(100.0 * n_failed <= V)


def _all_pairs_shortcut(v: MotionValidator, p: np.ndarray) -> np.ndarray:
    """The RRT* shortcut as it was (all pairs first, then greedy): the reference."""
    n = len(p)
    i, j = np.triu_indices(n, k=2)
    ok = np.zeros((n, n), dtype=bool)
    ok[i, j] = v.segments_valid(p[i], p[j])
    keep, cur = [0], 0
    while cur < n - 1:
        later = np.flatnonzero(ok[cur, cur + 2 :])
        cur = cur + 2 + int(later[-1]) if len(later) else cur + 1
        keep.append(cur)
    return p[keep]


def test_greedy_shortcut_is_valid_never_longer_and_matches_the_all_pairs_form() -> None:
    from uavplan.planners.sampling.rrt_star import RRTStarConfig, rrt_star, validity_problem

    sc = resolve("spso")
    v = validity_problem(sc)
    for seed in range(4):
        r = rrt_star(sc, None, RRTStarConfig(), np.random.default_rng(seed))
        assert r.path is not None
        s, t, checks = greedy_shortcut(v, r.path)
        assert t is None and checks > 0
        assert np.array_equal(s, _all_pairs_shortcut(v, r.path))
        assert v.paths_valid(s[None])[0]
        assert np.array_equal(s[0], r.path[0]) and np.array_equal(s[-1], r.path[-1])
        L = lambda q: float(np.linalg.norm(np.diff(q, axis=0), axis=1).sum())  # noqa: E731
        assert L(s) <= L(r.path) + 1e-9


def test_band_repair_follows_the_terrain_along_the_same_track() -> None:
    """A level line along jacksboro's southern edge, 150 m above the ground at its start,
    leaves the 50-300 m band over the ridges: terrain following moves and adds points
    vertically until every segment holds the band (strict validator), on the same horizontal
    line, start and goal kept; a path through a cylinder cannot be cured that way (None)."""
    sc = resolve("jacksboro")
    v = MotionValidator(sc, strict_altitude=True)
    a, b = np.array([1500.0, 1500.0, 0.0]), np.array([28000.0, 1500.0, 0.0])
    a[2], b[2] = (float(sc.terrain.height(p[0], p[1])) + 150.0 for p in (a, b))
    line = a + np.linspace(0.0, 1.0, 12)[:, None] * (b - a)
    line[1:-1, 2] = a[2]
    assert not v.paths_valid(line[None])[0]
    rep = band_repair(v, line)
    assert rep is not None and len(rep) > len(line)
    assert v.segments_valid(rep[:-1], rep[1:]).all()
    assert np.array_equal(rep[0], line[0]) and np.array_equal(rep[-1], line[-1])
    d, u = b[:2] - a[:2], rep[:, :2] - a[:2]
    assert np.abs(u[:, 0] * d[1] - u[:, 1] * d[0]).max() / np.linalg.norm(d) < 1e-6
    assert np.all(np.diff(u @ d) > 0)  # in order along the line: no loop
    assert band_repair(v, line, max_points=len(line) + 1) is None  # too few points allowed
    c = sc.cylinders[0]
    (cx, cy), z = c.center, 0.5 * (c.z_min + c.z_max)
    through = np.array([[cx - 3 * c.radius, cy, z], [cx + 3 * c.radius, cy, z]])
    assert band_repair(MotionValidator(sc), through) is None


def test_bad_shapes_are_refused() -> None:
    v = MotionValidator(world2())
    with pytest.raises(ValueError, match="paths must be"):
        v.paths_valid(np.zeros((3, 1, 2)))
    with pytest.raises(ValueError, match="paths must be"):
        v.paths_valid(np.zeros((3, 4, 3)))
    with pytest.raises(ValueError, match="differ in shape"):
        v.segments_valid(np.zeros((3, 2)), np.zeros((4, 2)))


@pytest.mark.parametrize(
    "name",
    ["ppswarm2", "spso", "jacksboro", "open", "topobathy", "w3s", "w3c", "many", "manyp"],
)
@pytest.mark.parametrize("strict", [False, True])
@pytest.mark.parametrize("lookup", ["bilinear", "nearest"])
@pytest.mark.parametrize("climb", [False, True])
def test_fused_static_checks_agree_with_the_checks_one_by_one(
    name: str, strict: bool, lookup: str, climb: bool
) -> None:
    """``passing`` (one fused kernel for bounds, cylinders, circles, polygons, terrain and
    band in 3-D, and the segments' climb angles when the validator checks them) gives exactly
    the verdicts of the checks run one by one (:meth:`violations`); ``many``: 300 cylinders,
    which the grid-indexed check tests after the kernel; ``manyp``: 80 polygons and circles,
    which the 2-D scene pass tests after it on its obstacle grid."""
    import dataclasses

    from uavplan.world import Circle, Cylinder

    if name == "w3s":  # finite cylinders, no polygons, no moving obstacles
        sc = dataclasses.replace(world3(), polygons=(), moving_obstacles=())
    elif name == "w3c":  # circles, and polygons convex and not, with and without a margin
        sc = dataclasses.replace(
            world3(),
            polygons=(
                *world3().polygons,
                Polygon(((20.0, 20.0), (60.0, 20.0), (60.0, 60.0), (40.0, 30.0), (20.0, 60.0))),
                Polygon(((150.0, 150.0), (190.0, 150.0), (170.0, 190.0)), margin=6.0),
                Polygon(
                    ((20.0, 150.0), (60.0, 150.0), (60.0, 190.0), (40.0, 160.0), (20.0, 190.0)),
                    margin=4.0,
                ),
            ),
            circles=(Circle((100.0, 30.0), 12.0), Circle((30.0, 100.0), 8.0, margin=3.0)),
            moving_obstacles=(),
        )
    elif name == "many":  # enough cylinders for the grid, some finite
        sc = resolve("spso")
        r = np.random.default_rng(3)
        lo2, hi2 = np.asarray(sc.bounds.lo[:2]), np.asarray(sc.bounds.hi[:2])
        cyl = [
            Cylinder(tuple(r.uniform(lo2, hi2)), float(r.uniform(3, 12)), z_max=float(z))
            for z in r.choice([np.inf, 300.0, 600.0], 300)
        ]
        sc = dataclasses.replace(sc, cylinders=tuple(cyl))
    elif name == "manyp":  # enough circles and polygons for the obstacle grid
        sc = resolve("spso")
        r = np.random.default_rng(5)
        lo2, hi2 = np.asarray(sc.bounds.lo[:2]), np.asarray(sc.bounds.hi[:2])
        c = r.uniform(lo2, hi2, (80, 2))
        tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]])
        sc = dataclasses.replace(
            sc,
            polygons=tuple(Polygon(tuple(map(tuple, q + 8.0 * tri))) for q in c[:60]),
            circles=tuple(Circle(tuple(q), 5.0) for q in c[60:]),
        )
    else:
        sc = resolve(name)  # jacksboro: finite cylinders on a real DEM, a revealed polygon
    if climb:  # limits that many of the random segments break
        sc = dataclasses.replace(
            sc, uav=dataclasses.replace(sc.uav, max_climb_angle=40.0, max_descent_angle=55.0)
        )
    v = MotionValidator(sc, sc.tasks[0], strict_altitude=strict, lookup=lookup, climb=climb)
    assert v._static_args is not None
    assert ("climb" in v.checks()) is climb
    rng = np.random.default_rng(11)
    lo, hi = np.asarray(sc.bounds.lo), np.asarray(sc.bounds.hi)
    span = hi - lo
    paths = rng.uniform(lo - 0.02 * span, hi + 0.02 * span, (600, 6, 3))
    # the first 200 short (within 15 m of a point), so that many pass every check
    paths[:200, :, :2] = paths[:200, :1, :2] + rng.uniform(-15, 15, (200, 6, 2))
    xy = paths[..., :2]
    band = sc.altitude
    g = sc.ground(xy[..., 0], xy[..., 1])
    mid = g + (0.5 * (band.min + band.max) if band and band.reference == "ground" else 0)
    if band is not None and band.reference != "ground":
        mid = np.full_like(g, 0.5 * (band.min + band.max))
    scale = (band.max - band.min) if band is not None else 0.3 * span[2]
    paths[..., 2] = mid + rng.normal(0, 0.5 * scale, g.shape)
    paths[:200, :, 2] = mid[:200] + rng.normal(0, 0.05 * scale, (200, 6))
    b = v.batch(paths)
    want = np.ones(len(paths), dtype=bool)
    for bad in v.violations(b).values():
        want &= ~bad
    got = np.zeros(len(paths), dtype=bool)
    got[v.passing(b)] = True
    np.testing.assert_array_equal(got, want)
    assert 0 < want.sum() < len(paths)
    if climb:  # the climb check decides some paths that pass every other check
        others = np.ones(len(paths), dtype=bool)
        for check, bad in v.violations(b).items():
            others &= ~bad if check != "climb" else True
        assert (others & ~want).any()
    if name == "many":
        assert v._cylinders_by_grid and v.violations(b)["cylinders"][:200].any()
    if name in ("w3c", "manyp"):  # the circles and polygons decide some paths
        scene = ("circles", "polygons")
        fails = [bad for check, bad in v.violations(b).items() if check in scene]
        others = np.ones(len(paths), dtype=bool)
        for check, bad in v.violations(b).items():
            others &= ~bad if check not in scene else True
        assert (others & np.any(fails, axis=0)).any()
        assert v._scene_by_grid is (name == "manyp")
        assert (v.segment_kernel is None) is (name == "manyp")
    if name == "jacksboro":
        assert v.segment_kernel is not None and "polygons" in v.checks()
    np.testing.assert_array_equal(v.paths_valid(paths), want)
