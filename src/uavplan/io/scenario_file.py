"""Scenario files: a :class:`~uavplan.world.Scenario` written as YAML or JSON.

The file format is a pydantic (v2) schema, :class:`ScenarioSpec`; the full reference, with units,
defaults and an example, is ``docs/scenario-format.md``. Frame: x east, y north, z up, metres.

* :func:`load_scenario` reads a ``.yaml``/``.yml``/``.json`` file (YAML for any other suffix) and
  builds the :class:`~uavplan.world.Scenario`; :func:`scenario_from_dict` does the same for an
  already parsed mapping.
* :func:`scenario_to_dict` / :func:`save_scenario` write the validated file-level spec back (the
  loaded Scenario keeps it in ``metadata["spec"]``), atomically.
* :func:`schema` is the JSON Schema of the format.
* ``fleet:`` (instead of ``tasks:``) generates the tasks with
  :func:`uavplan.world.fleet_tasks.fleet_tasks`; the spec kept and written back holds the
  ``fleet`` block, which regenerates the same tasks.

Every problem with a file is reported at once by :class:`ScenarioFileError`, one line per problem:
``<file>: <field path> = <value>: <reason>``, e.g.
``bad.yaml: tasks[0].start = [5000, 10, 150]: outside the bounds [1.0, 1.0, 48.0]..[...]``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import difflib
import json
import math
import os
import types
from collections.abc import Hashable, Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from uavplan.io.atomic import write_text_atomic
from uavplan.world import (
    UAV,
    AltitudeBand,
    Bounds,
    Circle,
    Cylinder,
    DangerArea,
    MovingObstacle,
    Polygon,
    Scenario,
    Task,
    Terrain,
    UncertainArea,
)
from uavplan.world.fleet_tasks import fleet_tasks
from uavplan.world.terrain import BUILTIN_TERRAINS, TerrainError

__all__ = [
    "ScenarioFileError",
    "ScenarioSpec",
    "load_scenario",
    "parse_scenario_spec",
    "read_scenario_data",
    "save_scenario",
    "scenario_from_dict",
    "scenario_to_dict",
    "schema",
    "spec_from_scenario",
]

#: Headroom above the highest terrain for the default z bound when there is no altitude band, m.
DEFAULT_Z_HEADROOM = 500.0

_YAML_SUFFIXES = (".yaml", ".yml")
_JSON_SUFFIXES = (".json",)


class ScenarioFileError(ValueError):
    """A scenario file (or mapping) that cannot be used.

    ``problems`` holds one line per problem, each naming the file, the field path, the offending
    value and the reason.
    """

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems: list[str] = list(problems) or ["invalid scenario"]
        super().__init__("\n".join(self.problems))


# ---------------------------------------------------------------------------- schema
def _no_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError("must be a number, not true/false")
    return value


Num = Annotated[float, BeforeValidator(_no_bool)]
PosNum = Annotated[float, BeforeValidator(_no_bool), Field(gt=0)]
NonNegNum = Annotated[float, BeforeValidator(_no_bool), Field(ge=0)]
XY = Annotated[list[Num], Field(min_length=2, max_length=2)]
Point = Annotated[list[Num], Field(min_length=2, max_length=3)]


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
    """A digital elevation model: a built-in map or a DEM file (exactly one of the two)."""

    model_config = ConfigDict(
        json_schema_extra={"oneOf": [{"required": ["builtin"]}, {"required": ["file"]}]}
    )

    builtin: Literal["spso", "jacksboro", "topobathy"] | None = Field(
        None, description="Name of a built-in terrain."
    )
    file: str | None = Field(
        None,
        min_length=1,
        description="DEM file (.tif/.tiff GeoTIFF, .npy, .npz); a relative path is relative to "
        "the scenario file's directory.",
    )
    cell_size: PosNum | None = Field(
        None,
        description="Grid spacing in metres (file only). Default: the GeoTIFF pixel scale, the "
        ".npz dx/dy, else 1.",
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

    @model_validator(mode="after")
    def _one_source(self) -> TerrainSpec:
        if (self.builtin is None) == (self.file is None):
            raise ValueError("give exactly one of 'builtin' or 'file'")
        if self.builtin is not None:
            extra = sorted({"cell_size", "origin", "key"} & self.model_fields_set)
            if extra:
                raise ValueError(f"{', '.join(extra)} only apply to a terrain 'file'")
        return self


class CylinderSpec(_Spec):
    """A vertical cylinder threat (3-D only)."""

    center: XY = Field(description="Axis position [x, y], metres.")
    radius: PosNum = Field(description="Radius, metres (> 0).")
    z_min: Num | None = Field(None, description="Bottom, absolute metres; null = unbounded.")
    z_max: Num | None = Field(None, description="Top, absolute metres; null = unbounded.")
    height: PosNum | None = Field(
        None,
        description="Top above the terrain at the center, metres (z_max = ground(center) + "
        "height); excludes z_max.",
    )
    margin: NonNegNum = Field(
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
    radius: PosNum = Field(description="Radius, metres (> 0).")
    margin: NonNegNum = Field(0.0, description="Added to the radius for collision checks, m.")


class PolygonSpec(_Spec):
    """A simple polygon obstacle, convex or not (an infinitely tall prism in 3-D)."""

    vertices: Annotated[list[XY], Field(min_length=3)] = Field(
        description="At least 3 vertices [[x, y], ...] in order, metres."
    )
    margin: NonNegNum = Field(0.0, description="Distance a path must keep from it, metres.")


class DangerAreaSpec(_Spec):
    """A cylindrical area that may be crossed at a cost (HR-MAGA Eq. 1)."""

    center: XY = Field(description="Center [x, y], metres.")
    radius: PosNum = Field(description="Radius, metres (> 0).")


class UncertainAreaSpec(_Spec):
    """A rectangle known only once revealed; revealed areas are no-fly (HR-MAGA Eq. 2)."""

    x: Num = Field(description="West edge, metres.")
    y: Num = Field(description="South edge, metres.")
    width: PosNum = Field(description="Extent along x, metres (> 0).")
    height: PosNum = Field(description="Extent along y, metres (> 0).")
    revealed: bool = Field(True, description="Whether the planner knows about it.")


class MovingObstacleSpec(_Spec):
    """A sphere (a disc in 2-D) moving along a timed piecewise-linear trajectory."""

    radius: PosNum = Field(description="Radius, metres (> 0).")
    times: Annotated[list[Num], Field(min_length=1)] = Field(
        description="Knot times, strictly increasing seconds."
    )
    positions: Annotated[list[Point], Field(min_length=1)] = Field(
        description="One position per time, [x, y, z] (3-D) or [x, y] (2-D), absolute metres."
    )


class AltitudeSpec(_Spec):
    """Allowed altitudes."""

    min: Num = Field(description="Lowest allowed altitude, metres.")
    max: Num = Field(description="Highest allowed altitude, metres (> min).")
    reference: Literal["ground", "absolute"] = Field(
        "ground", description="'ground': above the terrain; 'absolute': z values."
    )


class UAVSpec(_Spec):
    """UAV limits (defaults: PPSwarm Sect. 5.1)."""

    speed: PosNum = Field(20.0, description="Cruise speed, m/s (> 0).")
    turn_radius: NonNegNum = Field(20.0, description="Minimum turn radius, metres.")
    s1: NonNegNum = Field(15.0, description="Safety distance to threats, metres.")
    s2: NonNegNum = Field(10.0, description="Safety distance between UAVs, metres.")
    size: NonNegNum = Field(1.0, description="UAV size, metres.")


class TaskSpec(_Spec):
    """One UAV's mission."""

    id: str | None = Field(
        None, min_length=1, description="Task id; default 'uav<index>' (uav0, uav1, ...)."
    )
    start: Point = Field(description="Start [x, y] or [x, y, z], metres (z: see task_z).")
    goal: Point = Field(description="Goal, same form as start, metres.")
    start_time: NonNegNum = Field(0.0, description="Departure time, seconds.")


