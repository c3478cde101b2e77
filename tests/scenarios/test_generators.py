"""The RGG-PSO+ scene family: determinism, the paper's conditions, references, export."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from uavplan.io.scenario_file import load_scenario
from uavplan.problems.path_problem import PathProblem
from uavplan.scenarios.generators import (
    CLEARANCE,
    GAP,
    GOAL_BOX,
    MIN_DETOUR,
    REFERENCES_CSV,
    SETTINGS,
    START_BOX,
    export_family,
    family_names,
    load_family,
    read_references,
    rgg_family,
    rgg_name,
    rgg_scenario,
)
from uavplan.world import Circle, Polygon, Scenario
from uavplan.world.geometry import cylinder_distances, segment_polygon_distance
from uavplan.world.visibility import shortest_path

CASES = [(5, 0), (5, 1), (9, 4), (12, 7), (14, 0), (14, 3)]


@pytest.fixture(scope="module")
def scenes() -> dict[tuple[int, int], Scenario]:
    return {(n, i): rgg_scenario(n, i) for n, i in CASES}


def geometry(sc: Scenario):
    return (sc.tasks[0].start, sc.tasks[0].goal, sc.circles, sc.polygons)


def closed(poly: Polygon) -> np.ndarray:
    v = poly.array
    return np.concatenate([v, v[:1]])[None]


def obstacle_distance(a: Circle | Polygon, b: Circle | Polygon) -> float:
    """Exact distance between two disjoint obstacles."""
    if isinstance(a, Circle) and isinstance(b, Circle):
        return math.dist(a.center, b.center) - a.radius - b.radius
    if isinstance(a, Circle):
        a, b = b, a
    assert isinstance(a, Polygon)
    if isinstance(b, Circle):
        c = np.array([b.center])
        d = cylinder_distances(closed(a), c, np.array([-np.inf]), np.array([np.inf]))
        inside = bool(a.contains(c)[0])
        return -1.0 if inside else float(d.min()) - b.radius
    # polygon-polygon: edges of each against the other (0 if either has a vertex in the other)
    return float(min(_edges_to_polygon(a, b), _edges_to_polygon(b, a)))


def _edges_to_polygon(a: Polygon, b: Polygon) -> float:
    starts = np.array([0, len(b.vertices)], dtype=np.int64)
    return float(segment_polygon_distance(closed(a), b.array, starts).min())


def poly_is_convex(p: Polygon) -> bool:
    v = p.array
    e = np.roll(v, -1, axis=0) - v
    f = np.roll(e, -1, axis=0)
    turn = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    return bool(np.all(turn > 0) or np.all(turn < 0))


# ---------------------------------------------------------------------------- family layout
def test_settings_and_names():
    assert tuple(range(5, 15)) == SETTINGS
    assert len(SETTINGS) == 10
    names = family_names()
    assert len(names) == 1000 == len(set(names))
    assert names[0] == "rgg-n05-i000" and names[-1] == "rgg-n14-i099"
    assert rgg_name(7, 42) == "rgg-n07-i042"
    assert family_names(per_setting=2, settings=(5, 6)) == [
        "rgg-n05-i000",
        "rgg-n05-i001",
        "rgg-n06-i000",
        "rgg-n06-i001",
    ]


def test_family_matches_single_scenes(scenes):
    fam = list(rgg_family(per_setting=2, settings=(5,)))
    assert [s.name for s in fam] == ["rgg-n05-i000", "rgg-n05-i001"]
    for s in fam:
        ref = scenes[(5, int(s.metadata["index"]))]
        assert geometry(s) == geometry(ref)


# ---------------------------------------------------------------------------- determinism
def test_deterministic_and_different(scenes):
    again = rgg_scenario(9, 4)
    ref = scenes[(9, 4)]
    assert geometry(again) == geometry(ref)
    assert again.metadata["reference_length"] == ref.metadata["reference_length"]
    assert again.metadata["reference_path"] == ref.metadata["reference_path"]
    assert geometry(scenes[(5, 0)]) != geometry(scenes[(5, 1)])
    assert geometry(scenes[(14, 0)]) != geometry(scenes[(14, 3)])
    assert geometry(rgg_scenario(5, 0, root_seed=1)) != geometry(scenes[(5, 0)])


# ---------------------------------------------------------------------------- the paper's rules
@pytest.mark.parametrize(("n", "i"), CASES)
def test_scene_rules(scenes, n, i):
    sc = scenes[(n, i)]
    m = sc.metadata
    assert sc.name == rgg_name(n, i)
    assert sc.dim == 2 and sc.bounds.lower == (0.0, 0.0) and sc.bounds.upper == (100.0, 100.0)
    assert sc.cost == "length2d" and sc.n_waypoints == 20
    obstacles = [*sc.circles, *sc.polygons]
    assert len(obstacles) == n == m["n_obstacles"]
    assert len(sc.circles) == m["n_circles"]
    assert m["n_convex"] + m["n_nonconvex"] == len(sc.polygons)
    assert sum(poly_is_convex(p) for p in sc.polygons) == m["n_convex"]
    start, goal = np.array(sc.tasks[0].start), np.array(sc.tasks[0].goal)
    assert np.all((start >= START_BOX[0]) & (start <= START_BOX[1]))
    assert np.all((goal >= GOAL_BOX[0]) & (goal <= GOAL_BOX[1]))
    # start and goal outside every obstacle, with the clearance
    assert sc.point_problems(start) == [] and sc.point_problems(goal) == []
    for point in (start, goal):
        for ob in obstacles:
            probe = Circle(tuple(point), 1e-9)
            assert obstacle_distance(ob, probe) >= CLEARANCE - 1e-2
    # obstacles inside the box, apart from each other
    for ob in obstacles:
        pts = np.array(ob.vertices) if isinstance(ob, Polygon) else None
        if pts is None:
            assert isinstance(ob, Circle)
            lo = np.array(ob.center) - ob.radius
            hi = np.array(ob.center) + ob.radius
        else:
            lo, hi = pts.min(axis=0), pts.max(axis=0)
        assert np.all(lo >= GAP - 1e-3) and np.all(hi <= 100.0 - GAP + 1e-3)
    for a, b in combinations(obstacles, 2):
        assert obstacle_distance(a, b) >= GAP - 1e-2
    # the straight segment is blocked; the reference path is feasible and a real detour
    problem = PathProblem(sc)
    assert not problem.evaluate(np.stack([start, goal])[None]).feasible[0]
    path = np.array(m["reference_path"])
    assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal)
    assert problem.evaluate(path[None]).feasible[0]
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    assert m["reference_length"] == pytest.approx(length, abs=1e-12)
    assert m["reference_length"] >= np.linalg.norm(goal - start) + MIN_DETOUR


def test_kinds_are_mixed(scenes):
    kinds = [k for sc in scenes.values() for k in sc.metadata["kinds"]]
    assert {"circle", "convex", "nonconvex"} <= set(kinds)


@pytest.mark.parametrize(("n", "i"), [(5, 1), (14, 3)])
def test_reference_beats_a_random_geometric_graph(scenes, n, i):
    """A PRM/RGG over 400 random free points (checked by PathProblem) is never shorter."""
    sc = scenes[(n, i)]
    problem = PathProblem(sc)
    rng = np.random.default_rng(11)
    pts = rng.uniform(0.0, 100.0, (1500, 2))
    free = np.array([not sc.point_problems(p) for p in pts])
    pts = pts[free][:400]
    nodes = np.vstack([sc.tasks[0].start, sc.tasks[0].goal, pts])
    a, b = np.triu_indices(len(nodes), 1)
    ok = problem.evaluate(np.stack([nodes[a], nodes[b]], axis=1)).feasible
    a, b = a[ok], b[ok]
    w = np.linalg.norm(nodes[a] - nodes[b], axis=1)
    g = coo_matrix((w, (a, b)), shape=(len(nodes),) * 2).tocsr()
    dist = dijkstra(g, directed=False, indices=0)
    assert np.isfinite(dist[1])
    assert sc.metadata["reference_length"] <= dist[1]


def test_reference_is_close_to_a_finer_circle_approximation(scenes):
    sc = scenes[(14, 0)]
    fine, _ = shortest_path(sc, circle_sides=256)
    ref = sc.metadata["reference_length"]
    # both are within their factor above the exact length, which neither undercuts
    assert fine <= ref / math.cos(math.pi / 256) * (1 + 1e-8)
    assert ref <= fine / math.cos(math.pi / 64) * (1 + 1e-8)


def test_bad_arguments():
    with pytest.raises(ValueError):
        rgg_scenario(0, 0)
    with pytest.raises(ValueError):
        rgg_scenario(5, -1)


# ---------------------------------------------------------------------------- export
def test_export_round_trip(tmp_path, scenes):
    files = export_family(tmp_path, per_setting=1, root_seed=0, settings=(5, 14))
    assert [f.name for f in files] == ["rgg-n05-i000.yaml", "rgg-n14-i000.yaml"]
    assert (tmp_path / REFERENCES_CSV).exists()
    refs = read_references(tmp_path)
    assert list(refs) == ["rgg-n05-i000", "rgg-n14-i000"]
    for f, key in zip(files, [(5, 0), (14, 0)], strict=True):
        orig = scenes[key]
        loaded = load_scenario(f)
        assert geometry(loaded) == geometry(orig)
        assert loaded.cost == "length2d" and loaded.n_waypoints == 20
        row = refs[orig.name]
        assert row["n_obstacles"] == key[0] and row["index"] == key[1] and row["root_seed"] == 0
        assert row["reference_length"] == orig.metadata["reference_length"]
        assert row["reference_path"] == orig.metadata["reference_path"]
        # the file holds exactly the scene the reference was computed for
        assert shortest_path(loaded)[0] == row["reference_length"]
        path = np.array(row["reference_path"])
        assert PathProblem(loaded).evaluate(path[None]).feasible[0]
    loaded_all = list(load_family(tmp_path))
    assert [s.name for s in loaded_all] == ["rgg-n05-i000", "rgg-n14-i000"]
    assert (
        loaded_all[1].metadata["reference_length"] == scenes[(14, 0)].metadata["reference_length"]
    )
