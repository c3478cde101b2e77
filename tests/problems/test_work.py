"""The work counters: counted where the work is done, nested blocks add up, nothing outside."""

from __future__ import annotations

import numpy as np

from planners.test_planners import easy_2d as _scene
from uavplan.planners import get_planner
from uavplan.problems import PathProblem, work


def test_the_problem_counts_paths_costed_and_the_validator_paths_checked() -> None:
    pp = PathProblem(_scene())
    paths = np.random.default_rng(0).uniform(0, 100, (7, 5, 2))
    work.add(cost_paths=99)  # outside any block: not counted anywhere
    with work.counting() as outer:
        pp.evaluate(paths)  # the cost of 7 paths and the checks of 7 paths of 4 segments
        with work.counting() as inner:
            pp.validator.segments_valid(paths[:3, 0], paths[:3, 1])  # 3 segments
        assert inner.record() == {"cost_paths": 0, "checked_paths": 3, "checked_segments": 3}
    assert outer.record() == {"cost_paths": 7, "checked_paths": 10, "checked_segments": 31}


def test_a_run_reports_its_work_beside_the_evaluations_in_its_own_unit() -> None:
    sc = _scene()
    pso = get_planner("pso", pop_size=20).plan(sc, budget=10, seed=1)
    # every particle's cost went through the problem, plus one fresh evaluation of the result
    assert pso.info["work"]["cost_paths"] == pso.evaluations + 1
    rgg = get_planner("rgg").plan(sc, budget=3, seed=1)
    w = rgg.info["work"]
    # RGG's own count of edge checks is a part of what its validators were asked
    assert w["checked_segments"] >= rgg.info["edge_checks"] > 0
    assert w["cost_paths"] < w["checked_paths"]
