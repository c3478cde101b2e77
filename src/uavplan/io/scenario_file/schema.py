"""The file format: the pydantic spec models (:class:`ScenarioSpec` and its blocks), the number
types they use, :func:`schema` and :func:`dump_spec` (a spec as plain data).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from uavplan.world.geo import projected_crs_problem


def _no_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError("must be a number, not true/false")
    return value


#: Degrees in (0, 90].
Angle = Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=90)]
#: The largest coordinate accepted, metres (10,000 km: UTM northings fit; a float64 path
#: computation at that magnitude still resolves about 2 nm).
MAX_COORD = 1e7
#: The largest extent of a scenario's box on any axis, metres (1,000 km).
MAX_EXTENT = 1e6
#: Resource limits, checked when a file is read and before anything is allocated for it
#: (``docs/scenario-format.md``, "Limits"): a scenario file's size, its UAVs (tasks or a
#: generated fleet), the entries of each obstacle list, a polygon's vertices, a moving
#: obstacle's samples and the free waypoints per path.
MAX_FILE_BYTES = 64 * 2**20
#: A YAML scenario file's size: PyYAML builds Python objects node by node (3 MB of obstacles
#: took 26 s with libyaml's parser on the shared 2-core machine), JSON reads 100 times faster.
MAX_YAML_BYTES = 2**20
MAX_UAVS = 10_000
MAX_ITEMS = 100_000
MAX_VERTICES = 100_000
MAX_SAMPLES = 1_000_000
MAX_WAYPOINTS = 1_000
#: The most path points a population may hold (population size x points per path): 20 million
#: points of 3 float64 are 480 MB per copy of the population.
MAX_PATH_POINTS = 20_000_000
#: The largest iteration budget a scenario may ask for.
MAX_ITERATIONS = 1_000_000
#: The largest length that is not a coordinate (a radius, a margin, a safety distance, a turn
#: radius, an area's width, a fleet's spacing), metres: the largest extent of a box.
MAX_LENGTH = MAX_EXTENT
#: The smallest length that must be positive (a radius, an area's width, a spacing), metres:
#: 1 mm; below, a shape added to a coordinate of 10,000 km vanishes in float64.
MIN_LENGTH = 1e-3
#: Speeds, m/s: from 1 cm/s to 1,000 m/s (about Mach 3, beyond any UAV); a path of 1,000 km at
#: the slowest speed still takes a time a float64 holds to the nanosecond.
MIN_SPEED = 0.01
MAX_SPEED = 1000.0
#: Times (knots of moving obstacles, departures), seconds: within about 115 days.
MAX_TIME = 1e7
#: A DEM's grid spacing, metres: from 1 cm to 100 km.
MIN_CELL = 0.01
MAX_CELL = 1e5
Coord = Annotated[float, BeforeValidator(_no_bool), Field(ge=-MAX_COORD, le=MAX_COORD)]
Length = Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=MAX_LENGTH)]


def _not_tiny(value: float) -> float:
    if value < MIN_LENGTH:
        raise ValueError(
            f"must be at least {MIN_LENGTH:g} m (1 mm): a shape smaller than that vanishes when "
            "added to a coordinate in float64"
        )
    return value


PosLength = Annotated[
    float, BeforeValidator(_no_bool), Field(gt=0, le=MAX_LENGTH), AfterValidator(_not_tiny)
]
Speed = Annotated[float, BeforeValidator(_no_bool), Field(ge=MIN_SPEED, le=MAX_SPEED)]
Time = Annotated[float, BeforeValidator(_no_bool), Field(ge=-MAX_TIME, le=MAX_TIME)]
Departure = Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=MAX_TIME)]
Cell = Annotated[float, BeforeValidator(_no_bool), Field(ge=MIN_CELL, le=MAX_CELL)]
XY = Annotated[list[Coord], Field(min_length=2, max_length=2)]
Point = Annotated[list[Coord], Field(min_length=2, max_length=3)]


class _Spec(BaseModel):
    """Base of every file-level model: unknown keys are errors, numbers must be finite."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class BoundsSpec(_Spec):
    """The box paths must stay in."""

    lower: Point = Field(description="Lower corner [x, y] or [x, y, z], metres.")
    upper: Point = Field(
        description="Upper corner, same length as lower, metres. With a terrain, [x, y] bounds "
        "get the default z range."
    )


