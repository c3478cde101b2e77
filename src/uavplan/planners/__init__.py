"""Planners: ``plan(scenario, task, budget, seed) -> PlanResult``, found by name.

Importing this package imports every module in it, each planner module registering its
planners (:func:`~uavplan.planners.core.base.register_planner`): a new planner is a new module.
See :mod:`uavplan.planners.core.base` for the framework and ``docs/extending.md`` for an example.
"""

from __future__ import annotations

from typing import Any

from uavplan._discovery import import_submodules
from uavplan.planners.core.base import FleetPlanner, Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, PlannerError, describe_options, option
from uavplan.planners.core.registry import PlannerEntry, register_planner, registry
from uavplan.planners.core.results import FleetResult, PlanResult
from uavplan.planners.core.run import Outcome, Run
from uavplan.planners.population.optimizer_planner import OptimizerPlanner

import_submodules(__name__, __path__)  # registers every planner module's planners

__all__ = [
    "FleetPlanner",
    "FleetResult",
    "OptimizerPlanner",
    "Outcome",
    "PlanResult",
    "Planner",
    "PlannerConfig",
    "PlannerEntry",
    "PlannerError",
    "PlannerSpecs",
    "Run",
    "available_planners",
    "describe_options",
    "get_planner",
    "option",
    "planner_entry",
    "register_planner",
]


def available_planners() -> list[str]:
    """Names of the registered planners, sorted."""
    return sorted(registry())


def planner_entry(name: str) -> PlannerEntry:
    """The registry entry of ``name`` (its class, fixed options and summary)."""
    try:
        return registry()[name.lower()]
    except KeyError:
        raise PlannerError(f"unknown planner {name!r}; available: {available_planners()}") from None


def get_planner(name: str, **options: Any) -> Planner:
    """A planner by name; ``options`` configure it (e.g. ``pop_size=300``), checked against
    its config (unknown options and values out of range are refused, naming the valid ones)."""
    return planner_entry(name)(**options)
