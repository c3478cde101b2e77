"""Contract tests over every registered planner, and the PlanResult record."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.planners import PlannerError, PlanResult, available_planners, get_planner
from uavplan.problems import PathProblem
from uavplan.world import UAV, AltitudeBand, Bounds, Circle, Cylinder, Scenario, Task, Terrain


def easy_2d() -> Scenario:
    """One disc between start and goal: any decent planner goes around it."""
    return Scenario(
        "easy2d",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("uav0", (10.0, 50.0), (90.0, 50.0)),),
        circles=(Circle((50.0, 50.0), 10.0),),
        cost="length2d",
        n_waypoints=3,
    )


def easy_3d() -> Scenario:
    """A gentle slope, one cylinder, a band above ground."""
    x = np.arange(0, 201, 10.0)
    H = np.tile(x * 0.2, (21, 1))
    t = Terrain(H, 0.0, 0.0, 10.0, 10.0, "slope")
    s = (20.0, 100.0, 80.0 + t.height(20.0, 100.0))
    g = (180.0, 100.0, 80.0 + t.height(180.0, 100.0))
    return Scenario(
        "easy3d",
        Bounds((0.0, 0.0, 0.0), (200.0, 200.0, 300.0)),
        (Task("uav0", s, g),),
        terrain=t,
        cylinders=(Cylinder((100.0, 100.0), 20.0),),
        altitude=AltitudeBand(50.0, 120.0, "ground"),
        uav=UAV(speed=10.0, s1=5.0),
        cost="ppswarm",
        n_waypoints=3,
    )


PLANNERS = available_planners()


@pytest.mark.parametrize("name", PLANNERS)
@pytest.mark.parametrize("make", [easy_2d, easy_3d], ids=["2d", "3d"])
def test_planner_solves_easy_scenario(name: str, make) -> None:
    sc = make()
    planner = get_planner(name, pop_size=40)
    if sc.dim not in planner.dims:
        with pytest.raises(PlannerError, match=f"{sc.dim}-D"):
            planner.plan(sc, budget=60, seed=1)
        return
    r = planner.plan(sc, budget=60, seed=1)
    assert isinstance(r, PlanResult)
    assert r.feasible, (name, r.violations, r.cost)
    assert np.isfinite(r.cost)
    assert np.allclose(r.waypoints[0], sc.tasks[0].start)
    assert np.allclose(r.waypoints[-1], sc.tasks[0].goal)
    straight = np.linalg.norm(np.subtract(sc.tasks[0].goal, sc.tasks[0].start))
    assert r.length >= straight - 1e-9
    # the reported cost and flag agree with a fresh evaluation of the returned path
    ev = PathProblem(sc).evaluate(r.waypoints[None])
    assert ev.cost[0] == pytest.approx(r.cost)
    assert bool(ev.feasible[0]) == r.feasible
    # times at the UAV's speed
    seg = np.linalg.norm(np.diff(r.waypoints, axis=0), axis=1)
    assert np.allclose(np.diff(r.times), seg / sc.uav.speed)
    assert r.evaluations > 0 and r.iterations == 60 and len(r.history) == 60
    assert np.all(np.diff(r.history) <= 0)


@pytest.mark.parametrize("name", PLANNERS)
def test_planner_deterministic_per_seed(name: str) -> None:
    sc = easy_2d() if 2 in get_planner(name).dims else easy_3d()
    a = get_planner(name, pop_size=20).plan(sc, budget=10, seed=7)
    b = get_planner(name, pop_size=20).plan(sc, budget=10, seed=7)
    c = get_planner(name, pop_size=20).plan(sc, budget=10, seed=8)
    assert np.array_equal(a.waypoints, b.waypoints)
    assert np.array_equal(a.history, b.history)
    assert not np.array_equal(a.waypoints, c.waypoints)


def test_unknown_planner_and_parameter() -> None:
    with pytest.raises(PlannerError, match="unknown planner"):
        get_planner("nope")
    with pytest.raises(PlannerError, match="unknown parameter"):
        get_planner("pso", bogus=1)


def test_plan_result_json_ready() -> None:
    sc = easy_2d()
    r = get_planner("pso", pop_size=10).plan(sc, budget=3, seed=0)
    d = r.to_dict()
    assert d["id"] == "uav0"
    assert len(d["waypoints"]) == len(d["times"]) == 5
    assert set(d["terms"]) == {"length"}
    assert isinstance(d["feasible"], bool)
