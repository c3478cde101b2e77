"""Visibility-graph reference paths against hand-computed shortest paths."""

from __future__ import annotations

import math

import numpy as np
import pytest

import uavplan.world.visibility as vis
from uavplan.problems.path_problem import PathProblem
from uavplan.world import Bounds, Circle, Polygon, Scenario, Task
from uavplan.world.visibility import shortest_path

BOX = Bounds((0.0, 0.0), (100.0, 100.0))
SQUARE = Polygon(((40, 40), (60, 40), (60, 60), (40, 60)))
# a cup open at the top: outer [30, 70]^2, pocket [40, 60] x [40, 70]
CUP = Polygon(((30, 30), (70, 30), (70, 70), (60, 70), (60, 40), (40, 40), (40, 70), (30, 70)))


def scene(start, goal, circles=(), polygons=(), bounds=BOX) -> Scenario:
    return Scenario(
        "t",
        bounds,
        (Task("uav0", start, goal),),
        circles=tuple(circles),
        polygons=tuple(polygons),
        cost="length2d",
    )


def feasible(sc: Scenario, path: np.ndarray) -> bool:
    return bool(PathProblem(sc).evaluate(path[None]).feasible[0])


def path_length(path: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def tangent_arc_length(s, g, c, r) -> float:
    """Exact shortest path from s to g around one disc (both outside it)."""
    s, g, c = (np.asarray(v, dtype=float) for v in (s, g, c))
    d1 = float(np.linalg.norm(s - c))
    d2 = float(np.linalg.norm(g - c))
    ab = g - s
    t = float(np.clip(np.dot(c - s, ab) / np.dot(ab, ab), 0.0, 1.0))
    if np.linalg.norm(s + t * ab - c) >= r:
        return float(np.linalg.norm(ab))
    theta = math.acos(float(np.dot(s - c, g - c)) / (d1 * d2))
    phi = theta - math.acos(r / d1) - math.acos(r / d2)
    return math.sqrt(d1 * d1 - r * r) + math.sqrt(d2 * d2 - r * r) + r * phi


def test_square_around_two_corners():
    sc = scene((50.0, 10.0), (50.0, 90.0), polygons=[SQUARE])
    length, path = shortest_path(sc)
    hand = 2.0 * math.hypot(10.0, 30.0) + 20.0  # (50,10) -> (40,40) -> (40,60) -> (50,90)
    assert length == pytest.approx(hand, abs=1e-6)
    assert length >= hand  # nodes sit delta outside the corners
    assert path.shape == (4, 2)
    assert np.allclose(path[1:3, 1], [40.0, 60.0], atol=1e-6)
    assert np.allclose(path[1:3, 0], path[1, 0], atol=1e-6)  # both on one side
    assert length == pytest.approx(path_length(path), abs=1e-12)
    assert feasible(sc, path)  # the edge along the square's side is not "touching"


def test_clockwise_polygon_gives_the_same_answer():
    cw = Polygon(tuple(reversed(SQUARE.vertices)))
    a, _ = shortest_path(scene((50.0, 10.0), (50.0, 90.0), polygons=[SQUARE]))
    b, _ = shortest_path(scene((50.0, 10.0), (50.0, 90.0), polygons=[cw]))
    assert a == pytest.approx(b, abs=1e-12)


def test_non_convex_cup_start_in_the_pocket():
    sc = scene((50.0, 45.0), (50.0, 10.0), polygons=[CUP])
    length, path = shortest_path(sc)
    # out of the pocket over a tip, along the arm's top, down the outside, to the goal
    hand = math.hypot(10.0, 25.0) + 10.0 + 40.0 + math.hypot(20.0, 20.0)
    assert length == pytest.approx(hand, abs=1e-6)
    assert len(path) == 5
    assert feasible(sc, path)


@pytest.mark.parametrize("m", [8, 16, 64])
def test_single_circle_within_the_circumscribed_bound(m):
    s, g, c, r = (10.0, 47.0), (93.0, 55.0), (50.0, 50.0), 20.0
    sc = scene(s, g, circles=[Circle(c, r)])
    length, path = shortest_path(sc, circle_sides=m)
    exact = tangent_arc_length(s, g, c, r)
    assert exact < math.dist(s, g) + 10  # sanity: it is a detour, not a huge one
    assert exact <= length <= exact / math.cos(math.pi / m) * (1 + 1e-8)
    assert feasible(sc, path)
    assert np.all(np.linalg.norm(path - np.asarray(c), axis=1) >= r)


def test_circle_converges_to_the_tangent_arc_path():
    s, g, c, r = (10.0, 50.0), (90.0, 50.0), (50.0, 50.0), 20.0
    sc = scene(s, g, circles=[Circle(c, r)])
    exact = tangent_arc_length(s, g, c, r)
    length, path = shortest_path(sc, circle_sides=1024)
    assert length == pytest.approx(exact, rel=2e-6)
    assert feasible(sc, path)


def test_circle_margin_counts():
    s, g = (10.0, 50.0), (90.0, 50.0)
    bare, _ = shortest_path(scene(s, g, circles=[Circle((50, 50), 18.0)]), circle_sides=256)
    wide, path = shortest_path(scene(s, g, circles=[Circle((50, 50), 15.0, margin=3.0)]), 256)
    assert wide == pytest.approx(bare, abs=1e-9)
    assert feasible(scene(s, g, circles=[Circle((50, 50), 15.0, margin=3.0)]), path)


def test_clear_segment_is_the_answer():
    sc = scene((5.0, 5.0), (95.0, 20.0), circles=[Circle((50, 60), 10)], polygons=[SQUARE])
    length, path = shortest_path(sc)
    assert length == pytest.approx(math.hypot(90.0, 15.0), abs=1e-12)
    assert np.array_equal(path, [[5.0, 5.0], [95.0, 20.0]])


def test_mixed_scene_paths_are_feasible_and_beat_detours():
    sc = scene(
        (5.0, 5.0),
        (95.0, 95.0),
        circles=[Circle((25, 30), 10), Circle((50, 50), 12), Circle((78, 25), 9)],
        polygons=[Polygon(((60, 62), (88, 62), (88, 90), (78, 90), (78, 72), (60, 72)))],
    )
    length, path = shortest_path(sc)
    assert np.isfinite(length)
    assert feasible(sc, path)
    assert not feasible(sc, np.array([[5.0, 5.0], [95.0, 95.0]]))
    # any feasible perturbation of the path is no shorter (up to the circle factor)
    rng = np.random.default_rng(3)
    trial = np.repeat(path[None], 400, axis=0)
    trial[:, 1:-1] += rng.normal(0.0, 1.0, trial[:, 1:-1].shape)
    ok = PathProblem(sc).evaluate(trial).feasible
    assert ok.any()
    lengths = np.linalg.norm(np.diff(trial[ok], axis=1), axis=2).sum(axis=1)
    assert np.all(lengths >= length * math.cos(math.pi / 64))


def test_bitangent_pruning_loses_nothing_with_polygons(monkeypatch):
    polys = [
        SQUARE,
        Polygon(((10, 60), (25, 55), (20, 70), (30, 85), (12, 80))),
        Polygon(((70, 10), (90, 20), (80, 25), (85, 40), (65, 30))),
    ]
    sc = scene((5.0, 50.0), (95.0, 60.0), polygons=polys)
    pruned, _ = shortest_path(sc)
    monkeypatch.setattr(vis, "_tangent_ok", lambda frames, d: np.ones(len(d), dtype=bool))
    full, _ = shortest_path(sc)
    assert pruned == pytest.approx(full, abs=1e-12)


def test_no_path_gives_inf_and_empty():
    wall = Polygon(((-10, 45), (110, 45), (110, 55), (-10, 55)))
    length, path = shortest_path(scene((50.0, 10.0), (50.0, 90.0), polygons=[wall]))
    assert length == math.inf
    assert path.shape == (0, 2)
    # the start inside an obstacle, or outside the bounds
    assert shortest_path(scene((50.0, 50.0), (50.0, 90.0), polygons=[SQUARE]))[0] == math.inf
    inside = scene((50.0, 50.0), (50.0, 90.0), circles=[Circle((50, 50), 5)])
    assert shortest_path(inside)[0] == math.inf
    assert shortest_path(scene((150.0, 10.0), (50.0, 90.0)))[0] == math.inf


def test_unsupported_scenes():
    sc3 = Scenario(
        "t",
        Bounds((0.0, 0.0, 0.0), (10.0, 10.0, 10.0)),
        (Task("uav0", (1.0, 1.0, 1.0), (9.0, 9.0, 9.0)),),
    )
    with pytest.raises(ValueError, match="2-D"):
        shortest_path(sc3)
    margin = Polygon(SQUARE.vertices, margin=1.0)
    with pytest.raises(ValueError, match="margin"):
        shortest_path(scene((50.0, 10.0), (50.0, 90.0), polygons=[margin]))
