"""``uavplan export PLAN --format NAME --out PATH``: a plan in a mission format
(:mod:`uavplan.io.missions`). A plan that is not feasible, or does not say, is still written but
the command says so on stderr and exits 1."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from uavplan.cli._common import err, fail, out


def export(
    plan_file: Annotated[Path | None, typer.Argument(help="A plan.json (or its folder).")] = None,
    fmt: Annotated[str, typer.Option("--format", "-f", help="Export format (--list).")] = "csv",
    out_path: Annotated[
        Path | None, typer.Option("--out", "-o", help="Output file (folder for per-UAV formats).")
    ] = None,
    smoothed: Annotated[
        bool, typer.Option("--smoothed", help="Export the smoothed trajectories.")
    ] = False,
    list_formats: Annotated[bool, typer.Option("--list", help="List the formats.")] = False,
) -> None:
    """Write PLAN_FILE's trajectories in a mission format."""
    from uavplan.io.missions import ExportError, exporters, get_exporter
    from uavplan.io.plan_file import PlanFormatError, plan_path, read_plan_file

    if list_formats:
        for e in exporters().values():
            out.print(f"{e.name} ({e.suffix}{', one file per UAV' if e.per_uav else ''}): "
                      f"{e.description}")  # fmt: skip
        return
    if plan_file is None:
        raise fail("export: give a PLAN_FILE (or --list)")
    kind: Literal["planned", "smoothed"] = "smoothed" if smoothed else "planned"
    try:
        exporter = get_exporter(fmt)
        plan = read_plan_file(plan_file)
        target = out_path or plan_path(plan_file).with_suffix(exporter.suffix)
        if exporter.per_uav:
            target.mkdir(parents=True, exist_ok=True)
        written = exporter.write(plan, target, kind)
    except (ExportError, PlanFormatError) as exc:
        raise fail(str(exc).splitlines()[0]) from None
    except OSError as exc:
        raise fail(f"--out {out_path}: cannot write: {exc}") from None
    for p in written:
        out.print(f"wrote {p}")
    if plan.feasible is not True:
        state = "not feasible" if plan.feasible is False else "of unknown feasibility"
        err.print(f"WARNING: {plan.source}: the plan is {state}; do not fly it as it is")
        raise typer.Exit(1)
