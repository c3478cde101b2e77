"""An independent verifier for fleet plans (``plan.json``): is every UAV's timed path flyable, and
do the UAVs keep their distance from each other?

This module is written apart from the planner's own cost and feasibility code on purpose: it
does not import :mod:`uavplan.problems`, :mod:`uavplan.world.geometry`, the terrain kernels or
``Terrain.clears / min_clearance / max_clearance``, nor :mod:`uavplan.world.reservations`. It
reads the scenario only as data (bounds, obstacles, the DEM grid, the altitude band, UAV limits)
and does its own geometry, so that a bug in the planner's geometry cannot hide itself.

Semantics (frame: metres, x east, y north, z up, absolute altitudes; seconds):

* **Timed paths.** A UAV flies its polyline piecewise-linearly in time between
  ``(times[k], waypoints[k])``. It is in the air only during ``[times[0], times[-1]]`` (it takes
  off at its start and lands at its goal); before and after it is no hazard. A repeated time with
  two different points is an instantaneous jump: it is reported as a ``speed`` violation and, for
  separation, the jump is swept as a straight motion at that instant.
* **Separation** (``separation``): for every pair of UAVs, the minimum distance over continuous
  time must be at least ``S2 = scenario.uav.s2``. Between the union of both UAVs' time
  breakpoints the relative motion is linear, so the minimum on each common interval is the
  minimum of a quadratic (closed form, clamped to the interval): exact, not sampled. Pairs are
  pruned first (sort-and-sweep on whole-flight boxes grown by ``S2``, and the flights' time
  windows); a pruned pair is farther apart than ``S2`` at every instant. One violation is
  reported per close encounter (a stretch of time during which the pair is closer than ``S2``),
  at its closest point. The report's minimum separation is the fleet's exact minimum over all
  pairs (when no pair comes within ``S2``, the pruning is widened until it is found).
* **Obstacles.** Cylinders (``cylinder``): the part of a segment between ``z_min - margin`` and
  ``z_max + margin`` must stay at a horizontal distance of at least ``radius + margin`` from the
  axis. Circles (``circle``) are infinite vertical prisms of radius ``radius + margin``. Polygons
  and revealed uncertain areas (``polygon``) are infinite vertical prisms: a segment must not
  enter the interior and must keep at least ``margin`` from the boundary (touching a polygon
  with no margin is allowed). Moving obstacles (``moving``): the distance over continuous time
  from the UAV to the obstacle's centre (which holds its first and last positions outside its
  knots) must be at least its radius. All exact.
* **Bounds** (``bounds``): every waypoint lies in the scenario's box (the box is convex, so whole
  segments do).
* **Terrain** (``terrain``): ``z - h(x, y) >= 0`` along every segment against the bilinear DEM
  (outside the grid the height of the nearest edge point). Along a straight segment inside one
  grid cell the bilinear surface is a quadratic in the segment parameter, so each segment is split
  at the grid lines it crosses and the exact minimum is taken per piece.
* **Altitude band** (``altitude``): with reference ``"ground"`` the height above ground stays in
  ``[min, max]`` along the whole segment (exact, with the same per-cell quadratic for the minimum
  and the maximum; ground is 0 without terrain); with ``"absolute"``, ``z`` stays in
  ``[min, max]`` (linear along a segment, so the waypoints suffice).
* **Timing.** ``times`` must be non-decreasing (``times``); the implied speed of a segment must
  not exceed ``scenario.uav.speed * (1 + 1e-6)`` (``speed``), with an extra ``1e-6 (v + 2)`` m of
  slack per segment for the 6-decimal rounding of ``plan.json``. A UAV whose times decrease is left
  out of the separation and moving-obstacle checks (its motion is undefined) and a warning says
  so.
* **Warnings** (not violations): the plan's scenario name differs from the scenario's; a UAV's
  first or last point differs from its task's start or goal; a UAV the plan calls feasible
  fails a check.

All geometric comparisons use a tolerance of ``TOL = 1e-6`` m: a distance exactly equal to the
required one passes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.world.obstacles import AltitudeBand, Cylinder
from uavplan.world.scenario import Scenario
from uavplan.world.terrain import Terrain

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Geometric tolerance, metres.
TOL = 1e-6
#: Relative tolerance on the speed limit.
SPEED_RTOL = 1e-6

#: Every kind of violation, in the order they are reported.
KINDS = (
    "times",
    "speed",
    "bounds",
    "separation",
    "cylinder",
    "circle",
    "polygon",
    "moving",
    "terrain",
    "altitude",
)

PLAN_FORMAT = "uavplan.plan/1"


class PlanFormatError(ValueError):
    """A plan that cannot be read: ``problems`` holds one line naming the file, field and value."""

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems: list[str] = list(problems) or ["invalid plan"]
        super().__init__("\n".join(self.problems))


@dataclass(frozen=True)
class Violation:
    """One failed check.

    Attributes:
        kind: one of :data:`KINDS`.
        uavs: the UAV ids involved (two for ``separation``).
        time: seconds at the worst point (None when not tied to an instant).
        where: the worst point of each UAV in ``uavs``, metres (x, y[, z]).
        value: the measured quantity (distance, clearance, height, speed, time step), in its unit.
        required: the bound it breaks (the minimum, or the maximum for upper limits).
        message: one human-readable line.
    """

    kind: str
    uavs: tuple[str, ...]
    time: float | None
    where: tuple[tuple[float, ...], ...]
    value: float
    required: float
    message: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "uavs": list(self.uavs),
            "time": self.time,
            "where": [list(p) for p in self.where],
            "value": _num(self.value),
            "required": _num(self.required),
            "message": self.message,
        }


@dataclass
class VerifyReport:
    """What :func:`verify_plan` found.

    Attributes:
        scenario: the scenario's name; plan_scenario: the name the plan gives (None if absent).
        smoothed: whether the smoothed paths were verified instead of the waypoints.
        uav_ids: the UAVs, in plan order; n_segments: segments checked over all UAVs.
        s2: the required UAV-UAV separation, metres.
        pairs_total: ``n (n - 1) / 2``; pairs_checked: pairs left after pruning, checked exactly.
        min_separation: the smallest distance between two UAVs over continuous time, over all
            pairs (exact; inf if no two flights overlap in time).
        min_separation_pair, min_separation_time: where it happens (None if no pair checked).
        violations: every failed check; warnings: remarks that do not fail the plan.
    """

    scenario: str
    plan_scenario: str | None
    smoothed: bool
    uav_ids: list[str]
    n_segments: int
    s2: float
    pairs_total: int = 0
    pairs_checked: int = 0
    min_separation: float = math.inf
    min_separation_pair: tuple[str, str] | None = None
    min_separation_time: float | None = None
    violations: list[Violation] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True if no check failed."""
        return not self.violations

    @property
    def counts(self) -> dict[str, int]:
        """Violations per kind (every kind of :data:`KINDS`, zeros included)."""
        out = dict.fromkeys(KINDS, 0)
        for v in self.violations:
            out[v.kind] = out.get(v.kind, 0) + 1
        return out

    def by_uav(self) -> dict[str, int]:
        """Violations per UAV id (a separation violation counts for both UAVs)."""
        out = dict.fromkeys(self.uav_ids, 0)
        for v in self.violations:
            for u in v.uavs:
                out[u] = out.get(u, 0) + 1
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": "uavplan.verify/1",
            "scenario": self.scenario,
            "plan_scenario": self.plan_scenario,
            "smoothed": self.smoothed,
            "ok": self.ok,
            "uavs": len(self.uav_ids),
            "segments": self.n_segments,
            "s2": self.s2,
            "pairs_total": self.pairs_total,
            "pairs_checked": self.pairs_checked,
            "min_separation": _num(self.min_separation),
            "min_separation_pair": (
                list(self.min_separation_pair) if self.min_separation_pair else None
            ),
            "min_separation_time": self.min_separation_time,
            "counts": self.counts,
            "violations": [v.to_dict() for v in self.violations],
            "warnings": list(self.warnings),
        }


