"""Plan every task of a scenario: one by one with a single-UAV planner, or together with a fleet
planner (:func:`plan_all`); the plans of all tasks as one :class:`FleetPlan`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from uavplan.optimizers.base import Budget
from uavplan.planners.base import FleetPlanner, Planner
from uavplan.planners.results import FleetResult, PlanResult
from uavplan.planners.run import ProgressCallback
from uavplan.world.scenario import Scenario


@dataclass(frozen=True)
class FleetPlan:
    """Plans for every task of a scenario: planned one by one by a single-UAV planner, or
    together by a :class:`FleetPlanner` (then ``fleet`` holds its fleet-level result, and
    feasibility includes the separation between UAVs)."""

    scenario: Scenario
    algorithm: str
    config: dict[str, Any]
    seed: int | None
    results: tuple[PlanResult, ...]
    fleet: FleetResult | None = None

    @property
    def feasible(self) -> bool:
        if self.fleet is not None:
            return bool(self.fleet.feasible)
        return all(r.feasible for r in self.results)


def task_seeds(seed: int | None, n: int) -> list[int | None]:
    """One seed per task derived from the root ``seed`` (SeedSequence), or None."""
    if seed is None:
        return [None] * n
    return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(n)]


def plan_all(
    scenario: Scenario,
    planner: Planner,
    budget: Budget | int | None,
    seed: int | None,
    progress: Callable[[str], ProgressCallback | None] | None = None,
    tasks: Sequence[str] | None = None,
) -> FleetPlan:
    """Plan each task (or those named in ``tasks``) independently, or the whole fleet at once
    with a :class:`FleetPlanner` (``progress`` then gets the key ``"fleet"``)."""
    if isinstance(planner, FleetPlanner):
        cb = progress("fleet") if progress else None
        fr = planner.plan_fleet(scenario, budget, seed, cb, tuple(tasks) if tasks else None)
        return FleetPlan(scenario, planner.name, planner.describe(), seed, fr.results, fr)
    chosen = [t for t in scenario.tasks if tasks is None or t.id in tasks]
    results = []
    for task, s in zip(chosen, task_seeds(seed, len(chosen)), strict=True):
        cb = progress(task.id) if progress else None
        results.append(planner.plan(scenario, task, budget, s, cb))
    return FleetPlan(scenario, planner.name, planner.describe(), seed, tuple(results))
