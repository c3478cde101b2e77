"""Constraint handling for any optimizer: the cost and the constraint violation travel apart
(pymoo's ``F`` and ``G``) until a rule turns them into the one number an optimizer compares.

A *constrained problem* (:class:`ConstrainedProblem`) has, besides ``evaluate(X) -> f``, an
``evaluate_cv(X, exact) -> (f, cv)`` with ``cv >= 0`` and ``cv == 0`` for a feasible point.
:class:`Constrained` wraps it into a plain :class:`~uavplan.optimizers.base.Problem` under one
of the :data:`RULES`:

* ``"cost"``: the cost alone, as the paper defines it (with whatever infinities its cost has);
  feasibility is judged afterwards. The single-UAV planners' default (SPSO, PSO, ... on their
  papers' costs).
* ``"inf"``: a point that violates any constraint costs infinity (PPSwarm Sect. 2: "penalize
  it with a cost of infinity"); the fleet planners' default.
* ``"feasibility-first"``: Deb's rule (Deb 2000, "An efficient constraint handling method for
  genetic algorithms", CMAME 186): a feasible point beats an infeasible one, two feasible points
  compare by cost, two infeasible ones by violation. As a single number for optimizers that
  compare costs (every optimizer here): ``f`` where feasible and ``base + cv`` elsewhere (a
  point with an infinite cost counts as infeasible), which orders exactly as Deb's rule while
  every feasible cost is below ``base`` (:data:`FEASIBILITY_FIRST_BASE` = 1e7; a path's cost here
  is a few thousand): a feasible cost at or above it is refused with an error rather than
  misordered. Unlike "inf", the infeasible points still point the search towards feasibility,
  which uniformly seeded optimizers need when feasible points are rare.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import OptimizerError, Problem

FloatArray = NDArray[np.float64]

#: The constraint rules, in the order of the module docstring.
RULES = ("cost", "inf", "feasibility-first")
#: ``feasibility-first``: an infeasible point's number starts here.
FEASIBILITY_FIRST_BASE = 1e7


@runtime_checkable
class ConstrainedProblem(Problem, Protocol):
    """A box-bounded problem (:class:`~uavplan.optimizers.base.Problem`) with the cost and the
    constraint violation apart."""

    def evaluate_cv(self, X: FloatArray, exact: bool = True) -> tuple[FloatArray, FloatArray]:
        """``(f, cv)`` of ``X`` (pop, dim). With ``exact=False`` the problem may report any
        ``cv > 0`` for an infeasible point (and stop checking it early)."""
        ...


def infinite_if_violated(f: FloatArray, cv: FloatArray) -> FloatArray:
    """The ``"inf"`` rule: ``inf`` where ``cv > 0``, else ``f``."""
    return np.where(np.asarray(cv) > 0, np.inf, np.asarray(f, dtype=np.float64))


def feasibility_first(
    f: FloatArray, cv: FloatArray, base: float = FEASIBILITY_FIRST_BASE
) -> FloatArray:
    """Deb's rule as a number (see the module docstring): ``f`` where ``cv == 0`` and ``f`` is
    finite, ``base + cv`` elsewhere."""
    f = np.asarray(f, dtype=np.float64)
    cv = np.asarray(cv, dtype=np.float64)
    if np.any(cv < 0) or np.any(np.isnan(cv)):
        raise OptimizerError("constraint violations must be >= 0")
    bad = (cv > 0) | ~np.isfinite(f)
    if np.any(~bad & (f >= base)):
        worst = float(np.max(f[~bad]))
        raise OptimizerError(
            f"feasibility-first: a feasible cost ({worst:g}) is not below the base of the "
            f"infeasible ones ({base:g}); raise the base"
        )
    return np.where(bad, base + cv, f)


class Constrained:
    """The optimizer-facing problem of ``problem`` under ``rule`` (one of :data:`RULES`).

    ``dim``, ``lower``, ``upper`` and ``block`` are the wrapped problem's; ``evaluate(X)``
    returns the rule's number per row.
    """

    def __init__(
        self, problem: ConstrainedProblem, rule: str = "cost", base: float = FEASIBILITY_FIRST_BASE
    ) -> None:
        if rule not in RULES:
            raise OptimizerError(f"unknown constraint rule {rule!r}; choose from {list(RULES)}")
        if not (np.isfinite(base) and base > 0):
            raise OptimizerError(f"the feasibility-first base must be finite and > 0, got {base}")
        self.problem = problem
        self.rule = rule
        self.base = float(base)

    @property
    def dim(self) -> int:
        return int(self.problem.dim)

    @property
    def lower(self) -> FloatArray:
        return self.problem.lower

    @property
    def upper(self) -> FloatArray:
        return self.problem.upper

    @property
    def block(self) -> int:
        return int(getattr(self.problem, "block", 1))

    def evaluate(self, X: FloatArray) -> FloatArray:
        if self.rule == "cost":
            return self.problem.evaluate(X)
        f, cv = self.problem.evaluate_cv(X, exact=self.rule == "feasibility-first")
        if self.rule == "inf":
            return infinite_if_violated(f, cv)
        return feasibility_first(f, cv, self.base)
