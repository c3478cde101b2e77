"""What ``uavplan plan`` does: a :class:`Strategy` per kind of scenario (:data:`TABLE`,
:func:`strategy_for`), carried out by :func:`execute` (every attempt returned), in the world
:func:`planning_world` makes of the scenario under its execution model. The CLI's ``plan``,
``demo`` and ``fly`` and the ``strategy`` run kind of the experiments use it, so what a user
gets is one table and one function."""

from uavplan.strategy.execute import Attempt, Outcome, best_plan, execute, run_seeds
from uavplan.strategy.table import (
    TABLE,
    ScenarioKind,
    Strategy,
    chosen,
    fallbacks_for,
    scenario_kind,
    strategy_for,
)
from uavplan.strategy.world import PlanningWorld, WorldProblem, planning_world

__all__ = [
    "TABLE",
    "Attempt",
    "Outcome",
    "PlanningWorld",
    "ScenarioKind",
    "Strategy",
    "WorldProblem",
    "best_plan",
    "chosen",
    "execute",
    "fallbacks_for",
    "planning_world",
    "run_seeds",
    "scenario_kind",
    "strategy_for",
]
