"""``uavplan verify PLAN SCENARIO``: check a plan independently of the planner.

Prints every violation, then a summary (UAVs, pairs checked, minimum separation, violations by
kind). Exit codes: 0 no violation, 1 some violation, 2 bad input (a missing or unreadable file,
invalid JSON, a missing or malformed field, mismatched lengths, an unusable scenario), reported on
stderr as one line naming the file, the field and the value, without a traceback. It checks each
UAV's flown trajectory with its kinematic limits by default, the planned polylines geometrically
with ``--polylines``, the informative smoothed paths with ``--smoothed``. What is checked:
:mod:`uavplan.verify` and ``docs/verify.md``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from uavplan.cli._common import fail, load_world

if TYPE_CHECKING:
    from uavplan.io.plan_file import TrajectoryKind
    from uavplan.verify import VerifyReport


def _m(v: float) -> str:
    return f"{v:.3f}".rstrip("0").rstrip(".") if v == v and abs(v) != float("inf") else str(v)


#: How the summary names what was checked.
_CHECKED = {
    "flown": "flown trajectories",
    "planned": "planned polylines",
    "smoothed": "smoothed paths",
}


def summary_lines(report: VerifyReport, plan_name: str) -> list[str]:
    """The summary printed after the violations, as plain text lines."""
    n = len(report.uav_ids)
    what = _CHECKED.get(report.trajectory, report.trajectory)
    limits = "with kinematic limits" if report.kinematics else "geometric, no kinematic limits"
    lines = [
        f"plan: {plan_name} against scenario {report.scenario}: {n} UAV{'s' * (n != 1)}, "
        f"{report.n_segments} segment{'s' * (report.n_segments != 1)} ({what}, {limits})"
    ]
    lines.append(
        f"pairs: {report.pairs_total}, {report.pairs_checked} checked exactly after pruning"
    )
    need = f"S2 {_m(report.s2)} m"
    if report.s2_axes is not None:
        box = "/".join(_m(x) for x in report.s2_axes)
        need = f"S2 per axis {box} m: scaled to the widest axis"
    if report.min_separation_pair is not None:
        a, b = report.min_separation_pair
        lines.append(
            f"min separation: {_m(report.min_separation)} m between {a} and {b} at "
            f"t={report.min_separation_time:.3f} s ({need})"
        )
    elif n > 1:
        lines.append(f"min separation: more than {need} (no pair came close)")
    if report.terrain_source is not None:
        lines.append(f"terrain: checked against the raster {report.terrain_source} itself (read "
                     "again through GDAL, not the planner's grid)")  # fmt: skip
    counts = {k: c for k, c in report.counts.items() if c}
    if counts:
        detail = ", ".join(f"{k} {c}" for k, c in counts.items())
        lines.append(f"violations: {len(report.violations)} ({detail})")
    else:
        lines.append("violations: none")
    return lines


def verify(
    plan_file: Annotated[
        Path, typer.Argument(help="A plan.json written by `uavplan plan` (or its folder).")
    ],
    scenario: Annotated[
        str, typer.Argument(help="A scenario file (.yaml/.json) or built-in name.")
    ],
    smoothed: Annotated[
        bool,
        typer.Option(
            "--smoothed",
            help="Verify each UAV's informative smoothed path (with kinematic limits) instead "
            "of its flown trajectory.",
        ),
    ] = False,
    polylines: Annotated[
        bool,
        typer.Option(
            "--polylines",
            help="Verify each UAV's planned polyline geometrically (clearances, separation, "
            "times, maximum speed; no turn, climb or minimum-speed limit) instead of its flown "
            "trajectory.",
        ),
    ] = False,
    max_show: Annotated[
        int, typer.Option("--max-show", help="Print at most this many violations (0: all).")
    ] = 0,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Also write the report to this JSON file.")
    ] = None,
) -> None:
    """Check PLAN_FILE against SCENARIO independently of the planner: UAV-UAV separation over
    continuous time, obstacles, terrain and altitude band along every segment, bounds, times and
    speed, and the UAV's kinematic limits (turn radius, climb and descent angles, minimum speed).
    By default each UAV's flown trajectory (its planned polyline where the plan declares none).
    Exit 0 if all pass, 1 on any violation, 2 on bad input."""
    from uavplan.io.atomic import strict_json
    from uavplan.io.plan_file import PlanFormatError, load_plan_json, parse_plan, plan_path
    from uavplan.verify import verify_trajectories
    from uavplan.verify.verifier import TRAJECTORIES

    if smoothed and polylines:
        raise fail("--smoothed and --polylines: give at most one")
    kind: TrajectoryKind = "smoothed" if smoothed else ("planned" if polylines else "flown")
    try:
        data = load_plan_json(plan_file)
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    world = load_world(scenario)
    assert world is not None
    shown = plan_path(plan_file)
    try:
        pf = parse_plan(data, world.dim, source=str(shown))
        trajs = pf.trajectories(kind)
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    from uavplan.verify.source_terrain import SourceError

    try:
        report = verify_trajectories(
            trajs,
            world,
            pf.scenario,
            smoothed=smoothed,
            kinematics=TRAJECTORIES[kind],
            trajectory=kind,
        )
    except SourceError as exc:
        raise fail(f"{scenario}: {exc}") from None

    out = Console(highlight=False, soft_wrap=True)
    limit = max_show if max_show > 0 else len(report.violations)
    for v in report.violations[:limit]:
        out.print(f"{v.kind}: {v.message}", markup=False)
    if len(report.violations) > limit:
        out.print(f"... and {len(report.violations) - limit} more (--max-show 0 shows all)")
    for w in report.warnings:
        out.print(f"warning: {w}", markup=False)
    for line in summary_lines(report, str(shown)):
        out.print(line, markup=False)
    out.print("[bold green]OK[/]" if report.ok else "[bold red]FAILED[/]")
    if json_out is not None:
        try:
            json_out.parent.mkdir(parents=True, exist_ok=True)
            doc = strict_json(report.to_dict())
            json_out.write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")
        except OSError as exc:
            raise fail(f"--json {json_out}: cannot write: {exc}") from None
    if not report.ok:
        raise typer.Exit(1)
