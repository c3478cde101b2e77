"""``uavplan export PLAN --format NAME --out PATH``: a plan in a mission format
(:mod:`uavplan.io.missions`). By default each UAV's flown trajectory, the one the plan declares
and the verifier checks; ``--polylines`` or ``--smoothed`` export the planned polylines or the
informative smoothed paths instead, with a warning that they are not what the plan guarantees.
A plan that is not feasible, or does not say, is still written but the command says so on
stderr and exits 1."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from uavplan.cli._common import err, fail, out

if TYPE_CHECKING:
    from uavplan.io.plan_file import TrajectoryKind


def export(
    plan_file: Annotated[Path | None, typer.Argument(help="A plan.json (or its folder).")] = None,
    fmt: Annotated[str, typer.Option("--format", "-f", help="Export format (--list).")] = "csv",
    out_path: Annotated[
        Path | None, typer.Option("--out", "-o", help="Output file (folder for per-UAV formats).")
    ] = None,
    smoothed: Annotated[
        bool, typer.Option("--smoothed", help="Export the informative smoothed paths.")
    ] = False,
    polylines: Annotated[
        bool, typer.Option("--polylines", help="Export the planned polylines.")
    ] = False,
    list_formats: Annotated[bool, typer.Option("--list", help="List the formats.")] = False,
) -> None:
    """Write PLAN_FILE's trajectories in a mission format: each UAV's flown trajectory (the
    one the plan declares and guarantees) unless --polylines or --smoothed."""
    from uavplan.io.missions import ExportError, exporters, get_exporter
    from uavplan.io.plan_file import PlanFormatError, plan_path, read_plan_file

    if list_formats:
        for e in exporters().values():
            out.print(f"{e.name} ({e.suffix}{', one file per UAV' if e.per_uav else ''}): "
                      f"{e.description}")  # fmt: skip
        return
    if plan_file is None:
        raise fail("export: give a PLAN_FILE (or --list)")
    if smoothed and polylines:
        raise fail("export: --smoothed and --polylines: give at most one")
    kind: TrajectoryKind = "smoothed" if smoothed else ("planned" if polylines else "flown")
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
    if kind != "flown":
        what = "smoothed paths" if smoothed else "planned polylines"
        err.print(f"WARNING: {plan.source}: exported the {what}, not the flown trajectories "
                  "the plan declares and was verified for")  # fmt: skip
    if plan.feasible is not True:
        state = "not feasible" if plan.feasible is False else "of unknown feasibility"
        err.print(f"WARNING: {plan.source}: the plan is {state}; do not fly it as it is")
        raise typer.Exit(1)