class PlanningSpec(_Spec):
    """Planner defaults for this scenario."""

    cost: str | None = Field(
        None,
        min_length=1,
        description="Cost preset name; default 'ppswarm' in 3-D, 'length2d' in 2-D.",
    )
    n_waypoints: Annotated[int, BeforeValidator(_no_bool), Field(ge=1)] = Field(
        10, description="Free path nodes between start and goal."
    )


class FleetSpec(_Spec):
    """A generated fleet: tasks uav0 ... uav<count-1> (uavplan.world.fleet_tasks)."""

    count: Annotated[int, BeforeValidator(_no_bool), Field(ge=1)] = Field(
        description="Number of UAVs (tasks uav0 ... uav<count-1>)."
    )
    pattern: Literal["crossing", "random"] = Field(
        "crossing",
        description="'crossing': starts along the west/south edges, goals along the east/north "
        "edges, paired at random so the lines cross; 'random': anywhere.",
    )
    seed: Annotated[int, BeforeValidator(_no_bool), Field(ge=0)] = Field(
        0, description="Seed of the generator (the same seed gives the same tasks)."
    )
    min_spacing: PosNum | None = Field(
        None,
        description="Least distance between two starts, and between two goals, metres; "
        "null = 3 * uav.s2.",
    )


class _TasksMissing:
    """Stands for a missing ``tasks`` (and no ``fleet``), so the error names ``tasks``."""


_TASKS_MISSING = _TasksMissing()


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
    cylinders: list[CylinderSpec] = Field(default_factory=list, description="3-D only.")
    circles: list[CircleSpec] = Field(default_factory=list)
    polygons: list[PolygonSpec] = Field(default_factory=list)
    danger_areas: list[DangerAreaSpec] = Field(default_factory=list)
    uncertain_areas: list[UncertainAreaSpec] = Field(default_factory=list)
    moving_obstacles: list[MovingObstacleSpec] = Field(default_factory=list)
    altitude: AltitudeSpec | None = Field(None, description="Altitude band (3-D only).")
    uav: UAVSpec = Field(default_factory=lambda: UAVSpec.model_validate({}))
    task_z: Literal["absolute", "ground"] = Field(
        "absolute",
        description="Whether task z values are absolute or above the terrain (converted to "
        "absolute at load).",
    )
    tasks: Annotated[list[TaskSpec], Field(min_length=1)] | None = Field(
        None, description="At least one task. Required unless 'fleet' is given (not both)."
    )
    fleet: FleetSpec | None = Field(
        None,
        description="Generate the tasks (uav0 ... uav<count-1>) instead of listing them; not "
        "with 'tasks'.",
    )
    planning: PlanningSpec = Field(default_factory=lambda: PlanningSpec.model_validate({}))

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


# ---------------------------------------------------------------------------- problem lines
class _Missing:
    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return "<missing>"


