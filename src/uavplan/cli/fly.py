"""``uavplan fly SCENARIO -a PLANNER``: plan the first task, fly it with replanning in flight;
``uavplan fly PLAN.json [SCENARIO]``: fly a plan already made (one UAV of it, ``--uav``; its
scenario by default), repaired by the plan's own planner and options unless ``-a`` names one.

The scenario's uncertain areas marked ``revealed: false`` are unknown to the planner until the
UAV comes within ``--sensor-range`` of them; the planner then repairs the rest of its path from
the predicted state ``--latency`` s later (:mod:`uavplan.planners.replanning`). Prints one line
per event (area, time, what was done, the repair's compute time against the deadline), then
the flown trajectory's verdict by the independent verifier on the world with every area
revealed. Exit codes: 0 flown trajectory verified, 1 not (or a repair missed its deadline with
``--strict-deadline``), 2 bad input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from uavplan.cli._common import err, fail, out, parse_params


def _is_plan(arg: str) -> bool:
    """Whether ``arg`` names a plan file (a JSON file with ``uavs``, or a folder holding a
    ``plan.json``) rather than a scenario."""
    import json

    p = Path(arg)
    if p.is_dir():
        return (p / "plan.json").is_file()
    if p.suffix.lower() != ".json" or not p.is_file():
        return False
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(data, dict) and "uavs" in data


def _from_plan(
    path: str, scenario: str | None, algorithm: str | None, uav: str | None
) -> tuple[Any, Any, str, dict[str, Any], Any, int | None, Any]:
    """(scenario, task, planner name, its options, the initial PlanResult, the plan's seed,
    the execution model it was made for) of a plan file; ``fail`` naming the file and field
    otherwise."""
    import numpy as np

    from uavplan.io.plan_file import PlanFormatError, read_plan_file
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.planners import PlanResult
    from uavplan.scenarios import resolve

    try:
        pf = read_plan_file(path)
    except PlanFormatError as exc:
        raise fail(exc.problems) from None
    name = scenario or pf.scenario
    if not name:
        raise fail(f"{path}: the plan names no scenario; give one: uavplan fly {path} SCENARIO")
    try:
        sc = resolve(name)
    except ScenarioFileError as exc:
        raise fail(getattr(exc, "problems", None) or [str(exc)]) from None
    ids = [u.id for u in pf.uavs]
    rec = next((u for u in pf.uavs if u.id == (uav or ids[0])), None)
    if rec is None:
        raise fail(f"{path}: --uav {uav!r} is not in the plan (it has {', '.join(ids)})")
    if pf.scenario and pf.scenario != sc.name:
        err.print(
            f"warning: {path} was planned for scenario {pf.scenario!r}, flying it in {sc.name!r}",
            markup=False,
            highlight=False,
        )
    task = next((t for t in sc.tasks if t.id == rec.id), None)
    if task is None:
        raise fail(f"{path}: UAV {rec.id!r} has no task in scenario {sc.name!r}")
    planner = algorithm or pf.algorithm
    if not planner:
        raise fail(f"{path}: the plan names no planner to repair with; give one with -a")
    opts: dict[str, Any] = {}
    if algorithm is None:  # the plan's own options, those its planner still has
        from uavplan.planners import PlannerError, get_planner

        try:
            known = set(get_planner(planner).option_names())
        except PlannerError as exc:
            raise fail(f"{path}: {exc}") from None
        opts = {k: v for k, v in pf.config.items() if k in known}
    P, T = rec.planned.points, rec.planned.times
    first = PlanResult(
        rec.id, P, T, float(rec.cost) if rec.cost is not None else float("nan"), {},
        bool(rec.feasible), 0, 0, 0.0, np.zeros(0), planner,
    )  # fmt: skip
    from uavplan.world.execution import NOMINAL, ExecutionModel

    try:
        model = ExecutionModel.from_record(pf.execution) if pf.execution else NOMINAL
    except ValueError as exc:
        raise fail(f"{path}: execution: {exc}") from None
    return sc, task, planner, opts, first, pf.seed, model


def fly(
    scenario: Annotated[
        str, typer.Argument(help="A scenario file or built-in name, or a plan file to fly.")
    ],
    plan_scenario: Annotated[
        str | None,
        typer.Argument(help="With a plan file: the scenario to fly it in [the plan's own]."),
    ] = None,
    algorithm: Annotated[
        str | None,
        typer.Option("--algorithm", "-a", help="Planner name [hr-maga; a plan's own planner]."),
    ] = None,
    uav: Annotated[
        str | None, typer.Option(help="With a plan file: the UAV to fly [its first].")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Random seed [0; a plan file's own seed].")
    ] = None,
    iterations: Annotated[int | None, typer.Option(help="Iteration budget of the plan.")] = None,
    sensor_range: Annotated[
        float | None, typer.Option(help="Metres at which an area is seen [10 s of flight].")
    ] = None,
    latency: Annotated[float, typer.Option(help="Repair latency = deadline, s.")] = 0.1,
    strict_deadline: Annotated[
        bool, typer.Option(help="Exit 1 when a repair missed its deadline.")
    ] = False,
    nominal: Annotated[
        bool,
        typer.Option(
            "--nominal",
            help="Plan and repair for an exact execution (no take-off, speed or tracking "
            "error) instead of the plan's or scenario's execution model [uavplan's default].",
        ),
    ] = False,
    out_file: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write the mission as JSON here.")
    ] = None,
    param: Annotated[list[str] | None, typer.Option(help="Planner parameter NAME=VALUE.")] = None,
) -> None:
    """Plan SCENARIO's first task (or take PLAN.json's) and fly it, revealing unknown areas in
    flight and repairing the rest of the path when one is seen."""
    from uavplan.cli.plan import planning_world
    from uavplan.io.atomic import write_json_atomic
    from uavplan.io.plan_file import Trajectory
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.planners import PlannerError, get_planner
    from uavplan.planners.replanning import fly_mission, revealed_world
    from uavplan.scenarios import resolve
    from uavplan.verify import verify_trajectories

    initial = task = model = None
    if _is_plan(scenario):
        sc, task, algorithm, options, initial, plan_seed, model = _from_plan(
            scenario, plan_scenario, algorithm, uav
        )
        if seed is None:
            seed = plan_seed
    else:
        if plan_scenario is not None or uav is not None:
            raise fail(
                f"fly {scenario}: a second argument and --uav are for a plan file, and "
                f"{scenario!r} is not one"
            )
        try:
            sc = resolve(scenario)
        except ScenarioFileError as exc:
            raise fail(getattr(exc, "problems", None) or [str(exc)]) from None
        from uavplan.strategy import strategy_for

        algorithm, options = algorithm or strategy_for(sc).replanner, {}
    seed = 0 if seed is None else seed
    options = {**options, **parse_params(param or [])}
    pw = planning_world(sc, scenario, nominal, model)  # planned and repaired in it
    sc, given = pw.world, pw.given or sc
    if task is not None:  # the plan's task, its clearances widened as the world's are
        task = next(t for t in sc.tasks if t.id == task.id)
    try:
        planner = get_planner(algorithm, **options)
        m = fly_mission(
            planner, sc, task, budget=iterations, seed=seed, sensor_range=sensor_range,
            latency=latency, initial=initial,
        )  # fmt: skip
    except (PlannerError, ValueError) as exc:
        raise fail(f"fly {scenario}: {exc}") from None
    task = task if task is not None else sc.tasks[0]
    hidden = sum(not u.revealed for u in sc.uncertain_areas)
    out.print(
        f"{sc.name}: {algorithm}, seed {seed}; {hidden} area(s) unknown at take-off, sensor "
        f"range {m.sensor_range:g} m, latency {m.latency:g} s",
        markup=False,
        highlight=False,
    )
    misses = 0
    for e in m.events:
        late = " MISSED THE DEADLINE" if e.deadline_missed else ""
        misses += e.deadline_missed
        how = e.info.get("how", "")
        ok = "" if e.repaired_feasible else " (repaired path NOT clear)"
        what = f", {how}, {1000 * e.compute_time:.1f} ms{late}{ok}" if e.action == "repair" else ""
        out.print(
            f"  area {e.area} seen at t={e.time:.1f} s: {e.action}{what}",
            markup=False,
            highlight=False,
        )
    world = revealed_world(given)  # the world as given, under the model planned for
    rep = verify_trajectories(
        [Trajectory(task.id, m.waypoints, m.times, m.feasible)], world, kinematics=False,
        model=sc.execution,
    )  # fmt: skip
    verdict = "verified" if rep.ok else f"NOT SAFE: {len(rep.violations)} violation(s)"
    if rep.ok and sc.execution is not None and not sc.execution.nominal:
        verdict += " under the execution model"
    out.print(
        f"flown: {m.length:,.0f} m in {m.times[-1] - m.times[0]:,.1f} s, {verdict} (first plan "
        f"{m.initial.length:,.0f} m)",
        markup=False,
        highlight=False,
    )
    if out_file is not None:
        write_json_atomic(
            out_file,
            {
                "scenario": sc.name,
                "algorithm": algorithm,
                "seed": seed,
                "waypoints": m.waypoints.tolist(),
                "times": m.times.tolist(),
                "feasible": bool(m.feasible and rep.ok),
                "events": [
                    {"area": e.area, "time": e.time, "action": e.action,
                     "compute_time": e.compute_time, "deadline_missed": e.deadline_missed,
                     "repaired_feasible": e.repaired_feasible, "how": e.info.get("how")}
                    for e in m.events
                ],
            },
        )  # fmt: skip
        out.print(f"wrote {out_file}", markup=False, highlight=False)
    if not rep.ok or not m.feasible:
        for v in rep.violations[:10]:
            err.print(f"violation: {v.message}", markup=False, highlight=False)
        err.print("the flown trajectory is NOT safe", markup=False, highlight=False)
        raise typer.Exit(1)
    if strict_deadline and misses:
        err.print(f"{misses} repair(s) missed the {latency:g} s deadline", markup=False)
        raise typer.Exit(1)
