"""PathProblem: batch == loop for every preset, exact feasibility flags, shape checks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.problems import PRESETS, CartesianEncoding, Evaluation, PathProblem, cost_presets
from uavplan.world import (
    UAV,
    AltitudeBand,
    Circle,
    Cylinder,
    DangerArea,
    MovingObstacle,
    Polygon,
    Scenario,
    Task,
    Terrain,
    UncertainArea,
)
from uavplan.world.scenario import Bounds

SEEDS = st.integers(0, 2**32 - 1)
REL = 1e-6  # "just inside / just outside" by this relative amount


# ----------------------------------------------------------------------------- scenarios
def hills(seed: int = 0) -> Terrain:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:20, 0:30].astype(float)
    h = 20.0 + rng.normal(0, 3.0, (20, 30))
    for _ in range(3):
        cx, cy, w = rng.uniform(0, 30), rng.uniform(0, 20), rng.uniform(2, 5)
        h += rng.uniform(10, 60) * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * w * w))
    return Terrain(h, 0.0, 0.0, 10.0, 10.0, "hills")


def scenario_3d(cost: str = "ppswarm") -> Scenario:
    T = hills()
    s = (15.0, 15.0, float(T.height(15.0, 15.0)) + 60.0)
    g = (275.0, 175.0, float(T.height(275.0, 175.0)) + 60.0)
    return Scenario(
        name="rich3d",
        bounds=Bounds((0.0, 0.0, 0.0), (290.0, 190.0, 400.0)),
        tasks=(Task("a", s, g, start_time=1.0), Task("b", g, s)),
        terrain=T,
        circles=(Circle((60.0, 150.0), 12.0, margin=1.0),),
        polygons=(Polygon(((200.0, 20.0), (240.0, 20.0), (220.0, 60.0)), margin=2.0),),
        cylinders=(
            Cylinder((100.0, 100.0), 20.0, margin=2.0),
            Cylinder((180.0, 120.0), 15.0, z_min=40.0, z_max=120.0, margin=1.0),
        ),
        danger_areas=(DangerArea((150.0, 60.0), 30.0), DangerArea((240.0, 150.0), 20.0)),
        uncertain_areas=(
            UncertainArea(30.0, 60.0, 20.0, 15.0),
            UncertainArea(120.0, 160.0, 20.0, 10.0, revealed=False),
        ),
        moving_obstacles=(
            MovingObstacle(
                8.0,
                np.array([0.0, 5.0, 12.0]),
                np.array([[50.0, 50.0, 80.0], [150.0, 80.0, 90.0], [250.0, 100.0, 60.0]]),
            ),
        ),
        altitude=AltitudeBand(10.0, 150.0, "ground"),
        cost=cost,
        n_waypoints=4,
    )


def scenario_2d() -> Scenario:
    return Scenario(
        name="flat",
        bounds=Bounds((0.0, 0.0), (100.0, 100.0)),
        tasks=(Task("a", (2.0, 2.0), (98.0, 98.0)),),
        circles=(Circle((30.0, 30.0), 8.0, margin=0.5), Circle((70.0, 40.0), 10.0)),
        polygons=(Polygon(((50.0, 60.0), (60.0, 75.0), (50.0, 70.0), (40.0, 75.0))),),
        uncertain_areas=(UncertainArea(10.0, 70.0, 15.0, 10.0),),
        moving_obstacles=(
            MovingObstacle(3.0, np.array([0.0, 10.0]), np.array([[0.0, 50.0], [100.0, 50.0]])),
        ),
        cost="length2d",
        n_waypoints=3,
    )


def scenario_spso() -> Scenario:
    T = Terrain.builtin("spso")
    threats = [
        [400, 500, 80],
        [600, 200, 70],
        [500, 350, 80],
        [350, 200, 70],
        [700, 550, 70],
        [650, 750, 80],
    ]
    return Scenario(
        name="spso",
        bounds=Bounds((1.0, 1.0, 0.0), (1045.0, 879.0, 500.0)),
        tasks=(
            Task(
                "uav",
                (200.0, 100.0, 150.0 + float(T.height(200.0, 100.0))),
                (800.0, 800.0, 150.0 + float(T.height(800.0, 800.0))),
            ),
        ),
        terrain=T,
        cylinders=tuple(Cylinder((x, y), float(R), margin=1.0) for x, y, R in threats),
        altitude=AltitudeBand(100.0, 200.0, "ground"),
        cost="spso",
        n_waypoints=10,
    )


SCENARIOS = {"rich3d": scenario_3d, "flat": scenario_2d, "spso": scenario_spso}
CASES = [
    ("spso", "spso"),
    ("rich3d", "ppswarm"),
    ("rich3d", "hrmaga"),
    ("rich3d", "spso"),
    ("rich3d", "length2d"),
    ("flat", "length2d"),
    ("flat", "ppswarm"),
]


def random_population(sc: Scenario, rng: np.random.Generator, pop: int, n: int) -> np.ndarray:
    lo, hi = sc.bounds.lo, sc.bounds.hi
    span = hi - lo
    p = rng.uniform(lo - 0.05 * span, hi + 0.05 * span, (pop, n, sc.dim))
    p[:, 0] = sc.tasks[0].start
    p[:, -1] = sc.tasks[0].goal
    if sc.dim == 3 and sc.terrain is not None:  # mostly above the ground, within the band
        g = sc.terrain.height(p[..., 0], p[..., 1])
        p[:, 1:-1, 2] = g[:, 1:-1] + rng.uniform(-20, 220, (pop, n - 2))
    if pop > 2 and n > 2:
        p[1, 2] = p[1, 1]  # a repeated node
        p[2, 1:-1] = np.linspace(p[2, 0], p[2, -1], n)[1:-1]  # straight line
    return p


def assert_same_evaluation(a, b) -> None:
    np.testing.assert_allclose(a.cost, b.cost, rtol=1e-12, atol=0)
    assert a.terms.keys() == b.terms.keys()
    for k in a.terms:
        np.testing.assert_allclose(a.terms[k], b.terms[k], rtol=1e-12, atol=0, err_msg=k)
    np.testing.assert_array_equal(a.feasible, b.feasible)
    assert a.violations.keys() == b.violations.keys()
    for k in a.violations:
        np.testing.assert_array_equal(a.violations[k], b.violations[k], err_msg=k)


@pytest.fixture(scope="module")
def scenarios() -> dict[str, Scenario]:
    return {k: f() for k, f in SCENARIOS.items()}


# ----------------------------------------------------------------------------- batch == loop
def test_presets_are_the_documented_ones() -> None:
    assert cost_presets() == ["hrmaga", "length", "length2d", "ppswarm", "spso"]
    assert [(t.name, t.weight) for t in PRESETS["length"]] == [("length", 1.0)]
    assert [(t.name, t.weight) for t in PRESETS["spso"]] == [
        ("length", 5.0), ("threat", 1.0), ("altitude", 10.0), ("smoothness", 1.0)
    ]  # fmt: skip
    assert [(t.name, t.weight) for t in PRESETS["hrmaga"]] == [
        ("length", 1.0), ("terrain_height", 10.0), ("danger", 15.0)
    ]  # fmt: skip


@pytest.mark.parametrize(("scene", "preset"), CASES)
@settings(max_examples=5, deadline=None)
@given(seed=SEEDS, n=st.integers(2, 7))
def test_batch_equals_loop(scenarios, scene: str, preset: str, seed: int, n: int) -> None:
    sc = scenarios[scene]
    problem = PathProblem(sc, cost=preset)
    paths = random_population(sc, np.random.default_rng(seed), 7, n)
    batch = problem.evaluate(paths)
    assert batch.cost.shape == batch.feasible.shape == (7,)
    np.testing.assert_array_equal(problem.cost(paths), batch.cost)
    np.testing.assert_array_equal(problem.feasible(paths), batch.feasible)
    for i in range(7):
        assert_same_evaluation(problem.evaluate(paths[i : i + 1]), _row(batch, i))
        assert_same_evaluation(problem.evaluate(paths[i]), _row(batch, i))  # one (n, dim) path
    row = batch.row(0)
    assert set(row) == {"cost", "terms", "feasible"}
    # the total is the weighted sum of the terms
    total = sum(t.weight * batch.terms[t.name] for t in problem.terms)
    np.testing.assert_allclose(batch.cost, total, rtol=1e-12)


def _row(ev: Evaluation, i: int) -> Evaluation:
    return Evaluation(
        ev.cost[i : i + 1],
        {k: v[i : i + 1] for k, v in ev.terms.items()},
        ev.feasible[i : i + 1],
        {k: v[i : i + 1] for k, v in ev.violations.items()},
    )


def test_encoding_round_trip_and_batch(scenarios) -> None:
    for name in ("rich3d", "flat"):
        sc = scenarios[name]
        enc = CartesianEncoding(PathProblem(sc))
        rng = np.random.default_rng(1)
        X = rng.uniform(enc.lower, enc.upper, (9, enc.dim))
        paths = enc.decode(X)
        assert paths.shape == (9, sc.n_waypoints + 2, sc.dim)
        np.testing.assert_allclose(enc.encode(paths), X, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(enc.evaluate(X), enc.problem.cost(paths))
        assert enc.evaluations == 9
        if name == "rich3d":  # z gene is the height above the (bilinear) ground, inside the band
            g = sc.terrain.height(paths[:, 1:-1, 0], paths[:, 1:-1, 1])
            h = paths[:, 1:-1, 2] - g
            assert np.all((h >= 10.0 - 1e-9) & (h <= 150.0 + 1e-9))


# ----------------------------------------------------------------------------- feasibility
def open_3d(**kw) -> Scenario:
    return Scenario(
        name="open",
        bounds=Bounds((0.0, 0.0, 0.0), (100.0, 100.0, 100.0)),
        tasks=(Task("a", (0.0, 0.0, 20.0), (100.0, 100.0, 20.0)),),
        **kw,
    )


def line(y: float, z0: float = 20.0, z1: float = 20.0) -> np.ndarray:
    return np.array([[0.0, y, z0], [50.0, y, 0.5 * (z0 + z1)], [100.0, y, z1]])


def straight(a, b) -> np.ndarray:
    """A -> B as three collinear nodes."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.stack([a, 0.5 * (a + b), b])