class TerrainSpec(_Spec):
    """A digital elevation model: a built-in map, a DEM file or SRTM tiles (exactly one)."""

    model_config = ConfigDict(
        json_schema_extra={
            "oneOf": [{"required": ["builtin"]}, {"required": ["file"]}, {"required": ["srtm"]}]
        }
    )

    builtin: Literal["spso", "jacksboro", "topobathy", "virtual"] | None = Field(
        None, description="Name of a built-in terrain."
    )
    file: str | None = Field(
        None,
        min_length=1,
        description="DEM file: any raster GDAL reads (GeoTIFF, .hgt, ASCII grid, ...), or "
        ".npy/.npz; a relative path is relative to the scenario file's directory.",
    )
    srtm: Annotated[list[Annotated[str, Field(min_length=1)]], Field(min_length=1)] | None = Field(
        None,
        description="SRTM .hgt tiles (N36W085.hgt, ...; relative to the scenario file), "
        "mosaicked and resampled onto the local grid over 'bounds' through 'origin' "
        "(both required); voids are filled high and counted.",
    )
    cell_size: Cell | None = Field(
        None,
        description="Grid spacing in metres (file or srtm). Default: a projected raster's own "
        "grid, a reprojected one's smaller pixel side, the .npz dx/dy, else 1; SRTM: 90 m (3 "
        "arc-seconds) or 30 m (1 arc-second).",
    )
    origin: XY = Field(
        default_factory=lambda: [0.0, 0.0],
        description="Position [x0, y0] of grid node (0, 0) (the south-west node), metres "
        "(file only).",
    )
    key: str | None = Field(
        None,
        description="Array name inside an .npz file (file only). Default: heights, elevation "
        "or topo.",
    )
    band: int = Field(
        1, ge=1, le=65535, description="The raster's band holding the heights (file only)."
    )

    @model_validator(mode="after")
    def _one_source(self) -> TerrainSpec:
        given = [k for k in ("builtin", "file", "srtm") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'builtin', 'file' or 'srtm'")
        if self.builtin is not None:
            extra = sorted({"cell_size", "origin", "key", "band"} & self.model_fields_set)
            if extra:
                raise ValueError(f"{', '.join(extra)} only apply to a terrain 'file'")
        if self.srtm is not None:
            extra = sorted({"origin", "key", "band"} & self.model_fields_set)
            if extra:
                raise ValueError(
                    f"{', '.join(extra)}: not for SRTM tiles (they are placed by the "
                    "scenario's origin)"
                )
        return self


class CylinderSpec(_Spec):
    """A vertical cylinder threat (3-D only)."""

    center: XY = Field(description="Axis position [x, y], metres.")
    radius: PosLength = Field(description="Radius, metres (> 0).")
    z_min: Coord | None = Field(None, description="Bottom, absolute metres; null = unbounded.")
    z_max: Coord | None = Field(None, description="Top, absolute metres; null = unbounded.")
    height: PosLength | None = Field(
        None,
        description="Top above the terrain at the center, metres (z_max = ground(center) + "
        "height); excludes z_max.",
    )
    margin: Length = Field(
        0.0, description="Added to the radius for collision checks (e.g. the drone size), metres."
    )

    @model_validator(mode="after")
    def _height_or_top(self) -> CylinderSpec:
        if self.height is not None and self.z_max is not None:
            raise ValueError("give either 'height' or 'z_max', not both")
        return self


class CircleSpec(_Spec):
    """A disc obstacle (an infinitely tall prism in 3-D)."""

    center: XY = Field(description="Center [x, y], metres.")
    radius: PosLength = Field(description="Radius, metres (> 0).")
    margin: Length = Field(0.0, description="Added to the radius for collision checks, m.")


class PolygonSpec(_Spec):
    """A simple polygon obstacle, convex or not (an infinitely tall prism in 3-D)."""

    vertices: Annotated[list[XY], Field(min_length=3, max_length=MAX_VERTICES)] = Field(
        description="At least 3 vertices [[x, y], ...] in order, metres."
    )
    margin: Length = Field(0.0, description="Distance a path must keep from it, metres.")


class DangerAreaSpec(_Spec):
    """A cylindrical area that may be crossed at a cost (HR-MAGA Eq. 1)."""

    center: XY = Field(description="Center [x, y], metres.")
    radius: PosLength = Field(description="Radius, metres (> 0).")


class UncertainAreaSpec(_Spec):
    """A rectangle known only once revealed; revealed areas are no-fly (HR-MAGA Eq. 2)."""

    x: Coord = Field(description="West edge, metres.")
    y: Coord = Field(description="South edge, metres.")
    width: PosLength = Field(description="Extent along x, metres (> 0).")
    height: PosLength = Field(description="Extent along y, metres (> 0).")
    revealed: bool = Field(True, description="Whether the planner knows about it.")


class MovingObstacleSpec(_Spec):
    """A sphere (a disc in 2-D) moving along a timed piecewise-linear trajectory."""

    radius: PosLength = Field(description="Radius, metres (> 0).")
    times: Annotated[list[Time], Field(min_length=1, max_length=MAX_SAMPLES)] = Field(
        description="Knot times, strictly increasing seconds."
    )
    positions: Annotated[list[Point], Field(min_length=1, max_length=MAX_SAMPLES)] = Field(
        description="One position per time, [x, y, z] (3-D) or [x, y] (2-D), absolute metres."
    )


class AltitudeSpec(_Spec):
    """Allowed altitudes."""

    min: Coord = Field(description="Lowest allowed altitude, metres.")
    max: Coord = Field(description="Highest allowed altitude, metres (> min).")
    reference: Literal["ground", "absolute"] = Field(
        "ground", description="'ground': above the terrain; 'absolute': z values."
    )


class UAVSpec(_Spec):
    """UAV limits (speed, s1, s2 as PPSwarm Sect. 5.1; no turn, climb or minimum-speed limit
    unless given)."""

    speed: Speed = Field(
        20.0, description="Cruise speed, m/s (> 0); planners time their paths with it."
    )
    turn_radius: Length = Field(
        0.0,
        description="Minimum turn radius of the horizontal track, metres (>= 0; 0 = no limit, "
        "the UAV turns in place).",
    )
    s1: Length = Field(
        15.0,
        description="PPSwarm's S1, metres: the zone beyond a cylinder's edge where the threat "
        "cost grows (Eq. 5) and the spacing of generated fleets from obstacles. A cost, not a "
        "clearance a plan keeps (the execution block's tracking error is that).",
    )
    s2: Length = Field(10.0, description="Safety distance between UAVs, metres.")
    size: Length = Field(1.0, description="UAV size, metres.")
    min_speed: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=MAX_SPEED)] = Field(
        0.0,
        description="Slowest allowed speed, m/s (0 <= min_speed <= speed; 0 = it may hover).",
    )
    max_speed: Speed | None = Field(
        None, description="Fastest allowed speed, m/s (>= speed); null = speed."
    )
    max_climb_angle: Angle | None = Field(
        None,
        description="Steepest climb, degrees above the horizontal, in (0, 90]; null = no limit.",
    )
    max_descent_angle: Angle | None = Field(
        None,
        description="Steepest descent, degrees below the horizontal, in (0, 90]; null = no limit.",
    )
    s2_axes: tuple[PosLength, PosLength, PosLength] | None = Field(
        None,
        description="Separation between UAVs per axis [x, y, z], metres (e.g. the RSCDWOA "
        "paper's [50, 50, 20]): two UAVs are too close when closer than all three at once (an "
        "axis-aligned box); replaces the sphere s2 in every separation check. null = the "
        "sphere s2.",
    )
    airframe: Literal["small-fixed-wing", "fast-fixed-wing", "quadrotor"] | None = Field(
        None,
        description="The UAV's class and airframe for flight simulation (uavplan simulate): "
        "the dynamics, the autopilot's guidance and the navigation error. null = by its "
        "limits: a fixed wing with a turn radius or a minimum speed, else a quadrotor.",
    )

    @field_validator("min_speed")
    @classmethod
    def _min_below_speed(cls, value: float, info: ValidationInfo) -> float:
        speed = info.data.get("speed")
        if speed is not None and value > speed:
            raise ValueError(
                f"min_speed {value:g} m/s is above speed {speed:g} m/s (need min_speed <= speed)"
            )
        return value

    @field_validator("max_speed")
    @classmethod
    def _max_above_speed(cls, value: float | None, info: ValidationInfo) -> float | None:
        speed = info.data.get("speed")
        if value is not None and speed is not None and value < speed:
            raise ValueError(
                f"max_speed {value:g} m/s is below speed {speed:g} m/s (need speed <= max_speed)"
            )
        return value