def _num(v: float) -> float | str:
    v = float(v)
    return v if math.isfinite(v) else ("inf" if v > 0 else ("-inf" if v < 0 else "nan"))


# ================================================================================ plan reading
@dataclass(frozen=True, eq=False)
class Trajectory:
    """One UAV's timed polyline.

    Attributes:
        id: the UAV id.
        points: (n, dim) metres, n >= 2.
        times: (n,) seconds.
        feasible: what the plan claims (None if it does not say).
    """

    id: str
    points: FloatArray
    times: FloatArray
    feasible: bool | None = None

    @property
    def dim(self) -> int:
        return int(self.points.shape[1])

    @property
    def times_valid(self) -> bool:
        return bool(np.all(np.diff(self.times) >= 0))

    def position(self, t: float) -> FloatArray:
        """Position at time ``t`` (clamped to the flight), metres."""
        return np.array([np.interp(t, self.times, self.points[:, k]) for k in range(self.dim)])


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise PlanFormatError([f"{where}: {value!r} is not a number"])
    words = ("inf", "-inf", "+inf", "nan", "infinity", "-infinity")
    if isinstance(value, str) and value.strip().lower() not in words:
        raise PlanFormatError([f"{where}: {value!r} is not a number"])
    x = float(value)
    if not math.isfinite(x):
        raise PlanFormatError([f"{where}: {value!r} is not a finite number"])
    return x


def _array(value: Any, where: str, dim: int | None) -> FloatArray:
    if not isinstance(value, list):
        raise PlanFormatError([f"{where}: expected a list, got {_short(value)}"])
    if dim is None:
        return np.array([_number(v, f"{where}[{k}]") for k, v in enumerate(value)])
    rows = []
    for k, row in enumerate(value):
        if not isinstance(row, list) or len(row) != dim:
            raise PlanFormatError(
                [f"{where}[{k}]: expected a point of {dim} coordinates, got {_short(row)}"]
            )
        rows.append([_number(v, f"{where}[{k}][{c}]") for c, v in enumerate(row)])
    return np.array(rows, dtype=np.float64).reshape(len(rows), dim)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def parse_plan(
    plan: Any, dim: int, smoothed: bool = False, source: str = "plan"
) -> tuple[list[Trajectory], str | None]:
    """Read the UAV trajectories of a ``plan.json`` mapping.

    Args:
        plan: the decoded JSON.
        dim: the scenario's dimension (2 or 3): every point must have that many coordinates.
        smoothed: read each UAV's ``smoothed.points`` / ``smoothed.times`` instead of
            ``waypoints`` / ``times``.
        source: the file name used in error messages.

    Returns:
        The trajectories and the plan's ``scenario`` name (None if absent).

    Raises:
        PlanFormatError: a missing or malformed field, named with its path and value.
    """
    if not isinstance(plan, Mapping):
        raise PlanFormatError([f"{source}: expected a JSON object, got {_short(plan)}"])
    fmt = plan.get("format")
    if fmt is not None and fmt != PLAN_FORMAT:
        raise PlanFormatError([f"{source}: format: {fmt!r} is not {PLAN_FORMAT!r}"])
    name = plan.get("scenario")
    if name is not None and not isinstance(name, str):
        raise PlanFormatError([f"{source}: scenario: {_short(name)} is not a name"])
    uavs = plan.get("uavs")
    if uavs is None:
        raise PlanFormatError([f"{source}: uavs: missing"])
    if not isinstance(uavs, list) or not uavs:
        raise PlanFormatError([f"{source}: uavs: expected a non-empty list, got {_short(uavs)}"])
    out: list[Trajectory] = []
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
        if smoothed:
            sm = rec.get("smoothed")
            if sm is None:
                raise PlanFormatError(
                    [f"{here} ({uid}): no smoothed path (verify without --smoothed)"]
                )
            if not isinstance(sm, Mapping):
                raise PlanFormatError([f"{here}.smoothed: expected an object, got {_short(sm)}"])
            pts_key, t_key, base, data = "points", "times", f"{here}.smoothed", sm
        else:
            pts_key, t_key, base, data = "waypoints", "times", here, rec
        for key in (pts_key, t_key):
            if key not in data:
                raise PlanFormatError([f"{base}.{key}: missing"])
        pts = _array(data[pts_key], f"{base}.{pts_key}", dim)
        ts = _array(data[t_key], f"{base}.{t_key}", None)
        if len(pts) < 2:
            raise PlanFormatError([f"{base}.{pts_key}: {len(pts)} points, need at least 2"])
        if len(ts) != len(pts):
            raise PlanFormatError(
                [f"{base}.{t_key}: {len(ts)} values but {pts_key} has {len(pts)} points"]
            )
        feas = rec.get("feasible")
        out.append(Trajectory(uid, pts, ts, feas if isinstance(feas, bool) else None))
    return out, name


# ================================================================================ timing checks
def check_times(traj: Trajectory) -> list[Violation]:
    """``times`` must be non-decreasing: one violation per decreasing step."""
    out = []
    dt = np.diff(traj.times)
    for k in np.flatnonzero(dt < 0):
        t0, t1 = float(traj.times[k]), float(traj.times[k + 1])
        out.append(
            Violation(
                "times",
                (traj.id,),
                t1,
                (_pt(traj.points[k + 1]),),
                t1 - t0,
                0.0,
                f"{traj.id}: times decrease at waypoint {k + 1} ({t0:g} s then {t1:g} s)",
            )
        )
    return out