def test_cylinder_feasibility_is_exact() -> None:
    sc = open_3d(cylinders=(Cylinder((50.0, 50.0), 10.0, margin=1.0),), cost="ppswarm")
    pr = PathProblem(sc)
    R = 11.0
    ev = pr.evaluate(np.stack([line(50.0 - R * (1 + REL)), line(50.0 - R * (1 - REL)), line(50.0)]))
    np.testing.assert_array_equal(ev.feasible, [True, False, False])
    np.testing.assert_array_equal(ev.violations["cylinders"], [False, True, True])
    assert np.isfinite(ev.terms["threat"][0]) and ev.terms["threat"][0] > 0  # in the S1 band
    assert np.isinf(ev.terms["threat"][1:]).all()


def test_finite_cylinder_feasibility_uses_its_heights() -> None:
    sc = open_3d(cylinders=(Cylinder((50.0, 50.0), 10.0, z_min=0.0, z_max=30.0, margin=1.0),))
    pr = PathProblem(sc)
    top = 31.0  # z_max + margin
    paths = np.stack(
        [
            line(50.0, top * (1 + REL), top * (1 + REL)),  # just over the top
            line(50.0, top * (1 - REL), top * (1 - REL)),  # just under the top
            # climbing from z = 20 to 60: in the cylinder's heights only for x < 27.5, which is
            # 22.5 m from the axis, then over it
            straight([0.0, 50.0, 20.0], [100.0, 50.0, 60.0]),
            # the same climb 11 (1 - REL) m beside the axis: its low part still ends 25 m away
            straight([0.0, 50.0 - 11.0 * (1 - REL), 20.0], [100.0, 50.0 - 11.0 * (1 - REL), 60.0]),
            # descending through the top near the axis: below z = 31 from x = 54 on
            straight([40.0, 50.0, 80.0], [60.0, 50.0, 10.0]),
        ]
    )
    ev = pr.evaluate(paths)
    np.testing.assert_array_equal(ev.violations["cylinders"], [False, True, False, False, True])


