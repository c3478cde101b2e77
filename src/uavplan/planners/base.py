"""Planner interface: ``plan(scenario, task, budget, seed) -> PlanResult``, and a registry.

A planner turns one task of a scenario into a path (OMPL's ``Planner::solve``). Planners never
print, plot or read files; they report progress through an optional callback.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]

#: Progress callback: (iteration, best cost so far) -> True to stop early.
ProgressCallback = Callable[[int, float], bool | None]


class PlannerError(ValueError):
    """Unknown planner, bad configuration, or a task it cannot handle."""


@dataclass(frozen=True)
class PlanResult:
    """One UAV's planned path and how it was found.

    Attributes:
        uav_id: the task id.
        waypoints: (n, dim) metres, start and goal included.
        times: (n,) seconds at the UAV's speed from the task's start time.
        cost: total cost under the planner's cost model; terms: each term's raw value.
        feasible: decided on continuous segments (see PathProblem).
        evaluations, iterations, wall_time (s), history: best-so-far cost per iteration.
        algorithm, config, seed, cost_model: what produced it.
        feasible_history: best cost among feasible candidates so far, per iteration (inf
            before the first feasible one); empty when the planner did not track it.
        evaluations_history: evaluations used after each iteration (for plots against
            evaluations, the fair axis between algorithms).
        first_feasible_iteration: the 1-based iteration in which a feasible candidate was first
            evaluated (RGG-PSO+'s F-Measure counts the iterations before it), None if never or
            not tracked.
    """

    uav_id: str
    waypoints: FloatArray
    times: FloatArray
    cost: float
    terms: dict[str, float]
    feasible: bool
    evaluations: int
    iterations: int
    wall_time: float
    history: FloatArray
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    cost_model: str = ""
    violations: tuple[str, ...] = ()
    feasible_history: FloatArray = field(default_factory=lambda: np.zeros(0))
    first_feasible_iteration: int | None = None
    evaluations_history: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64)
    )

    @property
    def length(self) -> float:
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the per-UAV record of ``plan.json``)."""
        return {
            "id": self.uav_id,
            "waypoints": np.asarray(self.waypoints).round(6).tolist(),
            "times": np.asarray(self.times).round(6).tolist(),
            "cost": _num(self.cost),
            "terms": {k: _num(v) for k, v in self.terms.items()},
            "feasible": bool(self.feasible),
            "violations": list(self.violations),
            "length": self.length,
            "evaluations": int(self.evaluations),
            "iterations": int(self.iterations),
            "wall_time": float(self.wall_time),
            "history": [_num(v) for v in np.asarray(self.history)],
            "first_feasible_iteration": self.first_feasible_iteration,
        }


def _num(v: float) -> float | str:
    """JSON has no infinity: write it as the string "inf"."""
    v = float(v)
    return v if np.isfinite(v) else ("inf" if v > 0 else ("-inf" if v < 0 else "nan"))


class Planner(ABC):
    """Plans one task. Subclasses set ``name`` and implement :meth:`_plan`."""

    name: ClassVar[str] = "planner"

    def plan(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
    ) -> PlanResult:
        """Plan ``task`` (default: the first) of ``scenario`` within ``budget`` from ``seed``."""
        t = task if isinstance(task, Task) else scenario.task(task)
        t0 = time.perf_counter()
        result = self._plan(scenario, t, budget, seed, callback)
        if result.wall_time <= 0:
            object.__setattr__(result, "wall_time", time.perf_counter() - t0)
        return result

    @abstractmethod
    def _plan(
        self,
        scenario: Scenario,
        task: Task,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> PlanResult: ...

    def describe(self) -> dict[str, Any]:
        return {"name": self.name}


_REGISTRY: dict[str, Callable[..., Planner]] = {}


def register_planner(name: str, factory: Callable[..., Planner]) -> None:
    key = name.lower()
    if key in _REGISTRY:
        raise PlannerError(f"planner {key!r} is already registered")
    _REGISTRY[key] = factory


def available_planners() -> list[str]:
    _load_builtins()
    return sorted(_REGISTRY)


def get_planner(name: str, **options: Any) -> Planner:
    """A planner by name; ``options`` go to its constructor (e.g. ``pop_size=300``)."""
    _load_builtins()
    try:
        factory = _REGISTRY[name.lower()]
    except KeyError:
        raise PlannerError(f"unknown planner {name!r}; available: {available_planners()}") from None
    return factory(**options)


def _load_builtins() -> None:
    from uavplan.planners import optimizer_planner, rgg_pso

    optimizer_planner.register_all()
    rgg_pso.register_all()
