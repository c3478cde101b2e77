"""RRT*'s Numba loop (:func:`uavplan.planners.sampling._rrt_star_kernels.grow`) against the Python
reference (:meth:`RRTStarTree.iterate`): the same tree, node for node, on random 3-D worlds."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from uavplan.planners import get_planner
from uavplan.planners.sampling import _tighten_kernels as T
from uavplan.planners.sampling.rrt_star import RRTStarConfig, RRTStarTree, validity_problem
from uavplan.problems.validity import MotionValidator
from uavplan.scenarios import resolve
from uavplan.world import AltitudeBand, Bounds, Circle, Cylinder, Polygon, Scenario, Task

from .test_planners import easy_3d


def random_world(seed: int, n_cyl: int, band: str | None, n_poly: int = 0) -> Scenario:
    """A 400 x 300 x 200 m box with ``n_cyl`` cylinders (some finite) and ``n_poly`` no-fly
    polygons (some non-convex, some with a margin), start and goal clear."""
    rng = np.random.default_rng(seed)
    cyl = []
    for _ in range(n_cyl):
        c = (float(rng.uniform(60, 340)), float(rng.uniform(0, 300)))
        top = float(rng.uniform(40, 250)) if rng.random() < 0.5 else np.inf
        cyl.append(Cylinder(c, float(rng.uniform(5, 30)), 0.0, top))
    poly = []
    arrow = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 0.3], [0.0, 1.0]])
    for _ in range(n_poly):
        c = np.array([rng.uniform(60, 300), rng.uniform(0, 260)])
        shape = arrow if rng.random() < 0.5 else arrow[[0, 1, 2, 4]]
        v = c + rng.uniform(15, 40) * shape
        poly.append(Polygon(tuple(map(tuple, v)), margin=float(rng.choice([0.0, 4.0]))))
    altitude = None if band is None else AltitudeBand(20.0, 180.0, band)
    return Scenario(
        name="random",
        bounds=Bounds((0.0, 0.0, 0.0), (400.0, 300.0, 200.0)),
        tasks=(Task("u", (10.0, 150.0, 50.0), (390.0, float(rng.uniform(20, 280)), 60.0)),),
        cylinders=tuple(cyl),
        polygons=tuple(poly),
        altitude=altitude,
        cost="length",
    )


def assert_same_tree(a: RRTStarTree, b: RRTStarTree) -> None:
    assert a.n_nodes == b.n_nodes
    assert np.array_equal(a.points, b.points)
    assert np.array_equal(a.parent, b.parent)
    assert np.array_equal(a.cost, b.cost)
    assert a.goal_nodes == b.goal_nodes
    assert (a.iterations, a.rewires, a.rejected, a.found_iteration) == (
        b.iterations,
        b.rewires,
        b.rejected,
        b.found_iteration,
    )
    assert a.informed_bound() == b.informed_bound()


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    n_cyl=st.integers(0, 20),
    n_poly=st.integers(0, 3),
    band=st.sampled_from([None, "absolute"]),
    informed=st.booleans(),
    goal_bias=st.sampled_from([0.0, 0.05, 0.3]),
    step=st.sampled_from([15.0, 50.0, 200.0]),
    stop_at_goal=st.booleans(),
)
def test_numba_loop_builds_the_reference_tree(
    seed: int,
    n_cyl: int,
    n_poly: int,
    band: str | None,
    informed: bool,
    goal_bias: float,
    step: float,
    stop_at_goal: bool,
) -> None:
    sc = random_world(seed, n_cyl, band, n_poly)
    cfg = RRTStarConfig(step=step, informed=informed, goal_bias=goal_bias, goal_radius=step)
    fast = RRTStarTree(sc, None, cfg, np.random.default_rng(seed))
    ref = RRTStarTree(sc, None, cfg, np.random.default_rng(seed), fast=False)
    assert fast.fast and not ref.fast
    fast.run(400, stop_at_goal)
    ref.run(400, stop_at_goal)
    assert_same_tree(fast, ref)
    # the lazy loop checks fewer segments, never more
    assert fast.edge_checks <= ref.edge_checks


def test_numba_loop_on_terrain_with_a_ground_band() -> None:
    sc = resolve("ppswarm1")  # DEM, cylinders, a band above ground: the fused kernel's world
    cfg = RRTStarConfig(informed=True)
    fast = RRTStarTree(sc, None, cfg, np.random.default_rng(3))
    ref = RRTStarTree(sc, None, cfg, np.random.default_rng(3), fast=False)
    assert fast.fast
    fast.run(1500, False)
    ref.run(1500, False)
    assert_same_tree(fast, ref)
    # resumable: in pieces (as the planner calls it) the same as in one go
    parts = RRTStarTree(sc, None, cfg, np.random.default_rng(3))
    for end in (1, 2, 300, 301, 1500):
        parts.advance(end, False, False)
    assert_same_tree(parts, ref)


def test_segment_kernel_where_it_applies() -> None:
    sc = easy_3d()
    v = validity_problem(sc)
    sk = v.segment_kernel
    assert sk is not None
    rng = np.random.default_rng(0)
    lo, hi = sc.bounds.lo, sc.bounds.hi
    seg = lo + rng.random((500, 2, 3)) * (hi - lo)
    kernel, args = sk
    assert np.array_equal(kernel(seg, args), v.paths_valid(seg))
    # no-fly polygons and circles in 3-D: their ground tracks, in the same kernel
    walled = random_world(1, 6, "absolute", n_poly=3)
    walled = Scenario(walled.name, walled.bounds, walled.tasks, cylinders=walled.cylinders,
                      polygons=walled.polygons, circles=(Circle((200, 150), 20),),
                      altitude=walled.altitude)  # fmt: skip
    v = validity_problem(walled)
    assert v.segment_kernel is not None and {"circles", "polygons"} <= set(v.checks())
    kernel, args = v.segment_kernel
    seg = walled.bounds.lo + rng.random((4000, 2, 3)) * (walled.bounds.hi - walled.bounds.lo)
    want = v.paths_valid(seg)
    assert np.array_equal(kernel(seg, args), want) and 0 < want.mean() < 1
    # not where another check must run, nor with the cylinder grid
    flat = Scenario("flat", Bounds((0, 0), (10, 10)), (Task("u", (1, 1), (9, 9)),),
                    circles=(Circle((5, 5), 1),))  # fmt: skip
    assert MotionValidator(flat).segment_kernel is None
    row = tuple(Cylinder((10 + 12 * i, 500), 5) for i in range(70))
    many = Scenario("many", Bounds((0, 0, 0), (1000, 1000, 100)),
                    (Task("u", (1, 1, 1), (9, 9, 9)),), cylinders=row)  # fmt: skip
    assert MotionValidator(many).segment_kernel is None


def test_planner_fast_and_reference_give_the_same_result() -> None:
    sc = random_world(5, 12, None)
    a = get_planner("rrt-star", informed=True).plan(sc, budget=600, seed=4)
    b = get_planner("rrt-star", informed=True, loop="python").plan(sc, budget=600, seed=4)
    assert a.feasible
    assert np.array_equal(a.waypoints, b.waypoints)
    assert np.array_equal(a.history, b.history)
    assert a.info["rrt_iterations"] == b.info["rrt_iterations"] == 600
    assert a.info["edge_checks"] < b.info["edge_checks"]


# ------------------------------------------------------------------------------ tightening
def segment_ok(v: MotionValidator):  # type: ignore[no-untyped-def]
    def ok(a: np.ndarray, b: np.ndarray) -> bool:
        return bool(v.paths_valid(np.stack([a, b])[None])[0])

    return ok


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n_cyl=st.integers(1, 20), spacing=st.sampled_from([7.0, 25.0]))
def test_tightening_kernels_match_their_references(seed: int, n_cyl: int, spacing: float) -> None:
    sc = random_world(seed, n_cyl, None)
    tree = RRTStarTree(sc, None, RRTStarConfig(), np.random.default_rng(seed))
    tree.run(1500, True)
    path = tree.path()
    if path is None:
        return
    v = tree.validator
    sk = v.segment_kernel
    assert sk is not None
    ok = segment_ok(v)
    p = np.ascontiguousarray(path)
    short, _ = T.shortcut(p, sk[1])
    assert np.array_equal(short, T.shortcut_reference(ok, p))
    band, _, _ = T.band(short, spacing, 60, T.TOL, np.asarray(T.SHARES), sk[1])
    ref = T.band_reference(ok, short, spacing, 60, T.TOL)
    assert np.array_equal(band, ref)
    # valid, never longer, the ends kept
    for q in (short, band):
        assert v.paths_valid(q[None])[0]
        assert np.array_equal(q[0], p[0]) and np.array_equal(q[-1], p[-1])
    assert T.length(band) <= T.length(short) + 1e-9 <= T.length(p) + 2e-9


def test_tighten_option_shortens_and_stays_valid() -> None:
    sc = random_world(11, 15, None)
    plain = get_planner("rrt-star", informed=True).plan(sc, budget=1500, seed=2)
    tight = get_planner("rrt-star", informed=True, tighten=True).plan(sc, budget=1500, seed=2)
    assert plain.feasible and tight.feasible
    assert tight.info["tightenings"] >= 1
    assert tight.info["length"] < plain.info["length"]
    again = get_planner("rrt-star", informed=True, tighten=True).plan(sc, budget=1500, seed=2)
    assert np.array_equal(tight.waypoints, again.waypoints)  # deterministic per seed
    # the Python references give the same plan
    slow = get_planner("rrt-star", informed=True, tighten=True, loop="python")
    assert np.array_equal(slow.plan(sc, budget=1500, seed=2).waypoints, tight.waypoints)


def test_distinct_goal_nodes() -> None:
    from uavplan.planners.sampling import _rrt_star_kernels as K

    sc = random_world(3, 12, None)
    tree = RRTStarTree(sc, None, RRTStarConfig(goal_radius=150.0), np.random.default_rng(1))
    tree.run(3000, False)
    assert len(tree.goal_nodes) > 10
    args = (tree.grid.buffer, tree._parent, tree._cost, tree._goal_nodes, len(tree.goal_nodes),
            tree._goal3)  # fmt: skip
    total = {u: tree.cost[u] + np.linalg.norm(tree.points[u] - tree.goal) for u in tree.goal_nodes}
    for k, slack in ((1, 0.0), (4, 0.05), (6, 1.0)):
        nodes = [int(u) for u in K.distinct_goal_nodes(*args, k, slack)]
        assert 1 <= len(nodes) <= k
        assert nodes[0] == tree.best_goal_node()
        tots = [total[u] for u in nodes]
        assert tots == sorted(tots) and tots[-1] <= (1 + slack) * tots[0] + 1e-9
        for i, u in enumerate(nodes):
            path = set(tree.path_indices(u).tolist())
            for v in nodes[:i]:
                idx = tree.path_indices(v)
                mid = int(idx[len(idx) - 1 - (len(idx) - 1) // 2])
                assert mid not in path
