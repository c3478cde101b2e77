"""``uavplan schema plan|scenario``: the JSON Schema of plan files or of scenario files."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from uavplan.cli._common import fail

KINDS = ("plan", "scenario")


def schema(
    kind: Annotated[str, typer.Argument(help="plan (plan.json) or scenario (scenario files).")],
) -> None:
    """Print the JSON Schema of plan files or scenario files."""
    if kind == "plan":
        from uavplan.io.plan_file import plan_schema

        typer.echo(json.dumps(plan_schema(), indent=2))
    elif kind == "scenario":
        from uavplan.io.scenario_file import schema as scenario_schema

        typer.echo(json.dumps(scenario_schema(), indent=2))
    else:
        raise fail(f"schema: {kind!r} is not one of {list(KINDS)}")