def check_speed(traj: Trajectory, speed: float) -> list[Violation]:
    """The implied speed of every segment must not exceed ``speed * (1 + 1e-6)`` m/s (plus
    ``1e-6 (speed + 2)`` m of length slack for the rounding of plan files). Segments going back in
    time are left to :func:`check_times`."""
    out = []
    d = np.linalg.norm(np.diff(traj.points, axis=0), axis=1)
    dt = np.diff(traj.times)
    allowed = speed * (1 + SPEED_RTOL) * dt + 1e-6 * (speed + 2.0)
    for k in np.flatnonzero((dt >= 0) & (d > allowed)):
        v = float(d[k] / dt[k]) if dt[k] > 0 else math.inf
        t = float(traj.times[k])
        out.append(
            Violation(
                "speed",
                (traj.id,),
                t,
                (_pt(traj.points[k]), _pt(traj.points[k + 1])),
                v,
                speed,
                f"{traj.id}: segment {k} at {_f(v)} m/s (limit {speed:g} m/s): "
                f"{d[k]:.3f} m in {dt[k]:g} s from t={t:g} s",
            )
        )
    return out


# ================================================================================ bounds
def check_bounds(
    traj: Trajectory, lower: Sequence[float], upper: Sequence[float]
) -> list[Violation]:
    """Every waypoint inside the box ``lower..upper`` (metres, tolerance :data:`TOL`)."""
    lo = np.asarray(lower, dtype=np.float64)
    hi = np.asarray(upper, dtype=np.float64)
    p = traj.points[:, : lo.shape[0]]
    excess = np.maximum(lo - p, p - hi).max(axis=1)
    out = []
    for k in np.flatnonzero(excess > TOL):
        axis = int(np.argmax(np.maximum(lo - p[k], p[k] - hi)))
        out.append(
            Violation(
                "bounds",
                (traj.id,),
                float(traj.times[k]),
                (_pt(traj.points[k]),),
                float(excess[k]),
                0.0,
                f"{traj.id}: waypoint {k} {_pts(traj.points[k])} is {excess[k]:.3f} m outside "
                f"the bounds along {'xyz'[axis]} ({lo[axis]:g}..{hi[axis]:g})",
            )
        )
    return out


