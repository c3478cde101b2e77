"""Replanning in flight: an area revealed within sensor range is repaired from the predicted
state, the flown trajectory keeps the flown part and stays clear of every area."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from uavplan.planners import get_planner
from uavplan.planners.replanning import (
    first_sighting,
    fly_mission,
    position_at,
    prefix,
    revealed_world,
)
from uavplan.problems.path_problem import PathProblem
from uavplan.world.obstacles import UncertainArea

from .test_hr_maga import hills


def test_timed_polyline_helpers() -> None:
    w = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 10.0, 0.0]])
    t = np.array([0.0, 1.0, 3.0])
    assert np.allclose(position_at(w, t, 2.0), [10.0, 5.0, 0.0])
    pw, pt = prefix(w, t, 2.0)
    assert np.allclose(pw, [[0, 0, 0], [10, 0, 0], [10, 5, 0]]) and np.allclose(pt, [0, 1, 2])
    pw, pt = prefix(w, t, 1.0)  # at a waypoint: no duplicate point
    assert len(pw) == 2 and np.allclose(pt, [0, 1])
    a = UncertainArea(20.0, -5.0, 5.0, 10.0, revealed=False)
    # the UAV is within 10.5 m of the area's west edge at x >= 9.5, i.e. t >= 0.95
    seen = first_sighting(w, t, 0.0, {0: a}, 10.5, 0.05)
    assert seen is not None and seen[1] == 0 and seen[0] == pytest.approx(0.95, abs=0.051)
    assert first_sighting(w, t, 0.0, {0: a}, 5.0, 0.05) is None


def _hidden_on_path(sc, plan, size: float = 200.0):
    c = position_at(plan.waypoints, plan.times, 0.5 * plan.times[-1])
    area = UncertainArea(c[0] - size / 2, c[1] - size / 2, size, size, revealed=False)
    return dataclasses.replace(sc, uncertain_areas=(*sc.uncertain_areas, area))


@pytest.mark.parametrize(("seed", "detour"), [(0, True), (2, True), (0, False), (2, False)])
def test_hr_maga_repairs_an_area_revealed_on_its_path(seed: int, detour: bool) -> None:
    sc0 = hills()
    hr = get_planner("hr-maga", repair_detour=detour)
    first = hr.plan(sc0, budget=150, seed=seed)
    sc = _hidden_on_path(sc0, first)
    world = revealed_world(sc)
    assert not PathProblem(world).evaluate(first.waypoints[None]).feasible[0]  # must repair
    m = fly_mission(hr, sc, initial=first, seed=seed, sensor_range=300.0, latency=0.1)
    assert [e.action for e in m.events] == ["repair"]
    e = m.events[0]
    assert e.repaired_feasible and e.compute_time > 0
    assert e.info["how"] == ("detour" if detour else "local repair")
    assert m.feasible and not m.violations
    # what was flown before the repair is the first plan
    t_r = e.time + m.latency
    head, _ = prefix(first.waypoints, first.times, t_r)
    assert np.allclose(m.waypoints[: len(head)], head)
    assert np.all(np.diff(m.times) > 0) and np.allclose(m.waypoints[-1], sc.tasks[0].goal)
    # the flown trajectory avoids the revealed area everywhere (dense samples)
    a = sc.uncertain_areas[-1]
    dense = np.concatenate([np.linspace(p, q, 100) for p, q in itertools.pairwise(m.waypoints)])
    inside = (
        (dense[:, 0] > a.x) & (dense[:, 0] < a.x + a.width)
        & (dense[:, 1] > a.y) & (dense[:, 1] < a.y + a.height)
    )  # fmt: skip
    assert not inside.any()
    # the event came when the area was within range, and the UAV was outside it then
    assert 0 < e.time < first.times[-1]


def test_default_repair_plans_from_scratch_and_a_failed_repair_is_reported() -> None:
    sc0 = hills()
    spso = get_planner("spso", pop_size=30)
    first = spso.plan(sc0, budget=60, seed=0)
    sc = _hidden_on_path(sc0, first)
    m = fly_mission(spso, sc, initial=first, budget=60, seed=0, sensor_range=300.0)
    assert m.events and m.events[0].action == "repair"
    assert m.events[0].info["how"] == "from scratch"
    # SPSO's own cost does not see no-fly areas: its repair may enter the area, and then the
    # mission says so (never feasible while the flown path crosses an area)
    if not m.events[0].repaired_feasible:
        assert not m.feasible and "polygons" in m.violations


def test_sensor_range_must_exceed_the_reaction_distance() -> None:
    sc = hills()  # 20 m/s: 2 m flown during a 0.1 s latency
    with pytest.raises(ValueError, match="sensor range 2 m"):
        fly_mission(get_planner("hr-maga"), sc, budget=10, seed=0, sensor_range=2.0)