def test_circle_and_polygon_feasibility_2d() -> None:
    star = (
        (50.0, 90.0),
        (55.0, 60.0),
        (90.0, 50.0),
        (55.0, 40.0),
        (50.0, 10.0),
        (45.0, 40.0),
        (10.0, 50.0),
        (45.0, 60.0),
    )
    sc = Scenario(
        name="flat",
        bounds=Bounds((0.0, 0.0), (200.0, 200.0)),
        tasks=(Task("a", (0.0, 0.0), (200.0, 200.0)),),
        circles=(Circle((150.0, 150.0), 10.0, margin=0.5),),
        polygons=(
            Polygon(star),
            Polygon(((150.0, 20.0), (180.0, 20.0), (180.0, 40.0), (150.0, 40.0)), margin=2.0),
        ),
        cost="length2d",
    )
    pr = PathProblem(sc)
    R = 10.5
    paths = [
        [[100.0, 150.0 - R * (1 + REL)], [190.0, 150.0 - R * (1 + REL)]],  # circle: just outside
        [[100.0, 150.0 - R * (1 - REL)], [190.0, 150.0 - R * (1 - REL)]],  # circle: just inside
        [
            [100.0, 40.0 + 2.0 * (1 + REL)],
            [190.0, 40.0 + 2.0 * (1 + REL)],
        ],  # rectangle's margin: out
        [[100.0, 40.0 + 2.0 * (1 - REL)], [190.0, 40.0 + 2.0 * (1 - REL)]],  # in its margin
        [[160.0, 0.0], [160.0, 100.0]],  # through the rectangle
        [[75.0, 75.0], [60.0, 60.0]],  # in the star's notch (its convex hull would block it)
        [[70.0, 70.0], [50.0, 50.0]],  # into the star's centre
        [[100.0, 100.0], [55.0 + 1e-5, 60.0 + 1e-5]],  # towards the notch's vertex, stops short
        [[100.0, 100.0], [55.0, 60.0]],  # touching the notch's vertex
    ]
    ev = pr.evaluate(np.array(paths))
    np.testing.assert_array_equal(ev.violations["circles"], [False, True] + [False] * 7)
    np.testing.assert_array_equal(
        ev.violations["polygons"], [False, False, False, True, True, False, True, False, True]
    )
    np.testing.assert_array_equal(
        ev.feasible, [True, False, True, False, False, True, False, True, False]
    )
    # the length2d cost is the plain length exactly when nothing is inside an obstacle
    L = np.linalg.norm(np.diff(np.array(paths), axis=1), axis=-1)[:, 0]
    free = [0, 2, 3, 5, 7, 8]
    np.testing.assert_allclose(ev.cost[free], L[free], rtol=1e-12)
    assert np.all(ev.cost[[4, 6]] > L[[4, 6]])


