"""The CLI's repair of a fleet's looping or failing UAVs (``planners/fleet/fleet_polish.py``): what
it keeps flies (the independent verifier agrees), it is deterministic, and it leaves alone a fleet
that needs nothing."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from uavplan.io.plan_file import plan_document
from uavplan.planners import get_planner
from uavplan.planners.core.base import separated_problem
from uavplan.planners.core.flight import declare, fly
from uavplan.planners.core.results import FleetResult, PlanResult, make_result
from uavplan.planners.fleet.fleet_plan import FleetPlan
from uavplan.planners.fleet.fleet_polish import (
    _others_table,
    cut_loops,
    first_crossing,
    polish_fleet,
)
from uavplan.scenarios import resolve
from uavplan.verify import verify_plan
from uavplan.world import Scenario
from uavplan.world.fleet_tasks import with_fleet
from uavplan.world.geometry import track_crosses_itself

SMALL = {"pop_size": 24, "n_iter": 6, "n_restart": 1, "rrt_iterations": 2000}


def test_cut_loops_removes_every_crossing_and_keeps_the_ends() -> None:
    p = np.array([[0.0, 0, 5], [10, 0, 5], [10, 10, 5], [5, -5, 5], [20, 0, 5], [20, 9, 5],
                  [15, 5, 5], [30, 5, 5]])  # fmt: skip
    assert track_crosses_itself(p)
    i, j, x = first_crossing(p)  # type: ignore[misc]
    assert (i, j) == (0, 2) and np.allclose(x, [20 / 3, 0, 5])
    q = cut_loops(p)
    assert not track_crosses_itself(q)
    assert np.array_equal(q[0], p[0]) and np.array_equal(q[-1], p[-1])
    L = lambda a: np.linalg.norm(np.diff(a, axis=0), axis=1).sum()  # noqa: E731
    assert L(q) < L(p)
    straight = np.array([[0.0, 0, 1], [5, 1, 1], [9, 0, 1]])
    assert first_crossing(straight) is None and np.array_equal(cut_loops(straight), straight)


@pytest.fixture(scope="module")
def planned() -> tuple[Scenario, FleetResult, dict[str, object]]:
    sc = with_fleet(resolve("ppswarm1"), 3, seed=0)
    planner = get_planner("ppswarm", **SMALL)
    fr = planner.plan_fleet(sc, seed=5)
    assert fr.flown_feasible
    return sc, fr, planner.describe()


def _replace_uav(sc: Scenario, fr: FleetResult, k: int, path: np.ndarray) -> FleetResult:
    """``fr`` with UAV ``k`` declared to fly ``path`` (its flight checked against the others)."""
    results = list(fr.results)
    r = results[k]
    task = sc.task(r.uav_id)
    table = _others_table(sc, results, k, 0.0, 1.0)
    new = make_result(separated_problem(sc, task, table), path, algorithm=r.algorithm,
                      history=r.history, evaluations=r.evaluations,
                      evaluations_history=r.evaluations_history, wall_time=0.0)  # fmt: skip
    results[k] = declare(new, fly(sc, task, new.waypoints, new.times, table))
    feasible = all(x.flown_feasible for x in results)
    return dataclasses.replace(fr, results=tuple(results), flown_feasible=feasible)


def _verified(sc: Scenario, fr: FleetResult) -> bool:
    d = plan_document(FleetPlan(sc, "ppswarm", {}, 5, fr.results, fr))
    return bool(verify_plan(d, sc).ok)


def _through_a_cylinder(sc: Scenario, fr: FleetResult) -> tuple[Any, int, FleetResult]:
    """``fr`` with its second task's UAV flying straight through the cylinder nearest the
    middle of its way: (the task, its index in the results, the fleet)."""
    task = sc.tasks[1]
    c = sc.cylinders[int(np.argmin([np.hypot(*(np.asarray(cy.center[:2]) -
                                               (np.asarray(task.start[:2]) + task.goal[:2]) / 2))
                                    for cy in sc.cylinders]))]  # fmt: skip
    through = np.array([task.start, [c.center[0], c.center[1], task.start[2]], task.goal])
    k = [r.uav_id for r in fr.results].index(task.id)
    return task, k, _replace_uav(sc, fr, k, through)


def test_a_uav_through_a_cylinder_is_replanned_and_verified(planned) -> None:  # type: ignore[no-untyped-def]
    sc, fr, cfg = planned
    task, k, bad = _through_a_cylinder(sc, fr)
    assert not bad.flown_feasible and not bad.results[k].flown_ok
    assert not _verified(sc, bad)
    out = polish_fleet(sc, bad, 7, cfg)
    assert out.flown_feasible and np.isfinite(out.cost)
    assert set(out.info["repair"]) == {task.id} and out.info["repair"][task.id].startswith("RRT*")
    assert out.results[k].info["repaired"] == out.info["repair"][task.id]
    assert _verified(sc, out)
    for j, (a, b) in enumerate(zip(bad.results, out.results, strict=True)):  # others untouched
        assert (a is b) == (j != k)
    again = polish_fleet(sc, bad, 7, cfg)
    assert np.array_equal(again.results[k].waypoints, out.results[k].waypoints)


def test_a_looping_uav_is_untangled(planned) -> None:  # type: ignore[no-untyped-def]
    sc, fr, cfg = planned
    k = 0
    r: PlanResult = fr.results[k]
    W = np.array(r.waypoints, dtype=np.float64)
    m = len(W) // 2
    a, b = W[m - 1], W[m]
    d = (b - a)[:2] / np.linalg.norm((b - a)[:2])
    n = np.array([-d[1], d[0]])
    # a wide loop after vertex m - 1: ahead, to the side, then back across the segment
    loop = [a + np.r_[d * 300, 0], a + np.r_[d * 300 + n * 300, 0], a + np.r_[d * 100 - n * 200, 0]]
    looping = np.vstack([W[:m], np.array(loop), W[m:]])
    assert track_crosses_itself(looping)
    bent = _replace_uav(sc, fr, k, looping)
    assert bent.results[k].flown_ok  # it flies, around its loop
    out = polish_fleet(sc, bent, 7, cfg)
    assert out.info["repair"] == {r.uav_id: "loop cut"}
    assert not track_crosses_itself(out.results[k].waypoints)
    assert out.results[k].length < bent.results[k].length
    assert out.flown_feasible and _verified(sc, out)


def test_a_uav_no_repair_helps_keeps_its_plan_and_the_story_says_what_was_tried(
    planned, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    """Through a cylinder, with RRT* finding nothing (patched): the UAV keeps its failing
    plan, the fleet stays infeasible, and its unresolved event says what the repair tried."""
    from uavplan.planners.core.events import plan_events
    from uavplan.planners.fleet import fleet_polish

    sc, fr, cfg = planned
    task, _, bad = _through_a_cylinder(sc, fr)
    seeds: list[int] = []
    monkeypatch.setattr(fleet_polish, "_rrt_path", lambda s, t, seed: seeds.append(seed))
    out = polish_fleet(sc, bad, 7, cfg)
    assert not out.flown_feasible and out.info["repair"] == {}
    assert len(set(seeds)) == len(seeds) == fleet_polish.RRT_TRIES + fleet_polish.RRT_MORE
    tried = out.info["unrepaired"][task.id]
    assert "later take-offs: none flies" in tried
    n = fleet_polish.RRT_TRIES + fleet_polish.RRT_MORE  # none flew alone: the more tried too
    assert f"{n} RRT* tries: no path whose flight passes even alone" in tried
    plan = FleetPlan(sc, "ppswarm", {}, 7, out.results, out)
    (e,) = [e for e in plan_events(plan) if e.kind == "unresolved"]
    assert e.uav == task.id and "cylinders" in e.detail and tried in e.detail


def test_more_rrt_tries_only_when_no_path_flew_even_alone(planned, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A path that flies alone but at no take-off (patched: the UAV's own path through the
    cylinder, so every slot fails) stops the search after the first tries; the more tries are
    for UAVs whose every path failed even alone (the test above)."""
    from uavplan.planners.fleet import fleet_polish

    sc, fr, cfg = planned
    task, k, bad = _through_a_cylinder(sc, fr)
    calls: list[int] = []

    def through(s: Any, t: Any, seed: int) -> Any:
        calls.append(seed)
        return np.asarray(bad.results[k].waypoints)

    monkeypatch.setattr(fleet_polish, "_rrt_path", through)
    out = polish_fleet(sc, bad, 7, cfg)
    assert not out.flown_feasible and len(calls) == fleet_polish.RRT_TRIES
    tried = out.info["unrepaired"][task.id]
    assert f"{fleet_polish.RRT_TRIES} RRT* path(s): none flies at any take-off tried" in tried
    assert "even alone" not in tried


