"""Plan files (``plan.json``): the one module that writes and reads them.

**Format 4** (``"format": "uavplan.plan/4"``), a JSON object (its JSON Schema:
:func:`plan_schema`, ``uavplan schema plan``; described in ``docs/plan-format.md``):

* ``scenario``, ``algorithm``, ``config`` (the planner's options), ``seed``, ``version``,
  ``python``, ``frame`` (local ENU metres: x east, y north, z up, absolute altitudes; seconds);
* ``feasible``: the plan's verdict (with a fleet planner, separation between UAVs included);
  ``separation_checked``: whether separation between UAVs was part of planning;
* ``execution``: the execution model the plan was made for (take-off, speed and tracking
  errors; :mod:`uavplan.world.execution`), and ``margins`` (``null`` until the verifier has
  measured them): what each UAV and the tightest pairs tolerate (:mod:`uavplan.verify.robust`);
* ``fleet`` (fleet planners only): priority order, fleet cost, verdict, history, restart
  costs, wall time, the planner's figures;
* ``uavs``: one record per UAV: ``id``, ``waypoints`` ``[[x, y(, z)], ...]`` and ``times``
  (the planned timed polyline), ``cost``, ``terms``, ``cost_model``, ``feasible``,
  ``violations``, ``length``, ``evaluations``, ``iterations``, ``wall_time``, ``history``,
  ``first_feasible_iteration``, ``info`` (the planner's figures), ``flown`` (``kind``:
  ``smoothed`` or ``polyline``, ``points``, ``times``, ``feasible``, ``violations``: the
  trajectory the UAV is to fly and that the plan guarantees; ``feasible`` includes the UAV's
  kinematic limits), and optionally ``smoothed`` (``points``, ``times``, ``clear``,
  ``violations``: a Dubins-smoothed version that the plan does not declare, informative).

Every file is strict JSON (RFC 8259): a number that is not finite (the infinite cost of a path
that fails a check under the ``inf`` rule, a history entry before the first candidate) is
``null``, and every field that can be ``null`` says what it means in ``docs/plan-format.md``.
Format 2 was format 3 with such numbers as the strings ``"inf"``/``"-inf"``; format 3 had no
``execution`` and ``margins`` (its plans are read as made for the nominal model); both load.
Coordinates and times are rounded to 6 decimals (micrometres, microseconds).

**Reading** (:func:`read_plan_file`, :func:`parse_plan`) returns a typed :class:`PlanFile` whose
UAVs give their trajectories (:meth:`UAVPlan.trajectory`: flown, planned or smoothed, as
:class:`Trajectory`); it reads formats 3, 2 and 1 (no top-level ``feasible``, no per-UAV
``cost_model``, ``info`` and ``flown``: the planned polyline is then what is flown), and a bare
``{"uavs": [{"id", "waypoints", "times"}, ...]}``. A
file it cannot read raises :class:`PlanFormatError` with one line naming the file, the field
and the value.
"""

from __future__ import annotations

import itertools
import json
import math
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from uavplan import __version__
from uavplan.io.atomic import write_json_atomic
from uavplan.io.scenario_file.schema import MAX_COORD, MAX_TIME, ExecutionSpec, OriginSpec
from uavplan.world.geo import GeoError, GeoOrigin
from uavplan.world.terrain import not_a_regular_file

#: The largest plan file read (JSON takes about 15 times its text in memory once decoded).
MAX_PLAN_BYTES = 256 * 2**20

if TYPE_CHECKING:
    from uavplan.planners.core.results import FleetResult, PlanResult
    from uavplan.planners.fleet.fleet_plan import FleetPlan

FloatArray = NDArray[np.float64]

PLAN_FORMAT = "uavplan.plan/4"
#: Which trajectory of a UAV: the one it is to fly (declared), its planned polyline, or the
#: informative smoothed version.
TrajectoryKind = Literal["flown", "planned", "smoothed"]
#: Every format this module reads.
READABLE_FORMATS = ("uavplan.plan/1", "uavplan.plan/2", "uavplan.plan/3", PLAN_FORMAT)
FRAME = "local ENU metres: x east, y north, z up (absolute altitude)"