class OriginSpec(_Spec):
    """Where the local frame sits on Earth (WGS84): needed to export missions."""

    lat: Annotated[float, Field(gt=-90, lt=90, allow_inf_nan=False)] = Field(
        description="Latitude of the local point (x, y), degrees (WGS84)."
    )
    lon: Annotated[float, Field(ge=-180, le=180, allow_inf_nan=False)] = Field(
        description="Longitude of the local point (x, y), degrees (WGS84)."
    )
    alt: Coord = Field(0.0, description="Altitude above mean sea level of the local z = 0, m.")
    x: Coord = Field(0.0, description="Local x of the origin, metres.")
    y: Coord = Field(0.0, description="Local y of the origin, metres.")
    note: str = Field("", description="Where the origin comes from.")
    accuracy: Length = Field(
        0.0,
        description="At most this far (m) may an exported position lie from where the "
        "terrain data puts the local point (a lat/lon DEM laid out flat); exports warn "
        "above 1 m.",
    )
    crs: str = Field(
        "",
        max_length=100_000,
        description="Empty: the local frame is the azimuthal equidistant projection about "
        "(lat, lon). Else a projected CRS in metres (EPSG:32616, or WKT) whose grid, shifted "
        "so that the local (x, y) is at (lat, lon), is the local frame (a projected DEM's own "
        "grid).",
    )

    @field_validator("crs")
    @classmethod
    def _projected(cls, v: str) -> str:
        if v and (why := projected_crs_problem(v)) is not None:
            raise ValueError(why)
        return v


