"""``uavplan scenario ...`` commands (list, show, export, schema, check).

Any problem with a scenario file is printed to stderr, one line per problem, and the command exits
with code 2 (no traceback).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TypeVar

import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

if TYPE_CHECKING:
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.world import Scenario, Terrain

scenario_app = typer.Typer(help="Built-in scenarios and scenario files.", no_args_is_help=True)

T = TypeVar("T")


def _fail(exc: ScenarioFileError) -> typer.Exit:
    for line in exc.problems:
        typer.echo(line, err=True)
    return typer.Exit(code=2)


def _run(fn: Callable[[], T]) -> T:
    from uavplan.io.scenario_file import ScenarioFileError

    try:
        return fn()
    except ScenarioFileError as exc:
        raise _fail(exc) from None


def _console() -> Console:
    return Console(highlight=False, soft_wrap=False)


def _n(v: float) -> str:
    """A number for people: at most 2 decimals, no trailing zeros."""
    if not math.isfinite(v):
        return "inf" if v > 0 else "-inf"
    text = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def _pt(p: tuple[float, ...] | list[float]) -> str:
    return "[" + ", ".join(_n(float(v)) for v in p) + "]"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def raster_lines(ter: Terrain) -> list[str]:
    """What ``scenario show`` says of a terrain read from a raster: the file as GDAL read it,
    how it was placed, and how far the floor's and ceiling's grids stand from its ground."""
    g = ter.georef
    block = g.get("raster")
    if not block:
        return []
    lines = [f"  raster: {g.get('raster_info', ter.name)}"]
    frame = block.get("frame")
    if frame == "reprojected":
        how = ("reprojected onto the local grid through the origin (pyproj), the floor's grid "
               "never below the raster's ground and the ceiling's never above it")  # fmt: skip
    elif frame == "crs-offset":
        how = "on its own projected grid (its metres are the local metres)"
    else:
        how = "a plain grid (no CRS), node (0, 0) the south-west sample"
    lines.append(f"  placed: {how}")
    lift = g.get("lift")
    if lift:
        lines.append(
            f"  envelope: floor {_n(round(lift['floor_median'], 1))} m above the raster's ground "
            f"at a node (median; max {_n(round(lift['floor_max'], 1))} m), ceiling "
            f"{_n(round(lift['ceiling_median'], 1))} m below it (max "
            f"{_n(round(lift['ceiling_max'], 1))} m); a smaller cell_size narrows both"
        )
    if g.get("voids_filled"):
        lines.append(
            f"  voids: {g['voids_filled']:,} nodes stand on no-data samples of {ter.name} "
            "(filled with the highest height on each void's rim for the floor, the lowest for "
            "the ceiling; the ground there is unknown)"
        )
    return lines


def summary_lines(s: Scenario) -> list[str]:
    """The ``scenario show`` summary of a scenario, as plain text lines."""
    lines = [f"scenario: {s.name} ({s.dim}-D)"]
    if s.description:
        lines.append(f"description: {' '.join(s.description.split())}")
    if "source" in s.metadata:
        lines.append(f"source: {s.metadata['source']}")
    lines.append(f"bounds: {_pt(s.bounds.lower)} .. {_pt(s.bounds.upper)} m")
    if s.terrain is None:
        lines.append("terrain: none" + (" (flat, z = 0)" if s.dim == 3 else ""))
    else:
        ter = s.terrain
        ny, nx = ter.shape
        xmin, xmax, ymin, ymax = ter.extent
        hmin, hmax = float(ter.heights.min()), float(ter.heights.max())
        lines.append(
            f"terrain: {ter.name}, {ny} x {nx} nodes (rows x columns), "
            f"cell {_n(ter.dx)} x {_n(ter.dy)} m, "
            f"extent x {_n(xmin)}..{_n(xmax)} m, y {_n(ymin)}..{_n(ymax)} m, "
            f"heights {_n(hmin)}..{_n(hmax)} m"
        )
        lines += raster_lines(ter)
    if s.origin is None:
        lines.append("origin: none (not geo-referenced; mission export needs one)")
    else:
        o = s.origin
        at = f" at local ({_n(o.x)}, {_n(o.y)}) m" if o.x or o.y else ""
        acc = f"; positions up to {_n(o.accuracy)} m off the terrain data" if o.accuracy else ""
        lines.append(f"origin: {o.lat:.6f}, {o.lon:.6f} (WGS84){at}, z = 0 at {_n(o.alt)} m "
                     f"AMSL{acc}" + (f" ({o.note})" if o.note else ""))  # fmt: skip
    n_inf = sum(1 for c in s.cylinders if c.infinite)
    n_rev = sum(1 for u in s.uncertain_areas if u.revealed)
    lines.append(
        "obstacles: "
        + ", ".join(
            [
                _plural(len(s.cylinders), "cylinder")
                + (f" ({n_inf} infinite)" if s.cylinders else ""),
                _plural(len(s.circles), "circle"),
                _plural(len(s.polygons), "polygon"),
                _plural(len(s.danger_areas), "danger area"),
                _plural(len(s.uncertain_areas), "uncertain area")
                + (f" ({n_rev} revealed)" if s.uncertain_areas else ""),
                _plural(len(s.moving_obstacles), "moving obstacle"),
            ]
        )
    )
    if s.altitude is None:
        lines.append("altitude band: none")
    else:
        ref = "above ground" if s.altitude.reference == "ground" else "absolute"
        lines.append(f"altitude band: [{_n(s.altitude.min)}, {_n(s.altitude.max)}] m {ref}")
    u = s.uav
    s2 = (
        f"s2 {_n(u.s2)} m"
        if u.s2_axes is None
        else "separation per axis " + "/".join(_n(a) for a in u.s2_axes) + " m"
    )
    lines.append(
        f"uav: speed {_n(u.speed)} m/s, turn radius {_n(u.turn_radius)} m, "
        f"s1 (threat cost) {_n(u.s1)} m, {s2}, size {_n(u.size)} m"
    )
    climb = (
        "climb/descent unlimited"
        if u.max_climb_angle is None and u.max_descent_angle is None
        else "climb "
        + ("unlimited" if u.max_climb_angle is None else f"<= {_n(u.max_climb_angle)} deg")
        + ", descent "
        + ("unlimited" if u.max_descent_angle is None else f"<= {_n(u.max_descent_angle)} deg")
    )
    lines.append(
        f"kinematic limits: speed {_n(u.min_speed)}-{_n(u.v_max)} m/s, {climb}, "
        + ("no turn limit" if u.turn_radius <= 0 else f"turn radius >= {_n(u.turn_radius)} m")
    )
    lines.append(f"planning: cost {s.cost}, {s.n_waypoints} waypoints")
    lines.append(f"tasks ({len(s.tasks)}, absolute metres):")
    for t in s.tasks:
        extra = f" (leaves at {_n(t.start_time)} s)" if t.start_time else ""
        lines.append(f"  {t.id}: {_pt(t.start)} -> {_pt(t.goal)}{extra}")
    return lines


@scenario_app.command("list")
def list_cmd() -> None:
    """List the built-in scenarios."""
    from uavplan.scenarios import list_builtin

    table = Table(title="Built-in scenarios", show_lines=True)
    table.add_column("name", style="bold", no_wrap=True)
    table.add_column("description")
    for name, description in _run(list_builtin):
        table.add_row(Text(name), Text(description))
    _console().print(table)


@scenario_app.command("show")
def show_cmd(
    name_or_file: Annotated[str, typer.Argument(help="A built-in scenario name or a file.")],
) -> None:
    """Summarise a scenario: bounds, terrain, obstacles, altitude band, UAV, tasks."""
    from uavplan.scenarios import resolve

    scenario = _run(lambda: resolve(name_or_file))
    console = Console(highlight=False, soft_wrap=True)
    for line in summary_lines(scenario):
        console.print(Text(line))


@scenario_app.command("export")
def export_cmd(
    name: Annotated[str, typer.Argument(help="A built-in scenario name (or a scenario file).")],
    file: Annotated[Path, typer.Argument(help="Output file: .yaml/.yml (YAML) or .json (JSON).")],
) -> None:
    """Write a scenario to a file, YAML or JSON by the file's suffix."""
    from uavplan.scenarios import resolve

    scenario = _run(lambda: resolve(name))
    from uavplan.io.scenario_file import save_scenario

    written = _run(lambda: save_scenario(scenario, file))
    typer.echo(f"wrote {written}")


@scenario_app.command("schema")
def schema_cmd() -> None:
    """Print the JSON Schema of scenario files."""
    from uavplan.io.scenario_file import schema

    typer.echo(json.dumps(schema(), indent=2))


@scenario_app.command("check")
def check_cmd(
    file: Annotated[str, typer.Argument(help="A scenario file (or a built-in name).")],
) -> None:
    """Validate a scenario file: prints "ok", or every problem (exit code 2)."""
    from uavplan.scenarios import resolve

    _run(lambda: resolve(file))
    typer.echo("ok")
