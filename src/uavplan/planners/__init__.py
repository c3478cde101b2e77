"""Planners: ``plan(scenario, task, budget, seed) -> PlanResult``, found by name."""

from uavplan.planners.base import (
    Planner,
    PlannerError,
    PlanResult,
    available_planners,
    get_planner,
    register_planner,
)
from uavplan.planners.optimizer_planner import OptimizerPlanner

__all__ = [
    "OptimizerPlanner",
    "PlanResult",
    "Planner",
    "PlannerError",
    "available_planners",
    "get_planner",
    "register_planner",
]
