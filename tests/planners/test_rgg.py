"""Random geometric graph candidates (RGG-PSO+ Sect. 4.2.1) and the ``rgg`` planner."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from uavplan.planners import PlannerError, get_planner
from uavplan.planners.sampling.rgg import (
    RGG,
    build_rgg,
    connection_radius,
    prm_star_gamma,
    rgg_candidates,
    rgg_shortest_path,
)
from uavplan.problems import PathProblem
from uavplan.scenarios import load_builtin
from uavplan.world import Bounds, Circle, Polygon, Scenario, Task
from uavplan.world.geometry import cylinder_distances, segment_polygon_distance

from .test_planners import easy_3d


def gap_scene() -> Scenario:
    """A wall with one gap between start and goal, and two discs."""
    return Scenario(
        "gap",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("uav0", (10.0, 10.0), (90.0, 90.0)),),
        circles=(Circle((25.0, 60.0), 8.0), Circle((75.0, 40.0), 8.0)),
        polygons=(
            Polygon(((48.0, 0.0), (52.0, 0.0), (52.0, 70.0), (48.0, 70.0))),
            Polygon(((48.0, 80.0), (52.0, 80.0), (52.0, 100.0), (48.0, 100.0))),
        ),
        cost="length2d",
        n_waypoints=10,
    )


def walled_scene() -> Scenario:
    """A wall across the whole scene: the start cannot reach the goal."""
    return Scenario(
        "walled",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("uav0", (10.0, 50.0), (90.0, 50.0)),),
        polygons=(Polygon(((45.0, -1.0), (55.0, -1.0), (55.0, 101.0), (45.0, 101.0))),),
        cost="length2d",
        n_waypoints=5,
    )


def exact_clear(sc: Scenario, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Segments a -> b clear of every circle and polygon, by the exact kernels directly."""
    seg = np.ascontiguousarray(np.stack([a, b], axis=1))
    ok = np.ones(len(seg), dtype=bool)
    if sc.circles:
        centers = np.array([c.center for c in sc.circles])
        radii = np.array([c.effective_radius for c in sc.circles])
        inf = np.full(len(radii), np.inf)
        d = cylinder_distances(seg, centers, -inf, inf)[:, 0, :]
        ok &= np.all(d >= radii, axis=1)
    verts, starts = sc.packed_polygons()
    if len(starts) > 1:
        d = segment_polygon_distance(seg, verts, starts)[:, 0, :]
        ok &= np.all(d > 0, axis=1)
    return ok


def test_prm_star_constant_and_radius() -> None:
    assert prm_star_gamma(2) == pytest.approx(2 * np.sqrt(1.5 / np.pi))
    assert prm_star_gamma(2) == pytest.approx(1.382, abs=1e-3)
    assert prm_star_gamma(3) == pytest.approx(1.366, abs=1e-3)
    r = connection_radius(100, 2, 100.0 * 100.0, 1.5)
    assert r == pytest.approx(1.5 * np.sqrt(np.log(100) / 100) * 100.0)
    assert connection_radius(400, 2, 1e4) < r  # shrinks as the graph densifies


@pytest.mark.parametrize("make", [lambda: load_builtin("simple2d"), gap_scene])
def test_rgg_edges_collision_free(make) -> None:
    sc = make()
    g = build_rgg(sc, np.random.default_rng(3), n_samples=150)
    a, b = g.nodes[g.edges[:, 0]], g.nodes[g.edges[:, 1]]
    assert len(g.edges) > 50
    assert np.all(exact_clear(sc, a, b))
    assert np.all(g.edges[:, 0] < g.edges[:, 1])
    assert len(np.unique(g.edges, axis=0)) == len(g.edges)
    # every sample is in free space
    for p in g.nodes[2:]:
        assert sc.point_problems(p) == []
    # the check matters: some neighbour pairs within r were rejected, all of them blocked
    pairs = cKDTree(g.nodes).query_pairs(g.radius, output_type="ndarray")
    pairs = pairs[~((pairs[:, 0] == 0) & (pairs[:, 1] == 1))]
    have = {tuple(e) for e in g.edges.tolist()}
    rejected = np.array([p for p in pairs.tolist() if tuple(p) not in have])
    assert len(rejected) > 0
    assert not np.any(exact_clear(sc, g.nodes[rejected[:, 0]], g.nodes[rejected[:, 1]]))