# ================================================================================ obstacles
def segment_cylinder_distance(
    a: FloatArray, b: FloatArray, center: Sequence[float], z_lo: float, z_hi: float
) -> tuple[FloatArray, FloatArray]:
    """Horizontal distance from a vertical axis to the part of each segment inside a z range.

    Args:
        a, b: (m, 2 or 3) segment ends, metres (2-D segments are never outside the z range).
        center: the axis (x, y); z_lo, z_hi: the z range (may be infinite).

    Returns:
        ``(distance, s)``: (m,) metres (inf where no part of the segment is in the z range) and
        (m,) the segment parameter in [0, 1] of the closest point (nan where none).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    m = a.shape[0]
    lo = np.zeros(m)
    hi = np.ones(m)
    if a.shape[1] == 3:
        za, dz = a[:, 2], b[:, 2] - a[:, 2]
        flat = dz == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            s1 = (z_lo - za) / np.where(flat, 1.0, dz)
            s2 = (z_hi - za) / np.where(flat, 1.0, dz)
        inside = (za >= z_lo) & (za <= z_hi)
        lo = np.where(flat, np.where(inside, 0.0, 2.0), np.maximum(0.0, np.minimum(s1, s2)))
        hi = np.where(flat, np.where(inside, 1.0, -1.0), np.minimum(1.0, np.maximum(s1, s2)))
    c = np.asarray(center, dtype=np.float64)
    ax, ay = a[:, 0] - c[0], a[:, 1] - c[1]
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    dd = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(dd > 0, -(ax * dx + ay * dy) / np.where(dd > 0, dd, 1.0), 0.0)
    s = np.clip(s, lo, np.maximum(lo, hi))
    dist = np.hypot(ax + s * dx, ay + s * dy)
    empty = lo > hi
    return np.where(empty, np.inf, dist), np.where(empty, np.nan, s)


def _segments(traj: Trajectory) -> tuple[FloatArray, FloatArray]:
    return traj.points[:-1], traj.points[1:]


def _at(traj: Trajectory, k: int, s: float) -> tuple[tuple[float, ...], float]:
    """Point and time at parameter ``s`` of segment ``k``."""
    p = traj.points[k] + s * (traj.points[k + 1] - traj.points[k])
    t = traj.times[k] + s * (traj.times[k + 1] - traj.times[k])
    return _pt(p), float(t)


def check_cylinders(traj: Trajectory, cylinders: Sequence[Cylinder]) -> list[Violation]:
    """Every segment clears every cylinder: the part of the segment between ``z_min - margin``
    and ``z_max + margin`` stays at least ``radius + margin`` from the axis (exact)."""
    a, b = _segments(traj)
    out = []
    for ci, cyl in enumerate(cylinders):
        r = cyl.effective_radius
        d, s = segment_cylinder_distance(
            a, b, cyl.center, cyl.z_min - cyl.margin, cyl.z_max + cyl.margin
        )
        for k in np.flatnonzero(d < r - TOL):
            p, t = _at(traj, int(k), float(s[k]))
            out.append(
                Violation(
                    "cylinder",
                    (traj.id,),
                    t,
                    (p,),
                    float(d[k]),
                    r,
                    f"{traj.id}: segment {k} passes {_f(d[k])} m from the axis of cylinder {ci} "
                    f"(radius + margin {r:g} m) at {_pts(p)}, t={t:.3f} s",
                )
            )
    return out


def check_circles(traj: Trajectory, circles: Sequence[Any]) -> list[Violation]:
    """Circles are infinite vertical prisms: every segment stays at least ``radius + margin``
    from the centre in the horizontal plane (exact)."""
    a, b = _segments(traj)
    out = []
    for ci, circ in enumerate(circles):
        r = float(circ.effective_radius)
        d, s = segment_cylinder_distance(a[:, :2], b[:, :2], circ.center, -math.inf, math.inf)
        for k in np.flatnonzero(d < r - TOL):
            p, t = _at(traj, int(k), float(s[k]))
            out.append(
                Violation(
                    "circle",
                    (traj.id,),
                    t,
                    (p,),
                    float(d[k]),
                    r,
                    f"{traj.id}: segment {k} passes {_f(d[k])} m from the centre of circle {ci} "
                    f"(radius + margin {r:g} m) at {_pts(p)}, t={t:.3f} s",
                )
            )
    return out


def _point_segment_dist2(
    px: FloatArray, py: FloatArray, ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray
) -> FloatArray:
    dx, dy = bx - ax, by - ay
    dd = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(dd > 0, ((px - ax) * dx + (py - ay) * dy) / np.where(dd > 0, dd, 1.0), 0.0)
    s = np.clip(s, 0.0, 1.0)
    ex, ey = ax + s * dx - px, ay + s * dy - py
    return np.asarray(ex * ex + ey * ey)


def _orient(
    ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray, cx: FloatArray, cy: FloatArray
) -> FloatArray:
    return np.asarray((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))


def segment_polygon_distance(a: FloatArray, b: FloatArray, vertices: FloatArray) -> FloatArray:
    """Horizontal distance from each segment to a polygon's boundary.

    Args:
        a, b: (m, >=2) segment ends, metres (only x, y are used).
        vertices: (k, 2) the polygon, in order.

    Returns:
        (m,) metres, 0 where the segment touches or crosses the boundary.
    """
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    ax, ay = a[:, 0:1], a[:, 1:2]
    bx, by = b[:, 0:1], b[:, 1:2]
    cx, cy, ex, ey = v[None, :, 0], v[None, :, 1], w[None, :, 0], w[None, :, 1]
    d2 = np.minimum.reduce(
        [
            _point_segment_dist2(ax, ay, cx, cy, ex, ey),
            _point_segment_dist2(bx, by, cx, cy, ex, ey),
            _point_segment_dist2(cx, cy, ax, ay, bx, by),
            _point_segment_dist2(ex, ey, ax, ay, bx, by),
        ]
    )
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, ex, ey)
    o3 = _orient(cx, cy, ex, ey, ax, ay)
    o4 = _orient(cx, cy, ex, ey, bx, by)
    cross = (o1 * o2 < 0) & (o3 * o4 < 0)
    d2 = np.where(cross, 0.0, d2)
    return np.asarray(np.sqrt(d2.min(axis=1)))


def point_in_polygon(x: FloatArray, y: FloatArray, vertices: FloatArray) -> NDArray[np.bool_]:
    """Even-odd ray casting; points on the boundary may go either way (callers test the
    distance to the boundary separately)."""
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    px = np.asarray(x, dtype=np.float64)[..., None]
    py = np.asarray(y, dtype=np.float64)[..., None]
    y0, y1 = v[:, 1], w[:, 1]
    straddle = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = v[:, 0] + (py - y0) * (w[:, 0] - v[:, 0]) / (y1 - y0)
    hits = straddle & (px < xc)
    return np.asarray(np.count_nonzero(hits, axis=-1) % 2 == 1)


def _boundary_dist(x: FloatArray, y: FloatArray, vertices: FloatArray) -> FloatArray:
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    px, py = np.asarray(x)[..., None], np.asarray(y)[..., None]
    d2 = _point_segment_dist2(px, py, v[:, 0], v[:, 1], w[:, 0], w[:, 1])
    return np.asarray(np.sqrt(d2.min(axis=-1)))


def _deepest_inside(a: FloatArray, b: FloatArray, vertices: FloatArray) -> tuple[float, float]:
    """For one segment that touches a polygon's boundary: the segment parameter of the deepest
    point found strictly inside (midpoints of the pieces between boundary crossings) and its
    depth, or ``(nan, 0)`` if no piece enters the interior."""
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    d = b[:2] - a[:2]
    e = w - v
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = ((v[:, 0] - a[0]) * e[:, 1] - (v[:, 1] - a[1]) * e[:, 0]) / den
        u = ((v[:, 0] - a[0]) * d[1] - (v[:, 1] - a[1]) * d[0]) / den
    ok = (den != 0) & (u >= -1e-12) & (u <= 1 + 1e-12) & (s > 0) & (s < 1)
    cuts = np.unique(np.concatenate([[0.0, 1.0], s[ok]]))
    mids = 0.5 * (cuts[:-1] + cuts[1:])
    px, py = a[0] + mids * d[0], a[1] + mids * d[1]
    depth = _boundary_dist(px, py, v)
    inside = point_in_polygon(px, py, v) & (depth > TOL)
    if not np.any(inside):
        return math.nan, 0.0
    k = int(np.argmax(np.where(inside, depth, -1.0)))
    return float(mids[k]), float(depth[k])


def check_polygons(traj: Trajectory, polygons: Sequence[Any]) -> list[Violation]:
    """Polygons are infinite vertical prisms: no segment enters the interior, and every segment
    keeps at least ``margin`` from the boundary (exact; touching with no margin is allowed).

    ``value`` is the signed horizontal distance at the reported point (negative inside)."""
    a, b = _segments(traj)
    out = []
    for pi, poly in enumerate(polygons):
        verts = np.asarray(poly.vertices, dtype=np.float64)
        margin = float(poly.margin)
        dist = segment_polygon_distance(a, b, verts)
        # A segment that does not touch the boundary is wholly inside or wholly outside.
        start_inside = point_in_polygon(a[:, 0], a[:, 1], verts)
        suspects = (dist <= TOL) | start_inside | (dist < margin - TOL)
        for k in (int(i) for i in np.flatnonzero(suspects)):
            if dist[k] > TOL:
                if start_inside[k]:
                    s, depth = (
                        0.5,
                        _midpoint_depth(a[k], b[k], verts),
                    )
                elif dist[k] < margin - TOL:
                    s, depth = _closest_to_polygon(a[k], b[k], verts), -float(dist[k])
                else:
                    continue
            else:
                s, depth = _deepest_inside(a[k], b[k], verts)
                if math.isnan(s):
                    if margin <= TOL:
                        continue
                    s, depth = _closest_to_polygon(a[k], b[k], verts), 0.0
            p, t = _at(traj, k, s)
            value = -depth
            inside = value < 0
            text = (
                f"enters polygon {pi} ({_f(-value)} m deep)"
                if inside
                else f"passes {_f(value)} m from polygon {pi} (margin {margin:g} m)"
            )
            out.append(
                Violation(
                    "polygon",
                    (traj.id,),
                    t,
                    (p,),
                    value,
                    margin,
                    f"{traj.id}: segment {k} {text} at {_pts(p)}, t={t:.3f} s",
                )
            )
    return out


def _midpoint_depth(a: FloatArray, b: FloatArray, verts: FloatArray) -> float:
    m = 0.5 * (a[:2] + b[:2])
    return float(_boundary_dist(m[0:1], m[1:2], verts)[0])


def _closest_to_polygon(a: FloatArray, b: FloatArray, verts: FloatArray) -> float:
    """Segment parameter of a point of segment ``a``-``b`` closest to the polygon boundary
    (sampled finely; only used to say where a margin violation happens)."""
    s = np.linspace(0.0, 1.0, 1025)
    x = a[0] + s * (b[0] - a[0])
    y = a[1] + s * (b[1] - a[1])
    return float(s[int(np.argmin(_boundary_dist(x, y, verts)))])


# ================================================================================ terrain
@njit(cache=True)
def _terrain_extrema(A, B, H, x0, y0, dx, dy):  # pragma: no cover - numba
    """Exact min and max of ``z - h(x, y)`` along segments ``A[m] -> B[m]`` over the bilinear DEM
    ``H`` (clamped to its edges outside). Returns (m, 4): min, s at min, max, s at max."""
    m = A.shape[0]
    ny, nx = H.shape
    out = np.empty((m, 4))
    for q in range(m):
        u0 = (A[q, 0] - x0) / dx
        u1 = (B[q, 0] - x0) / dx
        v0 = (A[q, 1] - y0) / dy
        v1 = (B[q, 1] - y0) / dy
        za = A[q, 2]
        zb = B[q, 2]
        du = u1 - u0
        dv = v1 - v0
        # next grid line crossed along u and along v (only lines 0..n-1 change the formula)
        if du > 0:
            ku = max(math.floor(u0) + 1, 0)
            su = (ku - u0) / du if ku <= nx - 1 else 2.0
        elif du < 0:
            ku = min(math.ceil(u0) - 1, nx - 1)
            su = (ku - u0) / du if ku >= 0 else 2.0
        else:
            ku = 0
            su = 2.0
        if dv > 0:
            kv = max(math.floor(v0) + 1, 0)
            sv = (kv - v0) / dv if kv <= ny - 1 else 2.0
        elif dv < 0:
            kv = min(math.ceil(v0) - 1, ny - 1)
            sv = (kv - v0) / dv if kv >= 0 else 2.0
        else:
            kv = 0
            sv = 2.0
        cmin = np.inf
        smin = 0.0
        cmax = -np.inf
        smax = 0.0
        sa = 0.0
        while True:
            sb = min(su, sv, 1.0)
            if sb > sa:
                sm = 0.5 * (sa + sb)
                uc = min(max(u0 + du * sm, 0.0), nx - 1.0)
                vc = min(max(v0 + dv * sm, 0.0), ny - 1.0)
                i = min(math.floor(uc), nx - 2)
                j = min(math.floor(vc), ny - 2)
                a0 = min(max(u0 + du * sa, 0.0), nx - 1.0) - i
                a1 = min(max(u0 + du * sb, 0.0), nx - 1.0) - i - a0
                b0 = min(max(v0 + dv * sa, 0.0), ny - 1.0) - j
                b1 = min(max(v0 + dv * sb, 0.0), ny - 1.0) - j - b0
                z0 = za + (zb - za) * sa
                z1 = (zb - za) * (sb - sa)
                h00 = H[j, i]
                p = H[j, i + 1] - h00
                r = H[j + 1, i] - h00
                w = h00 - H[j, i + 1] - H[j + 1, i] + H[j + 1, i + 1]
                # c(t) = z - h along the piece, t in [0, 1]: c0 + c1 t + c2 t^2
                c0 = z0 - (h00 + p * a0 + r * b0 + w * a0 * b0)
                c1 = z1 - (p * a1 + r * b1 + w * (a0 * b1 + a1 * b0))
                c2 = -w * a1 * b1
                e0 = c0
                e1 = c0 + c1 + c2
                if e0 < cmin:
                    cmin = e0
                    smin = sa
                if e0 > cmax:
                    cmax = e0
                    smax = sa
                if e1 < cmin:
                    cmin = e1
                    smin = sb
                if e1 > cmax:
                    cmax = e1
                    smax = sb
                if c2 != 0.0:
                    tv = -c1 / (2.0 * c2)
                    if 0.0 < tv < 1.0:
                        ev = c0 + tv * (c1 + c2 * tv)
                        if c2 > 0.0 and ev < cmin:
                            cmin = ev
                            smin = sa + tv * (sb - sa)
                        elif c2 < 0.0 and ev > cmax:
                            cmax = ev
                            smax = sa + tv * (sb - sa)
            if sb >= 1.0:
                break
            if su <= sb:
                if du > 0:
                    ku += 1
                    su = (ku - u0) / du if ku <= nx - 1 else 2.0
                else:
                    ku -= 1
                    su = (ku - u0) / du if ku >= 0 else 2.0
            if sv <= sb:
                if dv > 0:
                    kv += 1
                    sv = (kv - v0) / dv if kv <= ny - 1 else 2.0
                else:
                    kv -= 1
                    sv = (kv - v0) / dv if kv >= 0 else 2.0
            sa = sb
        out[q, 0] = cmin
        out[q, 1] = smin
        out[q, 2] = cmax
        out[q, 3] = smax
    return out


def terrain_clearance_extrema(a: FloatArray, b: FloatArray, terrain: Terrain) -> FloatArray:
    """Exact minimum and maximum of ``z - h(x, y)`` along each segment over the bilinear DEM.

    Each segment is split where it crosses the grid lines; on each piece the clearance is a
    quadratic in the segment parameter, whose extrema are taken in closed form. Outside the grid
    the height is that of the nearest edge point (the grid extends its edges).

    Args:
        a, b: (m, 3) segment ends, metres.
        terrain: the DEM (only ``heights, x0, y0, dx, dy`` are read).

    Returns:
        (m, 4): minimum clearance (m), segment parameter of the minimum, maximum clearance (m),
        segment parameter of the maximum.
    """
    A = np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3)
    B = np.ascontiguousarray(b, dtype=np.float64).reshape(-1, 3)
    H = np.ascontiguousarray(terrain.heights, dtype=np.float64)
    return np.asarray(
        _terrain_extrema(
            A, B, H, float(terrain.x0), float(terrain.y0), float(terrain.dx), float(terrain.dy)
        )
    )


def bilinear_height(terrain: Terrain, x: FloatArray, y: FloatArray) -> FloatArray:
    """The verifier's own bilinear lookup (nearest edge outside the grid), metres."""
    H = np.asarray(terrain.heights, dtype=np.float64)
    ny, nx = H.shape
    u = np.clip((np.asarray(x, dtype=np.float64) - terrain.x0) / terrain.dx, 0.0, nx - 1.0)
    v = np.clip((np.asarray(y, dtype=np.float64) - terrain.y0) / terrain.dy, 0.0, ny - 1.0)
    i = np.minimum(np.floor(u).astype(np.intp), nx - 2)
    j = np.minimum(np.floor(v).astype(np.intp), ny - 2)
    s, r = u - i, v - j
    return np.asarray(
        H[j, i] * (1 - s) * (1 - r)
        + H[j, i + 1] * s * (1 - r)
        + H[j + 1, i] * (1 - s) * r
        + H[j + 1, i + 1] * s * r
    )


