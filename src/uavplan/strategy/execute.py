"""Carry out a :class:`~uavplan.strategy.table.Strategy` (:func:`execute`): its runs and the
other planners, the best plan kept (:func:`best_plan`), then its fallbacks in order while the
kept plan does not fly. Every attempt is returned (:class:`Attempt`), the kept one marked;
nothing is printed."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from uavplan.strategy.table import Strategy

if TYPE_CHECKING:
    from uavplan.optimizers.base import Budget
    from uavplan.planners.core.run import ProgressCallback
    from uavplan.planners.fleet.fleet_plan import FleetPlan
    from uavplan.world.scenario import Scenario

#: What an attempt was: a run of the strategy's planner, another planner run once beside it,
#: or a fallback tried because the kept plan did not fly.
Role = Literal["run", "also", "fallback"]


@dataclass(frozen=True)
class Attempt:
    """One planner run of a strategy: its ``role``, ``planner`` and root ``seed``, and the
    ``plan`` it made."""

    role: Role
    planner: str
    seed: int
    plan: FleetPlan

    @property
    def flies(self) -> bool:
        """Every UAV's flown trajectory passes every check."""
        return bool(self.plan.feasible)

    @property
    def cost(self) -> float:
        """The plan's total cost under the scenario's objective."""
        return float(sum(r.cost for r in self.plan.results))


@dataclass(frozen=True)
class Outcome:
    """What a strategy made: the ``plan`` kept (the kept attempt's, its story starting with the
    attempts when there were several), every attempt in order, which one was kept (``kept``)
    and which was the best of the runs and other planners (``best``: the kept one unless a
    fallback was)."""

    strategy: Strategy
    plan: FleetPlan
    attempts: tuple[Attempt, ...]
    kept: int
    best: int

    @property
    def competing(self) -> tuple[Attempt, ...]:
        """The runs and other planners the first choice was made among."""
        return tuple(a for a in self.attempts if a.role != "fallback")

    @property
    def fallbacks(self) -> tuple[Attempt, ...]:
        return tuple(a for a in self.attempts if a.role == "fallback")


def run_seeds(seed: int, runs: int) -> list[int]:
    """The root seeds of ``runs`` independent runs: ``seed`` itself first (so one run is
    ``-a NAME --seed SEED``), then seeds spawned from it (``SeedSequence(seed).spawn``), each
    printed so that any run can be made alone."""
    spawned = np.random.SeedSequence(seed).spawn(max(runs - 1, 0))
    return [int(seed)] + [int(ss.generate_state(1)[0]) for ss in spawned]


def best_plan(plans: Sequence[FleetPlan]) -> FleetPlan:
    """The best of several plans of one scenario: one that flies (every UAV's flown trajectory
    passes every check) before one that does not, then the lowest total cost under the
    scenario's own objective, then the first."""

    def key(k: int) -> tuple[bool, float, int]:
        p = plans[k]
        cost = float(sum(r.cost for r in p.results))
        return (not p.feasible, cost if np.isfinite(cost) else np.inf, k)

    return plans[min(range(len(plans)), key=key)]


#: ``progress(uav, planner)``: the progress callback of one UAV's (or ``"fleet"``'s) search.
ProgressFactory = Callable[[str, str], "ProgressCallback | None"]


def execute(
    strategy: Strategy,
    scenario: Scenario,
    budget: Budget | int | None,
    seed: int,
    progress: ProgressFactory | None = None,
) -> Outcome:
    """Carry out ``strategy`` on ``scenario`` from the root ``seed``: ``strategy.runs`` runs of
    its planner (:func:`run_seeds`) and each of ``strategy.also`` once, the best kept
    (:func:`best_plan`); while the kept plan does not fly, each fallback once, the first that
    flies kept. Repair after planning as ``strategy.repair`` says
    (:func:`~uavplan.planners.fleet.fleet_plan.plan_all`'s ``polish``: the same for every fleet).
    Raises what the planners raise (ValueError for a scenario they refuse)."""
    from uavplan.planners import get_planner

    attempts: list[Attempt] = []

    def attempt(role: Role, name: str, options: Mapping[str, Any], root: int) -> Attempt:
        from uavplan.planners.fleet.fleet_plan import plan_all

        planner = get_planner(name, **dict(options))
        cb = (lambda uav: progress(uav, name)) if progress is not None else None
        plan = plan_all(scenario, planner, budget, root, cb, polish=strategy.repair)
        a = Attempt(role, name, root, plan)
        attempts.append(a)
        return a

    for s in run_seeds(seed, strategy.runs):
        attempt("run", strategy.planner, strategy.options, s)
    for name in strategy.also:
        attempt("also", name, {}, seed)
    plans = [a.plan for a in attempts]
    kept_plan = best_plan(plans)
    kept = best = next(i for i, a in enumerate(attempts) if a.plan is kept_plan)
    if not kept_plan.feasible:
        for name, extra in strategy.fallbacks:
            a = attempt("fallback", name, {**extra, **strategy.options}, seed)
            if a.flies:
                kept = len(attempts) - 1
                break
    plan = attempts[kept].plan
    if len(attempts) > 1:  # the plan's story starts with the attempts
        from uavplan.planners.core.events import Event

        told = tuple(Event("attempt", None, f"{a.role}: {a.planner} seed {a.seed}: cost "
                           f"{a.cost:.6g}, {'flies' if a.flies else 'does not fly'}"
                           + (" (kept)" if i == kept else ""), a.cost)
                     for i, a in enumerate(attempts))  # fmt: skip
        plan = dataclasses.replace(plan, events=told + plan.events)
    return Outcome(strategy, plan, tuple(attempts), kept, best)
