"""The CLI's polish (:mod:`uavplan.planners.core.polish`): tightening never raises the cost, keeps
start and goal and every segment valid, and does pull a zigzag straight."""

from __future__ import annotations

import numpy as np

from uavplan.planners import get_planner
from uavplan.planners.core.flight import flight_validator
from uavplan.planners.core.polish import polished, tighten
from uavplan.scenarios import resolve


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
    assert set(note["steps"]) <= {"terrain following", "shortcut", "tightening"}
    assert note["points"] == [len(P), len(out)]
    assert bool(problem.evaluate(out[None]).feasible[0])
