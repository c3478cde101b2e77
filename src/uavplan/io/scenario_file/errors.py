""":class:`ScenarioFileError` and :class:`Problems`, which collects one line per problem
(``<file>: <field path> = <value>: <reason>``), pydantic's errors included.
"""

from __future__ import annotations

import difflib
import json
import types
from collections.abc import Mapping, Sequence
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, ValidationError

from uavplan.io.scenario_file.schema import ScenarioSpec


class ScenarioFileError(ValueError):
    """A scenario file (or mapping) that cannot be used.

    ``problems`` holds one line per problem, each naming the file, the field path, the offending
    value and the reason.
    """

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems: list[str] = list(problems) or ["invalid scenario"]
        super().__init__("\n".join(self.problems))


class _Missing:
    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return "<missing>"


NO_VALUE: Any = _Missing()
_RAW: Any = _Missing()


def _loc_str(loc: Sequence[Any]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _clip(value: Any, budget: list[int], depth: int = 0) -> Any:
    """``value`` cut to about ``budget[0]`` scalars and 20 levels, so that formatting a value
    costs little whatever its size (a YAML alias bomb expands to billions of items)."""
    budget[0] -= 1
    if budget[0] < 0 or depth > 20:
        return ...
    if isinstance(value, Mapping):
        out: dict[str, Any] = {}
        for k, v in value.items():
            if budget[0] < 0:
                break
            out[str(k)[:100]] = _clip(v, budget, depth + 1)
        return out
    if isinstance(value, list | tuple):
        items = []
        for v in value:
            if budget[0] < 0:
                break
            items.append(_clip(v, budget, depth + 1))
        return items
    if isinstance(value, str):
        return value[:200]
    return value


def fmt_value(value: Any, limit: int = 100) -> str:
    """A value as JSON-like text of at most ``limit`` characters."""
    value = _clip(value, [limit])
    try:
        text = json.dumps(value, ensure_ascii=False, allow_nan=True, default=repr)
    except (TypeError, ValueError, RecursionError):
        text = repr(value)
    text = text.replace("Ellipsis", "...")
    return text if len(text) <= limit else text[: limit - 3] + "..."


#: Why a number is out of its range, by field name (the limits: ``schema.py``).
_RANGE_WHY = {
    **dict.fromkeys(
        ("lower", "upper", "start", "goal", "center", "vertices", "positions", "origin", "x",
         "y", "z_min", "z_max", "min", "max", "alt"),
        "coordinates and altitudes are within 10,000 km (1e7 m): beyond, a float64 path "
        "computation loses its metre-level meaning; check the units (metres)",
    ),
    **dict.fromkeys(
        ("radius", "margin", "s1", "s2", "size", "turn_radius", "width", "height",
         "min_spacing", "accuracy", "s2_axes"),
        "lengths are from 1 mm to 1,000 km, the largest area planned over; check the units "
        "(metres)",
    ),
    **dict.fromkeys(
        ("speed", "min_speed", "max_speed"),
        "speeds are from 0.01 to 1,000 m/s (about Mach 3); check the units (m/s)",
    ),
    **dict.fromkeys(("times", "start_time"), "times are within 1e7 s (about 115 days)"),
    "cell_size": "a DEM cell is from 1 cm to 100 km",
    "n_waypoints": "the limit of free waypoints per path (docs/scenario-format.md, Limits)",
    "count": "the limit of UAVs per scenario (docs/scenario-format.md, Limits)",
}  # fmt: skip
_RANGE_OPS = {"less_than_equal": ("<=", "le"), "less_than": ("<", "lt"),
              "greater_than_equal": (">=", "ge"), "greater_than": (">", "gt")}  # fmt: skip


def _raw_at(data: Any, loc: Sequence[Any]) -> Any:
    cur = data
    for part in loc:
        in_map = isinstance(cur, Mapping) and part in cur
        in_list = isinstance(cur, list) and isinstance(part, int) and -len(cur) <= part < len(cur)
        if in_map or in_list:
            cur = cur[part]
        else:
            return NO_VALUE
    return cur


class Problems:
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
            value = _raw_at(self.raw, loc) if loc else NO_VALUE
        reason = " ".join(str(reason).split())
        where = _loc_str(loc)
        if where and value is not NO_VALUE:
            self.lines.append(f"{self.source}: {where} = {fmt_value(value)}: {reason}")
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
    text = msg[:1].lower() + msg[1:]
    if kind in _RANGE_OPS:  # pydantic's words, and why the range is what it is
        op, key = _RANGE_OPS[kind]
        why = _RANGE_WHY.get(last)
        return f"{text}: {why}" if why and not (op in (">", ">=") and ctx.get(key) == 0) else text
    return text


def validation_problems(exc: ValidationError, problems: Problems) -> None:
    for err in exc.errors():
        loc = tuple(err["loc"])
        value: Any = NO_VALUE if err["type"] == "missing" else err.get("input", NO_VALUE)
        if err["type"] == "value_error" and isinstance(value, Mapping):
            value = NO_VALUE  # a whole block: the reason says what is wrong with it
        problems.add(loc, _reason(err), value)
