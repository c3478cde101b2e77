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
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console

from uavplan.cli._common import fail, load_world, world_of_plan

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
    if report.model is not None:
        from uavplan.world.execution import ExecutionModel

        m = ExecutionModel.from_record(report.model)
        lines.append(f"execution model: {m.describe()} ({m.source}); --nominal checks the plan "
                     "as flown exactly")  # fmt: skip
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


def margins_record(report: Any, pairs: int = 20) -> dict[str, Any]:
    """plan.json's ``margins``: every UAV's, and the ``pairs`` tightest pairs with every
    failing one."""
    tight = report.pair_margins[:pairs]
    failing = [p for p in report.pair_margins[pairs:] if not p.ok]
    return {"uavs": [m.to_dict() for m in report.uav_margins],
            "pairs": [p.to_dict() for p in tight + failing]}  # fmt: skip


def margin_lines(report: Any, k: int = 5, cruise: float = 0.0) -> list[str]:
    """What the console says of the margins: the fleet's least, and the tightest pairs. The
    speed margin is a fraction of the planned speed that includes the model's wind (its share
    at the UAVs' ``cruise`` speed, m/s), so the model's speed error it is held against does."""
    import math

    from uavplan.verify.robust import timing_of

    rec = dict(report.model or {})
    if rec.get("wind") and cruise > 0:
        rec["speed"] = timing_of(rec, cruise).rho

    def show(v: float, unit: str, scale: float = 1.0) -> str:
        return "any" if not math.isfinite(v) else f"{v * scale:.3g} {unit}".strip()

    ms = report.uav_margins
    if not ms:
        return []
    lines = []
    for what, unit, scale, need in (("takeoff_s", "s", 1.0, rec.get("takeoff_s", 0.0)),
                                    ("speed", "%", 100.0, rec.get("speed", 0.0)),
                                    ("track_h", "m", 1.0, rec.get("track_h", 0.0)),
                                    ("track_v", "m", 1.0, rec.get("track_v", 0.0))):  # fmt: skip
        worst = min(ms, key=lambda m: getattr(m, what))
        v = getattr(worst, what)
        label = {"takeoff_s": "take-off error", "speed": "speed error",
                 "track_h": "horizontal tracking error",
                 "track_v": "vertical tracking error"}[what]  # fmt: skip
        by = worst.limited_by.get(what, "")
        verdict = "meets" if v >= need - 1e-6 else "BELOW"
        who = "the fleet" if len(ms) > 1 else worst.uav
        amount = "any" if not math.isfinite(v) else f"up to {show(v, unit, scale)} of"
        lines.append(f"margin: {who} tolerates {amount} {label} "
                     f"(model: {show(need, unit, scale)}: {verdict}; tightest: {worst.uav}"
                     + (f" with {by}" if by else "") + ")")  # fmt: skip
    for p in report.pair_margins[:k]:
        if not math.isfinite(p.takeoff_s) and not math.isfinite(p.speed):
            continue
        where = (f"{p.distance:.1f} m apart at worst about t={p.time:.0f} s"
                 if math.isfinite(p.distance) and math.isfinite(p.time)
                 else "never close under the model's errors")  # fmt: skip
        lines.append(f"  tight pair: {p.uav} and {p.other}: take-off ±{show(p.takeoff_s, 's')}, "
                     f"speed ±{show(p.speed, '%', 100.0)}, tracking {show(p.track_h, 'm')} "
                     f"horizontal and {show(p.track_v, 'm')} vertical, {where}")  # fmt: skip
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
    nominal: Annotated[
        bool,
        typer.Option(
            help="Check the plan as flown exactly, not under the execution model it states "
            "(plan.json's execution, else the scenario's)."
        ),
    ] = False,
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

    out = Console(highlight=False, soft_wrap=True)
    placed = world_of_plan(world, scenario, pf.execution, {t.id: t.points[0] for t in trajs})
    if placed is not world:
        world = placed
        out.print(f"{scenario}: the generated fleet placed again in the world widened by the "
                   "plan's execution model, as `uavplan plan` placed it", markup=False)  # fmt: skip
    model = None
    if not nominal:
        model = pf.execution or (world.execution.record() if world.execution else None)
    try:
        report = verify_trajectories(
            trajs,
            world,
            pf.scenario,
            smoothed=smoothed,
            kinematics=TRAJECTORIES[kind],
            trajectory=kind,
            model=model,
        )
    except SourceError as exc:
        raise fail(f"{scenario}: {exc}") from None

    limit = max_show if max_show > 0 else len(report.violations)
    for v in report.violations[:limit]:
        out.print(f"{v.kind}: {v.message}", markup=False)
    if len(report.violations) > limit:
        out.print(f"... and {len(report.violations) - limit} more (--max-show 0 shows all)")
    for w in report.warnings:
        out.print(f"warning: {w}", markup=False)
    for line in summary_lines(report, str(shown)):
        out.print(line, markup=False)
    for line in margin_lines(report, cruise=float(world.uav.speed)):
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
