"""RRT* (PPSwarm Alg. 1): the grid index against brute force, the tree, rrt_star, the planner."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from uavplan.planners import PlannerError, get_planner
from uavplan.planners.sampling.grid_index import GridIndex, near_brute, nearest_brute
from uavplan.planners.sampling.rrt_star import (
    RRTStarConfig,
    RRTStarPlanner,
    RRTStarTree,
    rrt_star,
    validity_problem,
)
from uavplan.problems import PathProblem
from uavplan.scenarios import resolve
from uavplan.world import AltitudeBand, Bounds, Cylinder, Scenario, Task

from .test_planners import easy_2d, easy_3d


@pytest.fixture(scope="module")
def spso() -> Scenario:
    return resolve("spso")


def walled_3d() -> Scenario:
    """easy_3d with the goal inside a closed ring of infinitely tall cylinders."""
    sc = easy_3d()
    gx, gy = 150.0, 100.0
    n, ring, rc = 14, 25.0, 8.0  # neighbours overlap: 2 ring sin(pi / n) < 2 rc
    cyl = tuple(
        Cylinder((gx + ring * np.cos(a), gy + ring * np.sin(a)), rc)
        for a in np.linspace(0, 2 * np.pi, n, endpoint=False)
    )
    t = sc.tasks[0]
    goal = (gx, gy, 80.0 + float(sc.ground(gx, gy)))
    return dataclasses.replace(sc, cylinders=cyl, tasks=(Task("uav0", t.start, goal),))


def assert_valid_path(sc: Scenario, path: np.ndarray) -> None:
    t = sc.tasks[0]
    assert np.array_equal(path[0], np.asarray(t.start))
    assert np.array_equal(path[-1], np.asarray(t.goal))  # exactly the goal
    edges = np.stack([path[:-1], path[1:]], axis=1)
    strict = PathProblem(sc, t, cost="ppswarm", strict_altitude=True)
    ev = strict.evaluate(edges)
    assert ev.feasible.all(), {k: v.nonzero() for k, v in ev.violations.items()}
    # and the whole path under the scenario's own preset (spso: nearest-node heights)
    assert PathProblem(sc, t).evaluate(path[None]).feasible[0]


def assert_tree_consistent(tree: RRTStarTree) -> None:
    n = tree.n_nodes
    parent, cost, pts = tree.parent, tree.cost, tree.points
    assert parent[0] == -1 and cost[0] == 0.0
    assert np.all((parent[1:] >= 0) & (parent[1:] < n))
    seg = np.linalg.norm(pts[1:] - pts[parent[1:]], axis=1)
    np.testing.assert_allclose(cost[1:], cost[parent[1:]] + seg, rtol=1e-12, atol=1e-9)
    # no cycles: every node reaches the root within n steps (depth by pointer doubling)
    up = parent.copy()
    up[0] = 0
    for _ in range(int(np.ceil(np.log2(max(n, 2)))) + 1):
        up = up[up]
    assert np.all(up == 0)


# ------------------------------------------------------------------------------ grid index
@pytest.mark.parametrize("dim", [2, 3])
def test_grid_matches_brute_force(dim: int) -> None:
    rng = np.random.default_rng(42)
    lo, hi = np.zeros(dim), np.array([1000.0, 800.0, 300.0][:dim])
    for trial in range(6):
        n = int(rng.integers(1, 400))
        if trial % 2:  # points on a lattice: many exact distance ties
            pts = rng.integers(0, 6, (n, dim)) * (hi / 5)
        else:
            pts = lo + rng.random((n, dim)) * (hi - lo)
        cell = float(rng.choice([7.0, 60.0, 250.0, 5000.0]))
        g = GridIndex(lo, hi, cell, capacity=4)  # grows by doubling
        for p in pts:
            g.add(p)
        assert g.n == n and np.array_equal(g.points, pts)
        g.scan_limit = [np.inf, 1.0][trial % 2]  # rings only / rings or a scan if cheaper
        # queries inside, on the lattice, and outside the box
        qs = np.concatenate(
            [
                lo + rng.random((40, dim)) * (hi - lo),
                pts[rng.integers(0, n, 10)],
                lo - 200 + rng.random((10, dim)) * (hi - lo + 400),
            ]
        )
        for q in qs:
            i, d = g.nearest(q)
            j, e = nearest_brute(pts, q)
            assert (i, d) == (j, e)
            for r in (1.0, 0.5 * cell, cell, 2.5 * cell):
                assert np.array_equal(g.near(q, r), near_brute(pts, q, r))
        g.set_cell(cell / 3)  # rebuilt grid, same answers
        for q in qs[:20]:
            assert g.nearest(q) == nearest_brute(pts, q)
            assert np.array_equal(g.near(q, cell), near_brute(pts, q, cell))


def test_grid_caps_the_cell_count_and_balances() -> None:
    g = GridIndex(np.zeros(3), np.full(3, 1e5), 1.0)
    assert g.n_cells <= 1 << 21 and g.cell > 1.0
    g.add(np.array([5.0, 5.0, 5.0]))
    assert g.nearest(np.array([9e4, 9e4, 9e4]))[0] == 0
    g = GridIndex(np.zeros(3), np.full(3, 1000.0), 1000.0)
    rng = np.random.default_rng(0)
    for p in rng.random((1000, 3)) * 1000:
        g.add(p)
    g.balance(20.0)  # about a point per cell: (1e9 / 1000)^(1/3) = 100 m > r
    assert g.cell == pytest.approx(100.0)
    g.balance(80.0)  # not below half the cell: kept
    assert g.cell == pytest.approx(100.0)
    for q in rng.random((50, 3)) * 1200 - 100:
        assert g.nearest(q) == nearest_brute(g.points, q)


# ------------------------------------------------------------------------------ rrt_star
def test_finds_a_valid_path_on_spso(spso: Scenario) -> None:
    cfg = RRTStarConfig()
    for seed in range(4):
        r = rrt_star(spso, None, cfg, np.random.default_rng(seed))
        assert r.path is not None and r.found_iteration is not None
        assert r.found_iteration == r.iterations <= 3000  # Alg. 1 line 12: break at the goal
        assert r.path.shape[1] == 3 and len(r.path) >= 3
        assert_valid_path(spso, r.path)
        seg = np.linalg.norm(np.diff(r.path, axis=0), axis=1)
        assert r.cost == pytest.approx(seg.sum())
        assert np.all(seg <= max(cfg.near_radius, cfg.goal_radius) + 1e-9)


def test_same_seed_same_path_other_seed_other_path(spso: Scenario) -> None:
    cfg = RRTStarConfig()
    a = rrt_star(spso, None, cfg, np.random.default_rng(5))
    b = rrt_star(spso, None, cfg, np.random.default_rng(5))
    c = rrt_star(spso, None, cfg, np.random.default_rng(6))
    assert a.path is not None and b.path is not None and c.path is not None
    assert np.array_equal(a.path, b.path) and a.iterations == b.iterations
    assert not (a.path.shape == c.path.shape and np.array_equal(a.path, c.path))


def test_samples_in_the_band_above_ground(spso: Scenario) -> None:
    tree = RRTStarTree(spso, None, RRTStarConfig(goal_bias=0.0), np.random.default_rng(0))
    s = np.array([tree.sample() for _ in range(600)])
    assert spso.bounds.contains(s).all()
    h = s[:, 2] - spso.ground(s[:, 0], s[:, 1])
    assert h.min() >= 100.0 - 1e-9 and h.max() <= 200.0 + 1e-9
    assert np.ptp(h) > 90.0


def test_absolute_band_and_2d_sampling() -> None:
    sc = dataclasses.replace(easy_3d(), altitude=AltitudeBand(60.0, 90.0, "absolute"))
    tree = RRTStarTree(sc, None, RRTStarConfig(goal_bias=0.0), np.random.default_rng(0))
    z = np.array([tree.sample() for _ in range(300)])[:, 2]
    assert z.min() >= 60.0 and z.max() <= 90.0
    flat = easy_2d()
    t2 = RRTStarTree(flat, None, RRTStarConfig(step=10.0), np.random.default_rng(0))
    t2.run(300, stop_at_goal=True)
    path = t2.path()
    assert path is not None and path.shape[1] == 2
    assert PathProblem(flat).evaluate(path[None]).feasible[0]


def test_walled_goal_gives_no_path() -> None:
    sc = walled_3d()
    assert sc.point_problems(sc.tasks[0].goal) == []  # the goal itself is free
    cfg = RRTStarConfig(step=20.0, goal_radius=20.0, near_radius=40.0, max_iterations=400)
    r = rrt_star(sc, None, cfg, np.random.default_rng(0))
    assert r.path is None and r.found_iteration is None and r.iterations == 400
    assert r.cost == np.inf and r.n_nodes > 50
    p = get_planner("rrt-star", step=20.0, goal_radius=20.0, near_radius=40.0)
    res = p.plan(sc, budget=200, seed=0)
    assert not res.feasible and "no_path" in res.violations
    assert np.array_equal(res.waypoints, np.array([sc.tasks[0].start, sc.tasks[0].goal]))
    assert res.iterations == 200 and np.all(np.isinf(res.history))
    assert res.first_feasible_iteration is None


def test_tiny_budget_is_honest(spso: Scenario) -> None:
    r = rrt_star(spso, None, RRTStarConfig(), np.random.default_rng(0), max_iterations=3)
    assert r.path is None and r.iterations == 3
    res = get_planner("rrt-star").plan(spso, budget=3, seed=0)
    assert not res.feasible and "no_path" in res.violations


def test_rewiring_keeps_the_tree_consistent(spso: Scenario) -> None:
    cfg = RRTStarConfig(stop_at_goal=False)
    tree = RRTStarTree(spso, None, cfg, np.random.default_rng(3))
    tree.run(1500, stop_at_goal=False)
    assert tree.rewires > 50 and tree.n_nodes > 1000
    assert_tree_consistent(tree)
    # the near radius shrank with n and the grid followed it
    r = tree.radius()
    assert r < cfg.near_radius
    target = max(r, (tree.grid.measure / tree.n_nodes) ** (1 / 3))
    assert target <= tree.grid.cell < 2 * target
    # every tree edge is free
    n = tree.n_nodes
    edges = np.stack([tree.points[tree.parent[1:]], tree.points[1:n]], axis=1)
    assert validity_problem(spso).paths_valid(edges).all()
    path = tree.path()
    assert path is not None
    assert_valid_path(spso, path)


def test_anytime_paths_get_shorter(spso: Scenario) -> None:
    tree = RRTStarTree(spso, None, RRTStarConfig(stop_at_goal=False), np.random.default_rng(1))
    lengths = []
    for _ in range(6):
        tree.run(tree.iterations + 300, stop_at_goal=False)
        p = tree.path()
        if p is not None:
            lengths.append(float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    assert len(lengths) >= 3 and np.all(np.diff(lengths) <= 1e-9)


def test_greedy_shortcut_of_a_tree_path(spso: Scenario) -> None:
    from uavplan.problems.validity import greedy_shortcut

    r = rrt_star(spso, None, RRTStarConfig(), np.random.default_rng(2))
    assert r.path is not None
    problem = validity_problem(spso)
    s = greedy_shortcut(problem, r.path)[0]
    assert len(s) <= len(r.path)
    assert_valid_path(spso, s)
    length = float(np.sum(np.linalg.norm(np.diff(s, axis=0), axis=1)))
    assert length <= r.cost + 1e-9
    rs = rrt_star(spso, None, RRTStarConfig(shortcut=True), np.random.default_rng(2))
    assert rs.path is not None and np.array_equal(rs.path, s) and rs.cost == pytest.approx(length)


# ------------------------------------------------------------------------------ planner
def test_planner_on_spso(spso: Scenario) -> None:
    res = get_planner("rrt-star").plan(spso, budget=400, seed=0)
    assert res.feasible and res.algorithm == "rrt-star" and res.cost_model == "spso"
    assert_valid_path(spso, res.waypoints)
    ev = PathProblem(spso).evaluate(res.waypoints[None])
    assert res.cost == pytest.approx(ev.cost[0])
    assert res.iterations == 400 == len(res.history) == len(res.evaluations_history)
    run = res.info
    assert run["rrt_iterations"] == 400 and res.evaluations == run["edge_checks"]
    assert res.first_feasible_iteration == run["found_iteration"]
    h = res.history
    assert np.all(np.isinf(h[: res.first_feasible_iteration - 1]))
    fin = h[np.isfinite(h)]
    assert fin[-1] == pytest.approx(res.cost) and np.all(np.diff(fin) <= 0)
    assert np.all(np.diff(res.evaluations_history) >= 0)


def test_planner_stop_at_goal_and_iterations(spso: Scenario) -> None:
    a = get_planner("rrt-star", stop_at_goal=True).plan(spso, seed=4)
    r = rrt_star(spso, None, RRTStarConfig(), np.random.default_rng(np.random.SeedSequence(4)))
    assert a.feasible and a.iterations == r.found_iteration
    assert r.path is not None and np.array_equal(a.waypoints, r.path)
    b = get_planner("rrt-star").plan(spso, budget=200, seed=4)  # one RRT* iteration each
    assert b.iterations == 200 and b.info["rrt_iterations"] == 200
    c = get_planner("rrt-star", max_iterations=150).plan(spso, seed=4)  # the default budget
    assert c.iterations == 150


def test_planner_parameters() -> None:
    p = get_planner("rrt-star", step=30.0)
    assert isinstance(p, RRTStarPlanner) and p.config.step == 30.0
    assert p.config.stop_at_goal is False  # the planner is anytime by default
    assert p.describe()["step"] == 30.0
    with pytest.raises(PlannerError, match="unknown option"):
        get_planner("rrt-star", bogus=1)
    with pytest.raises(PlannerError, match="step"):
        get_planner("rrt-star", step=-1.0)
    with pytest.raises(PlannerError, match="goal_bias"):
        RRTStarConfig(goal_bias=1.0)
    bounds = Bounds((0.0, 0.0, 0.0), (10.0, 10.0, 10.0))
    sc = Scenario(
        "bad", bounds, (Task("u", (1, 1, 1), (9, 9, 1)),), altitude=AltitudeBand(20, 30, "absolute")
    )
    with pytest.raises(PlannerError, match="band"):
        get_planner("rrt-star").plan(sc, budget=5, seed=0)


def test_informed_samples_stay_where_a_shorter_path_can_pass(spso: Scenario) -> None:
    cfg = RRTStarConfig(informed=True, goal_bias=0.0)
    tree = RRTStarTree(spso, None, cfg, np.random.default_rng(1))
    while not tree.goal_nodes:
        tree.iterate()
    c = tree.informed_bound()
    path = tree.path()
    assert path is not None
    assert c == pytest.approx(float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()))
    s = np.array([tree.sample() for _ in range(300)])
    focal = np.linalg.norm(s - tree.start, axis=1) + np.linalg.norm(s - tree.goal, axis=1)
    assert (focal < c).all() and tree.rejected > 0
    h = s[:, 2] - spso.ground(s[:, 0], s[:, 1])  # still the sampler's region: the band
    assert h.min() >= 100.0 - 1e-9 and h.max() <= 200.0 + 1e-9
    # off by default: the same seed draws the same samples as before
    plain = RRTStarTree(spso, None, RRTStarConfig(goal_bias=0.0), np.random.default_rng(1))
    again = RRTStarTree(spso, None, RRTStarConfig(goal_bias=0.0), np.random.default_rng(1))
    for _ in range(50):
        plain.iterate()
        again.iterate()
    assert plain.rejected == 0 and np.array_equal(plain.points, again.points)


def test_a_time_budget_alone_sets_no_iteration_limit() -> None:
    from uavplan.optimizers.base import Budget

    p = RRTStarPlanner()
    assert p.iteration_limit(Budget(max_time=1.0)) is None
    assert p.iteration_limit(Budget(max_time=1.0, max_iterations=7)) == 7
    assert p.iteration_limit(Budget(max_evaluations=100)) == p.config.max_iterations