@pytest.mark.parametrize("make", [lambda: load_builtin("simple2d"), gap_scene])
def test_rgg_shortest_path_feasible(make) -> None:
    sc = make()
    path = rgg_shortest_path(sc, np.random.default_rng(0))
    assert path is not None
    assert np.array_equal(path[0], sc.tasks[0].start)
    assert np.array_equal(path[-1], sc.tasks[0].goal)
    ev = PathProblem(sc).evaluate(path[None])
    assert ev.feasible[0]
    assert ev.cost[0] == pytest.approx(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def test_candidates_distinct_sorted_feasible() -> None:
    sc = load_builtin("simple2d")
    c = rgg_candidates(sc, np.random.default_rng(5), n_candidates=6)
    assert 2 <= len(c.paths) <= 6
    keys = {p.tobytes() for p in c.paths}
    assert len(keys) == len(c.paths)
    lengths = [np.linalg.norm(np.diff(p, axis=0), axis=1).sum() for p in c.paths]
    assert lengths == sorted(lengths)
    prob = PathProblem(sc)
    assert all(prob.evaluate(p[None]).feasible[0] for p in c.paths)
    assert c.edge_checks > 0


def test_rgg_3d_nodes_in_band_and_edges_feasible() -> None:
    sc = easy_3d()
    g = build_rgg(sc, np.random.default_rng(2), n_samples=60)
    assert sc.altitude is not None and sc.terrain is not None
    h = g.nodes[2:, 2] - sc.terrain.height(g.nodes[2:, 0], g.nodes[2:, 1])
    assert np.all((h >= sc.altitude.min - 1e-9) & (h <= sc.altitude.max + 1e-9))
    seg = np.stack([g.nodes[g.edges[:, 0]], g.nodes[g.edges[:, 1]]], axis=1)
    assert np.all(PathProblem(sc).evaluate(seg).feasible)
    idx = g.shortest_path()
    assert idx is not None
    assert PathProblem(sc).evaluate(g.path(idx)[None]).feasible[0]


def test_straight_line_when_free() -> None:
    sc = Scenario(
        "free",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("uav0", (10.0, 10.0), (90.0, 80.0)),),
        circles=(Circle((80.0, 20.0), 5.0),),
        cost="length2d",
    )
    path = rgg_shortest_path(sc, np.random.default_rng(0), n_samples=20)
    assert path is not None and len(path) == 2


def test_disconnected_graph() -> None:
    sc = walled_scene()
    assert rgg_shortest_path(sc, np.random.default_rng(0), n_samples=50, max_doublings=1) is None
    assert rgg_candidates(sc, np.random.default_rng(0), n_samples=50, max_doublings=1).paths == []
    r = get_planner("rgg", samples=30).plan(sc, budget=3, seed=0)
    assert not r.feasible
    assert "disconnected" in r.violations
    assert "not connected" in r.info["reason"]
    assert r.first_feasible_iteration is None
    assert np.all(np.isinf(r.history))
    assert len(r.history) == 3


def test_rgg_planner_anytime() -> None:
    sc = load_builtin("simple2d")
    r = get_planner("rgg", samples=50).plan(sc, budget=8, seed=4)
    assert r.feasible and r.iterations == 8 and len(r.evaluations_history) == 8
    assert np.all(np.diff(r.history) <= 0)
    assert r.first_feasible_iteration == 1
    assert r.info["n_samples"] == 400
    assert r.evaluations == r.evaluations_history[-1]
    again = get_planner("rgg", samples=50).plan(sc, budget=8, seed=4)
    assert np.array_equal(r.waypoints, again.waypoints)


def test_rgg_graph_grows_and_keeps_edges() -> None:
    sc = load_builtin("simple2d")
    g = RGG(sc)
    rng = np.random.default_rng(1)
    g.add_samples(50, rng)
    e1, r1 = len(g.edges), g.radius
    first = g.shortest_path()
    g.add_samples(50, rng)
    assert g.n_samples == 100 and g.radius < r1 and len(g.edges) >= e1
    second = g.shortest_path()
    if first is not None and second is not None:
        length = [np.linalg.norm(np.diff(g.path(i), axis=0), axis=1).sum() for i in (first, second)]
        assert length[1] <= length[0] + 1e-9


def test_rgg_bad_parameters() -> None:
    with pytest.raises(PlannerError, match="unknown option"):
        get_planner("rgg", bogus=1)
    with pytest.raises(PlannerError):
        get_planner("rgg", gamma=0.0)


def test_shortest_path_reuses_the_graph_matrix_with_the_same_answers() -> None:
    """The sparse matrix is built once per edge set and its entries reset per search: the same
    distances and predecessors as a matrix built from the weights, for any weights."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    from uavplan.planners.sampling.rgg import build_rgg
    from uavplan.scenarios import resolve

    for i in range(6):
        rng = np.random.default_rng(i)
        g = build_rgg(resolve(f"rgg-n{5 + 2 * i:02d}-i{i:03d}"), rng, n_samples=40)
        n = len(g.nodes)
        for _ in range(4):
            w = g.lengths * rng.uniform(1.0, 3.0, len(g.lengths))
            fresh = csr_matrix((w, (g.edges[:, 0], g.edges[:, 1])), shape=(n, n))
            want = dijkstra(fresh, directed=False, indices=0, return_predecessors=True)
            m, entry_edge = g._csr()
            m.data = w[entry_edge]
            got = dijkstra(m, directed=False, indices=0, return_predecessors=True)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
        assert g._csr()[0] is m  # kept while the graph does not change
        g.add_samples(10, rng)
        assert g._csr()[0] is not m  # rebuilt when it does
