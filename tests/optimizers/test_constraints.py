"""Constraint rules: cost and violation apart until a rule makes one number of them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uavplan.optimizers import OptimizerError, available, minimize
from uavplan.optimizers.constraints import (
    RULES,
    Constrained,
    feasibility_first,
    infinite_if_violated,
)

finite = st.floats(-1e6, 1e6, allow_nan=False)
viol = st.one_of(st.just(0.0), st.floats(1e-6, 1e5))


def deb_less(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Deb's rule, literally: is (f, cv) a better than b?"""
    fa, ca = a
    fb, cb = b
    if ca == 0 and cb == 0:
        return fa < fb
    if ca == 0 or cb == 0:
        return ca == 0
    return ca < cb


@given(st.lists(st.tuples(finite, viol), min_size=2, max_size=30))
def test_feasibility_first_orders_as_debs_rule(points: list[tuple[float, float]]) -> None:
    f = np.array([p[0] for p in points])
    cv = np.array([p[1] for p in points])
    s = feasibility_first(f, cv)
    for i in range(len(points)):
        for j in range(len(points)):
            if deb_less(points[i], points[j]):
                # two violations closer than the base's ulp may round to one number
                tie = s[i] == s[j] and min(cv[i], cv[j]) > 0 and abs(cv[i] - cv[j]) < 1e-8
                assert s[i] < s[j] or tie
    np.testing.assert_array_equal(s[cv == 0], f[cv == 0])  # a feasible point keeps its cost


def test_rules_on_a_few_points() -> None:
    f = np.array([3.0, 1.0, np.inf, 2.0])
    cv = np.array([0.0, 5.0, 0.0, 1.0])
    np.testing.assert_array_equal(infinite_if_violated(f, cv), [3.0, np.inf, np.inf, np.inf])
    np.testing.assert_array_equal(feasibility_first(f, cv), [3.0, 1e7 + 5, 1e7, 1e7 + 1])
    with pytest.raises(OptimizerError, match="not below the base"):
        feasibility_first(np.array([2e7]), np.array([0.0]))
    with pytest.raises(OptimizerError, match=">= 0"):
        feasibility_first(f, -cv)


class Disc:
    """Minimize x + y on [-2, 2]^2 subject to x^2 + y^2 <= 1: optimum -sqrt(2) at the rim."""

    dim = 2
    lower = np.array([-2.0, -2.0])
    upper = np.array([2.0, 2.0])

    def __init__(self) -> None:
        self.calls: list[bool] = []

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(X.sum(axis=1))

    def evaluate_cv(self, X: np.ndarray, exact: bool = True) -> tuple[np.ndarray, np.ndarray]:
        self.calls.append(exact)
        return self.evaluate(X), np.maximum(0.0, np.sum(X * X, axis=1) - 1.0)


@pytest.mark.parametrize("name", available())
def test_feasibility_first_solves_a_constrained_problem_with_every_optimizer(name: str) -> None:
    problem = Disc()
    r = minimize(Constrained(problem, "feasibility-first"), name, 150, seed=0)
    x = np.asarray(r.x)
    assert np.sum(x * x) <= 1.0 + 1e-12  # the best point found is feasible
    assert r.f < -1.0  # and good: the unconstrained optimum (-4) is infeasible
    assert all(problem.calls)  # exact violations asked for


def test_the_inf_rule_asks_for_a_cheap_violation_and_cost_for_none() -> None:
    problem = Disc()
    X = np.array([[0.0, 0.0], [2.0, 2.0]])
    np.testing.assert_array_equal(Constrained(problem, "inf").evaluate(X), [0.0, np.inf])
    assert problem.calls == [False]
    np.testing.assert_array_equal(Constrained(problem, "cost").evaluate(X), [0.0, 4.0])
    assert problem.calls == [False]


def test_bad_rule_and_base() -> None:
    with pytest.raises(OptimizerError, match="unknown constraint rule"):
        Constrained(Disc(), "graded")
    with pytest.raises(OptimizerError, match="base"):
        Constrained(Disc(), "feasibility-first", base=-1.0)
    assert RULES == ("cost", "inf", "feasibility-first")