def test_among_moving_obstacles_no_rrt_path_is_tried_and_the_uav_is_left(
    planned, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    """RRT* cannot plan around moving obstacles (its graph has no time): with one in the
    world, the failing UAV gets no RRT* try, is left unrepaired, and the story says why."""
    from uavplan.planners.fleet import fleet_polish
    from uavplan.world.dynamic import MovingObstacle

    sc, fr, cfg = planned
    far = MovingObstacle(5.0, np.array([0.0, 1e4]), np.array([[-900.0, -900.0, 0.0]] * 2))
    moving = dataclasses.replace(sc, moving_obstacles=(far,))
    task, _, bad = _through_a_cylinder(moving, fr)

    def never(*args: Any) -> Any:
        raise AssertionError("RRT* tried among moving obstacles")

    monkeypatch.setattr(fleet_polish, "_rrt_path", never)
    out = polish_fleet(moving, bad, 7, cfg)
    assert not out.flown_feasible
    assert "it cannot plan around moving obstacles" in out.info["unrepaired"][task.id]


def test_a_fleet_that_needs_nothing_is_left_as_it_is(planned) -> None:  # type: ignore[no-untyped-def]
    sc, fr, cfg = planned
    out = polish_fleet(sc, fr, 7, cfg)
    assert out.info["repair"] == {} and out.results == fr.results and out.cost == fr.cost


def test_the_last_resort_takes_off_after_every_other_uav_has_landed() -> None:
    """Under a drifting schedule: the latest landing of the flights reserved, plus the
    take-off error; the nominal table: the last landing."""
    from uavplan.planners.fleet.fleet_polish import _after_all
    from uavplan.world.execution import DEFAULT, widened
    from uavplan.world.reservations import ReservationTable

    given = with_fleet(resolve("ppswarm1"), 3, seed=0)
    timed = ReservationTable.for_scenario(widened(given, DEFAULT))
    plain = ReservationTable.for_scenario(given)
    assert _after_all(timed) == 1.0 + 2.0  # nothing reserved: right away (at 0 s at the latest)
    for k, (t0, t1) in enumerate(((0.0, 50.0), (10.0, 110.0), (5.0, 60.0))):
        P = np.array([[0.0, 0, 100], [100, 0, 100]]) + 100 * k
        for table in (timed, plain):
            table.add(f"u{k}", P, np.array([t0, t1]))
    late = 10.0 + 2.0 + 100.0 / (1 - 0.03)  # u1 at its latest, landing
    assert timed.clear_time() == pytest.approx(late)
    assert _after_all(timed) == np.floor(late + 2.0) + 1
    assert plain.clear_time() == 110.0 and _after_all(plain) == 111.0


def test_a_repaired_uav_takes_the_first_free_slot_before_all_have_landed() -> None:
    """A UAV blocked at its start for a minute, whose delays (20 s at most) do not reach past
    that, takes off at the first 5 s step after the blocker has gone, found by the batched
    table queries between the delays and the last resort; without them, only after every
    other UAV has landed (501 s)."""
    from uavplan.planners.fleet.fleet_polish import _after_all, _first_slot
    from uavplan.world.reservations import ReservationTable

    sc = with_fleet(resolve("open"), 2, seed=0)  # its straight path flies
    task = sc.tasks[0]
    path = np.array([task.start, task.goal], dtype=np.float64)
    table = ReservationTable.for_scenario(sc)
    start = np.asarray(task.start, dtype=np.float64)
    sitting = np.stack([start, start + np.array([1.0, 0.0, 0.0])])  # at its start for 60 s
    table.add("blocker", sitting, np.array([0.0, 60.0]))
    far = np.array([[5.0, 5.0, float(start[2])], [6.0, 5.0, float(start[2])]])
    table.add("far", far, np.array([0.0, 500.0]))
    last = _after_all(table)
    assert last == 501.0
    starts = [5.0 * w for w in range(5)] + [last]
    old = make_result(separated_problem(sc, task, None), path, algorithm="test", history=[],
                      evaluations=0, evaluations_history=[], wall_time=0.0)  # fmt: skip
    opts = {"timing": "planned", "step": 5.0}
    found = {
        fill: _first_slot(sc, task, old, path, table, opts, starts, lambda w: f"{w:g}", fill=fill)
        for fill in (5.0, None)
    }
    assert found[5.0] is not None and found[None] is not None
    t5 = float(np.asarray(found[5.0].flown_times)[0])
    assert 60.0 <= t5 <= 65.0 + 1e-9 and found[5.0].info["repaired"] == f"{t5:g}"
    assert float(np.asarray(found[None].flown_times)[0]) == last


def test_a_single_uav_planner_run_as_a_fleet_is_repaired_too() -> None:
    """The prioritized frame around a single-UAV planner (here the potential field) gets the
    same repair as a fleet planner, and what it keeps passes the verifier under the model."""
    from uavplan.planners.fleet.fleet_plan import plan_all
    from uavplan.world.execution import DEFAULT, widened

    given = with_fleet(resolve("ppswarm1"), 6, seed=0)
    world = widened(given, DEFAULT)
    plan = plan_all(world, get_planner("apf"), None, 0, polish=True)
    assert plan.fleet is not None and "repair" in plan.fleet.info
    from uavplan.io.plan_file import parse_plan
    from uavplan.verify import verify_trajectories

    pf = parse_plan(plan_document(plan), world.dim)
    report = verify_trajectories(pf.trajectories("flown"), given, pf.scenario, model=DEFAULT)
    assert plan.feasible and report.ok, report.violations[:3]