def check_terrain(
    traj: Trajectory, terrain: Terrain | None, band: AltitudeBand | None = None
) -> list[Violation]:
    """Terrain and altitude band along every segment (3-D only).

    * ``terrain``: the clearance ``z - h`` must stay >= 0 (exact, bilinear DEM);
    * ``altitude``, ground reference: ``z - h`` in ``[band.min, band.max]`` along the segment
      (exact min and max; ground is 0 without terrain);
    * ``altitude``, absolute reference: ``z`` in ``[band.min, band.max]`` at every waypoint
      (``z`` is linear along a segment).
    """
    if traj.dim != 3:
        return []
    a, b = _segments(traj)
    out: list[Violation] = []
    ground = band is not None and band.reference == "ground"
    ext: FloatArray | None = None
    if terrain is not None:
        ext = terrain_clearance_extrema(a, b, terrain)
    elif ground:  # flat ground at z = 0: z - h is linear
        za, zb = a[:, 2], b[:, 2]
        ext = np.stack(
            [
                np.minimum(za, zb),
                np.where(za <= zb, 0.0, 1.0),
                np.maximum(za, zb),
                np.where(za >= zb, 0.0, 1.0),
            ],
            axis=1,
        )
    if terrain is not None and ext is not None:
        for k in (int(i) for i in np.flatnonzero(ext[:, 0] < -TOL)):
            p, t = _at(traj, k, float(ext[k, 1]))
            out.append(
                Violation(
                    "terrain",
                    (traj.id,),
                    t,
                    (p,),
                    float(ext[k, 0]),
                    0.0,
                    f"{traj.id}: segment {k} goes {_f(-ext[k, 0])} m under the terrain at "
                    f"{_pts(p)}, t={t:.3f} s",
                )
            )
    if band is None:
        return out
    if ground and ext is not None:
        for k in range(a.shape[0]):
            for col, bad, bound, word in (
                (0, ext[k, 0] < band.min - TOL, band.min, "below"),
                (2, ext[k, 2] > band.max + TOL, band.max, "above"),
            ):
                if not bad:
                    continue
                p, t = _at(traj, k, float(ext[k, col + 1]))
                out.append(
                    Violation(
                        "altitude",
                        (traj.id,),
                        t,
                        (p,),
                        float(ext[k, col]),
                        bound,
                        f"{traj.id}: segment {k} at {_f(ext[k, col])} m above ground, {word} the "
                        f"band [{band.min:g}, {band.max:g}] m, at {_pts(p)}, t={t:.3f} s",
                    )
                )
    elif not ground:
        z = traj.points[:, 2]
        for w in np.flatnonzero((z < band.min - TOL) | (z > band.max + TOL)):
            k = int(w)
            zk = float(z[k])
            bound = band.min if zk < band.min else band.max
            out.append(
                Violation(
                    "altitude",
                    (traj.id,),
                    float(traj.times[k]),
                    (_pt(traj.points[k]),),
                    zk,
                    bound,
                    f"{traj.id}: waypoint {k} at altitude {_f(zk)} m, outside the band "
                    f"[{band.min:g}, {band.max:g}] m",
                )
            )
    return out