def test_uncertain_areas_count_only_when_revealed() -> None:
    base = dict(
        name="u",
        bounds=Bounds((0.0, 0.0), (100.0, 100.0)),
        tasks=(Task("a", (0.0, 50.0), (100.0, 50.0)),),
    )
    path = np.array([[[0.0, 50.0], [100.0, 50.0]]])
    hidden = Scenario(
        **base, uncertain_areas=(UncertainArea(40.0, 40.0, 20.0, 20.0, revealed=False),)
    )
    shown = Scenario(**base, uncertain_areas=(UncertainArea(40.0, 40.0, 20.0, 20.0),))
    assert PathProblem(hidden, cost="length2d").evaluate(path).feasible[0]
    ev = PathProblem(shown, cost="length2d").evaluate(path)
    assert not ev.feasible[0] and ev.violations["polygons"][0]
    assert ev.cost[0] == pytest.approx(100.0 * (1 + 100 * 0.2))


def test_segment_dipping_under_a_ridge_is_infeasible() -> None:
    h = np.zeros((20, 30))
    h[:, 15] = 100.0  # a ridge along x = 15 (bilinear: rises from x = 14 to 15, falls to 16)
    T = Terrain(h)
    sc = Scenario(
        name="ridge",
        bounds=Bounds((0.0, 0.0, 0.0), (29.0, 19.0, 300.0)),
        tasks=(Task("a", (2.0, 10.0, 50.0), (27.0, 10.0, 50.0)),),
        terrain=T,
        altitude=AltitudeBand(10.0, 200.0, "ground"),
    )
    pr = PathProblem(sc, cost="ppswarm")
    paths = np.array(
        [
            [[2.0, 10.0, 50.0], [10.0, 10.0, 90.0], [20.0, 10.0, 90.0], [27.0, 10.0, 50.0]],  # dips
            [
                [2.0, 10.0, 50.0],
                [10.0, 10.0, 150.0],
                [20.0, 10.0, 150.0],
                [27.0, 10.0, 50.0],
            ],  # over
            # over the ridge by 1e-6 relative, at the ridge line itself
            [
                [2.0, 10.0, 50.0],
                [14.0, 10.0, 100.0 * (1 + REL)],
                [16.0, 10.0, 100.0 * (1 + REL)],
                [27.0, 10.0, 50.0],
            ],
            [
                [2.0, 10.0, 50.0],
                [14.0, 10.0, 100.0 * (1 - REL)],
                [16.0, 10.0, 100.0 * (1 - REL)],
                [27.0, 10.0, 50.0],
            ],
        ]
    )
    # every waypoint is well above the ground it stands on
    g = T.height(paths[..., 0], paths[..., 1])
    assert np.all(paths[..., 2] - g >= 10.0)
    ev = pr.evaluate(paths)
    np.testing.assert_array_equal(ev.violations["terrain"], [True, False, False, True])
    np.testing.assert_array_equal(ev.violations["altitude"], [False] * 4)
    np.testing.assert_array_equal(ev.feasible, [False, True, True, False])
    # strict_altitude also asks every point of every segment for the band's 10 m minimum: the
    # path that clears the ridge by 1e-4 m now fails it; the one 50 m over the ridge does not
    strict = PathProblem(sc, cost="ppswarm", strict_altitude=True)
    ev2 = strict.evaluate(paths)
    np.testing.assert_array_equal(ev2.violations["terrain"], [True, False, True, True])


