"""Plan files (``plan.json``): the one place their format is written."""

from __future__ import annotations

import platform
from pathlib import Path
from typing import Any

from uavplan import __version__
from uavplan.io.atomic import write_json_atomic
from uavplan.planners.fleet_plan import FleetPlan

PLAN_FORMAT = "uavplan.plan/1"


def plan_document(plan: FleetPlan) -> dict[str, Any]:
    """The JSON-ready ``plan.json`` of a plan."""
    return {
        "format": PLAN_FORMAT,
        "scenario": plan.scenario.name,
        "algorithm": plan.algorithm,
        "config": plan.config,
        "seed": plan.seed,
        "version": __version__,
        "python": platform.python_version(),
        "frame": "local ENU metres: x east, y north, z up (absolute altitude)",
        "separation_checked": plan.fleet is not None,
        **({"fleet": plan.fleet.to_dict()} if plan.fleet is not None else {}),
        "uavs": [r.to_dict() for r in plan.results],
    }


def write_plan_file(plan: FleetPlan, path: str | Path) -> Path:
    """Write ``plan``'s ``plan.json`` to ``path`` atomically."""
    return write_json_atomic(Path(path), plan_document(plan))