# ================================================================================ separation
@njit(cache=True)
def _walk(P, T, a0, a1, b0, b1, rec, record):  # pragma: no cover - numba
    """Exact minimum distance between two timed polylines over their common flight time.

    Rows ``a0:a1`` of ``P`` (N, 3) / ``T`` (N,) are UAV a, rows ``b0:b1`` UAV b (>= 2 rows each,
    times non-decreasing). Walks the union of both breakpoint lists; on each common interval the
    relative motion is linear, so the minimum is that of a quadratic. A zero-length segment (a
    jump) is swept as a straight motion at its instant. If ``record``, writes one row per interval
    into ``rec`` (t_start, t_end, d_min, t_min, pa xyz and pb xyz at the minimum, b - a at
    t_start and at t_end).

    Returns (d_min, t_min, pa_x, pa_y, pa_z, pb_x, pb_y, pb_z, n_rows); d_min is inf when the
    flights do not overlap in time.
    """
    best = np.inf
    res = np.full(8, np.nan)
    res[0] = np.inf
    n = 0
    T0 = max(T[a0], T[b0])
    T1 = min(T[a1 - 1], T[b1 - 1])
    if T0 > T1:
        return res, 0
    i = a0
    while i < a1 - 2 and T[i + 1] < T0:
        i += 1
    j = b0
    while j < b1 - 2 and T[j + 1] < T0:
        j += 1
    t = T0
    pa = np.empty(3)
    qa = np.empty(3)
    pb = np.empty(3)
    qb = np.empty(3)
    while True:
        # once one UAV has landed (at t = T1), the other's jumps at that instant still count
        a_done = i >= a1 - 1
        b_done = j >= b1 - 1
        if (a_done and b_done) or (a_done and T[j + 1] > t) or (b_done and T[i + 1] > t):
            break
        ea = np.inf if a_done else T[i + 1]
        eb = np.inf if b_done else T[j + 1]
        e = min(ea, eb)
        for c in range(3):
            if a_done:
                pa[c] = P[a1 - 1, c]
                qa[c] = P[a1 - 1, c]
            elif ea > T[i]:
                va = (P[i + 1, c] - P[i, c]) / (ea - T[i])
                pa[c] = P[i, c] + va * (t - T[i])
                qa[c] = P[i, c] + va * (e - T[i])
            else:
                pa[c] = P[i, c]
                qa[c] = P[i + 1, c]
            if b_done:
                pb[c] = P[b1 - 1, c]
                qb[c] = P[b1 - 1, c]
            elif eb > T[j]:
                vb = (P[j + 1, c] - P[j, c]) / (eb - T[j])
                pb[c] = P[j, c] + vb * (t - T[j])
                qb[c] = P[j, c] + vb * (e - T[j])
            else:
                pb[c] = P[j, c]
                qb[c] = P[j + 1, c]
        r0x = pb[0] - pa[0]
        r0y = pb[1] - pa[1]
        r0z = pb[2] - pa[2]
        drx = (qb[0] - qa[0]) - r0x
        dry = (qb[1] - qa[1]) - r0y
        drz = (qb[2] - qa[2]) - r0z
        dd = drx * drx + dry * dry + drz * drz
        w = 0.0
        if dd > 0.0:
            w = -(r0x * drx + r0y * dry + r0z * drz) / dd
            w = min(max(w, 0.0), 1.0)
        x = r0x + w * drx
        y = r0y + w * dry
        z = r0z + w * drz
        d = math.sqrt(x * x + y * y + z * z)
        tm = t + w * (e - t)
        if record:
            rec[n, 0] = t
            rec[n, 1] = e
            rec[n, 2] = d
            rec[n, 3] = tm
            for c in range(3):
                rec[n, 4 + c] = pa[c] + w * (qa[c] - pa[c])
                rec[n, 7 + c] = pb[c] + w * (qb[c] - pb[c])
                rec[n, 10 + c] = pb[c] - pa[c]
                rec[n, 13 + c] = qb[c] - qa[c]
        n += 1
        if d < best:
            best = d
            res[0] = d
            res[1] = tm
            for c in range(3):
                res[2 + c] = pa[c] + w * (qa[c] - pa[c])
                res[5 + c] = pb[c] + w * (qb[c] - pb[c])
        if ea == e:
            i += 1
        if eb == e:
            j += 1
        t = e
    return res, n


@njit(cache=True)
def _pairs_min(P, T, off, pairs):  # pragma: no cover - numba
    """(m, 2) minimum distance and its time for each pair of trajectories (rows of ``off``)."""
    m = pairs.shape[0]
    out = np.empty((m, 2))
    dummy = np.empty((1, 16))
    for q in range(m):
        a = pairs[q, 0]
        b = pairs[q, 1]
        res, _ = _walk(P, T, off[a], off[a + 1], off[b], off[b + 1], dummy, False)
        out[q, 0] = res[0]
        out[q, 1] = res[1]
    return out


