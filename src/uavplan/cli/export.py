"""``uavplan export PLAN [SCENARIO] --format NAME --out PATH``: a plan in a mission format
(:mod:`uavplan.io.missions`). By default each UAV's flown trajectory, the one the plan declares
and the verifier checks; ``--polylines`` or ``--smoothed`` export the planned polylines or the
informative smoothed paths instead, with a warning that they are not what the plan guarantees.
Geodetic formats need the scenario's origin (recorded in the plan, or from SCENARIO, or
``--origin``); the geofence and the terrain frame need the scenario (SCENARIO, else the plan's
scenario name when it is a built-in one). A plan that is not feasible, or does not say, is
still written but the command says so on stderr and exits 1."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from uavplan.cli._common import err, fail, load_world, out

if TYPE_CHECKING:
    from uavplan.io.plan_file import TrajectoryKind


def _origin(text: str) -> Any:
    from uavplan.io.scenario_file.schema import MAX_COORD
    from uavplan.world.geo import GeoError, GeoOrigin

    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
        if len(values) not in (2, 3):
            raise ValueError
        if len(values) == 3 and not abs(values[2]) <= MAX_COORD:
            raise GeoError(f"altitude {values[2]:g} m is not within {MAX_COORD:g} m")
        return GeoOrigin(values[0], values[1], values[2] if len(values) == 3 else 0.0,
                         note="--origin")  # fmt: skip
    except ValueError as exc:
        why = str(exc) if isinstance(exc, GeoError) else "give LAT,LON[,ALT] in degrees, metres"
        raise fail(f"--origin {text!r}: {why}") from None


def export(
    plan_file: Annotated[Path | None, typer.Argument(help="A plan.json (or its folder).")] = None,
    scenario: Annotated[
        str | None,
        typer.Argument(
            help="Its scenario (file or built-in name; default: the plan's, if built in)."
        ),
    ] = None,
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
    frame: Annotated[
        str, typer.Option(help="Mission altitudes: amsl, relative (to home) or terrain.")
    ] = "amsl",
    end: Annotated[str, typer.Option(help="After the last waypoint: land, rtl or none.")] = "land",
    firmware: Annotated[str, typer.Option(help="px4, ardupilot or generic (.plan).")] = "px4",
    vehicle: Annotated[
        str,
        typer.Option(
            help="auto (the scenario UAV's airframe class; unnamed: fixed-wing if it has a "
            "turn radius or a minimum speed), fixed-wing, multirotor."
        ),
    ] = "auto",
    origin: Annotated[
        str | None, typer.Option(help="LAT,LON[,ALT]: geodetic origin of the local frame.")
    ] = None,
    epoch: Annotated[
        str, typer.Option(help="UTC time of the plan's t = 0 (KML times), ISO 8601.")
    ] = "2000-01-01T00:00:00Z",
    list_formats: Annotated[bool, typer.Option("--list", help="List the formats.")] = False,
    drone: Annotated[
        str,
        typer.Option(
            help="wpml: the DJI aircraft: m300, m350, m30, m30t, m3e, m3t, m3m, m3d or m3td."
        ),
    ] = "m3e",
    max_items: Annotated[
        int,
        typer.Option(
            help="Most MAVLink items of a per-vehicle mission (qgc, wpl): the flown trajectory "
            "is thinned to fit (PX4 holds 500, ArduPilot about 700 without SD storage)."
        ),
    ] = 500,
) -> None:
    """Write PLAN_FILE's trajectories in a mission format: each UAV's flown trajectory (the
    one the plan declares and guarantees) unless --polylines or --smoothed."""
    from uavplan.io.missions import (
        ExportError,
        ExportOptions,
        Mission,
        exporters,
        get_exporter,
        tolerances,
        write_launch_schedule,
    )
    from uavplan.io.missions.wpml import DRONES
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
    choices = {"frame": (frame, ("amsl", "relative", "terrain")),
               "end": (end, ("land", "rtl", "none")),
               "firmware": (firmware, ("px4", "ardupilot", "generic")),
               "vehicle": (vehicle, ("auto", "fixed-wing", "multirotor")),
               "drone": (drone, tuple(DRONES))}  # fmt: skip
    for name, (value, allowed) in choices.items():
        if value not in allowed:
            raise fail(f"--{name} {value!r}: choose from {', '.join(allowed)}")
    kind: TrajectoryKind = "smoothed" if smoothed else ("planned" if polylines else "flown")
    if not 3 <= max_items <= 100_000:
        raise fail(f"--max-items {max_items}: from 3 to 100,000")
    geo_origin = _origin(origin) if origin is not None else None
    notes: list[str] = []
    try:
        exporter = get_exporter(fmt)
        plan = read_plan_file(plan_file)
        world = None
        if scenario is not None:
            world = load_world(scenario)
        elif plan.scenario is not None:
            world = load_world(plan.scenario, quiet=True)
            if world is None:
                notes.append(f"scenario {plan.scenario!r} is not a built-in one: no geofence "
                             "and no terrain frame (give SCENARIO)")  # fmt: skip
        if world is not None and world.dim != plan.dim:
            raise fail(f"{scenario or plan.scenario}: a {world.dim}-D scenario for a "
                       f"{plan.dim}-D plan")  # fmt: skip
        if geo_origin is not None:
            plan = dataclasses.replace(plan, origin=geo_origin)
        elif plan.origin is None and world is not None and world.origin is not None:
            plan = dataclasses.replace(plan, origin=world.origin)
        options = ExportOptions(kind=kind, frame=frame, end=end, firmware=firmware,  # type: ignore[arg-type]
                                vehicle=vehicle, epoch=epoch,  # type: ignore[arg-type]
                                max_items=max_items, drone=drone)  # fmt: skip
        mission = Mission(plan, world, options)
        shown = plan_path(plan_file)
        default = shown.parent / fmt if exporter.per_uav else shown.with_suffix(exporter.suffix)
        target = out_path or default
        if not exporter.per_uav and target.is_dir():  # into the folder, as cp does
            target = target / default.name
        if exporter.per_uav:
            target.mkdir(parents=True, exist_ok=True)
        written = exporter.write(mission, target)
        if exporter.per_uav:  # what a per-vehicle mission cannot carry
            written.append(write_launch_schedule(mission, target))
    except (ExportError, PlanFormatError) as exc:
        raise fail(str(exc).splitlines()[0]) from None
    except OSError as exc:
        raise fail(f"--out {out_path}: cannot write: {exc}") from None
    for p in written:
        out.print(f"wrote {p}")
    for note in (*notes, *mission.warnings):
        err.print(f"WARNING: {plan.source}: {note}")
    for line in tolerances(mission):
        err.print(f"WARNING: {plan.source}: {line}")
    thin = 0.0
    if exporter.per_uav:
        thin = max((r["thinning_m"] for r in mission.report.values()), default=0.0)
        most = max((int(r["items"]) for r in mission.report.values()), default=0)
        err.print(f"WARNING: {plan.source}: take-off times are in {target / 'launch.csv'} (the "
                  f"missions carry none); missions thinned to at most {most} items, up to "
                  f"{thin:.3g} m from the verified trajectories")  # fmt: skip
    if kind != "flown":
        what = "smoothed paths" if smoothed else "planned polylines"
        err.print(f"WARNING: {plan.source}: exported the {what}, not the flown trajectories "
                  "the plan declares and was verified for")  # fmt: skip
    if plan.feasible is not True:
        state = "not feasible" if plan.feasible is False else "of unknown feasibility"
        err.print(f"WARNING: {plan.source}: the plan is {state}; do not fly it as it is")
        raise typer.Exit(1)
    rec = dict(plan.execution or {})
    track = min(float(rec.get("track_h", 0.0)), float(rec.get("track_v", 0.0)))
    if track > 0 and thin > track:
        err.print(f"UNSAFE: {plan.source}: the missions depart up to {thin:.3g} m from the "
                  f"verified trajectories, more than the {track:g} m of tracking error the "
                  "plan tolerates; raise --max-items or re-plan with a larger tracking "
                  "error")  # fmt: skip
        raise typer.Exit(1)
