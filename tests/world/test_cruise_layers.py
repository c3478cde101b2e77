"""Cruise altitude layers by heading (:mod:`uavplan.world.cruise_layers`) and what they do to
PPSwarm's altitude cost and to a fleet's plan."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from uavplan.planners import get_planner
from uavplan.problems.path_problem import PathProblem
from uavplan.world import AltitudeBand, Scenario, Task
from uavplan.world.cruise_layers import course, layer_heights, layered, sector
from uavplan.world.scenario import Bounds


def _task(dx: float, dy: float) -> Task:
    return Task("u", (500.0, 500.0, 150.0), (500.0 + dx, 500.0 + dy, 150.0))


def test_layers_split_the_band_evenly() -> None:
    band = AltitudeBand(100.0, 200.0, "ground")
    np.testing.assert_allclose(layer_heights(band, 1), [150.0])
    np.testing.assert_allclose(layer_heights(band, 4), [112.5, 137.5, 162.5, 187.5])
    with pytest.raises(ValueError, match="layers"):
        layer_heights(band, 0)


@pytest.mark.parametrize(
    ("dx", "dy", "deg", "of2", "of4"),
    [(0, 1, 0, 0, 0), (1, 0, 90, 0, 1), (0, -1, 180, 1, 2), (-1, 0, 270, 1, 3),
     (1, 1, 45, 0, 0), (-1e-9, 1, 360 - 5.7e-8, 1, 3), (0, 0, 0, 0, 0)],
)  # fmt: skip
def test_courses_fall_in_sectors_clockwise_from_north(
    dx: float, dy: float, deg: float, of2: int, of4: int
) -> None:
    t = _task(dx, dy)
    assert course(t) == pytest.approx(deg, abs=1e-6)
    assert 0.0 <= course(t) < 360.0
    assert (sector(t, 2), sector(t, 4)) == (of2, of4)


def test_opposite_courses_get_different_layers_and_one_layer_changes_nothing() -> None:
    band = AltitudeBand(100.0, 200.0, "ground")
    east, west = _task(100, 0), _task(-100, 0)
    a, b = layered((east, west), band, 2)
    assert (a.cruise, b.cruise) == (125.0, 175.0)
    assert layered((east, west), band, 1) == (east, west)
    assert layered((east, west), None, 2) == (east, west)


def _crossing() -> Scenario:
    """Two UAVs crossing a flat, empty 1 km box head on, a band of 50-150 m."""
    tasks = (Task("east", (100.0, 500.0, 100.0), (900.0, 500.0, 100.0)),
             Task("west", (900.0, 520.0, 100.0), (100.0, 520.0, 100.0)))  # fmt: skip
    return Scenario("crossing", Bounds((0.0, 0.0, 0.0), (1000.0, 1000.0, 200.0)), tasks,
                    altitude=AltitudeBand(50.0, 150.0, "absolute"), cost="ppswarm",
                    n_waypoints=5)  # fmt: skip


def test_the_altitude_cost_pulls_toward_the_cruise_layer() -> None:
    sc = _crossing()
    path = np.array([[[100.0, 500, 100], [500, 500, 75], [900, 500, 100]]])
    mid = PathProblem(sc, "east").evaluate(path).terms["altitude"][0]
    low = dataclasses.replace(sc.tasks[0], cruise=75.0)
    lay = PathProblem(sc, low).evaluate(path).terms["altitude"][0]
    assert mid == pytest.approx(25.0)  # |75 - 100| at the middle node, the ends at 100
    assert lay == pytest.approx(50.0)  # |100 - 75| at both ends


def test_a_fleet_planned_in_layers_cruises_in_them() -> None:
    sc = _crossing()
    heights = {}
    for k in (1, 2):
        planner = get_planner("ppswarm", pop_size=40, n_iter=15, n_restart=1, layers=k,
                              rrt_iterations=400)  # fmt: skip
        fr = planner.plan_fleet(sc, None, 0)
        heights[k] = {r.uav_id: float(np.median(r.waypoints[1:-1, 2])) for r in fr.results}
    # one layer: both near the band's middle (100 m); two: eastbound low (75), westbound high
    assert abs(heights[1]["east"] - heights[1]["west"]) < 15.0
    assert heights[2]["east"] < 90.0 < 110.0 < heights[2]["west"]
