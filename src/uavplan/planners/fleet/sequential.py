"""A single-UAV planner on a scenario with several UAVs: the prioritized frame around it.

:func:`plan_sequentially` plans the UAVs one at a time, longest straight line first (PPSwarm's
LH order), each with the planner's own search against a reservation table of the flights of
the UAVs planned before it (the search then sees PPSwarm's F5: a path that comes closer than
S2 to a reserved UAV at some instant costs infinity), and reserves the flight it declares
(:mod:`uavplan.planners.core.flight`), so that separation holds between the trajectories that will
be flown. A planner whose search cannot see other UAVs (``supports_reservations`` false:
RRT*, the RGG) is refused with a message naming the planners that can.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from uavplan.compile_clock import Stopwatch
from uavplan.optimizers.base import Budget
from uavplan.planners.core.base import Planner
from uavplan.planners.core.options import PlannerError
from uavplan.planners.core.registry import registry
from uavplan.planners.core.results import FleetResult, PlanResult
from uavplan.planners.core.run import ProgressCallback
from uavplan.world.geometry import as_3d
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario
from uavplan.world.tolerances import RESERVE_TOL


def separating_planners() -> list[str]:
    """The single-UAV planners whose search keeps clear of other UAVs, and the fleet ones."""
    return sorted(n for n, e in registry().items() if e.fleet or e.cls.specs.supports_reservations)


def task_seeds(seed: int | None, n: int) -> list[int | None]:
    """One seed per task derived from the root ``seed`` (SeedSequence), or None."""
    if seed is None:
        return [None] * n
    return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(n)]


def plan_sequentially(
    planner: Planner,
    scenario: Scenario,
    budget: Budget | int | None = None,
    seed: int | None = None,
    progress: Callable[[str], ProgressCallback | None] | None = None,
    dt: float = 1.0,
) -> FleetResult:
    """Plan every task of ``scenario`` with ``planner`` in LH order, each UAV clear of the
    flights of those before it (see the module docstring). ``progress(task_id)`` gives each
    task's callback."""
    if not planner.specs.supports_reservations:
        raise PlannerError(
            f"{planner.name} plans one UAV and cannot keep clear of others while it searches; "
            f"{scenario.name!r} has {len(scenario.tasks)} UAVs: plan it with one of "
            f"{', '.join(separating_planners())}"
        )
    clock = Stopwatch()  # kernel compilation left out
    tasks = scenario.tasks
    seeds = task_seeds(seed, len(tasks))
    straight = [float(np.linalg.norm(np.subtract(t.goal, t.start))) for t in tasks]
    order = [int(i) for i in np.argsort(-np.asarray(straight), kind="stable")]
    table = ReservationTable.for_scenario(scenario, dt=dt)
    results: dict[int, PlanResult] = {}
    for m in order:
        task = tasks[m]
        cb = progress(task.id) if progress else None
        r = planner.plan(scenario, task, budget, seeds[m], cb, reservations=table)
        pts, ts = r.flown_trajectory()
        table.add(task.id, as_3d(pts), ts, RESERVE_TOL if r.flown_kind == "smoothed" else 0.0)
        results[m] = r
    out = tuple(results[m] for m in range(len(tasks)))
    planned = all(r.feasible for r in out)
    flown = all(r.flown_feasible for r in out)
    total = float(sum(r.cost for r in out))
    return FleetResult(
        results=out,
        priority=tuple(tasks[m].id for m in order),
        cost=total if flown else math.inf,
        flown_feasible=all(r.flown_feasible for r in out),
        planned_feasible=planned,
        history=np.zeros(0),
        restart_costs=np.asarray([total if planned else math.inf]),
        wall_time=clock.elapsed,
        algorithm=planner.name,
        config=planner.describe(),
        seed=seed,
        info={"frame": "sequential", "order": "lh", "separated": "flights"},
    )
