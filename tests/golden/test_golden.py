"""The smoke-scale results of every built-in plan and of ``uavplan demo`` stay what they were
when recorded (``tests/golden/smoke.json``, written by ``python tests/golden/record.py`` before
the planner framework refactoring): the same seeds give the same numbers."""

from __future__ import annotations

import json

from golden.record import GOLDEN, collect, differences


def test_smoke_results_unchanged() -> None:
    want = json.loads(GOLDEN.read_text())
    got = collect()
    diffs = differences(want, got)
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
    assert differences(want, {"run": {"evaluations": 20300, "iterations": 30}})
    assert differences(want, {"run": {"evaluations": 20366, "iterations": 31}})


def test_evaluation_histories_take_the_same_tolerance_and_costs_do_not() -> None:
    want = {"run": {"evaluations_history": [17489.0], "history": [1.0]}}
    assert differences(want, {"run": {"evaluations_history": [17495.0], "history": [1.0]}}) == []
    assert differences(want, {"run": {"evaluations_history": [17600.0], "history": [1.0]}})
    assert differences(want, {"run": {"evaluations_history": [17489.0], "history": [1.0001]}})
