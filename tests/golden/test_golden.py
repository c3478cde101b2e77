"""The smoke-scale results of every built-in plan and of ``uavplan demo`` stay what they were
when recorded (``tests/golden/smoke.json``, written by ``python tests/golden/record.py`` before
the planner framework refactoring): the same seeds give the same numbers. Each plan's record is
compared by ``tests/bench/test_plans.py`` on the smoke sweep it runs anyway; the demo's here."""

from __future__ import annotations

import json

from golden.record import GOLDEN, collect_demo, differences

WANT = json.loads(GOLDEN.read_text())


def test_every_plan_has_a_golden_record() -> None:
    from uavplan.bench.catalog import available_plans

    assert sorted(available_plans()) == sorted(WANT["plans"])


def test_demo_unchanged() -> None:
    diffs = differences(WANT["demo"], collect_demo(), "/demo")
    assert not diffs, "\n".join(diffs[:40])


def test_differences_detects_a_change() -> None:
    want = {"a": [1.0, 2.0], "b": True, "c": "inf"}
    assert differences(want, {"a": [1.0, 2.0 * (1 + 1e-12)], "b": True, "c": "inf"}) == []
    assert differences(want, {"a": [1.0, 2.001], "b": True, "c": "inf"})
    assert differences(want, {"a": [1.0, 2.0], "b": False, "c": "inf"})
    assert differences(want, {"a": [1.0, 2.0], "b": True, "c": 3.0})
    assert differences(want, {"a": [1.0], "b": True, "c": "inf"})


def test_evaluation_counts_allow_a_tie_flipped_by_an_ulp_and_nothing_more() -> None:
    want = {"run": {"evaluations": 20368, "iterations": 30}}
    assert differences(want, {"run": {"evaluations": 20366, "iterations": 30}}) == []
    assert differences(want, {"run": {"evaluations": 20200, "iterations": 30}})
    assert differences(want, {"run": {"evaluations": 20366, "iterations": 31}})


def test_evaluation_histories_take_the_same_tolerance_and_costs_do_not() -> None:
    want = {"run": {"evaluations_history": [17489.0], "history": [1.0]}}
    assert differences(want, {"run": {"evaluations_history": [17495.0], "history": [1.0]}}) == []
    assert differences(want, {"run": {"evaluations_history": [17600.0], "history": [1.0]}})
    assert differences(want, {"run": {"evaluations_history": [17489.0], "history": [1.0001]}})