class TaskSpec(_Spec):
    """One UAV's mission."""

    id: str | None = Field(
        None, min_length=1, description="Task id; default 'uav<index>' (uav0, uav1, ...)."
    )
    start: Point = Field(description="Start [x, y] or [x, y, z], metres (z: see task_z).")
    goal: Point = Field(description="Goal, same form as start, metres.")
    start_time: Departure = Field(0.0, description="Departure time, seconds.")

    @field_validator("id")
    @classmethod
    def _plain_id(cls, value: str | None) -> str | None:
        """An id names the UAV's files in per-UAV exports: no path in it."""
        if value is not None and (
            value in (".", "..") or any(c in value for c in "/\\") or not value.isprintable()
        ):
            raise ValueError(
                "a task id names files (one per UAV in exports): no '/', '\\', control "
                "characters, '.' or '..'"
            )
        return value

    frame: Literal["local", "wgs84"] = Field(
        "local",
        description="local: start and goal in metres; wgs84: [lat, lon] or [lat, lon, alt] "
        "(degrees; alt as 'height' says), converted through the scenario's origin (required).",
    )
    height: Literal["amsl", "ground", "takeoff"] | None = Field(
        None,
        description="wgs84 tasks: what the third number is measured from: amsl (above mean sea "
        "level), ground (above the terrain under the point) or takeoff (above the terrain "
        "under the start, as a ground station shows heights). Default: ground with task_z: "
        "ground, else amsl. Local tasks use task_z.",
    )

    @model_validator(mode="after")
    def _height_for_wgs84(self) -> TaskSpec:
        if self.height is not None and self.frame != "wgs84":
            raise ValueError(
                f"height: {self.height!r} is for frame: wgs84 tasks; a local task's z is "
                "absolute or above ground by the scenario's task_z"
            )
        return self


