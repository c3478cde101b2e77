"""``uavplan explain PLAN [SCENARIO]``: why a plan is what it is, per UAV, in a few lines.

It reads the plan's story (``plan.json``'s ``diagnostics``: the strategy's attempts, the
fleet's restarts, each UAV's later candidate, slower speed, later take-off, repair or failure,
:mod:`uavplan.planners.core.events`) and has the independent verifier check every flown trajectory
against the scenario under the plan's execution model: each failure it finds is a value (the
check, the UAVs, the time, the distance or clearance and the bound). Then, for each UAV that
fails or was rescued, what happened and why. Exit 0 when the plan flies and the verifier
agrees, 1 when it does not (the lines say why), 2 on bad input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from uavplan.cli._common import fail, load_world, world_of_plan


def story_lines(doc: dict[str, Any], report: Any, everyone: bool = False) -> list[str]:
    """The explanation of a plan (its JSON ``doc``) given the verifier's ``report`` on it."""
    from uavplan.planners.core.events import Event

    diag = doc.get("diagnostics") or {}
    events = [Event.from_record(e) for e in diag.get("events", [])]
    ids = [str(u["id"]) for u in doc.get("uavs", [])]
    lines = []
    attempts = [e for e in events if e.kind == "attempt"]
    if attempts:
        lines.append("strategy (uavplan plan without -a):")
        lines += [f"  {e.detail}" for e in attempts]
    restarts = [e for e in events if e.kind == "restart"]
    if restarts:
        lines.append("restarts of the whole fleet: " + "; ".join(e.detail for e in restarts))
    by_uav: dict[str, list[str]] = {u: [] for u in ids}
    for e in events:
        if e.uav in by_uav and e.kind != "unresolved":  # the verifier's finding says more
            by_uav[e.uav].append(f"{e.kind}: {e.detail}")
    for v in report.violations:
        for u in v.uavs:
            if u in by_uav:
                by_uav[u].append(f"FAILS {v.kind}: {v.message}")
    unresolved = {e.uav for e in events if e.kind == "unresolved"}
    for u in unresolved:
        if u in by_uav and not any(x.startswith("FAILS") for x in by_uav[u]):
            detail = next(e.detail for e in events if e.kind == "unresolved" and e.uav == u)
            by_uav[u].append(f"the planner says {detail}; the verifier finds no violation")
    quiet = 0
    for u in ids:
        told = by_uav[u]
        if not told:
            quiet += 1
            if everyone:
                lines.append(f"{u}: flies its first planned flight")
            continue
        lines.append(f"{u}:")
        lines += [f"  {t}" for t in told]
    if quiet and not everyone:
        lines.append(f"{quiet} other UAV(s) fly their first planned flight (--all lists them)")
    if not events and "diagnostics" not in doc:
        lines.append("(this plan file has no diagnostics: it was written before uavplan kept "
                     "them; the verifier's findings above are all there is)")  # fmt: skip
    return lines


def explain(
    plan_file: Annotated[
        Path, typer.Argument(help="A plan.json written by `uavplan plan` (or its folder).")
    ],
    scenario: Annotated[
        str | None, typer.Argument(help="The scenario it was planned in [the plan's own].")
    ] = None,
    everyone: Annotated[
        bool, typer.Option("--all", help="List every UAV, also those with nothing to tell.")
    ] = False,
    nominal: Annotated[
        bool,
        typer.Option(help="Check the flights as flown exactly, not under the plan's model."),
    ] = False,
) -> None:
    """Why PLAN_FILE is what it is: the strategy's attempts, the fleet's restarts, and for each
    UAV that fails or was rescued (a later candidate, a slower speed, a later take-off, a
    repair), what happened and why; failures as the independent verifier finds them (which
    check, which UAVs, when, by how much). Exit 0: the plan flies; 1: it does not; 2: bad
    input."""
    from uavplan.io.plan_file import PlanFormatError, load_plan_json, parse_plan, plan_path
    from uavplan.verify import verify_trajectories
    from uavplan.verify.source_terrain import SourceError

    try:
        doc = load_plan_json(plan_file)
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    shown = plan_path(plan_file)
    ref = scenario or doc.get("scenario")
    if not ref:
        raise fail(f"{shown}: the plan names no scenario; give one: uavplan explain "
                   f"{plan_file} SCENARIO")  # fmt: skip
    world = load_world(str(ref))
    assert world is not None
    try:
        pf = parse_plan(doc, world.dim, source=str(shown))
        trajs = pf.trajectories("flown")
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    world = world_of_plan(world, str(ref), pf.execution, {t.id: t.points[0] for t in trajs})
    own = world.execution.record() if world.execution else None
    model = None if nominal else (pf.execution or own)
    try:
        report = verify_trajectories(trajs, world, pf.scenario, model=model)
    except SourceError as exc:
        raise fail(f"{ref}: {exc}") from None
    out = Console(highlight=False, soft_wrap=True)
    n = len(doc.get("uavs", []))
    said = "flies" if doc.get("feasible") else "does NOT fly"
    found = ("the verifier agrees: every flown trajectory passes" if report.ok
             else f"the verifier finds {len(report.violations)} violation(s)")  # fmt: skip
    under = "" if model is None else " under its execution model"
    out.print(f"{shown}: {doc.get('algorithm')} on {ref}, seed {doc.get('seed')}, {n} UAV(s): "
              f"the planner says it {said}; {found}{under}", markup=False)  # fmt: skip
    for line in story_lines(doc, report, everyone):
        out.print(line, markup=False)
    if not report.ok or not doc.get("feasible"):
        raise typer.Exit(1)