_NO_VALUE: Any = _Missing()
_RAW: Any = _Missing()


def _loc_str(loc: Sequence[Any]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _fmt_value(value: Any, limit: int = 100) -> str:
    try:
        text = json.dumps(value, ensure_ascii=False, allow_nan=True, default=repr)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _raw_at(data: Any, loc: Sequence[Any]) -> Any:
    cur = data
    for part in loc:
        in_map = isinstance(cur, Mapping) and part in cur
        in_list = isinstance(cur, list) and isinstance(part, int) and -len(cur) <= part < len(cur)
        if in_map or in_list:
            cur = cur[part]
        else:
            return _NO_VALUE
    return cur


class _Problems:
    """Collects problem lines for one source.

    ``index_map[key][i]`` is the index in the file of item ``i`` of list ``key`` after invalid
    items were left out (so later problems still name the right item).
    """

    def __init__(self, source: str, raw: Any) -> None:
        self.source = source
        self.raw = raw
        self.lines: list[str] = []
        self.index_map: dict[str, list[int]] = {}

    def orig(self, key: str, i: int) -> int:
        m = self.index_map.get(key)
        return m[i] if m is not None and 0 <= i < len(m) else i

    def add(self, loc: Sequence[Any], reason: str, value: Any = _RAW) -> None:
        loc = tuple(loc)
        if len(loc) >= 2 and isinstance(loc[0], str) and isinstance(loc[1], int):
            loc = (loc[0], self.orig(loc[0], loc[1]), *loc[2:])
        if value is _RAW:
            value = _raw_at(self.raw, loc) if loc else _NO_VALUE
        reason = " ".join(str(reason).split())
        where = _loc_str(loc)
        if where and value is not _NO_VALUE:
            self.lines.append(f"{self.source}: {where} = {_fmt_value(value)}: {reason}")
        elif where:
            self.lines.append(f"{self.source}: {where}: {reason}")
        else:
            self.lines.append(f"{self.source}: {reason}")

    def raise_if_any(self) -> None:
        if self.lines:
            raise ScenarioFileError(self.lines)


def _unwrap(tp: Any) -> Any:
    while True:
        origin = get_origin(tp)
        if origin is Annotated:
            tp = get_args(tp)[0]
            continue
        if origin in (Union, types.UnionType):
            args = [a for a in get_args(tp) if a is not type(None)]
            if len(args) == 1:
                tp = args[0]
                continue
        return tp


def _model_at(loc: Sequence[Any]) -> type[BaseModel] | None:
    """The file-level model found at a field path (for listing its keys)."""
    cur: Any = ScenarioSpec
    for part in loc:
        cur = _unwrap(cur)
        if isinstance(part, int):
            if get_origin(cur) is list:
                cur = get_args(cur)[0]
                continue
            return None
        if isinstance(cur, type) and issubclass(cur, BaseModel) and part in cur.model_fields:
            cur = cur.model_fields[part].annotation
        else:
            return None
    cur = _unwrap(cur)
    return cur if isinstance(cur, type) and issubclass(cur, BaseModel) else None


_POINT_FIELDS = {"start", "goal", "lower", "upper", "positions"}
_XY_FIELDS = {"center", "origin", "vertices"}


def _reason(err: Mapping[str, Any]) -> str:
    kind = err["type"]
    loc = tuple(err["loc"])
    ctx = err.get("ctx") or {}
    msg = str(err["msg"])
    last = next((p for p in reversed(loc) if isinstance(p, str)), "")
    if kind == "extra_forbidden":
        model = _model_at(loc[:-1])
        allowed = list(model.model_fields) if model is not None else []
        close = difflib.get_close_matches(str(loc[-1]), allowed, n=1)
        if close:
            return f"unknown key (did you mean '{close[0]}'?)"
        return "unknown key" + (f" (allowed: {', '.join(allowed)})" if allowed else "")
    if kind == "missing":
        if loc == ("tasks",):
            return "required field missing (or give 'fleet' to generate the tasks)"
        return "required field missing"
    if kind == "finite_number":
        hint = "; use null for no limit" if last in ("z_min", "z_max") else ""
        return f"must be a finite number (NaN and infinity are not allowed{hint})"
    if kind in ("too_short", "too_long") and "actual_length" in ctx:
        n = ctx["actual_length"]
        if loc and isinstance(loc[-1], int) and last in _POINT_FIELDS:
            last = "point"
        if loc == ("tasks",):
            return "at least one task is required"
        if last == "vertices" and not isinstance(loc[-1], int):
            return f"a polygon needs at least 3 vertices, got {n}"
        if last in _POINT_FIELDS or last == "point":
            return f"a point needs 2 or 3 coordinates, [x, y] or [x, y, z], got {n}"
        if last in _XY_FIELDS:
            return f"needs exactly 2 numbers [x, y], got {n}"
        bound = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        word = "at least" if kind == "too_short" else "at most"
        return f"needs {word} {bound} item(s), got {n}"
    if kind == "value_error":
        return msg.removeprefix("Value error, ")
    return msg[:1].lower() + msg[1:]


def _validation_problems(exc: ValidationError, problems: _Problems) -> None:
    for err in exc.errors():
        loc = tuple(err["loc"])
        value: Any = _NO_VALUE if err["type"] == "missing" else err.get("input", _NO_VALUE)
        if err["type"] == "value_error" and isinstance(value, Mapping):
            value = _NO_VALUE  # a whole block: the reason says what is wrong with it
        problems.add(loc, _reason(err), value)


# ---------------------------------------------------------------------------- reading
class _UniqueKeyLoader(yaml.SafeLoader):
    """A safe YAML loader that rejects duplicate keys (PyYAML keeps the last one silently)."""


def _construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> dict[Any, Any]:
    seen: set[Any] = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":  # '<<: *anchor' (merged keys may repeat)
            continue
        key = loader.construct_object(key_node, deep=True)
        if isinstance(key, Hashable):
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.add(key)
    return loader.construct_mapping(node, deep=True)


_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
    _construct_mapping,
)