class PlanFormatError(ValueError):
    """A plan that cannot be read: ``problems`` holds one line naming the file, field and value."""

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems: list[str] = list(problems) or ["invalid plan"]
        super().__init__("\n".join(self.problems))


# ====================================================================================== writing
def _num(v: float) -> float | None:
    """JSON has no infinity: a number that is not finite is written as null."""
    v = float(v)
    return v if math.isfinite(v) else None


def _points(a: Any) -> list[Any]:
    out: list[Any] = np.asarray(a, dtype=np.float64).round(6).tolist()
    return out


def _plain(obj: Any) -> Any:
    """JSON-ready: NumPy scalars and arrays as Python numbers and lists, non-finite as null."""
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return _num(float(obj))
    return obj


def uav_record(r: PlanResult) -> dict[str, Any]:
    """The ``uavs`` entry of one UAV's result."""
    rec: dict[str, Any] = {
        "id": r.uav_id,
        "waypoints": _points(r.waypoints),
        "times": _points(r.times),
        "cost": _num(r.cost),
        "terms": {k: _num(v) for k, v in r.terms.items()},
        "cost_model": r.cost_model,
        "feasible": bool(r.feasible),
        "violations": list(r.violations),
        "length": r.length,
        "evaluations": int(r.evaluations),
        "iterations": int(r.iterations),
        "wall_time": float(r.wall_time),
        "history": [_num(v) for v in np.asarray(r.history)],
        "first_feasible_iteration": r.first_feasible_iteration,
        "info": _plain(r.info),
    }
    pts, ts = r.flown_trajectory()
    rec["flown"] = {
        "kind": r.flown_kind if r.flown is not None else "polyline",
        "points": _points(pts),
        "times": _points(ts),
        "feasible": r.flown_feasible,
        "violations": list(r.flown_violations if r.flown_ok is not None else r.violations),
    }
    if r.smoothed is not None:
        rec["smoothed"] = {
            "points": _points(r.smoothed),
            "times": _points(r.smoothed_times),
            "clear": r.smoothed_ok,
            "violations": list(r.smoothed_violations),
        }
    return rec


def fleet_record(f: FleetResult) -> dict[str, Any]:
    """The ``fleet`` block of a fleet planner's result."""
    return {
        "priority": list(f.priority),
        "cost": _num(f.cost),
        "feasible": bool(f.flown_feasible),
        "history": [_num(v) for v in np.asarray(f.history)],
        "restart_costs": [_num(v) for v in np.asarray(f.restart_costs)],
        "wall_time": float(f.wall_time),
        "info": _plain(f.info),
    }


def plan_document(plan: FleetPlan) -> dict[str, Any]:
    """The JSON-ready ``plan.json`` of a plan (format 4; ``margins`` null: the verifier fills
    them in, :func:`with_margins`)."""
    return {
        "format": PLAN_FORMAT,
        "scenario": plan.scenario.name,
        "algorithm": plan.algorithm,
        "config": _plain(plan.config),
        "seed": plan.seed,
        "version": __version__,
        "python": platform.python_version(),
        "frame": FRAME,
        **({"origin": plan.scenario.origin.record()} if plan.scenario.origin else {}),
        "feasible": bool(plan.feasible),
        "separation_checked": plan.fleet is not None,
        "execution": _execution_record(plan),
        "margins": None,
        **({"fleet": fleet_record(plan.fleet)} if plan.fleet is not None else {}),
        "diagnostics": plan.diagnostics(),
        "uavs": [uav_record(r) for r in plan.results],
    }


def _execution_record(plan: FleetPlan) -> dict[str, Any] | None:
    model = plan.scenario.execution
    return model.record() if model is not None else None


