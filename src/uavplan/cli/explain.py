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

#: Rescued UAVs of one kind listed one by one up to this many; beyond it, a line for the kind
#: (how many, the range of their take-off delays, the first few) unless ``--all``.
LIST_MAX = 12
#: UAVs named on a kind's line when the kind is told as a group.
NAMED = 8


def story_lines(doc: dict[str, Any], report: Any, everyone: bool = False) -> list[str]:
    """The explanation of a plan (its JSON ``doc``) given the verifier's ``report`` on it: the
    strategy's attempts and the restarts, then every UAV that fails (what the verifier finds,
    with the planner's story of it), then those repaired after planning, then the rescued ones
    (each, or by kind when a kind has more than :data:`LIST_MAX` UAVs; ``everyone``: each UAV,
    also those with nothing to tell)."""
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
    told: dict[str, list[Event]] = {u: [] for u in ids}
    for e in events:
        if e.uav in told:  # an unresolved UAV's event says what the repair tried
            told[e.uav].append(e)
    fails: dict[str, list[str]] = {}
    for v in report.violations:
        for u in v.uavs:
            if u in told:
                fails.setdefault(u, []).append(f"FAILS {v.kind}: {v.message}")
    for e in events:
        if e.kind == "unresolved" and e.uav in told and e.uav not in fails:
            fails[e.uav] = ["the verifier finds no violation in this UAV's flight"]

    def story(u: str) -> list[str]:
        return (
            [f"{u}:"]
            + [f"  {e.kind}: {e.detail}" for e in told[u]]
            + [f"  {t}" for t in fails.get(u, ())]
        )

    failing = [u for u in ids if u in fails]
    repaired = [u for u in ids if u not in fails and any(e.kind == "repaired" for e in told[u])]
    rescued = [u for u in ids if u not in fails and u not in repaired and told[u]]
    if failing:
        lines.append(f"fails ({len(failing)} UAV(s)):")
        lines += [x for u in failing for x in story(u)]
    if repaired:
        lines.append(f"repaired after planning ({len(repaired)} UAV(s)):")
        lines += [x for u in repaired for x in story(u)]
    if everyone:
        for u in ids:
            if u in rescued:
                lines += story(u)
            elif u not in fails and u not in repaired:
                lines.append(f"{u}: flies its first planned flight")
        return lines + _without_diagnostics(events, doc)
    kinds: dict[str, list[Event]] = {}
    for u in rescued:
        for e in told[u]:
            kinds.setdefault(e.kind, []).append(e)
    grouped = any(len(es) > LIST_MAX for es in kinds.values())
    if rescued:
        lines.append(f"rescued while planning ({len(rescued)} UAV(s)):")
    if grouped:
        lines += [_kind_line(kind, es) for kind, es in kinds.items()]
    else:
        lines += [x for u in rescued for x in story(u)]
    quiet = len(ids) - len(failing) - len(repaired) - len(rescued)
    if quiet:
        more = "every UAV" if grouped else "them"
        lines.append(f"{quiet} other UAV(s) fly their first planned flight (--all lists {more})")
    elif grouped:
        lines.append("(--all lists every UAV)")
    return lines + _without_diagnostics(events, doc)


def _kind_line(kind: str, es: list[Any]) -> str:
    """One line for the UAVs rescued in one way: how many, their take-off delays, a few."""
    from uavplan.planners.core.events import KINDS

    late = [e.value for e in es if e.value]
    span = f"; {min(late):g}-{max(late):g} s later" if late else ""
    named = ", ".join(f"{e.uav} ({e.value:g} s)" if e.value else str(e.uav) for e in es[:NAMED])
    more = f" and {len(es) - NAMED} more" if len(es) > NAMED else ""
    return f"  {kind}: {len(es)} UAV(s), each: {KINDS[kind]}{span}: {named}{more}"


def _without_diagnostics(events: list[Any], doc: dict[str, Any]) -> list[str]:
    if not events and "diagnostics" not in doc:
        return ["(this plan file has no diagnostics: it was written before uavplan kept them; "
                "the verifier's findings above are all there is)"]  # fmt: skip
    return []


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
