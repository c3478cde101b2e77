"""Planner options: a config field declared with :func:`option` (documentation, range,
choices; ``uavplan.params``), checked by :class:`Options` when a config is built; the errors
planners raise."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uavplan.params import bad_value, check_fields, describe_options, option, type_hints

FloatArray = NDArray[np.float64]


class PlannerError(ValueError):
    """Unknown planner, bad configuration, or a task it cannot handle."""


class OptionError(PlannerError):
    """An option value out of its declared range, choices or type."""

    def __init__(self, option: str, why: str) -> None:
        self.option = option
        self.why = why
        super().__init__(f"option {option} {why}")


@dataclass(frozen=True)
class Options:
    """Base of every planner configuration: checks each field against its :func:`option`
    declaration (type, range, choices) when built; ints given for numbers become floats."""

    def __post_init__(self) -> None:
        bad = check_fields(self)
        if bad is not None:
            raise OptionError(*bad)


@dataclass(frozen=True)
class PlannerConfig(Options):
    """Options every single-UAV planner has."""

    cost: str | None = option(None, "cost preset (default: the scenario's)")
    weights: dict[str, float] | None = option(None, "cost term weight overrides, by term name")
    track_feasibility: bool = option(
        True,
        "record the best feasible cost after every iteration (feasible_history, "
        "first_feasible_iteration); optimizer planners then check every candidate's feasibility",
    )
    flight_check: bool = option(
        False,
        "search against the flight's own check: the altitude band along whole segments, as the "
        "declared flight is checked (default: at the waypoints, the SPSO paper's rule)",
    )


@dataclass(frozen=True)
class FleetPlannerConfig(Options):
    """Base of the fleet planners' configurations."""


__all__ = [
    "FleetPlannerConfig",
    "OptionError",
    "Options",
    "PlannerConfig",
    "PlannerError",
    "bad_value",
    "describe_options",
    "option",
    "type_hints",
]