def test_altitude_bounds_and_moving_obstacle_violations() -> None:
    T = Terrain(np.full((11, 11), 10.0), 0.0, 0.0, 10.0, 10.0)
    mover = MovingObstacle(
        5.0, np.array([0.0, 10.0]), np.array([[50.0, 0.0, 40.0], [50.0, 100.0, 40.0]])
    )
    sc = Scenario(
        name="m",
        bounds=Bounds((0.0, 0.0, 0.0), (100.0, 100.0, 200.0)),
        tasks=(Task("a", (0.0, 50.0, 40.0), (100.0, 50.0, 40.0)),),
        terrain=T,
        moving_obstacles=(mover,),
        altitude=AltitudeBand(20.0, 60.0, "ground"),
        uav=UAV(speed=10.0),
    )
    pr = PathProblem(sc, cost="ppswarm")
    straight = np.array([[0.0, 50.0, 40.0], [100.0, 50.0, 40.0]])  # meets the mover at t = 5
    ev = pr.evaluate(straight)
    assert ev.violations["moving"][0] and not ev.feasible[0]
    # a detour south: the UAV crosses x = 50 at t = 10, when the mover is at y = 100
    detour = np.array(
        [[0.0, 50.0, 40.0], [0.0, 0.0, 40.0], [100.0, 0.0, 40.0], [100.0, 50.0, 40.0]]
    )
    assert not pr.evaluate(detour).violations["moving"][0]
    low = np.array(
        [[0.0, 50.0, 40.0], [50.0, 90.0, 25.0], [100.0, 50.0, 40.0]]
    )  # 15 m above ground
    assert pr.evaluate(low).violations["altitude"][0]
    assert np.isinf(pr.evaluate(low).terms["altitude"][0])
    out = np.array([[0.0, 50.0, 40.0], [50.0, 100.0 + 1e-6, 40.0], [100.0, 50.0, 40.0]])
    ev = pr.evaluate(out)
    assert ev.violations["bounds"][0] and not ev.feasible[0]
    edge = np.array([[0.0, 50.0, 40.0], [50.0, 100.0, 40.0], [100.0, 50.0, 40.0]])
    assert not pr.evaluate(edge).violations["bounds"][0]


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "shape",
    [(5, 4, 2), (5, 4, 4), (5, 1, 3), (1, 3), (3,), (2, 5, 4, 3), (0,)],
)
def test_bad_path_shapes_raise(shape) -> None:
    pr = PathProblem(scenario_3d())
    with pytest.raises(ValueError):
        pr.evaluate(np.zeros(shape))
    with pytest.raises(ValueError):
        pr.cost(np.zeros(shape))


def test_bad_presets_and_weights_raise() -> None:
    sc = scenario_3d()
    with pytest.raises(ValueError):
        PathProblem(sc, cost="nope")
    with pytest.raises(ValueError):
        PathProblem(sc, weights={"nope": 1.0})
    pr = PathProblem(sc, cost="ppswarm", weights={"length": 0.0})
    paths = random_population(sc, np.random.default_rng(0), 4, 5)
    base = PathProblem(sc, cost="ppswarm").evaluate(paths)
    ev = pr.evaluate(paths)
    np.testing.assert_allclose(ev.cost, base.cost - 5.0 * base.terms["length"], rtol=1e-9)
    with pytest.raises(ValueError):
        CartesianEncoding(PathProblem(sc), n_waypoints=0)
    with pytest.raises(ValueError):
        CartesianEncoding(PathProblem(sc)).encode(paths)  # 3 free waypoints, needs 4