def with_margins(path: str | Path, margins: dict[str, Any]) -> Path:
    """Rewrite the plan file at ``path`` with the verifier's ``margins`` (atomically)."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    doc["margins"] = margins
    return write_json_atomic(Path(path), doc)


def write_plan_file(plan: FleetPlan, path: str | Path) -> Path:
    """Write ``plan``'s ``plan.json`` to ``path`` atomically (a reader never sees half a file,
    and a failed write leaves what was there)."""
    return write_json_atomic(Path(path), plan_document(plan))


# ====================================================================================== reading
@dataclass(frozen=True, eq=False)
class Trajectory:
    """One UAV's timed polyline.

    Attributes:
        id: the UAV id.
        points: (n, dim) metres, n >= 2.
        times: (n,) seconds.
        feasible: what the plan claims of it (None if it does not say).
    """

    id: str
    points: FloatArray
    times: FloatArray
    feasible: bool | None = None

    @property
    def dim(self) -> int:
        return int(self.points.shape[1])

    def position(self, t: float) -> FloatArray:
        """Position at time ``t`` (clamped to the flight), metres."""
        return np.array([np.interp(t, self.times, self.points[:, k]) for k in range(self.dim)])


@dataclass(frozen=True, eq=False)
class UAVPlan:
    """One UAV's record of a plan file.

    Attributes:
        id: the UAV id; planned: its planned timed polyline (``waypoints``, ``times``).
        feasible, cost, cost_model, violations: what the planner said of it (None: not said).
        smoothed: a smoothed version (None if none); smoothed_clear, smoothed_violations: what
            the planner said of that.
        flown: the declared trajectory (None: not declared, format 1), flown_kind,
            flown_feasible (the plan's guarantee), flown_violations.
        record: the whole record as read.
    """

    id: str
    planned: Trajectory
    feasible: bool | None = None
    cost: float | None = None
    cost_model: str | None = None
    violations: tuple[str, ...] = ()
    smoothed: Trajectory | None = None
    smoothed_clear: bool | None = None
    smoothed_violations: tuple[str, ...] = ()
    flown: Trajectory | None = None
    flown_kind: str = "polyline"
    flown_feasible: bool | None = None
    flown_violations: tuple[str, ...] = ()
    record: Mapping[str, Any] = field(default_factory=dict)

    def trajectory(self, kind: TrajectoryKind = "flown") -> Trajectory:
        """``flown`` (declared; the planned polyline when the file declares none),
        ``planned`` (the polyline) or ``smoothed`` (the informative smoothed version)."""
        if kind == "planned":
            return self.planned
        if kind == "flown":
            return self.flown if self.flown is not None else self.planned
        if self.smoothed is None:
            raise PlanFormatError([f"{self.id}: no smoothed path"])
        return self.smoothed


@dataclass(frozen=True, eq=False)
class PlanFile:
    """A plan file as read: its header fields and one :class:`UAVPlan` per UAV.

    ``format`` is the file's format (None for a bare ``{"uavs": ...}``), ``feasible`` the plan's
    verdict (format 1: every UAV feasible), ``dim`` the points' dimension."""

    format: str | None
    scenario: str | None
    algorithm: str | None
    seed: int | None
    config: Mapping[str, Any]
    separation_checked: bool | None
    feasible: bool | None
    fleet: Mapping[str, Any] | None
    uavs: tuple[UAVPlan, ...]
    dim: int
    source: str = "plan"
    #: the scenario's geodetic origin as the plan recorded it (None: not geo-referenced)
    origin: GeoOrigin | None = None
    #: the execution model the plan was made for (its record; None: nominal, or not said)
    execution: Mapping[str, Any] | None = None
    #: what the verifier measured the plan to tolerate (None: not measured)
    margins: Mapping[str, Any] | None = None

    def trajectories(self, kind: TrajectoryKind = "flown") -> list[Trajectory]:
        """Every UAV's trajectory of ``kind``; PlanFormatError naming the first UAV without a
        smoothed path when ``kind="smoothed"``."""
        out = []
        for k, u in enumerate(self.uavs):
            if kind == "smoothed" and u.smoothed is None:
                raise PlanFormatError(
                    [
                        f"{self.source}: uavs[{k}] ({u.id}): no smoothed path (verify without "
                        "--smoothed)"
                    ]
                )
            out.append(u.trajectory(kind))
        return out


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _number(
    value: Any, where: str, finite: bool = True, limit: tuple[float, str] | None = None
) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise PlanFormatError([f"{where}: {_short(value)} is not a number"])
    words = ("inf", "-inf", "+inf", "nan", "infinity", "-infinity")
    if isinstance(value, str) and value.strip().lower() not in words:
        raise PlanFormatError([f"{where}: {value!r} is not a number"])
    try:
        x = float(value)
    except OverflowError:  # an integer beyond any float
        raise PlanFormatError([f"{where}: {_short(value)} is beyond any float64"]) from None
    if finite and not math.isfinite(x):
        raise PlanFormatError([f"{where}: {value!r} is not a finite number"])
    if math.isnan(x):
        raise PlanFormatError([f"{where}: {value!r} is not a number"])
    if limit is not None and abs(x) > limit[0]:
        raise PlanFormatError([f"{where}: {value!r} is beyond {limit[0]:g} ({limit[1]})"])
    return x


#: The ranges of a plan's coordinates and times (the scenario format's limits) and why.
_COORDS = (MAX_COORD, "coordinates are within 10,000 km, metres")
_TIMES = (MAX_TIME, "times are within 1e7 s, about 115 days")


def _plain_array(value: list[Any], dim: int | None, limit: tuple[float, str]) -> FloatArray | None:
    """``value`` as an array when it is plainly valid: finite JSON numbers only (no bool, no
    string), in rows of ``dim``; else None, and :func:`_array` finds the error element by
    element (the fast path: a flight has tens of thousands of points)."""
    try:
        flat = itertools.chain.from_iterable(value) if dim is not None else iter(value)
        if not set(map(type, flat)) <= {float, int}:
            return None
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        return None
    shape_ok = a.ndim == 1 if dim is None else (a.ndim == 2 and a.shape[1] == dim)
    if not shape_ok or not np.isfinite(a).all() or (a.size and np.abs(a).max() > limit[0]):
        return None
    return a


def _array(value: Any, where: str, dim: int | None) -> FloatArray:
    """Points (rows of ``dim`` coordinates, within :data:`MAX_COORD`) or, ``dim`` None, times
    (within :data:`MAX_TIME`)."""
    if not isinstance(value, list):
        raise PlanFormatError([f"{where}: expected a list, got {_short(value)}"])
    limit = _TIMES if dim is None else _COORDS
    fast = _plain_array(value, dim, limit)
    if fast is not None:
        return fast.reshape(len(value), dim) if dim is not None else fast
    if dim is None:
        return np.array([_number(v, f"{where}[{k}]", limit=limit) for k, v in enumerate(value)])
    rows = []
    for k, row in enumerate(value):
        if not isinstance(row, list) or len(row) != dim:
            raise PlanFormatError(
                [f"{where}[{k}]: expected a point of {dim} coordinates, got {_short(row)}"]
            )
        rows.append([_number(v, f"{where}[{k}][{c}]", limit=limit) for c, v in enumerate(row)])
    return np.array(rows, dtype=np.float64).reshape(len(rows), dim)


def _timed(
    data: Mapping[str, Any], pts_key: str, base: str, dim: int, uid: str, feasible: bool | None
) -> Trajectory:
    for key in (pts_key, "times"):
        if key not in data:
            raise PlanFormatError([f"{base}.{key}: missing"])
    pts = _array(data[pts_key], f"{base}.{pts_key}", dim)
    ts = _array(data["times"], f"{base}.times", None)
    if len(pts) < 2:
        raise PlanFormatError([f"{base}.{pts_key}: {len(pts)} points, need at least 2"])
    if len(ts) != len(pts):
        raise PlanFormatError(
            [f"{base}.times: {len(ts)} values but {pts_key} has {len(pts)} points"]
        )
    return Trajectory(uid, pts, ts, feasible)


def _infer_dim(uavs: list[Any], source: str) -> int:
    for k, rec in enumerate(uavs):
        if isinstance(rec, Mapping):
            wp = rec.get("waypoints")
            if isinstance(wp, list) and wp and isinstance(wp[0], list):
                if len(wp[0]) in (2, 3):
                    return len(wp[0])
                raise PlanFormatError(
                    [
                        f"{source}: uavs[{k}].waypoints[0]: expected a point of 2 or 3 "
                        f"coordinates, got {_short(wp[0])}"
                    ]
                )
    return 3


def _opt_bool(rec: Mapping[str, Any], key: str, where: str) -> bool | None:
    v = rec.get(key)
    if v is None or isinstance(v, bool):
        return v
    raise PlanFormatError([f"{where}.{key}: {_short(v)} is not true or false"])


def _names(rec: Mapping[str, Any], key: str, where: str) -> tuple[str, ...]:
    v = rec.get(key, [])
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        raise PlanFormatError([f"{where}.{key}: expected a list of names, got {_short(v)}"])
    return tuple(v)


def parse_plan(data: Any, dim: int | None = None, source: str = "plan") -> PlanFile:
    """A decoded ``plan.json`` as a :class:`PlanFile`.

    Args:
        data: the decoded JSON.
        dim: the scenario's dimension (2 or 3): every point must have that many coordinates
            (default: the first point's).
        source: the file name used in error messages.

    Raises:
        PlanFormatError: a missing or malformed field, named with its path and value.
    """
    if not isinstance(data, Mapping):
        raise PlanFormatError([f"{source}: expected a JSON object, got {_short(data)}"])
    fmt = data.get("format")
    if fmt is not None and fmt not in READABLE_FORMATS:
        raise PlanFormatError([f"{source}: format: {fmt!r} is not one of {list(READABLE_FORMATS)}"])
    name = data.get("scenario")
    if name is not None and not isinstance(name, str):
        raise PlanFormatError([f"{source}: scenario: {_short(name)} is not a name"])
    uavs = data.get("uavs")
    if uavs is None:
        raise PlanFormatError([f"{source}: uavs: missing"])
    if not isinstance(uavs, list) or not uavs:
        raise PlanFormatError([f"{source}: uavs: expected a non-empty list, got {_short(uavs)}"])
    d = dim if dim is not None else _infer_dim(uavs, source)
    out: list[UAVPlan] = []
    seen: set[str] = set()
    for k, rec in enumerate(uavs):
        here = f"{source}: uavs[{k}]"
        if not isinstance(rec, Mapping):
            raise PlanFormatError([f"{here}: expected an object, got {_short(rec)}"])
        uid = rec.get("id", f"#{k}")
        if not isinstance(uid, str | int) or isinstance(uid, bool):
            raise PlanFormatError([f"{here}.id: {_short(uid)} is not an id"])
        uid = str(uid)
        if uid in seen:
            raise PlanFormatError([f"{here}.id: {uid!r} appears twice"])
        seen.add(uid)
        feasible = _opt_bool(rec, "feasible", here)
        planned = _timed(rec, "waypoints", here, d, uid, feasible)
        smoothed = None
        clear: bool | None = None
        sm_viol: tuple[str, ...] = ()
        sm = rec.get("smoothed")
        if sm is not None:
            if not isinstance(sm, Mapping):
                raise PlanFormatError([f"{here}.smoothed: expected an object, got {_short(sm)}"])
            clear = _opt_bool(sm, "clear", f"{here}.smoothed")
            smoothed = _timed(sm, "points", f"{here}.smoothed", d, uid, clear)
            sm_viol = _names(sm, "violations", f"{here}.smoothed")
        flown = None
        fl_kind = "polyline"
        fl_ok: bool | None = None
        fl_viol: tuple[str, ...] = ()
        fl = rec.get("flown")
        if fl is not None:
            if not isinstance(fl, Mapping):
                raise PlanFormatError([f"{here}.flown: expected an object, got {_short(fl)}"])
            fl_kind = fl.get("kind", "polyline")
            if fl_kind not in ("smoothed", "polyline"):
                raise PlanFormatError(
                    [f"{here}.flown.kind: {_short(fl_kind)} is not smoothed or polyline"]
                )
            fl_ok = _opt_bool(fl, "feasible", f"{here}.flown")
            flown = _timed(fl, "points", f"{here}.flown", d, uid, fl_ok)
            fl_viol = _names(fl, "violations", f"{here}.flown")
        cost = rec.get("cost")
        if cost is None and "cost" in rec and fmt == PLAN_FORMAT:
            cost = "inf"  # format 3 writes an infinite cost as null
        cm = rec.get("cost_model")
        out.append(
            UAVPlan(
                id=uid,
                planned=planned,
                feasible=feasible,
                cost=None if cost is None else _number(cost, f"{here}.cost", finite=False),
                cost_model=cm if isinstance(cm, str) else None,
                violations=_names(rec, "violations", here),
                smoothed=smoothed,
                smoothed_clear=clear,
                smoothed_violations=sm_viol,
                flown=flown,
                flown_kind=fl_kind,
                flown_feasible=fl_ok,
                flown_violations=fl_viol,
                record=rec,
            )
        )
    verdict = _opt_bool(data, "feasible", source)
    if verdict is None and fmt == "uavplan.plan/1":
        fleet = data.get("fleet")
        if isinstance(fleet, Mapping) and isinstance(fleet.get("feasible"), bool):
            verdict = fleet["feasible"]
        elif all(u.feasible is not None for u in out):
            verdict = all(bool(u.feasible) for u in out)
    seed = data.get("seed")
    fleet_block = data.get("fleet")
    origin = None
    if data.get("origin") is not None:
        try:
            origin = GeoOrigin.from_record(data["origin"])
        except GeoError as exc:
            raise PlanFormatError([f"{source}: {exc}"]) from None
    config = data.get("config")
    execution = data.get("execution")
    if execution is not None:
        from uavplan.world.execution import ExecutionModel

        try:
            ExecutionModel.from_record(execution)
        except (ValueError, TypeError) as exc:
            raise PlanFormatError([f"{source}: {exc}"]) from None
    margins = data.get("margins")
    return PlanFile(
        format=fmt,
        scenario=name,
        algorithm=data.get("algorithm") if isinstance(data.get("algorithm"), str) else None,
        seed=seed if isinstance(seed, int) and not isinstance(seed, bool) else None,
        config=config if isinstance(config, Mapping) else {},
        separation_checked=_opt_bool(data, "separation_checked", source),
        feasible=verdict,
        fleet=fleet_block if isinstance(fleet_block, Mapping) else None,
        uavs=tuple(out),
        dim=d,
        source=source,
        origin=origin,
        execution=execution,
        margins=margins if isinstance(margins, Mapping) else None,
    )


def load_plan_json(path: str | Path) -> Any:
    """The decoded JSON of a plan file (``path`` may be the folder holding ``plan.json``);
    PlanFormatError naming the file otherwise."""
    p = Path(path)
    if p.is_dir() and (p / "plan.json").is_file():
        p = p / "plan.json"
    if not p.exists():
        raise PlanFormatError([f"{p}: no such plan file"])
    if p.is_dir():
        raise PlanFormatError([f"{p}: a folder without a plan.json"])
    why = not_a_regular_file(p)
    if why is not None:
        raise PlanFormatError([f"{p}: {why}, not a plan file"])
    size = p.stat().st_size
    if size > MAX_PLAN_BYTES:
        raise PlanFormatError([f"{p}: {size:,} bytes; a plan file is at most {MAX_PLAN_BYTES:,}"])
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise PlanFormatError([f"{p}: cannot read: {exc}"]) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise PlanFormatError(
            [f"{p}: invalid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}"]
        ) from None
    except RecursionError:
        raise PlanFormatError([f"{p}: invalid JSON: nested too deeply"]) from None


def plan_path(path: str | Path) -> Path:
    """The plan file ``path`` names (the ``plan.json`` inside a folder)."""
    p = Path(path)
    return p / "plan.json" if p.is_dir() and (p / "plan.json").is_file() else p


def read_plan_file(path: str | Path, dim: int | None = None) -> PlanFile:
    """Read a plan file (see :func:`parse_plan`)."""
    return parse_plan(load_plan_json(path), dim, str(plan_path(path)))


# ====================================================================================== schema
#: a number in a plan file: null where it is not finite (format 3), the strings of format 2
Number = float | Literal["inf", "-inf"] | None


class _Spec(BaseModel):
    model_config = ConfigDict(extra="allow")


class SmoothedSpec(_Spec):
    """The smoothed (flyable) version of a UAV's path."""

    points: list[list[float]] = Field(description="[[x, y(, z)], ...] metres, dense")
    times: list[float] = Field(description="seconds, one per point, non-decreasing")
    clear: bool | None = Field(None, description="whether it keeps every clearance")
    violations: list[str] = Field(default_factory=list)


class FlownSpec(_Spec):
    """The trajectory a UAV is to fly, as the plan declares and guarantees it."""

    kind: Literal["smoothed", "polyline"] = "polyline"
    points: list[list[float]] = Field(description="[[x, y(, z)], ...] metres, straight between")
    times: list[float] = Field(description="seconds, one per point, non-decreasing")
    feasible: bool | None = Field(None, description="passes every check, kinematic limits included")
    violations: list[str] = Field(default_factory=list)


class UAVSpec(_Spec):
    """One UAV's planned path and how it was found."""

    id: str
    waypoints: list[list[float]] = Field(description="[[x, y(, z)], ...] metres, start..goal")
    times: list[float] = Field(description="seconds at each waypoint")
    cost: Number | None = None
    terms: dict[str, Number] = Field(default_factory=dict)
    cost_model: str | None = None
    feasible: bool | None = None
    violations: list[str] = Field(default_factory=list)
    length: float | None = None
    evaluations: int | None = None
    iterations: int | None = None
    wall_time: float | None = None
    history: list[Number] = Field(default_factory=list)
    first_feasible_iteration: int | None = None
    info: dict[str, Any] = Field(default_factory=dict)
    flown: FlownSpec | None = None
    smoothed: SmoothedSpec | None = None


class FleetSpec(_Spec):
    """A fleet planner's fleet-level result."""

    priority: list[str]
    cost: Number
    feasible: bool
    history: list[Number] = Field(default_factory=list)
    restart_costs: list[Number] = Field(default_factory=list)
    wall_time: float | None = None
    info: dict[str, Any] = Field(default_factory=dict)


class EventSpec(_Spec):
    """One event of the plan's story (``uavplan.planners.core.events.KINDS``)."""

    kind: Literal["candidate", "slower", "waited", "delayed", "repaired", "unresolved",
                  "restart", "attempt"]  # fmt: skip
    uav: str | None = Field(None, description="the UAV it concerns; null: the fleet or plan")
    detail: str = ""
    value: float | None = Field(
        None, description="seconds of a later take-off, or a restart's or attempt's cost"
    )


class DiagnosticsSpec(_Spec):
    """What happened while planning."""

    schema_: str = Field("uavplan.diagnostics/1", alias="schema")
    events: list[EventSpec] = Field(default_factory=list)


class PlanSpec(_Spec):
    """A uavplan plan file (``plan.json``)."""

    format: (
        Literal["uavplan.plan/1", "uavplan.plan/2", "uavplan.plan/3", "uavplan.plan/4"] | None
    ) = "uavplan.plan/4"
    scenario: str | None = None
    algorithm: str | None = None
    config: dict[str, Any] = Field(default_factory=dict)
    seed: int | None = None
    version: str | None = None
    python: str | None = None
    frame: str | None = FRAME
    origin: OriginSpec | None = None
    feasible: bool | None = None
    separation_checked: bool | None = None
    execution: ExecutionSpec | None = Field(
        None, description="the execution model the plan was made for (null: nominal)"
    )
    margins: dict[str, Any] | None = Field(
        None,
        description="what the verifier measured the plan to tolerate: 'uavs' (per UAV: "
        "takeoff_s, speed, track_h, track_v, limited_by) and 'pairs' (the tightest pairs and "
        "every failing one: uav, other, time, distance, required, takeoff_s, speed, track, "
        "ok); null: not measured",
    )
    fleet: FleetSpec | None = None
    diagnostics: DiagnosticsSpec | None = Field(
        None, description="what happened while planning, as typed events (uavplan explain)"
    )
    uavs: list[UAVSpec] = Field(min_length=1)


def plan_schema() -> dict[str, Any]:
    """The JSON Schema of plan files."""
    out = PlanSpec.model_json_schema()
    out["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    out["title"] = "uavplan plan file"
    return out