@njit(cache=True)
def _sweep(lo, hi, t0, t1, gap, out, fill):  # pragma: no cover - numba
    """Sort-and-sweep along x: pairs (a < b) whose boxes ``lo..hi`` (n, 3), grown by ``gap``,
    overlap on every axis and whose time windows ``[t0, t1]`` overlap. Returns their number;
    if ``fill``, writes them into ``out`` (m, 2) int64."""
    n = lo.shape[0]
    order = np.argsort(lo[:, 0], kind="mergesort")
    m = 0
    for p in range(n):
        a = order[p]
        for r in range(p + 1, n):
            b = order[r]
            if lo[b, 0] - hi[a, 0] > gap:
                break
            if t0[a] > t1[b] or t0[b] > t1[a]:
                continue
            ok = True
            for c in range(1, 3):
                if lo[b, c] - hi[a, c] > gap or lo[a, c] - hi[b, c] > gap:
                    ok = False
                    break
            if not ok:
                continue
            if fill:
                out[m, 0] = min(a, b)
                out[m, 1] = max(a, b)
            m += 1
    return m


def _pack(trajs: Sequence[Trajectory]) -> tuple[FloatArray, FloatArray, IntArray]:
    """Stack trajectories into P (N, 3) (z = 0 for 2-D), T (N,), offsets (n + 1,)."""
    counts = [len(t.times) for t in trajs]
    off = np.zeros(len(trajs) + 1, dtype=np.int64)
    off[1:] = np.cumsum(counts)
    P = np.zeros((int(off[-1]), 3))
    T = np.zeros(int(off[-1]))
    for k, tr in enumerate(trajs):
        P[off[k] : off[k + 1], : tr.dim] = tr.points
        T[off[k] : off[k + 1]] = tr.times
    return P, T, off


def candidate_pairs(trajs: Sequence[Trajectory], gap: float) -> IntArray:
    """Pairs ``(a, b)``, a < b, that could come closer than ``gap``: their flight time windows
    overlap and their whole-flight boxes, grown by ``gap``, overlap (sort-and-sweep). Every
    pair left out stays farther than ``gap`` apart at every instant. Returns (m, 2) int64."""
    if len(trajs) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    lo = np.zeros((len(trajs), 3))
    hi = np.zeros((len(trajs), 3))
    for k, tr in enumerate(trajs):
        lo[k, : tr.dim] = tr.points.min(axis=0)
        hi[k, : tr.dim] = tr.points.max(axis=0)
    t0 = np.array([tr.times.min() for tr in trajs])
    t1 = np.array([tr.times.max() for tr in trajs])
    m = int(_sweep(lo, hi, t0, t1, float(gap), np.zeros((1, 2), dtype=np.int64), False))
    pairs = np.zeros((m, 2), dtype=np.int64)
    _sweep(lo, hi, t0, t1, float(gap), pairs, True)
    if len(pairs):
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    return pairs


def pair_min_distance(a: Trajectory, b: Trajectory) -> tuple[float, float]:
    """Exact minimum distance between two UAVs over continuous time while both fly, and the
    time it happens: ``(metres, seconds)``, ``(inf, nan)`` if their flights do not overlap."""
    P, T, off = _pack([a, b])
    res, _ = _walk(P, T, off[0], off[1], off[1], off[2], np.empty((1, 16)), False)
    return float(res[0]), float(res[1])


def pair_encounters(a: Trajectory, b: Trajectory, s2: float) -> list[Violation]:
    """Every close encounter of two UAVs (a run of consecutive common intervals on which they
    come closer than ``s2 - TOL``), reported at its closest point."""
    P, T, off = _pack([a, b])
    rec = np.empty((len(a.times) + len(b.times) + 2, 16))
    _, n = _walk(P, T, off[0], off[1], off[1], off[2], rec, True)
    rows = rec[:n]
    out = []
    k = 0
    while k < n:
        if rows[k, 2] >= s2 - TOL:
            k += 1
            continue
        e = k
        # the run goes on while the distance stays below s2 across the shared breakpoint
        while (
            e + 1 < n
            and rows[e + 1, 2] < s2 - TOL
            and float(np.linalg.norm(rows[e, 13:16])) < s2 - TOL
            and float(np.linalg.norm(rows[e + 1, 10:13])) < s2 - TOL
        ):
            e += 1
        run = rows[k : e + 1]
        w = int(np.argmin(run[:, 2]))
        d, t = float(run[w, 2]), float(run[w, 3])
        pa = _pt(run[w, 4 : 4 + a.dim])
        pb = _pt(run[w, 7 : 7 + b.dim])
        t_in = _crossing(run[0], s2, first=True)
        t_out = _crossing(run[-1], s2, first=False)
        out.append(
            Violation(
                "separation",
                (a.id, b.id),
                t,
                (pa, pb),
                d,
                s2,
                f"{a.id} and {b.id} {_f(d)} m apart at t={t:.3f} s (S2 {s2:g} m; "
                f"closer from t={t_in:.3f} to {t_out:.3f} s): "
                f"{a.id} at {_pts(pa)}, {b.id} at {_pts(pb)}",
            )
        )
        k = e + 1
    return out


def _crossing(row: FloatArray, s2: float, first: bool) -> float:
    """The time at which the distance of a recorded interval crosses ``s2``: the first time it
    drops below (``first``) or the last time it is below; the interval's end if it never
    crosses inside it."""
    t0, t1 = float(row[0]), float(row[1])
    r0 = row[10:13]
    dr = row[13:16] - r0
    qa, qb, qc = float(dr @ dr), 2.0 * float(r0 @ dr), float(r0 @ r0) - s2 * s2
    disc = qb * qb - 4 * qa * qc
    if qa <= 0 or disc < 0:
        return t0 if first else t1
    w = (-qb - math.sqrt(disc)) / (2 * qa) if first else (-qb + math.sqrt(disc)) / (2 * qa)
    w = min(max(w, 0.0), 1.0)
    return t0 + w * (t1 - t0)


@dataclass(frozen=True)
class SeparationResult:
    """What :func:`check_separation` found: the violations, the number of pairs checked exactly,
    and the overall minimum distance among them with its pair and time."""

    violations: list[Violation]
    pairs_checked: int
    min_distance: float
    min_pair: tuple[str, str] | None
    min_time: float | None