class PlanningSpec(_Spec):
    """Planner defaults for this scenario."""

    cost: str | None = Field(
        None,
        min_length=1,
        description="Cost preset name; default 'ppswarm' in 3-D, 'length2d' in 2-D.",
    )
    n_waypoints: Annotated[int, BeforeValidator(_no_bool), Field(ge=1, le=MAX_WAYPOINTS)] = Field(
        10, description="Free path nodes between start and goal."
    )
    planner: str | None = Field(
        None,
        min_length=1,
        description="Planner name (`uavplan planners`); default: the one for the scenario's "
        "kind. `uavplan plan -a` overrides it.",
    )
    options: dict[str, Any] = Field(
        default_factory=dict,
        description="Planner options, NAME: value as `uavplan planners NAME` lists them, "
        "checked against the planner's declared options when the file is read; `uavplan plan "
        "--param` overrides them.",
    )
    iterations: Annotated[int, BeforeValidator(_no_bool), Field(ge=1, le=MAX_ITERATIONS)] | None = (
        Field(None, description="Iteration budget of `uavplan plan` (--iterations overrides it).")
    )
    pop_size: Annotated[int, BeforeValidator(_no_bool), Field(ge=1, le=MAX_PATH_POINTS)] | None = (
        Field(None, description="Population size of `uavplan plan` (--pop-size overrides it).")
    )
    time: Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=MAX_TIME)] | None = Field(
        None, description="Wall-time budget per UAV's search, seconds (--time overrides it)."
    )

    @field_validator("options", mode="before")
    @classmethod
    def _numbers(cls, value: Any) -> Any:
        """Numbers YAML 1.1 reads as text (``1e9``: PyYAML wants ``1.0e9``) as numbers, the way
        every typed field of the format takes them."""
        if not isinstance(value, Mapping):
            return value
        return {k: _number(v) for k, v in value.items()}


_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def _number(value: Any) -> Any:
    """A string that spells a finite number, as that number (else the value as it is)."""
    if isinstance(value, str) and _NUMBER.fullmatch(value.strip()):
        text = value.strip()
        number = float(text)
        if re.fullmatch(r"[-+]?\d+", text):
            return int(text)
        return number if math.isfinite(number) else value
    return value


class FleetSpec(_Spec):
    """A generated fleet: tasks uav0 ... uav<count-1> (uavplan.world.fleet_tasks)."""

    count: Annotated[int, BeforeValidator(_no_bool), Field(ge=1, le=MAX_UAVS)] = Field(
        description="Number of UAVs (tasks uav0 ... uav<count-1>)."
    )
    pattern: Literal["crossing", "random"] = Field(
        "crossing",
        description="'crossing': starts along the west/south edges, goals along the east/north "
        "edges, paired at random so the lines cross; 'random': anywhere.",
    )
    seed: Annotated[int, BeforeValidator(_no_bool), Field(ge=0, lt=2**63)] = Field(
        0, description="Seed of the generator (the same seed gives the same tasks)."
    )
    min_spacing: PosLength | None = Field(
        None,
        description="Least distance between two starts, and between two goals, metres; "
        "null = 3 * uav.s2.",
    )


class _TasksMissing:
    """Stands for a missing ``tasks`` (and no ``fleet``), so the error names ``tasks``."""


_TASKS_MISSING = _TasksMissing()


class ExecutionSpec(_Spec):
    """How far flown trajectories may depart from the plan, which a plan is made robust to
    (``uavplan.world.execution``): each UAV takes off within ``takeoff_s`` of its time, flies
    its path at a ground speed within ``speed`` (a fraction) of the planned one, and stays
    within ``track_h`` / ``track_v`` of its path."""

    takeoff_s: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=3600)] = Field(
        0.0, description="Take-off time error, seconds (either way)."
    )
    speed: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, lt=0.5)] = Field(
        0.0, description="Ground-speed error along the path, a fraction (0.03 for 3 %)."
    )
    track_h: Length = Field(0.0, description="Horizontal tracking error, metres.")
    track_v: Length = Field(0.0, description="Vertical tracking error, metres.")
    wind: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=100)] = Field(
        0.0,
        description="A steady wind's speed, m/s: adds wind / cruise speed to the speed error "
        "(a UAV that holds airspeed, the worst heading).",
    )
    source: str = Field(
        "", max_length=1000, description="Where the model comes from (plan files say it)."
    )


