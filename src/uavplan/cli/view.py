"""``uavplan view PLAN [SCENARIO] [--out FILE]``: the plan as one self-contained HTML page
(:mod:`uavplan.viz.viewer`): terrain, obstacles, planned and flown paths, a time slider; opens
offline in any browser."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from uavplan.cli._common import fail, load_world, out


def view(
    plan_file: Annotated[Path, typer.Argument(help="A plan.json (or its folder).")],
    scenario: Annotated[
        str | None,
        typer.Argument(help="Its scenario (file or built-in name; default: the plan's)."),
    ] = None,
    out_path: Annotated[
        Path | None, typer.Option("--out", "-o", help="The page (default: beside the plan).")
    ] = None,
) -> None:
    """Write PLAN_FILE as an HTML page with the terrain, obstacles, paths and a time slider."""
    from uavplan.io.atomic import write_text_atomic
    from uavplan.io.plan_file import PlanFormatError, plan_path, read_plan_file
    from uavplan.viz.viewer import viewer_html

    try:
        plan = read_plan_file(plan_file)
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    name = scenario or plan.scenario
    world = None if name is None else load_world(name, quiet=scenario is None)
    if world is not None and world.dim != plan.dim:
        raise fail(f"{name}: a {world.dim}-D scenario for a {plan.dim}-D plan")
    target = out_path or plan_path(plan_file).with_suffix(".html")
    try:
        write_text_atomic(target, viewer_html(plan, world))
    except OSError as exc:
        raise fail(f"--out {target}: cannot write: {exc}") from None
    what = "" if world is not None else " (no scenario: paths only; give SCENARIO)"
    out.print(f"wrote {target}{what}")
