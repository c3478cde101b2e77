"""Plan every task of a scenario: one by one with a single-UAV planner, or together with a fleet
planner (:func:`plan_all`); the plans of all tasks as one :class:`FleetPlan`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from uavplan.optimizers.base import Budget
from uavplan.planners.core.base import FleetPlanner, Planner
from uavplan.planners.core.events import Event
from uavplan.planners.core.options import PlannerError
from uavplan.planners.core.results import FleetResult, PlanResult
from uavplan.planners.core.run import ProgressCallback
from uavplan.planners.fleet.sequential import plan_sequentially, task_seeds
from uavplan.planners.polish import polished
from uavplan.problems.work import Work
from uavplan.world.scenario import Scenario


@dataclass(frozen=True)
class FleetPlan:
    """Plans for every task of a scenario. With several UAVs they are planned together, by a
    :class:`FleetPlanner` or by a single-UAV planner in the prioritized frame
    (:func:`~uavplan.planners.fleet.sequential.plan_sequentially`): ``fleet`` then holds the
    fleet-level result and feasibility includes the separation between UAVs. ``events``: what
    happened around the planner (a strategy's attempts, :mod:`uavplan.planners.core.events`); the
    UAVs' own are read from the results."""

    scenario: Scenario
    algorithm: str
    config: dict[str, Any]
    seed: int | None
    results: tuple[PlanResult, ...]
    fleet: FleetResult | None = None
    events: tuple[Event, ...] = ()

    @property
    def feasible(self) -> bool:
        """The plan's guarantee: every UAV's flown trajectory passes every check."""
        if self.fleet is not None:
            return bool(self.fleet.flown_feasible)
        return all(r.flown_feasible for r in self.results)

    @property
    def work(self) -> dict[str, int]:
        """What planning computed (:mod:`uavplan.problems.work`): the fleet planner's count,
        else the sum of the UAVs' runs' (zeros where nothing was counted)."""
        if self.fleet is not None and "work" in self.fleet.info:
            return dict(self.fleet.info["work"])
        total = Work()
        for r in self.results:
            total.add(Work(**(r.info or {}).get("work", {})))
        return total.record()

    def diagnostics(self) -> dict[str, Any]:
        """``plan.json``'s ``diagnostics``: :attr:`events`, then the UAVs' and the restarts'
        (:func:`~uavplan.planners.core.events.plan_events`)."""
        from uavplan.planners.core.events import diagnostics, plan_events

        return diagnostics((*self.events, *plan_events(self)))

    @property
    def planned_feasible(self) -> bool:
        """Every planned polyline is feasible (separation from the others included)."""
        if self.fleet is not None:
            return bool(self.fleet.planned_feasible)
        return all(r.feasible for r in self.results)


def plan_all(
    scenario: Scenario,
    planner: Planner,
    budget: Budget | int | None,
    seed: int | None,
    progress: Callable[[str], ProgressCallback | None] | None = None,
    tasks: Sequence[str] | None = None,
    polish: bool = False,
) -> FleetPlan:
    """Plan every task (or those named in ``tasks``): one with any planner; several together,
    with a :class:`FleetPlanner` (``progress`` then gets the key ``"fleet"``) or with a
    single-UAV planner in the prioritized frame (refused, naming the planners that can, for a
    planner whose search cannot keep clear of other UAVs). Never several UAVs planned alone.
    ``polish``: a single UAV's path is shortened by line of sight where that keeps it feasible
    and costs no more (:meth:`Planner.plan`); a fleet's looping or failing UAVs (a fleet
    planner's, or a single-UAV planner's in the prioritized frame) are repaired one by one
    against all the others' flights
    (:func:`~uavplan.planners.fleet.fleet_polish.polish_fleet`)."""
    if isinstance(planner, FleetPlanner):
        cb = progress("fleet") if progress else None
        fr = planner.plan_fleet(scenario, budget, seed, cb, tuple(tasks) if tasks else None)
        if polish and len(fr.results) > 1:
            from uavplan.planners.fleet.fleet_polish import polish_fleet

            fr = polish_fleet(scenario, fr, seed, planner.describe())
        return FleetPlan(scenario, planner.name, planner.describe(), seed, fr.results, fr)
    chosen = tuple(t for t in scenario.tasks if tasks is None or t.id in tasks)
    if not chosen:
        raise PlannerError(f"none of the tasks {list(tasks or [])} is in {scenario.name!r}")
    if len(chosen) == 1:
        cb = progress(chosen[0].id) if progress else None
        how = polished if polish else None
        r = planner.plan(scenario, chosen[0], budget, task_seeds(seed, 1)[0], cb, polish=how)
        return FleetPlan(scenario, planner.name, planner.describe(), seed, (r,))
    sc = dataclasses.replace(scenario, tasks=chosen)
    fr = plan_sequentially(planner, sc, budget, seed, progress)
    if polish:  # the same repair as a fleet planner's: a failing UAV re-planned against all
        from uavplan.planners.fleet.fleet_polish import polish_fleet

        # the table's buckets as plan_sequentially's (a planner's own dt is its time step)
        fr = polish_fleet(sc, fr, seed, {**planner.describe(), "dt": 1.0})
    return FleetPlan(sc, planner.name, planner.describe(), seed, fr.results, fr)
