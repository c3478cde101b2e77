"""A planner that wraps any registered optimizer with the Cartesian waypoint encoding.

The optimizer searches ``n_waypoints`` free waypoints (x, y[, z]) between the task's start and
goal under the scenario's cost preset (see :mod:`uavplan.problems.path_problem`).
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np

from uavplan import optimizers
from uavplan.optimizers.base import Budget, config_dict
from uavplan.planners.base import (
    _REGISTRY,
    Planner,
    PlannerError,
    PlanResult,
    ProgressCallback,
    register_planner,
)
from uavplan.problems.encoding import ENCODINGS
from uavplan.problems.path_problem import PathProblem
from uavplan.world.scenario import Scenario, Task

#: Iterations when no budget is given (SPSO's 200).
DEFAULT_ITERATIONS = 200


class OptimizerPlanner(Planner):
    """Plan with optimizer ``algorithm`` over encoded waypoints.

    Args:
        algorithm: a registered optimizer name.
        n_waypoints: free waypoints (default: the scenario's).
        cost: cost preset (default: the scenario's).
        weights: term weight overrides.
        encoding: ``cartesian`` or ``spherical`` (default: the optimizer's ``encoding``
            attribute, else cartesian; SPSO uses the spherical one).
        **params: optimizer hyperparameters (e.g. ``pop_size=500``).
    """

    def __init__(
        self,
        algorithm: str,
        n_waypoints: int | None = None,
        cost: str | None = None,
        weights: dict[str, float] | None = None,
        track_feasibility: bool = False,
        encoding: str | None = None,
        **params: Any,
    ) -> None:
        self.algorithm = algorithm.lower()
        self.name = self.algorithm  # type: ignore[misc]
        self.optimizer_cls = optimizers.get(self.algorithm)
        known = {f.name for f in fields(self.optimizer_cls.Config)}
        unknown = set(params) - known
        if unknown:
            raise PlannerError(
                f"{self.algorithm}: unknown parameter(s) {sorted(unknown)}; known: {sorted(known)}"
            )
        self.config = self.optimizer_cls.Config(**params)
        self.explicit = dict(params)
        self.n_waypoints = n_waypoints
        self.cost = cost
        self.weights = weights
        self.track_feasibility = track_feasibility
        self.encoding = str(encoding or getattr(self.optimizer_cls, "encoding", "cartesian"))
        if self.encoding not in ENCODINGS:
            raise PlannerError(
                f"unknown encoding {self.encoding!r}; choose from {sorted(ENCODINGS)}"
            )

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.algorithm,
            "encoding": self.encoding,
            "n_waypoints": self.n_waypoints,
            "cost": self.cost,
            "weights": self.weights,
            **config_dict(self.config),
        }

    def _plan(
        self,
        scenario: Scenario,
        task: Task,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> PlanResult:
        problem = PathProblem(scenario, task, cost=self.cost, weights=self.weights)
        enc = ENCODINGS[self.encoding](problem, self.n_waypoints, self.track_feasibility)
        config = optimizers.base.fit_schedule(
            self.config, budget or DEFAULT_ITERATIONS, self.explicit
        )
        opt = self.optimizer_cls(enc, config, seed=seed)

        def cb(o: optimizers.Optimizer) -> bool:
            return bool(callback(o.iterations, o.best_f)) if callback else False

        res = optimizers.run(opt, budget if budget is not None else DEFAULT_ITERATIONS, seed, cb)
        path = enc.decode(res.x[None])
        ev = problem.evaluate(path)
        times = problem.times(path)[0]
        return PlanResult(
            uav_id=task.id,
            waypoints=path[0],
            times=times,
            cost=float(ev.cost[0]),
            terms={k: float(v[0]) for k, v in ev.terms.items()},
            feasible=bool(ev.feasible[0]),
            evaluations=res.evaluations,
            iterations=res.iterations,
            wall_time=res.wall_time,
            history=res.history,
            evaluations_history=res.evaluations_history,
            algorithm=self.algorithm,
            config=self.describe(),
            seed=seed,
            cost_model=problem.cost_name,
            violations=tuple(k for k, v in ev.violations.items() if v[0]),
            feasible_history=np.asarray(enc.feasible_history),
            first_feasible_iteration=_first_finite(enc.feasible_history),
        )


def _first_finite(history: list[float]) -> int | None:
    """1-based index of the first finite entry, or None."""
    finite = np.flatnonzero(np.isfinite(np.asarray(history, dtype=np.float64)))
    return int(finite[0]) + 1 if len(finite) else None


def register_all() -> None:
    """Register an optimizer planner for every registered optimizer not yet a planner."""
    for name in optimizers.available():
        if name not in _REGISTRY:
            register_planner(name, lambda _n=name, **kw: OptimizerPlanner(_n, **kw))