def _no_duplicate_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _parse_text(text: str, fmt: str, source: str) -> Any:
    if fmt == "json":
        try:
            return json.loads(text, object_pairs_hook=_no_duplicate_pairs)
        except json.JSONDecodeError as exc:
            raise ScenarioFileError(
                [f"{source}: line {exc.lineno}, column {exc.colno}: not valid JSON: {exc.msg}"]
            ) from None
        except ValueError as exc:
            raise ScenarioFileError([f"{source}: not valid JSON: {exc}"]) from None
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # a SafeLoader subclass
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        what = " ".join(str(exc.problem or exc.context or "syntax error").split())
        raise ScenarioFileError([f"{source}: {where}not valid YAML: {what}"]) from None
    except yaml.YAMLError as exc:
        what = " ".join(str(exc).split())
        raise ScenarioFileError([f"{source}: not valid YAML: {what}"]) from None
    except RecursionError:
        raise ScenarioFileError([f"{source}: not valid YAML: nested too deeply"]) from None


def _format_for(path: Path) -> str:
    return "json" if path.suffix.lower() in _JSON_SUFFIXES else "yaml"


def read_scenario_data(path: str | Path) -> Any:
    """The parsed (not yet validated) content of a scenario file.

    Raises:
        ScenarioFileError: the file is missing, unreadable, binary, or not YAML/JSON.
    """
    p = Path(path)
    source = str(path)
    if not p.exists():
        raise ScenarioFileError([f"{source}: no such file ({os.path.abspath(p)})"])
    if p.is_dir():
        raise ScenarioFileError([f"{source}: is a directory, not a scenario file"])
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise ScenarioFileError([f"{source}: cannot read: {exc.strerror or exc}"]) from None
    if b"\x00" in data:
        raise ScenarioFileError([f"{source}: not a YAML or JSON file (binary data)"])
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ScenarioFileError(
            [f"{source}: not a YAML or JSON file (not UTF-8 text: byte {exc.start})"]
        ) from None
    return _parse_text(text, _format_for(p), source)


def _check_mapping(data: Any, source: str) -> dict[str, Any]:
    if data is None:
        raise ScenarioFileError([f"{source}: the file is empty (expected a mapping of keys)"])
    if not isinstance(data, Mapping):
        kind = "a list" if isinstance(data, list) else f"a single value {_fmt_value(data, 60)}"
        raise ScenarioFileError(
            [f"{source}: the top level must be a mapping of keys (name, tasks, ...), got {kind}"]
        )
    return dict(data)


def parse_scenario_spec(data: Any, source: str = "<scenario>") -> ScenarioSpec:
    """Validate parsed file content against the schema (structure only, no semantic checks)."""
    mapping = _check_mapping(data, source)
    problems = _Problems(source, mapping)
    try:
        return ScenarioSpec.model_validate(mapping)
    except ValidationError as exc:
        _validation_problems(exc, problems)
        problems.raise_if_any()
        raise  # pragma: no cover - a ValidationError always has errors


_LIST_KEYS = (
    "cylinders",
    "circles",
    "polygons",
    "danger_areas",
    "uncertain_areas",
    "moving_obstacles",
    "tasks",
)
#: Top-level keys that can be left out, after their problems are reported, without changing any
#: other check (they do not affect bounds, obstacles or where tasks start and end).
_DROPPABLE_KEYS = ("description", "uav", "planning")