def test_spso_threat_term_agrees_with_cylinder_feasibility_uniform_margins() -> None:
    sc = open_3d(
        cylinders=(
            Cylinder((50.0, 20.0), 10.0, margin=1.0),
            Cylinder((50.0, 90.0), 5.0, margin=1.0),
        )
    )
    pr = PathProblem(sc, cost="spso")
    ev = pr.evaluate(np.stack([line(20.0 - 11.0 * (1 + REL)), line(20.0 - 11.0 * (1 - REL))]))
    np.testing.assert_array_equal(ev.violations["cylinders"], [False, True])
    assert np.isfinite(ev.terms["threat"][0]) and np.isinf(ev.terms["threat"][1])


def test_spso_threat_term_agrees_with_cylinder_feasibility_mixed_margins() -> None:
    sc = open_3d(
        cylinders=(
            Cylinder((50.0, 20.0), 10.0, margin=0.0),
            Cylinder((50.0, 90.0), 5.0, margin=5.0),
        )
    )
    pr = PathProblem(sc, cost="spso")
    ev = pr.evaluate(line(20.0 - 10.5))  # 10.5 m from the first axis: clear of its 10 m
    assert not ev.violations["cylinders"][0]
    assert np.isfinite(ev.terms["threat"][0])


def test_length_preset_is_the_path_length_and_keeps_feasibility() -> None:
    from uavplan.scenarios import resolve

    sc = resolve("spso")
    plain = PathProblem(sc, cost="length")
    full = PathProblem(sc)
    rng = np.random.default_rng(4)
    lo, hi = sc.bounds.lo, sc.bounds.hi
    inner = rng.uniform(lo, hi, (16, 5, 3))
    t = sc.tasks[0]
    P = np.concatenate(
        [np.broadcast_to(t.start, (16, 1, 3)), inner, np.broadcast_to(t.goal, (16, 1, 3))], axis=1
    )
    a, b = plain.evaluate(P), full.evaluate(P)
    L = np.linalg.norm(np.diff(P, axis=1), axis=2).sum(axis=1)
    np.testing.assert_allclose(a.cost, L, rtol=1e-12)  # violations travel apart from the cost
    assert np.array_equal(a.feasible, b.feasible)  # the preset changes the cost, not the checks


def test_below_with_a_term_s_lower_bound_gives_the_same_answers() -> None:
    """HR-MAGA's terrain term has a cheaper lower bound: ``evaluate_cv(below=...)`` skips the
    exact term for rows whose bounded cost is already not below ``below``, and answers every
    row as without the bound, bit for bit (the skipped ones ``(inf, 1)`` either way); some rows
    are skipped."""
    import dataclasses

    from uavplan.scenarios import resolve

    sc = resolve("hrmaga-spso")
    problem = PathProblem(sc)
    assert any(t.lower is not None for t in problem.terms)
    plain = PathProblem(sc)
    plain.terms = tuple(dataclasses.replace(t, lower=None) for t in plain.terms)
    rng = np.random.default_rng(3)
    lo, hi = np.asarray(sc.bounds.lo), np.asarray(sc.bounds.hi)
    task = sc.tasks[0]
    line = np.linspace(task.start, task.goal, 12)
    paths = np.clip(line + rng.normal(0.0, 1.0, (500, 1, 1)) * rng.normal(0, 40, (500, 12, 3)),
                    lo, hi)  # fmt: skip
    paths[:, 0], paths[:, -1] = task.start, task.goal
    ref_cost = plain._total(plain.validator.batch(paths), checks_too=False)
    for below in (np.full(500, np.inf), ref_cost * rng.uniform(0.98, 1.02, 500),
                  np.full(500, np.median(ref_cost)), np.full(500, -np.inf)):  # fmt: skip
        got = problem.evaluate_cv(paths, exact=False, below=below)
        want = plain.evaluate_cv(paths, exact=False, below=below)
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    kept = problem._maybe_below(problem.validator.batch(paths), np.full(500, np.median(ref_cost)))
    assert kept is not None and 0 < kept.size < 500
