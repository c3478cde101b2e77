"""Contract tests over every registered planner (OMPL's PlannerTest, pymoo's deterministic
tests): each solves an easy case, is deterministic per seed and differs across seeds, reports
what a fresh evaluation of its path says, describes itself, stops when asked, and refuses
malformed input with a PlannerError that says why."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import fields
from typing import Any

import numpy as np
import pytest

from uavplan.planners import (
    FleetPlanner,
    Planner,
    PlannerError,
    PlanResult,
    available_planners,
    get_planner,
    planner_entry,
)
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
SINGLE = [n for n in PLANNERS if not planner_entry(n).fleet]


def quick(name: str, **extra: Any) -> Planner:
    """The planner with a small population, where it has one."""
    small = {"pop_size": 40} if "pop_size" in get_planner(name).option_names() else {}
    return get_planner(name, **small, **extra)


def scenario_for(name: str) -> Scenario:
    return easy_2d() if 2 in get_planner(name).specs.dims else easy_3d()


@pytest.mark.parametrize("name", PLANNERS)
@pytest.mark.parametrize("make", [easy_2d, easy_3d], ids=["2d", "3d"])
def test_planner_solves_easy_scenario(name: str, make: Callable[[], Scenario]) -> None:
    sc = make()
    planner = quick(name)
    if sc.dim not in planner.specs.dims:
        with pytest.raises(PlannerError, match=f"{sc.dim}-D"):
            planner.plan(sc, budget=60, seed=1)
        return
    r = planner.plan(sc, budget=60, seed=1)
    assert isinstance(r, PlanResult) and r.algorithm == name
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
    n_it = 60 if planner.specs.anytime else r.iterations  # a planner that ends on arrival: fewer
    assert r.evaluations > 0 and 0 < r.iterations <= 60
    assert r.iterations == n_it and len(r.history) == n_it
    assert np.all(r.history[1:] <= r.history[:-1])  # inf until a first path, then falling
    eh = np.asarray(r.evaluations_history)
    assert len(eh) == n_it and np.all(np.diff(eh) >= 0) and eh[-1] <= r.evaluations
    # what the run computed, counted where it was done: at least the returned path's costing
    # and checks (RRT*'s evaluations are segment checks, all of them seen by the counters)
    w = r.info["work"]
    assert w["cost_paths"] >= 1 and w["checked_segments"] >= w["checked_paths"] >= 1
    if name == "rrt-star":
        assert w["checked_segments"] >= r.evaluations


@pytest.mark.parametrize("name", PLANNERS)
def test_planner_deterministic_per_seed(name: str) -> None:
    sc = scenario_for(name)
    a = quick(name).plan(sc, budget=10, seed=7)
    b = quick(name).plan(sc, budget=10, seed=7)
    c = quick(name).plan(sc, budget=10, seed=8)
    assert np.array_equal(a.waypoints, b.waypoints)
    assert np.array_equal(a.history, b.history)
    # a deterministic method gives one plan whatever the seed; the others differ by seed
    assert np.array_equal(a.waypoints, c.waypoints) == quick(name).specs.deterministic


@pytest.mark.parametrize("name", PLANNERS)
def test_describe_is_generated_from_the_config(name: str) -> None:
    p = get_planner(name)
    d = p.describe()
    assert d["name"] == name == p.name
    for f in fields(p.config):
        assert f.name in d
    json.dumps(d)  # JSON-ready (plan.json's config)
    assert planner_entry(name).summary  # `uavplan planners` lists it with one line


@pytest.mark.parametrize("name", SINGLE)
def test_callback_stops_the_run(name: str) -> None:
    sc = scenario_for(name)
    seen: list[tuple[int, float]] = []

    def cb(it: int, best: float) -> bool:
        seen.append((it, best))
        return it >= 3

    r = quick(name).plan(sc, budget=50, seed=0, callback=cb)
    assert r.iterations == 3 and [s[0] for s in seen] == [1, 2, 3]
    assert seen[-1][1] >= r.history[-1]  # the last iteration may fold in a final result


# ------------------------------------------------------------------------ malformed input
@pytest.mark.parametrize("name", PLANNERS)
def test_unknown_option_is_refused_naming_the_valid_ones(name: str) -> None:
    with pytest.raises(PlannerError, match=r"unknown option\(s\) \['bogus'\]; it takes") as e:
        get_planner(name, bogus=1)
    assert all(o in str(e.value) for o in get_planner(name).option_names())


@pytest.mark.parametrize("name", PLANNERS)
def test_out_of_range_options_are_refused(name: str) -> None:
    p = get_planner(name)
    checked = 0
    for f in fields(p.config):
        m = f.metadata
        bad: list[Any] = []
        if m.get("low") is not None:
            bad.append(m["low"] if m.get("low_open") else m["low"] - 1)
        if m.get("high") is not None:
            bad.append(m["high"] if m.get("high_open") else m["high"] + 1)
        if m.get("choices") is not None:
            bad.append("no-such-choice")
        for v in bad:
            with pytest.raises(PlannerError, match=f"option {f.name} must be"):
                get_planner(name, **{f.name: v})
            checked += 1
    if "pop_size" in p.option_names():  # the inner optimizer's options are checked too
        with pytest.raises(PlannerError, match="pop_size"):
            get_planner(name, pop_size=0)
    with pytest.raises(PlannerError, match="must be"):  # a wrong type
        get_planner(name, **{p.option_names()[0]: object()})
    assert checked > 0 or name in ("rgg",)


@pytest.mark.parametrize("name", PLANNERS)
def test_malformed_tasks_and_budgets_are_refused(name: str) -> None:
    sc = scenario_for(name)
    p = quick(name)
    outside = Task("out", tuple(np.array(sc.tasks[0].start) - 1000.0), sc.tasks[0].goal)
    with pytest.raises(PlannerError, match="outside the bounds"):
        p.plan(sc, outside, budget=5, seed=0)
    with pytest.raises(PlannerError, match="no task 'nope'"):
        p.plan(sc, "nope", budget=5, seed=0)
    other_dim = Task("flat", tuple(sc.tasks[0].start[:2]) + (1.0,) * (sc.dim == 2),
                     tuple(sc.tasks[0].goal[:2]) + (1.0,) * (sc.dim == 2))  # fmt: skip
    with pytest.raises(PlannerError, match="coordinates, the scenario is"):
        p.plan(sc, other_dim if sc.dim == 2 else Task("flat", (1.0, 1.0), (2.0, 2.0)), budget=5)
    with pytest.raises(PlannerError, match="budget"):
        p.plan(sc, budget=0, seed=0)
    if isinstance(p, FleetPlanner):
        with pytest.raises(PlannerError, match="outside the bounds"):
            p.plan_fleet(Scenario(**{**sc.__dict__, "tasks": (outside,), "metadata": {}}))


@pytest.mark.parametrize("rule", ["cost", "inf", "feasibility-first"])
def test_every_constraint_rule_runs_with_every_optimizer_planner(rule: str) -> None:
    sc = easy_3d()
    for name in SINGLE:
        p = get_planner(name)
        if "constraints" not in p.option_names():
            continue
        r = quick(name, constraints=rule).plan(sc, budget=8, seed=2)
        assert r.iterations == 8 and len(r.feasible_history) == 8, name
        assert np.isfinite(r.cost) or not r.feasible


def test_named_configurations_share_one_class() -> None:
    """PPSwarm's baselines are configurations of one engine, as every optimizer planner is of
    the optimizer planner (nevergrad's ConfiguredOptimizer)."""
    a, b = planner_entry("ppswarm"), planner_entry("prioritized")
    assert a.cls is b.cls and a.options != b.options
    assert planner_entry("pso").cls is planner_entry("de").cls
    assert get_planner("prioritized", optimizer="de").optimizer_config.__class__.__name__ == (
        "DEConfig"
    )
    # another optimizer drops the configuration's PSO parameters
    assert get_planner("prioritized", optimizer="de").config.optimizer_options == {}
    assert get_planner("prioritized").config.optimizer_options["w"] == 0.8


def test_a_planner_says_what_it_can_do_in_one_specs_record() -> None:
    """Capabilities are one frozen record per class, inherited and changed by replace; a class
    that sets one as a loose attribute (where the framework would never read it) is refused."""
    import dataclasses

    from uavplan.planners import Planner, PlannerSpecs
    from uavplan.planners.core.base import SPEC_FIELDS

    assert {f.name for f in dataclasses.fields(PlannerSpecs)} == set(SPEC_FIELDS)
    for name in PLANNERS:
        assert isinstance(planner_entry(name).cls.specs, PlannerSpecs), name
    assert planner_entry("rgg-pso+").cls.specs.inner_optimizer == "pso"  # inherited
    assert not planner_entry("rrt-star").cls.specs.handles_moving
    assert planner_entry("apf").cls.specs.steps_in_time
    with pytest.raises(TypeError, match="declare them in specs"):

        class Loose(Planner):
            supports_reservations = True

    with pytest.raises(dataclasses.FrozenInstanceError):
        Planner.specs.anytime = False  # type: ignore[misc]


def test_unknown_planner() -> None:
    with pytest.raises(PlannerError, match="unknown planner 'nope'; available"):
        get_planner("nope")


def with_traffic(sc: Scenario) -> Scenario:
    """``sc`` with a moving obstacle crossing the straight line midway when the UAV would be
    there (radius 5 % of the map)."""
    import dataclasses

    from uavplan.world.dynamic import MovingObstacle

    s, g = np.asarray(sc.tasks[0].start), np.asarray(sc.tasks[0].goal)
    mid = 0.5 * (s + g)
    t_mid = float(np.linalg.norm(g - s)) / sc.uav.speed / 2
    side = np.zeros_like(mid)
    side[1] = 0.4 * float(sc.bounds.hi[1] - sc.bounds.lo[1])
    r = 0.05 * float(sc.bounds.hi[0] - sc.bounds.lo[0])
    obs = MovingObstacle(r, [0.0, 2 * t_mid], [mid + side, mid - side])
    return dataclasses.replace(sc, name=sc.name + "-traffic", moving_obstacles=(obs,))


@pytest.mark.parametrize("name", PLANNERS)
def test_moving_obstacles_are_planned_around_or_refused_naming_why(name: str) -> None:
    planner = quick(name)
    sc = with_traffic(scenario_for(name))
    if not planner.specs.handles_moving:
        with pytest.raises(PlannerError, match="cannot plan around moving obstacles"):
            planner.plan(sc, budget=20, seed=0)
        return
    r = planner.plan(sc, budget=20, seed=0)
    # judged over continuous time as flown at the UAV's speed, by a fresh evaluation
    ev = PathProblem(sc).evaluate(r.waypoints[None])
    assert bool(ev.feasible[0]) == r.feasible
    if not r.feasible:
        assert r.violations
    d = sc.moving_obstacles[0].min_distance(r.flown[None], r.flown_times[None])
    assert r.flown_ok == r.flown_feasible
    if r.flown_ok:
        assert d.min() >= sc.moving_obstacles[0].radius
    if name in ("apf", "rscdwoa-apf"):
        assert r.feasible and r.flown_ok, r.violations
