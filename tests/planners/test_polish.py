"""The CLI's polish (:mod:`uavplan.planners.polish`): tightening never raises the cost, keeps
start and goal and every segment valid, and does pull a zigzag straight; a segment steeper than
the UAV climbs is eased, and a polish never makes one."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.planners import get_planner, polish
from uavplan.planners.core.flight import flight_validator
from uavplan.planners.polish import polished, tighten
from uavplan.problems.validity import climb_violations, limit_climb
from uavplan.scenarios import resolve
from uavplan.world import UAV, AltitudeBand, Cylinder, Scenario, Task
from uavplan.world.scenario import Bounds


def test_tighten_never_costs_more_and_keeps_the_ends_and_the_segments_valid() -> None:
    sc = resolve("spso")
    planner = get_planner("spso", pop_size=40)
    task = sc.tasks[0]
    problem = planner.problem(sc, task)
    v = flight_validator(sc, task, kinematics=False)
    checked = 0
    for seed in (0, 1, 3):
        raw = planner.plan(sc, budget=100 if seed < 3 else 20, seed=seed)
        P = np.asarray(raw.waypoints, dtype=np.float64)
        if not (raw.feasible and v.paths_valid(P[None])[0]):
            continue
        T = tighten(problem, v, P)
        assert np.array_equal(T[0], P[0]) and np.array_equal(T[-1], P[-1])
        assert T.shape == P.shape
        assert v.segments_valid(T[:-1], T[1:]).all()
        before, after = problem.evaluate(P[None]), problem.evaluate(T[None])
        assert bool(after.feasible[0])
        assert float(after.cost[0]) <= float(before.cost[0])
        checked += 1
    assert checked  # at least one seed's path flies, so tightening was tried


def test_tighten_pulls_a_zigzag_in_open_space_towards_the_straight_line() -> None:
    from uavplan.io.scenario_file import scenario_from_dict

    sc = scenario_from_dict(
        {
            "name": "open",
            "bounds": {"lower": [0, 0], "upper": [100, 100]},
            "tasks": [{"start": [5, 5], "goal": [95, 95]}],
        }
    )
    task = sc.tasks[0]
    problem = get_planner("spso").problem(sc, task)
    v = flight_validator(sc, task, kinematics=False)
    s, g = np.asarray(task.start, float), np.asarray(task.goal, float)
    line = s + np.linspace(0.0, 1.0, 7)[:, None] * (g - s)
    normal = np.array([-(g - s)[1], (g - s)[0]]) / np.linalg.norm(g - s)
    zig = line + np.array([0, 1, -1, 1, -1, 1, 0])[:, None] * 3.0 * normal
    assert v.segments_valid(zig[:-1], zig[1:]).all()
    T = tighten(problem, v, zig)
    c0 = float(problem.evaluate(zig[None]).cost[0])
    c1 = float(problem.evaluate(T[None]).cost[0])
    assert c1 < c0
    off = lambda X: float(np.abs((X - line) @ normal).max())  # noqa: E731
    assert off(T) < 0.5 * off(zig)


def test_polished_says_what_it_did_and_never_returns_an_infeasible_path() -> None:
    sc = resolve("spso")
    planner = get_planner("spso", pop_size=40)
    task = sc.tasks[0]
    problem = planner.problem(sc, task)
    raw = planner.plan(sc, budget=20, seed=4)
    P = np.asarray(raw.waypoints, dtype=np.float64)
    out, note = polished(sc, task, problem, P)
    assert note  # this seed's path has corners to cut
    assert set(note["steps"]) <= {"terrain following", "shortcut", "tightening", "climb limits"}
    assert note["points"] == [len(P), len(out)]
    assert bool(problem.evaluate(out[None]).feasible[0])


def _box_with_a_tower() -> Scenario:
    tasks = (Task("u", (0.0, 0.0, 100.0), (900.0, 0.0, 100.0)),)
    return Scenario("box", Bounds((-100.0, -100.0, 0.0), (1000.0, 100.0, 300.0)), tasks,
                    cylinders=(Cylinder((150.0, 0.0), 25.0),),
                    uav=UAV(max_climb_angle=30.0, max_descent_angle=30.0),
                    altitude=AltitudeBand(20.0, 280.0, "absolute"), cost="ppswarm")  # fmt: skip


@pytest.mark.parametrize("tightening", [True, False])
def test_a_segment_steeper_than_the_uav_climbs_is_eased_where_the_world_lets_it(
    tightening: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if not tightening:  # the easing alone (the tightening here also flattens the vertex)
        monkeypatch.setattr(polish, "tighten", lambda problem, v, P: P)
    sc = _box_with_a_tower()
    task = sc.tasks[0]
    # a vertex 43 m out and 30 m down (35 degrees; the UAV descends at most 30), kept by the
    # tower that blocks the line from the start to the next vertex
    P = np.array([[0.0, 0, 100], [15, 40, 70], [300, 40, 90], [600, 0, 160], [900, 0, 100]])
    assert climb_violations(P[None], 30.0, 30.0)[0]
    problem = get_planner("ppswarm").problem(sc, task)
    out, note = polished(sc, task, problem, P)
    assert ("climb limits" in note["steps"]) is not tightening
    assert not climb_violations(out[None], 30.0, 30.0)[0]
    np.testing.assert_array_equal(out[[0, -1]], P[[0, -1]])
    assert bool(flight_validator(sc, task, kinematics=False).paths_valid(out[None])[0])


def test_climb_limits_move_heights_only_and_say_when_nothing_can() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(2, 9))
        P = np.cumsum(rng.normal(0, 30, (n, 3)), axis=0)
        up, down = rng.uniform(5, 60, 2)
        out = limit_climb(P, up, down)
        h = np.hypot(*np.diff(P[:, :2], axis=0).T)
        need_up = P[-1, 2] - P[0, 2] <= np.tan(np.radians(up)) * 0.9 * h.sum()
        need_down = P[0, 2] - P[-1, 2] <= np.tan(np.radians(down)) * 0.9 * h.sum()
        if not (need_up and need_down):
            assert out is None or n == 2  # the ends alone cannot be joined within the slopes
            continue
        assert out is not None
        np.testing.assert_array_equal(out[:, :2], P[:, :2])
        np.testing.assert_array_equal(out[[0, -1]], P[[0, -1]])
        assert not climb_violations(out[None], up, down)[0]
        ok = not climb_violations(P[None], up * 0.9, down * 0.9)[0]
        if ok:  # nothing to ease: nothing moves
            np.testing.assert_allclose(out, P)