def _pruned(
    data: dict[str, Any], exc: ValidationError
) -> tuple[dict[str, Any], dict[str, list[int]]] | None:
    """``data`` without the parts that failed validation, when the rest can still be checked.

    Invalid list items (an obstacle, a task) and unknown or droppable top-level keys are left
    out; any other structural problem (bounds, terrain, altitude, ...) stops the checks there.
    Returns the pruned data and, per pruned list, the file index of each remaining item.
    """
    drop_keys: set[str] = set()
    drop_items: dict[str, set[int]] = {}
    fill_name = False
    for err in exc.errors():
        loc = tuple(err["loc"])
        if not loc or not isinstance(loc[0], str):
            return None
        top = loc[0]
        if (len(loc) == 1 and err["type"] == "extra_forbidden") or top in _DROPPABLE_KEYS:
            drop_keys.add(top)
        elif top == "name" and len(loc) == 1:
            fill_name = True
        elif top in _LIST_KEYS and len(loc) >= 2 and isinstance(loc[1], int):
            drop_items.setdefault(top, set()).add(loc[1])
        else:
            return None
    out = {k: v for k, v in data.items() if k not in drop_keys}
    if fill_name:
        out["name"] = "unnamed"
    index_map: dict[str, list[int]] = {}
    for key, bad in drop_items.items():
        items = out[key]
        keep = [i for i in range(len(items)) if i not in bad]
        out[key] = [items[i] for i in keep]
        index_map[key] = keep
    if not out.get("tasks") and out.get("fleet") is None:
        return None
    return out, index_map


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario file (``.yaml``/``.yml``/``.json``; YAML for other suffixes).

    The returned Scenario keeps the validated file-level spec in ``metadata["spec"]`` (a plain
    dict), the file in ``metadata["source"]`` and its directory in ``metadata["base_dir"]``.

    Raises:
        ScenarioFileError: with every problem found, one line each.
    """
    p = Path(path)
    data = read_scenario_data(p)
    return scenario_from_dict(data, source=str(path), base_dir=p.resolve().parent)


def scenario_from_dict(
    data: Any, source: str = "<scenario>", base_dir: str | Path | None = None
) -> Scenario:
    """Build a Scenario from parsed file content.

    Args:
        data: the mapping read from a file (or written by hand).
        source: the name used in problem lines (usually the file name).
        base_dir: directory relative terrain file paths start from (default: the current one).

    Raises:
        ScenarioFileError: with every problem found, one line each.
    """
    mapping = _check_mapping(data, source)
    problems = _Problems(source, mapping)
    base = (Path(base_dir) if base_dir is not None else Path.cwd()).resolve()
    try:
        spec = ScenarioSpec.model_validate(mapping)
    except ValidationError as exc:
        _validation_problems(exc, problems)
        # Check what is left too, so that one pass reports every problem it can.
        pruned = _pruned(mapping, exc)
        if pruned is not None:
            rest: ScenarioSpec | None = None
            with contextlib.suppress(ValidationError):
                rest = ScenarioSpec.model_validate(pruned[0])
            if rest is not None:
                problems.index_map = pruned[1]
                with contextlib.suppress(ScenarioFileError):
                    _build(rest, problems, base)
        problems.raise_if_any()
        raise  # pragma: no cover - a ValidationError always has errors
    return _build(spec, problems, base)


# ---------------------------------------------------------------------------- building
@cache
def _builtin_terrain(name: str) -> Terrain:
    """Built-in terrains are immutable (read-only heights), so they are read once per process."""
    return Terrain.builtin(name)


def _load_terrain(ts: TerrainSpec, problems: _Problems, base_dir: Path) -> Terrain | None:
    if ts.builtin is not None:
        try:
            return _builtin_terrain(ts.builtin)
        except Exception as exc:
            problems.add(("terrain", "builtin"), f"cannot load the built-in terrain: {exc}")
            return None
    assert ts.file is not None
    path = Path(ts.file).expanduser()
    if not path.is_absolute():
        path = base_dir / path
    resolved = Path(os.path.abspath(path))
    if not resolved.exists():
        problems.add(("terrain", "file"), f"DEM file not found: {resolved}")
        return None
    if resolved.is_dir():
        problems.add(("terrain", "file"), f"is a directory, not a DEM file: {resolved}")
        return None
    origin = (float(ts.origin[0]), float(ts.origin[1]))
    try:
        return Terrain.from_file(resolved, cell_size=ts.cell_size, origin=origin, key=ts.key)
    except TerrainError as exc:
        problems.add(("terrain", "file"), str(exc))
        return None
    except Exception as exc:
        problems.add(("terrain", "file"), f"cannot read the DEM {resolved}: {exc}")
        return None


def _default_z(terrain: Terrain, altitude: AltitudeSpec | None) -> tuple[float, float]:
    hmin = float(np.min(terrain.heights))
    hmax = float(np.max(terrain.heights))
    if altitude is None:
        top = hmax + DEFAULT_Z_HEADROOM
    elif altitude.reference == "ground":
        top = hmax + altitude.max
    else:
        top = altitude.max
    return float(math.floor(hmin)), float(math.ceil(top))


def _dim_reason(spec: ScenarioSpec, dim: int) -> str:
    if spec.terrain is not None:
        return "3-D (it has a terrain)"
    return f"{dim}-D (bounds have {dim} values)"


def _build(spec: ScenarioSpec, problems: _Problems, base_dir: Path) -> Scenario:
    terrain: Terrain | None = None
    terrain_failed = False
    if spec.terrain is not None:
        terrain = _load_terrain(spec.terrain, problems, base_dir)
        terrain_failed = terrain is None

    # ---- dimension
    dim: int | None
    if spec.terrain is not None:
        dim = 3
    elif spec.bounds is not None:
        dim = len(spec.bounds.lower)
    else:
        problems.add(
            ("bounds",), "required when there is no terrain (lower and upper corners)", _NO_VALUE
        )
        dim = None

    def ground(x: float, y: float) -> float:
        return float(terrain.height(x, y)) if terrain is not None else 0.0

    # ---- altitude band
    altitude: AltitudeBand | None = None
    if spec.altitude is not None:
        if dim == 2:
            problems.add(
                ("altitude",),
                "an altitude band needs a 3-D scenario (a terrain or [x, y, z] bounds)",
            )
        a = spec.altitude
        try:
            altitude = AltitudeBand(a.min, a.max, a.reference)
        except ValueError as exc:
            problems.add(("altitude",), str(exc))

    # ---- bounds
    bounds: Bounds | None = None
    if spec.bounds is not None:
        lo, hi = list(spec.bounds.lower), list(spec.bounds.upper)
        if len(lo) != len(hi):
            problems.add(
                ("bounds",),
                f"lower has {len(lo)} values and upper {len(hi)}; give both as [x, y] or both "
                "as [x, y, z]",
            )
        else:
            bad = [f"{'xyz'[k]}: {lo[k]:g} >= {hi[k]:g}" for k in range(len(lo)) if lo[k] >= hi[k]]
            if bad:
                problems.add(
                    ("bounds",), f"lower must be below upper on every axis ({'; '.join(bad)})"
                )
            elif len(lo) == 2 and spec.terrain is not None:
                if terrain is not None:
                    zlo, zhi = _default_z(terrain, spec.altitude)
                    try:
                        bounds = Bounds((*lo, zlo), (*hi, zhi))
                    except ValueError as exc:
                        problems.add(("bounds",), f"default z range [{zlo:g}, {zhi:g}]: {exc}")
            else:
                try:
                    bounds = Bounds(tuple(lo), tuple(hi))
                except ValueError as exc:
                    problems.add(("bounds",), str(exc))
    elif terrain is not None:
        xmin, xmax, ymin, ymax = (float(v) for v in terrain.extent)
        zlo, zhi = _default_z(terrain, spec.altitude)
        try:
            bounds = Bounds((xmin, ymin, zlo), (xmax, ymax, zhi))
        except ValueError as exc:
            problems.add(
                ("altitude",) if spec.altitude is not None else ("terrain",),
                f"the default bounds z range [{zlo:g}, {zhi:g}] is empty ({exc}); give bounds",
            )

    # ---- UAV
    uav: UAV | None = None
    try:
        uav = UAV(**spec.uav.model_dump())
    except ValueError as exc:
        problems.add(("uav",), str(exc))

    # ---- static obstacles
    cylinders: list[Cylinder] = []
    if spec.cylinders and dim == 2:
        problems.add(
            ("cylinders",),
            "a 2-D scenario has no cylinders (use circles, or make it 3-D with a terrain or "
            "[x, y, z] bounds)",
            _NO_VALUE,
        )
    else:
        for i, c in enumerate(spec.cylinders):
            z_max = c.z_max
            if c.height is not None:
                if terrain_failed:
                    continue
                z_max = ground(c.center[0], c.center[1]) + c.height
            try:
                cylinders.append(
                    Cylinder(
                        (c.center[0], c.center[1]),
                        c.radius,
                        -np.inf if c.z_min is None else c.z_min,
                        np.inf if z_max is None else z_max,
                        c.margin,
                    )
                )
            except ValueError as exc:
                problems.add(("cylinders", i), str(exc), _NO_VALUE)

    circles: list[Circle] = []
    for i, ci in enumerate(spec.circles):
        try:
            circles.append(Circle((ci.center[0], ci.center[1]), ci.radius, ci.margin))
        except ValueError as exc:
            problems.add(("circles", i), str(exc), _NO_VALUE)

    polygons: list[Polygon] = []
    for i, pg in enumerate(spec.polygons):
        try:
            polygons.append(Polygon(tuple((v[0], v[1]) for v in pg.vertices), pg.margin))
        except ValueError as exc:
            problems.add(("polygons", i, "vertices"), str(exc))

    dangers: list[DangerArea] = []
    for i, d in enumerate(spec.danger_areas):
        try:
            dangers.append(DangerArea((d.center[0], d.center[1]), d.radius))
        except ValueError as exc:
            problems.add(("danger_areas", i), str(exc), _NO_VALUE)

    uncertain: list[UncertainArea] = []
    for i, u in enumerate(spec.uncertain_areas):
        try:
            uncertain.append(UncertainArea(u.x, u.y, u.width, u.height, u.revealed))
        except ValueError as exc:
            problems.add(("uncertain_areas", i), str(exc), _NO_VALUE)

    moving: list[MovingObstacle] = []
    for i, m in enumerate(spec.moving_obstacles):
        ok = True
        for k, pos in enumerate(m.positions):
            if dim is not None and len(pos) != dim:
                problems.add(
                    ("moving_obstacles", i, "positions", k),
                    f"has {len(pos)} coordinates but the scenario is {_dim_reason(spec, dim)}",
                )
                ok = False
        if len(m.positions) != len(m.times):
            problems.add(
                ("moving_obstacles", i),
                f"{len(m.times)} times but {len(m.positions)} positions (one position per time)",
                _NO_VALUE,
            )
            ok = False
        if not ok:
            continue
        try:
            moving.append(MovingObstacle(m.radius, np.asarray(m.times), np.asarray(m.positions)))
        except ValueError as exc:
            problems.add(("moving_obstacles", i), str(exc), _NO_VALUE)

    # ---- tasks
    tasks: list[Task] = []
    checks: list[tuple[int, str, tuple[float, ...]]] = []  # (spec index, which, point)
    seen: dict[str, int] = {}
    for i, t in enumerate(spec.tasks or []):
        tid = t.id if t.id is not None else f"uav{problems.orig('tasks', i)}"
        if tid in seen:
            problems.add(
                ("tasks", i, "id"),
                f"duplicate task id (also tasks[{problems.orig('tasks', seen[tid])}])",
                tid,
            )
        seen.setdefault(tid, i)
        points: dict[str, tuple[float, ...]] = {}
        for which in ("start", "goal"):
            v = [float(c) for c in getattr(t, which)]
            if dim is not None and len(v) != dim:
                problems.add(
                    ("tasks", i, which),
                    f"has {len(v)} coordinates but the scenario is {_dim_reason(spec, dim)}",
                )
                continue
            if spec.task_z == "ground" and len(v) == 3:
                if terrain_failed:
                    continue
                v[2] += ground(v[0], v[1])
            points[which] = tuple(v)
            checks.append((i, which, tuple(v)))
        if len(points) != 2:
            continue
        try:
            tasks.append(Task(tid, points["start"], points["goal"], t.start_time))
        except ValueError as exc:
            problems.add(("tasks", i), str(exc), _NO_VALUE)

    # ---- the scenario (with whatever was valid), then where the tasks start and end
    if not tasks and checks:  # no valid task, but single points to check: scene for checks only
        p0 = checks[0][2]
        tasks.append(Task("check", p0, p0))
    if spec.fleet is not None and bounds is not None:  # stands in until the fleet is generated
        tasks.append(Task("fleet", bounds.lower, bounds.lower))
    if bounds is None or uav is None or not tasks or dim is None or terrain_failed:
        problems.raise_if_any()
        raise ScenarioFileError([f"{problems.source}: invalid scenario"])  # pragma: no cover
    try:
        scenario = Scenario(
            name=spec.name,
            bounds=bounds,
            tasks=tuple(tasks),
            terrain=terrain,
            circles=tuple(circles),
            polygons=tuple(polygons),
            cylinders=tuple(cylinders),
            danger_areas=tuple(dangers),
            uncertain_areas=tuple(uncertain),
            moving_obstacles=tuple(moving),
            altitude=altitude,
            uav=uav,
            cost=spec.planning.cost or ("length2d" if dim == 2 else "ppswarm"),
            n_waypoints=spec.planning.n_waypoints,
            description=spec.description,
            metadata={
                "source": problems.source,
                "base_dir": str(base_dir),
                "spec": _dump_spec(spec),
            },
        )
    except ValueError as exc:
        problems.add((), str(exc))
        problems.raise_if_any()
        raise  # pragma: no cover
    for i, which, point in checks:
        for reason in scenario.point_problems(np.asarray(point)):
            problems.add(("tasks", i, which), reason)
    problems.raise_if_any()
    if spec.fleet is not None:
        scenario = _with_generated_fleet(scenario, spec.fleet, problems)
    return scenario


def _with_generated_fleet(scenario: Scenario, fleet: FleetSpec, problems: _Problems) -> Scenario:
    """The scenario with the tasks its ``fleet`` block generates (every other check passed)."""
    try:
        tasks = fleet_tasks(
            scenario,
            fleet.count,
            seed=fleet.seed,
            pattern=fleet.pattern,
            min_spacing=fleet.min_spacing,
        )
    except ValueError as exc:
        problems.add(("fleet",), str(exc))
        problems.raise_if_any()
        raise  # pragma: no cover
    scenario.metadata["fleet"] = fleet.model_dump()
    return dataclasses.replace(scenario, tasks=tasks)


# ---------------------------------------------------------------------------- writing
def _tidy(obj: Any) -> Any:
    """Whole floats as ints, recursively (``200`` rather than ``200.0`` in written files)."""
    if isinstance(obj, float) and obj.is_integer() and abs(obj) < 1e15:
        return int(obj)
    if isinstance(obj, dict):
        return {k: _tidy(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_tidy(v) for v in obj]
    return obj


def _dump_spec(spec: ScenarioSpec) -> dict[str, Any]:
    data: dict[str, Any] = _tidy(spec.model_dump(mode="json", exclude_unset=True))
    return data


def _num_or_none(v: float) -> float | None:
    return None if math.isinf(v) else float(v)


def spec_from_scenario(scenario: Scenario) -> ScenarioSpec:
    """The file-level spec of a Scenario built in code (absolute task z, full bounds).

    Raises:
        ScenarioFileError: the terrain is not a built-in one (a file cannot embed a DEM).
    """
    s = scenario
    terrain: dict[str, Any] | None = None
    if s.terrain is not None:
        t = s.terrain
        same = False
        if t.name in BUILTIN_TERRAINS:
            b = _builtin_terrain(t.name)
            same = (t.shape, t.x0, t.y0, t.dx, t.dy) == (b.shape, b.x0, b.y0, b.dx, b.dy)
        if not same:
            raise ScenarioFileError(
                [
                    f"{s.name}: terrain = {t.name!r}: not a built-in terrain; a scenario file "
                    "cannot embed a DEM (save the heights to .npy and use terrain.file)"
                ]
            )
        terrain = {"builtin": t.name}
    data: dict[str, Any] = {
        "name": s.name,
        "description": s.description,
        "bounds": {"lower": list(s.bounds.lower), "upper": list(s.bounds.upper)},
        "terrain": terrain,
        "cylinders": [
            {
                "center": list(c.center),
                "radius": c.radius,
                "z_min": _num_or_none(c.z_min),
                "z_max": _num_or_none(c.z_max),
                "margin": c.margin,
            }
            for c in s.cylinders
        ],
        "circles": [
            {"center": list(c.center), "radius": c.radius, "margin": c.margin} for c in s.circles
        ],
        "polygons": [
            {"vertices": [list(v) for v in p.vertices], "margin": p.margin} for p in s.polygons
        ],
        "danger_areas": [{"center": list(d.center), "radius": d.radius} for d in s.danger_areas],
        "uncertain_areas": [
            {"x": u.x, "y": u.y, "width": u.width, "height": u.height, "revealed": u.revealed}
            for u in s.uncertain_areas
        ],
        "moving_obstacles": [
            {
                "radius": m.radius,
                "times": m.times.tolist(),
                "positions": m.positions[:, : s.dim].tolist(),
            }
            for m in s.moving_obstacles
        ],
        "uav": {
            "speed": s.uav.speed,
            "turn_radius": s.uav.turn_radius,
            "s1": s.uav.s1,
            "s2": s.uav.s2,
            "size": s.uav.size,
        },
        "task_z": "absolute",
        "tasks": [
            {"id": t.id, "start": list(t.start), "goal": list(t.goal), "start_time": t.start_time}
            for t in s.tasks
        ],
        "planning": {"cost": s.cost, "n_waypoints": s.n_waypoints},
    }
    if s.altitude is not None:
        a = s.altitude
        data["altitude"] = {"min": a.min, "max": a.max, "reference": a.reference}
    if terrain is None:
        del data["terrain"]
    return _validated(data, s.name)


def _validated(data: Any, source: str) -> ScenarioSpec:
    return parse_scenario_spec(data, source)


def scenario_to_dict(spec: ScenarioSpec | Mapping[str, Any] | Scenario) -> dict[str, Any]:
    """The file form of a scenario: the validated spec dumped to plain data.

    Accepts a :class:`ScenarioSpec`, a mapping (validated first) or a :class:`Scenario` (its
    ``metadata["spec"]`` when it was loaded from a file, else :func:`spec_from_scenario`). Keys
    that were not given are left out, so a file round-trips to the same content.
    """
    if isinstance(spec, ScenarioSpec):
        model = spec
    elif isinstance(spec, Scenario):
        stored = spec.metadata.get("spec")
        if isinstance(stored, Mapping):
            model = _validated(dict(stored), spec.metadata.get("source", spec.name))
        else:
            model = spec_from_scenario(spec)
    else:
        model = _validated(spec, "<scenario>")
    return _dump_spec(model)


def _json_text(obj: Any, indent: int = 0) -> str:
    """JSON with lists of plain numbers/strings kept on one line."""
    pad = "  " * (indent + 1)
    end = "  " * indent
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{pad}{json.dumps(k)}: {_json_text(v, indent + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + end + "}"
    if isinstance(obj, list):
        if all(not isinstance(v, dict | list) for v in obj) or all(
            isinstance(v, list) and all(not isinstance(w, dict | list) for w in v) for v in obj
        ):
            return json.dumps(obj, ensure_ascii=False)
        return "[\n" + ",\n".join(pad + _json_text(v, indent + 1) for v in obj) + "\n" + end + "]"
    return json.dumps(obj, ensure_ascii=False)


_HEADER = "# uavplan scenario file (format: docs/scenario-format.md)\n"


def dumps_scenario(data: Mapping[str, Any], fmt: Literal["yaml", "json"]) -> str:
    """Text of a scenario file dict in ``"yaml"`` or ``"json"``."""
    if fmt == "json":
        return _json_text(dict(data)) + "\n"
    body = yaml.safe_dump(
        dict(data), sort_keys=False, default_flow_style=None, allow_unicode=True, width=100
    )
    return _HEADER + body


def _rebase_terrain_file(data: dict[str, Any], from_dir: Path, to_dir: Path) -> None:
    terrain = data.get("terrain")
    if not isinstance(terrain, dict) or not terrain.get("file"):
        return
    f = Path(terrain["file"]).expanduser()
    if f.is_absolute():
        return
    target = (from_dir / f).resolve()
    try:
        terrain["file"] = Path(os.path.relpath(target, to_dir.resolve())).as_posix()
    except ValueError:  # another drive (Windows)
        terrain["file"] = str(target)


def _atomic_write(path: Path, text: str) -> None:
    where = str(path)
    parent = path.parent
    if not parent.is_dir():
        raise ScenarioFileError(
            [f"{where}: cannot write: directory {os.path.abspath(parent)} does not exist"]
        )
    if path.is_dir():
        raise ScenarioFileError([f"{where}: cannot write: it is a directory"])
    try:
        write_text_atomic(path, text)
    except OSError as exc:
        raise ScenarioFileError([f"{where}: cannot write: {exc.strerror or exc}"]) from None


def save_scenario(
    spec: ScenarioSpec | Mapping[str, Any] | Scenario,
    path: str | Path,
    *,
    base_dir: str | Path | None = None,
) -> Path:
    """Write a scenario file, YAML (``.yaml``/``.yml``) or JSON (``.json``) by ``path``'s suffix.

    The file is written to a temporary file beside ``path`` and moved over it, so an existing
    file is replaced whole or not at all. A relative ``terrain.file`` is rewritten relative to the
    new file's directory (it is taken relative to ``base_dir``, or to the directory the Scenario
    was loaded from, or else to the current directory).

    Raises:
        ScenarioFileError: invalid content, an unknown suffix, or a failed write (the old file,
            if any, is left intact).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in _YAML_SUFFIXES + _JSON_SUFFIXES:
        raise ScenarioFileError(
            [f"{path}: cannot write: unknown suffix {suffix or '(none)'!r} (.yaml, .yml, .json)"]
        )
    data = scenario_to_dict(spec)
    if base_dir is None and isinstance(spec, Scenario):
        base_dir = spec.metadata.get("base_dir")
    _rebase_terrain_file(data, Path(base_dir) if base_dir else Path.cwd(), p.parent)
    _atomic_write(p, dumps_scenario(data, "json" if suffix in _JSON_SUFFIXES else "yaml"))
    return p
