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
    #: a flyable version of ``waypoints`` (Dubins-smoothed dense polyline, (m, dim)), its times
    #: (m,) and whether it keeps every clearance (None: not smoothed)
    smoothed: FloatArray | None = None
    smoothed_times: FloatArray | None = None
    smoothed_ok: bool | None = None
    smoothed_violations: tuple[str, ...] = ()

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
            **(
                {
                    "smoothed": {
                        "points": np.asarray(self.smoothed).round(6).tolist(),
                        "times": np.asarray(self.smoothed_times).round(6).tolist(),
                        "clear": self.smoothed_ok,
                        "violations": list(self.smoothed_violations),
                    }
                }
                if self.smoothed is not None
                else {}
            ),
        }


def _num(v: float) -> float | str:
    """JSON has no infinity: write it as the string "inf"."""
    v = float(v)
    return v if np.isfinite(v) else ("inf" if v > 0 else ("-inf" if v < 0 else "nan"))


class Planner(ABC):
    """Plans one task. Subclasses set ``name`` and implement :meth:`_plan`."""

    name: ClassVar[str] = "planner"
    #: the scenario dimensions this planner handles (2-D scenes, 3-D worlds)
    dims: ClassVar[tuple[int, ...]] = (2, 3)

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
        if scenario.dim not in self.dims:
            raise PlannerError(
                f"{self.name} plans {' or '.join(f'{d}-D' for d in self.dims)} scenarios; "
                f"{scenario.name!r} is {scenario.dim}-D"
            )
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


@dataclass(frozen=True)
class FleetResult:
    """A whole fleet's plan from a :class:`FleetPlanner`.

    Attributes:
        results: one :class:`PlanResult` per task, in the scenario's task order.
        priority: task ids in the order they were planned in the kept solution.
        cost: total cost (sum of the UAVs' costs; inf if any is infeasible).
        feasible: every UAV feasible, including separation from the others.
        history: the fleet's cost per low-level iteration (see the planner's docs).
        restart_costs: the fleet cost after each restart.
        wall_time: seconds; info: planner-specific figures (timings, smoothing report).
    """

    results: tuple[PlanResult, ...]
    priority: tuple[str, ...]
    cost: float
    feasible: bool
    history: FloatArray
    restart_costs: FloatArray
    wall_time: float
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "priority": list(self.priority),
            "cost": _num(self.cost),
            "feasible": bool(self.feasible),
            "history": [_num(v) for v in np.asarray(self.history)],
            "restart_costs": [_num(v) for v in np.asarray(self.restart_costs)],
            "wall_time": float(self.wall_time),
            "info": self.info,
        }


class FleetPlanner(Planner):
    """Plans all tasks of a scenario together (UAV-UAV separation included).

    Subclasses implement :meth:`_plan_fleet`; planning a single task plans a fleet of one.
    """

    def plan_fleet(
        self,
        scenario: Scenario,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
        tasks: tuple[str, ...] | None = None,
    ) -> FleetResult:
        """Plan every task of ``scenario`` (or those named in ``tasks``)."""
        if scenario.dim not in self.dims:
            raise PlannerError(
                f"{self.name} cannot plan {scenario.dim}-D scenario {scenario.name!r}"
            )
        sc = scenario
        if tasks is not None:
            chosen = tuple(t for t in scenario.tasks if t.id in set(tasks))
            if not chosen:
                raise PlannerError(f"none of the tasks {list(tasks)} is in {scenario.name!r}")
            sc = _with_tasks(scenario, chosen)
        return self._plan_fleet(sc, budget, seed, callback)

    @abstractmethod
    def _plan_fleet(
        self,
        scenario: Scenario,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> FleetResult: ...

    def _plan(
        self,
        scenario: Scenario,
        task: Task,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> PlanResult:
        return self._plan_fleet(_with_tasks(scenario, (task,)), budget, seed, callback).results[0]


def _with_tasks(scenario: Scenario, tasks: tuple[Task, ...]) -> Scenario:
    import dataclasses

    return dataclasses.replace(scenario, tasks=tasks)


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
    from uavplan.planners import optimizer_planner, ppswarm, rgg_pso, rrt_star

    optimizer_planner.register_all()
    rgg_pso.register_all()
    rrt_star.register_all()
    ppswarm.register_all()
