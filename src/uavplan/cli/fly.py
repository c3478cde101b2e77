"""``uavplan fly SCENARIO -a PLANNER``: plan the first task, fly it with replanning in flight.

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


def fly(
    scenario: Annotated[str, typer.Argument(help="A scenario file or built-in name.")],
    algorithm: Annotated[str, typer.Option("--algorithm", "-a", help="Planner name.")] = "hr-maga",
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    iterations: Annotated[int | None, typer.Option(help="Iteration budget of the plan.")] = None,
    sensor_range: Annotated[
        float | None, typer.Option(help="Metres at which an area is seen [10 s of flight].")
    ] = None,
    latency: Annotated[float, typer.Option(help="Repair latency = deadline, s.")] = 0.1,
    strict_deadline: Annotated[
        bool, typer.Option(help="Exit 1 when a repair missed its deadline.")
    ] = False,
    out_file: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write the mission as JSON here.")
    ] = None,
    param: Annotated[list[str] | None, typer.Option(help="Planner parameter NAME=VALUE.")] = None,
) -> None:
    """Plan SCENARIO's first task and fly it, revealing unknown areas in flight."""
    from uavplan.io.atomic import write_json_atomic
    from uavplan.io.plan_file import Trajectory
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.planners import PlannerError, get_planner
    from uavplan.planners.replanning import fly_mission, revealed_world
    from uavplan.scenarios import resolve
    from uavplan.verify import verify_trajectories

    try:
        sc = resolve(scenario)
    except ScenarioFileError as exc:
        raise fail(getattr(exc, "problems", None) or [str(exc)]) from None
    options: dict[str, Any] = parse_params(param or [])
    try:
        planner = get_planner(algorithm, **options)
        m = fly_mission(
            planner, sc, budget=iterations, seed=seed, sensor_range=sensor_range, latency=latency
        )
    except (PlannerError, ValueError) as exc:
        raise fail(f"fly {scenario}: {exc}") from None
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
    world = revealed_world(sc)
    rep = verify_trajectories(
        [Trajectory(sc.tasks[0].id, m.waypoints, m.times, m.feasible)], world, kinematics=False
    )
    verdict = "verified" if rep.ok else f"NOT SAFE: {len(rep.violations)} violation(s)"
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
            err.print(f"violation: {v}", markup=False, highlight=False)
        err.print("the flown trajectory is NOT safe", markup=False, highlight=False)
        raise typer.Exit(1)
    if strict_deadline and misses:
        err.print(f"{misses} repair(s) missed the {latency:g} s deadline", markup=False)
        raise typer.Exit(1)