def check_separation(
    trajs: Sequence[Trajectory], s2: float, prune: bool = True, exact_min: bool = True
) -> SeparationResult:
    """Every pair of UAVs at least ``s2`` apart over continuous time (exact).

    Args:
        trajs: the UAVs (times non-decreasing).
        s2: the required separation, metres.
        prune: skip pairs that cannot come within ``s2`` (see :func:`candidate_pairs`); False
            checks every pair exactly (for tests and benchmarks).
        exact_min: when no checked pair comes within ``s2``, widen the pruning until the fleet's
            overall minimum separation is found exactly (pairs pruned at a gap ``g`` are farther
            than ``g`` apart, so once some pair is found at ``<= g`` it is the minimum); False
            reports the minimum over the pairs checked for ``s2`` only (inf if none).

    Returns:
        The violations (one per close encounter), the number of pairs checked exactly for
        ``s2``, and the minimum separation with its pair and time.
    """
    n = len(trajs)
    if n < 2:
        return SeparationResult([], 0, math.inf, None, None)
    P, T, off = _pack(trajs)

    def exact(pairs: IntArray) -> FloatArray:
        if len(pairs) == 0:
            return np.zeros((0, 2))
        return np.asarray(_pairs_min(P, T, off, np.ascontiguousarray(pairs)))

    if prune:
        pairs = candidate_pairs(trajs, s2)
    else:
        ia, ib = np.triu_indices(n, 1)
        pairs = np.stack([ia, ib], axis=1).astype(np.int64)
    res = exact(pairs)
    out: list[Violation] = []
    for bad in np.flatnonzero(res[:, 0] < s2 - TOL):
        a, b = trajs[int(pairs[bad, 0])], trajs[int(pairs[bad, 1])]
        out.extend(pair_encounters(a, b, s2))
    checked = len(pairs)
    best = float(res[:, 0].min()) if len(res) else math.inf
    if prune and exact_min and not best <= s2:
        lo = np.min([t.points.min(axis=0) for t in trajs], axis=0)
        hi = np.max([t.points.max(axis=0) for t in trajs], axis=0)
        diameter = float(np.linalg.norm(hi - lo))
        gap = best if math.isfinite(best) else 2.0 * max(s2, 1.0)
        while True:
            pairs = candidate_pairs(trajs, gap)
            res = exact(pairs)
            best = float(res[:, 0].min()) if len(res) else math.inf
            if best <= gap or gap > diameter:
                break
            gap = best if math.isfinite(best) else 2.0 * gap
    if not len(res) or not math.isfinite(best):
        return SeparationResult(out, checked, math.inf, None, None)
    q = int(np.argmin(res[:, 0]))
    pair = (trajs[int(pairs[q, 0])].id, trajs[int(pairs[q, 1])].id)
    return SeparationResult(out, checked, float(res[q, 0]), pair, float(res[q, 1]))


def check_moving(traj: Trajectory, obstacles: Sequence[Any]) -> list[Violation]:
    """The UAV stays at least ``radius`` from every moving obstacle's centre over continuous
    time (the obstacle holds its first and last positions outside its knots)."""
    out = []
    for oi, obs in enumerate(obstacles):
        ot = np.asarray(obs.times, dtype=np.float64)
        op = np.asarray(obs.positions, dtype=np.float64)[:, : traj.dim]
        t_lo, t_hi = float(traj.times[0]), float(traj.times[-1])
        times = np.concatenate([[min(t_lo, ot[0])], ot, [max(t_hi, ot[-1])]])
        pts = np.concatenate([op[:1], op, op[-1:]])
        other = Trajectory(f"moving obstacle {oi}", pts, times)
        for v in pair_encounters(traj, other, float(obs.radius)):
            d, t = v.value, v.time
            out.append(
                Violation(
                    "moving",
                    (traj.id,),
                    t,
                    v.where,
                    d,
                    float(obs.radius),
                    f"{traj.id}: {_f(d)} m from the centre of moving obstacle {oi} (radius "
                    f"{obs.radius:g} m) at t={t:.3f} s, UAV at {_pts(v.where[0])}, obstacle at "
                    f"{_pts(v.where[1])}",
                )
            )
    return out


# ================================================================================ everything
def verify_trajectories(
    trajs: Sequence[Trajectory],
    scenario: Scenario,
    plan_scenario: str | None = None,
    smoothed: bool = False,
) -> VerifyReport:
    """Run every check on parsed trajectories (see the module docstring)."""
    sc = scenario
    report = VerifyReport(
        scenario=sc.name,
        plan_scenario=plan_scenario,
        smoothed=smoothed,
        uav_ids=[t.id for t in trajs],
        n_segments=sum(len(t.times) - 1 for t in trajs),
        s2=float(sc.uav.s2),
    )
    if plan_scenario is not None and plan_scenario != sc.name:
        report.warnings.append(
            f"the plan is for scenario {plan_scenario!r}, verifying against {sc.name!r}"
        )
    tasks = {t.id: t for t in sc.tasks}
    per_uav: list[Violation] = []
    timed: list[Trajectory] = []
    polygons = sc.no_fly_polygons
    for tr in trajs:
        task = tasks.get(tr.id)
        if task is not None:
            for what, want, got in (
                ("start", task.start, tr.points[0]),
                ("goal", task.goal, tr.points[-1]),
            ):
                gap = float(np.linalg.norm(np.asarray(want) - got))
                if gap > 1e-3:
                    report.warnings.append(
                        f"{tr.id}: path {what} {_pts(got)} is {gap:.3f} m from the task's "
                        f"{what} {_pts(want)}"
                    )
        vs = check_times(tr)
        times_ok = not vs
        if not times_ok:
            report.warnings.append(
                f"{tr.id}: times decrease, left out of the separation and moving-obstacle checks"
            )
        else:
            timed.append(tr)
        vs += check_speed(tr, float(sc.uav.speed))
        vs += check_bounds(tr, sc.bounds.lower, sc.bounds.upper)
        if tr.dim == 3 and sc.cylinders:
            vs += check_cylinders(tr, sc.cylinders)
        if sc.circles:
            vs += check_circles(tr, sc.circles)
        if polygons:
            vs += check_polygons(tr, polygons)
        if sc.moving_obstacles and times_ok:
            vs += check_moving(tr, sc.moving_obstacles)
        vs += check_terrain(tr, sc.terrain, sc.altitude)
        if tr.feasible and vs:
            report.warnings.append(
                f"{tr.id}: the plan calls it feasible, the verifier found {len(vs)} violation(s)"
            )
        per_uav += vs
    sep = check_separation(timed, report.s2)
    n = len(trajs)
    report.pairs_total = n * (n - 1) // 2
    report.pairs_checked = sep.pairs_checked
    report.min_separation = sep.min_distance
    report.min_separation_pair = sep.min_pair
    report.min_separation_time = sep.min_time
    order = {k: i for i, k in enumerate(KINDS)}
    report.violations = sorted(per_uav + sep.violations, key=lambda v: order.get(v.kind, 99))
    return report


def verify_plan(
    plan: Mapping[str, Any], scenario: Scenario, smoothed: bool = False
) -> VerifyReport:
    """Verify a decoded ``plan.json`` against ``scenario`` (see the module docstring).

    Args:
        plan: the decoded plan (``{"format", "scenario", "uavs": [{"id", "waypoints", "times",
            ...}, ...]}``).
        scenario: the world to check against.
        smoothed: verify each UAV's ``smoothed`` polyline instead of its waypoints.

    Raises:
        PlanFormatError: the plan cannot be read (a missing or malformed field, mismatched
            lengths, points of the wrong dimension, no smoothed path with ``smoothed=True``).
    """
    trajs, name = parse_plan(plan, scenario.dim, smoothed=smoothed)
    return verify_trajectories(trajs, scenario, name, smoothed)


# ================================================================================ formatting
def _pt(p: Iterable[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in p)


def _f(v: float) -> str:
    v = float(v)
    if not math.isfinite(v):
        return "inf" if v > 0 else "-inf"
    return f"{v:.3f}"


def _pts(p: Iterable[float]) -> str:
    return "(" + ", ".join(f"{float(v):.2f}" for v in p) + ")"
