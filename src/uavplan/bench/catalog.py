"""The catalog of experiment plans: every plan registered by the modules of
:mod:`uavplan.bench.papers` (one per paper), found by name (the CLI and the report use it)."""

from __future__ import annotations

from uavplan.bench import papers  # noqa: F401  (its modules register their plans)
from uavplan.bench.plans import ExperimentPlan, PlanError, registered_plans


def available_plans() -> list[str]:
    """Names of the built-in (and any other registered) plans, sorted."""
    return sorted(registered_plans())


def get_plan(name: str) -> ExperimentPlan:
    """The plan registered under ``name``."""
    plans = registered_plans()
    try:
        return plans[name]
    except KeyError:
        raise PlanError(f"unknown plan {name!r}; available: {sorted(plans)}") from None


def find_plan(name: str | None) -> ExperimentPlan | None:
    """The plan registered under ``name``, or None (a results folder of an unknown plan)."""
    return registered_plans().get(name) if name else None