class ScenarioSpec(_Spec):
    """A uavplan scenario file (frame: x east, y north, z up; metres, seconds)."""

    model_config = ConfigDict(
        title="uavplan scenario",
        json_schema_extra={"oneOf": [{"required": ["tasks"]}, {"required": ["fleet"]}]},
    )

    name: str = Field(min_length=1, description="Scenario name.")
    description: str = Field("", description="Free text (sources, citations).")
    bounds: BoundsSpec | None = Field(
        None,
        description="Box the paths stay in. Optional with a terrain: x/y default to the "
        "terrain extent, z to [min terrain, max terrain + altitude max] (ground band), "
        "[min terrain, altitude max] (absolute band) or [min terrain, max terrain + 500] "
        "(no band), rounded outward to whole metres.",
    )
    terrain: TerrainSpec | None = Field(
        None, description="Terrain; absent = none (a 2-D scene, or a flat 3-D world)."
    )
    cylinders: Annotated[list[CylinderSpec], Field(max_length=MAX_ITEMS)] = Field(
        default_factory=list, description="3-D only."
    )
    circles: Annotated[list[CircleSpec], Field(max_length=MAX_ITEMS)] = Field(default_factory=list)
    polygons: Annotated[list[PolygonSpec], Field(max_length=MAX_ITEMS)] = Field(
        default_factory=list
    )
    danger_areas: Annotated[list[DangerAreaSpec], Field(max_length=MAX_ITEMS)] = Field(
        default_factory=list
    )
    uncertain_areas: Annotated[list[UncertainAreaSpec], Field(max_length=MAX_ITEMS)] = Field(
        default_factory=list
    )
    moving_obstacles: Annotated[list[MovingObstacleSpec], Field(max_length=MAX_ITEMS)] = Field(
        default_factory=list
    )
    altitude: AltitudeSpec | None = Field(None, description="Altitude band (3-D only).")
    uav: UAVSpec = Field(default_factory=lambda: UAVSpec.model_validate({}))
    task_z: Literal["absolute", "ground"] = Field(
        "absolute",
        description="Whether task z values are absolute or above the terrain (converted to "
        "absolute at load).",
    )
    tasks: Annotated[list[TaskSpec], Field(min_length=1, max_length=MAX_UAVS)] | None = Field(
        None, description="At least one task. Required unless 'fleet' is given (not both)."
    )
    fleet: FleetSpec | None = Field(
        None,
        description="Generate the tasks (uav0 ... uav<count-1>) instead of listing them; not "
        "with 'tasks'.",
    )
    planning: PlanningSpec = Field(default_factory=lambda: PlanningSpec.model_validate({}))
    no_fly: list[Annotated[str, Field(min_length=1)]] = Field(
        default_factory=list,
        description="GeoJSON files (RFC 7946, relative to the scenario file) whose Polygon and "
        "MultiPolygon features are no-fly polygons (exterior rings; a hole is no-fly too); "
        "needs 'origin'.",
    )
    execution: ExecutionSpec | None = Field(
        None,
        description="The execution error plans must tolerate. Absent: `uavplan plan` uses "
        "its default (take-off 2 s, speed 3 %, tracking 3 m / 2 m, or the named airframe's "
        "calibrated tracking error when larger) and the Python API and "
        "experiments the nominal model (flown exactly).",
    )
    origin: OriginSpec | None = Field(
        None,
        description="Geodetic origin (WGS84 lat/lon of a local point, AMSL of z = 0); "
        "absent = not geo-referenced (mission export then asks for one).",
    )

    @model_validator(mode="before")
    @classmethod
    def _tasks_or_fleet(cls, data: Any) -> Any:
        if isinstance(data, Mapping) and data.get("tasks") is None and data.get("fleet") is None:
            return {**data, "tasks": _TASKS_MISSING}
        return data

    @field_validator("tasks", mode="before")
    @classmethod
    def _tasks_given(cls, value: Any) -> Any:
        if value is _TASKS_MISSING:
            raise PydanticCustomError("missing", "Field required")
        return value

    @field_validator("fleet")
    @classmethod
    def _not_both(cls, value: FleetSpec | None, info: ValidationInfo) -> FleetSpec | None:
        if value is not None and info.data.get("tasks") is not None:
            raise ValueError(
                "give either 'tasks' or 'fleet', not both ('fleet' generates the tasks)"
            )
        return value


def schema() -> dict[str, Any]:
    """The JSON Schema of the scenario file format."""
    return ScenarioSpec.model_json_schema()


def _tidy(obj: Any) -> Any:
    """Whole floats as ints, recursively (``200`` rather than ``200.0`` in written files)."""
    if isinstance(obj, float) and obj.is_integer() and abs(obj) < 1e15:
        return int(obj)
    if isinstance(obj, dict):
        return {k: _tidy(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_tidy(v) for v in obj]
    return obj


def dump_spec(spec: ScenarioSpec) -> dict[str, Any]:
    """The spec as plain data: keys not given left out, whole floats as ints."""
    data: dict[str, Any] = _tidy(spec.model_dump(mode="json", exclude_unset=True))
    return data
