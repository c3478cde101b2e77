"""From a planned polyline to the trajectory a UAV flies, checked as it will be flown.

A planner's polyline is a geometric path; a UAV with a minimum turn radius cannot fly its
corners. :func:`fly` turns it into a flight, the timed trajectory the plan declares and
guarantees (``PlanResult.flown``):

* **Without a turn radius** (``uav.turn_radius == 0``) the polyline is flown as planned.
* **With one**, Dubins CSC curves (PPSwarm Sect. 4.4, :mod:`uavplan.smoothing.dubins`), in up to
  four variants: through every waypoint with headings bisecting the turns (the paper's),
  corner-cutting between segment midpoints (:func:`~uavplan.smoothing.dubins.midpoint_poses`),
  and each of those on the polyline shortcut by line of sight (a waypoint dropped where the
  straight segment replacing it is clear of the world and of the reserved UAVs, flown between
  the planned times). Each is sampled at most ``min(step, turn_radius / 4)`` apart, so that its
  samples' curvature estimate stays within 1 % of the curves'.
* **Timing**: ``"planned"`` reaches each pose at its planned time where the UAV's speed range
  allows (never faster than ``v_max``, never slower than ``min_speed``: late where a curve is
  longer than its segment, early where it is so much shorter that the UAV cannot slow down
  enough); ``"constant"`` flies at the cruise speed from the take-off (the paper's model).
  A world with moving obstacles uses ``"constant"``.

Every variant is checked by the motion validator exactly as the verifier will check it: the
world (terrain and altitude band along whole segments), the reserved UAVs' flights (separation,
continuous time) and the kinematic limits (speed range, climb and descent angles, turn radius).
The variant with the fewest kinds of violation, then the shortest, is the flight; it is
``ok`` only if it has none.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uavplan.planners.core.results import PlanResult
from uavplan.problems.path_problem import lookup_for
from uavplan.problems.validity import TIME_CHECKS, MotionValidator, greedy_shortcut
from uavplan.smoothing.dubins import (
    SmoothedPath,
    drop_consecutive_duplicates,
    midpoint_poses,
    schedule,
    smooth_path,
)
from uavplan.world.geometry import as_3d
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.tolerances import DUPLICATE_TOL

FloatArray = NDArray[np.float64]

TIMINGS = ("planned", "constant")
#: Default spacing of a smoothed trajectory's samples, metres (at most a quarter turn radius).
DEFAULT_STEP = 5.0


@dataclass(frozen=True, eq=False)
class Flight:
    """A UAV's flight: ``points`` (m, dim) and ``times`` (m,), flown straight between samples.

    Attributes:
        kind: ``"smoothed"`` (Dubins curves) or ``"polyline"`` (the planned polyline).
        variant: which construction (``polyline``, ``as planned``, ``through``, ``corners``,
            ``shortcut-through``, ``shortcut-corners``).
        violations: the checks it fails (empty: ``ok``).
        late: the most it arrives after a planned pose time, seconds (0 for on time or early).
    """

    points: FloatArray
    times: FloatArray
    kind: str
    variant: str
    violations: tuple[str, ...]
    late: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.violations

    @property
    def length(self) -> float:
        return float(np.sum(np.linalg.norm(np.diff(self.points, axis=0), axis=1)))


def flight_validator(
    scenario: Scenario,
    task: Task,
    reservations: ReservationTable | None = None,
    kinematics: bool = True,
) -> MotionValidator:
    """The validator a flight must pass: the world with the band along whole segments, the
    reserved UAVs and the UAV's kinematic limits (what ``uavplan verify`` checks). Without
    ``kinematics``: the validator of a shortcut's straight segments (the smoothing and the
    schedule after it make the flight)."""
    return MotionValidator(
        scenario,
        task,
        strict_altitude=True,
        lookup=lookup_for(scenario.cost),
        reservations=reservations,
        kinematics=kinematics,
    )


def pose_times(
    curve_lengths: FloatArray,
    sample_lengths: FloatArray,
    planned: FloatArray,
    v_min: float,
    v_max: float,
    cruise: float,
    timing: str,
) -> FloatArray:
    """When a UAV reaches each pose, (k,) s, flying each piece at a constant speed and leaving
    the first pose at ``planned[0]``. ``"planned"``: each pose at its planned time where the
    speed range allows, else as close to it as it can: never sooner than the piece's curve
    length (``curve_lengths``, m, at least its samples') at ``v_max`` and never later than its
    samples' length (``sample_lengths``) at ``v_min``; where those two bounds cross (a speed
    range narrower than the curve's excess over its chords, e.g. ``min_speed == speed``), the
    samples' length at ``v_max`` is the bound instead, so the flight as declared (straight
    between samples) keeps the range; ``"constant"``: every piece's samples at ``cruise``."""
    Lc = np.asarray(curve_lengths, dtype=np.float64)
    Ls = np.asarray(sample_lengths, dtype=np.float64)
    tp = np.asarray(planned, dtype=np.float64)
    out = np.empty_like(tp)
    out[0] = tp[0]
    if timing == "constant":
        out[1:] = tp[0] + np.cumsum(Ls / cruise)
        return out
    if v_min <= 0:  # only a floor: a running maximum (no Python loop)
        c = np.concatenate([[0.0], np.cumsum(Lc / v_max)])
        return np.asarray(c + np.maximum.accumulate(tp - c))
    for k in range(1, len(tp)):
        earliest = out[k - 1] + Lc[k - 1] / v_max
        latest = out[k - 1] + Ls[k - 1] / v_min
        if latest < earliest:  # a range too narrow for the curve's length beyond its samples'
            earliest = out[k - 1] + Ls[k - 1] / v_max  # (a constant-speed UAV): the samples
        out[k] = min(max(tp[k], earliest), latest)
    return out


def _planned_pose_times(waypoints: FloatArray, times: FloatArray, variant: str) -> FloatArray:
    """Planned times of the poses that a ``variant`` smooths through: the kept waypoints' own
    times (``through``) or the start, the segment midpoints (the mean of their ends' times)
    and the goal (``corners``), with the same duplicate dropping as the smoothing."""
    keep = drop_consecutive_duplicates(waypoints, DUPLICATE_TOL)
    t = np.asarray(times, dtype=np.float64)[keep]
    if variant == "through" or t.shape[0] < 2:
        return t
    return np.concatenate([t[:1], 0.5 * (t[:-1] + t[1:]), t[-1:]])


def candidate_flights(
    scenario: Scenario,
    waypoints: FloatArray,
    times: FloatArray,
    timing: str = "planned",
    step: float = DEFAULT_STEP,
    shortcut: MotionValidator | None = None,
    cruise: float | None = None,
) -> list[Flight]:
    """The flights worth checking for a planned polyline (see the module docstring), not yet
    checked (``violations`` empty). ``shortcut``: the validator that allows shortcuts by line
    of sight (None: no shortcut variants). ``cruise``: the speed of ``"constant"`` timing
    (default: the UAV's cruise speed; a slower one flies the same curves later)."""
    uav = scenario.uav
    wp = np.asarray(waypoints, dtype=np.float64)
    wt = np.asarray(times, dtype=np.float64)
    if timing not in TIMINGS:
        raise ValueError(f"timing must be one of {TIMINGS}, got {timing!r}")
    v = uav.speed if cruise is None else float(cruise)
    if uav.turn_radius <= 0:
        if timing == "constant" and cruise is not None:  # the polyline, re-timed
            seg = np.linalg.norm(np.diff(wp, axis=0), axis=1)
            wt = wt[0] + np.concatenate([[0.0], np.cumsum(seg)]) / v
        return [Flight(wp, wt, "polyline", "polyline", ())]
    h = min(float(step), uav.turn_radius / 4.0)
    bases: list[tuple[FloatArray, FloatArray, str]] = [(wp, wt, "")]
    if shortcut is not None and timing == "planned":
        short, short_t, _ = greedy_shortcut(shortcut, wp, wt)
        if short.shape[0] < wp.shape[0] and short_t is not None:
            bases.append((short, short_t, "shortcut-"))
    out: list[Flight] = []
    dim = wp.shape[1]
    for (w, t, tag), kind in itertools.product(bases, ("through", "corners")):
        w3 = np.ascontiguousarray(as_3d(w), dtype=np.float64)
        sm = _smoothed(w3.tobytes(), w3.shape[0], float(uav.turn_radius), float(h), kind)
        if sm is None:
            continue
        tp = _planned_pose_times(w3, t, kind)
        if tp.shape != sm.waypoint_index.shape:  # not for distinct waypoints; be safe
            tp = np.concatenate([[t[0]], t[0] + np.cumsum(sm.piece_lengths) / uav.speed])
        tk = pose_times(
            sm.piece_lengths, _sample_lengths(sm), tp, uav.min_speed, uav.v_max, v, timing
        )
        late = float(max(0.0, np.max(tk - tp)))
        pts = sm.points if dim == 3 else sm.points[:, :2]
        out.append(Flight(np.asarray(pts), schedule(sm, tk), "smoothed", tag + kind, (), late))
    return out


@functools.lru_cache(maxsize=128)
def _smoothed(
    key: bytes, n: int, turn_radius: float, step: float, kind: str
) -> SmoothedPath | None:
    """The Dubins smoothing of the (n, 3) waypoints whose bytes are ``key`` (``through``: the
    waypoints with bisecting headings; ``corners``: between segment midpoints), None where
    no smoothing exists. Memoized: a fleet planner flies the same polyline at several speeds
    and take-off times (:mod:`uavplan.planners.fleet.prioritized`), and the curves depend on
    the geometry alone; the arrays are read-only, as they are shared."""
    w3 = np.frombuffer(key, dtype=np.float64).reshape(n, 3)
    try:
        if kind == "through":
            sm = smooth_path(w3, turn_radius, step)
        else:
            poses, heads = midpoint_poses(w3)
            sm = smooth_path(poses, turn_radius, step, heads)
    except ValueError:
        return None
    for a in (sm.points, sm.headings, sm.waypoints, sm.waypoint_index):
        a.setflags(write=False)
    return sm


def _sample_lengths(sm: SmoothedPath) -> FloatArray:
    """The length of each piece of a smoothed path along its samples (what is flown), (k-1,)."""
    seg = np.linalg.norm(np.diff(sm.points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    return np.asarray(np.diff(s[sm.waypoint_index]))


def check_flights(validator: MotionValidator, flights: Sequence[Flight]) -> list[Flight]:
    """Each flight with the checks it fails."""
    out = []
    for f in flights:
        b = validator.batch(f.points[None], f.times[None])
        viol = tuple(k for k, v in validator.violations(b).items() if v[0])
        out.append(dataclasses.replace(f, violations=viol))
    return out


class ClearAt:
    """Whether a flight is clear of ``table``'s reserved flights taking off ``waits[i]`` seconds
    later than its times say, where separation is the only check that reads time: asked
    lazily, in any order, each query running through the flight's next ``chunk`` waits up to
    the first clear one (:meth:`ReservationTable.first_free`, which searches each wait from
    where the conflict at the wait before was found), so that waits asked in increasing order
    (as :func:`first_clear` asks them) are mostly answered by the query before.
    ``clear(key, flight, i)``; ``key`` names the flight (answers are kept per key)."""

    def __init__(self, table: ReservationTable, waits: Sequence[float], chunk: int) -> None:
        self.table = table
        self.W = np.asarray(waits, dtype=np.float64)
        self.chunk = int(chunk)
        #: per key: the waits from the first index to the second are blocked, the second
        #: itself clear if it is the third
        self._known: dict[object, tuple[int, int, int]] = {}
        self._hint: dict[object, int] = {}

    def clear(self, key: object, f: Flight, i: int) -> bool:
        start, blocked, clear = self._known.get(key, (0, 0, -1))
        if start <= i < blocked:
            return False
        if i == clear:
            return True
        j, self._hint[key] = self.table.first_free(
            as_3d(f.points), f.times, self.W, i, i + self.chunk, self._hint.get(key, 0)
        )
        self._known[key] = (i, j if j >= 0 else i + self.chunk, j)
        return j == i


def only_separation_reads_time(scenario: Scenario, task: Task, table: ReservationTable) -> bool:
    """Whether, of ``task``'s checks against ``table``, separation is the only one that reads
    time (no moving obstacles) and the table holds flights: then a flight's take-off times can
    be tried in batched table queries (:class:`ClearAt`)."""
    checks = flight_validator(scenario, task, table).checks()
    return [n for n in TIME_CHECKS if n in checks] == ["separation"] and len(table) > 0


def first_clear(
    scenario: Scenario,
    table: ReservationTable,
    flights: Sequence[Flight],
    waits: Sequence[float],
    task_at: Callable[[int], Task],
    chunk: int,
) -> tuple[int, int, Task, Flight] | None:
    """The first wait, then the first of ``flights`` (in the orders given), at which the
    flight, its times moved ``waits[i]`` seconds later, passes every check in full:
    ``(i, flight index, task_at(i), the flight as checked)``; None if at none. ``task_at(i)``:
    the task taking off at that wait. The flights are already clear of everything that does
    not read time; where separation is the only check that does, the waits are answered by
    batched table queries (:class:`ClearAt`, ``chunk`` waits a query) and a validator is made
    only at a wait where a flight is clear, else each flight is asked at each wait."""
    task0 = task_at(0) if len(waits) else None
    if task0 is None:
        return None
    batched = only_separation_reads_time(scenario, task0, table)
    slots = ClearAt(table, waits, chunk)
    for i, wait in enumerate(waits):
        later: Task | None = None
        v: MotionValidator | None = None
        for k, f in enumerate(flights):
            if batched and not slots.clear(k, f, i):
                continue
            if v is None:
                later = task_at(i)
                v = flight_validator(scenario, later, table)
            if not batched:
                skip = [n for n in v.checks() if n not in TIME_CHECKS]
                if not len(v.passing(v.batch(f.points[None], (f.times + wait)[None]), skip=skip)):
                    continue
            flight = check_flights(v, [dataclasses.replace(f, times=f.times + wait)])[0]
            if flight.ok:  # else the full check disagrees: keep searching
                assert later is not None
                return i, k, later, flight
    return None


def best_flight(flights: Sequence[Flight]) -> Flight | None:
    """The flight with the fewest kinds of violation, then the shortest (None if none)."""
    if not flights:
        return None
    return min(flights, key=lambda f: (len(f.violations), f.length))


def fly(
    scenario: Scenario,
    task: Task,
    waypoints: FloatArray,
    times: FloatArray,
    reservations: ReservationTable | None = None,
    timing: str = "planned",
    step: float = DEFAULT_STEP,
    cruise: float | None = None,
    as_planned: bool = False,
) -> Flight:
    """The flight of a planned polyline (see the module docstring), checked against the world,
    the ``reservations`` and the UAV's kinematic limits. The task's start time is the
    polyline's first time (a delayed take-off keeps its delay). ``cruise``: fly at this
    constant speed instead (``timing`` is then ``"constant"``). ``as_planned``: the polyline
    is already a trajectory within the UAV's limits (a planner that steps in time, as the
    APF): it is the flight if it passes every check, kinematics included; else the usual
    variants are tried."""
    t = dataclasses.replace(task, start_time=float(np.asarray(times)[0]))
    validator = flight_validator(scenario, t, reservations)
    if as_planned:
        own = Flight(np.asarray(waypoints), np.asarray(times), "polyline", "as planned", ())
        checked = check_flights(validator, [own])[0]
        if not checked.violations:
            return checked
    timing = "constant" if scenario.moving_obstacles or cruise is not None else timing
    short = flight_validator(scenario, t, reservations, kinematics=False)
    flights = check_flights(
        validator,
        candidate_flights(scenario, waypoints, times, timing, step, shortcut=short, cruise=cruise),
    )
    best = best_flight(flights)
    if best is None:  # no variant could be built: the polyline, checked as it is
        best = check_flights(validator, [Flight(np.asarray(waypoints), np.asarray(times),
                                               "polyline", "polyline", ())])[0]  # fmt: skip
    return best


def declare(result: PlanResult, flight: Flight) -> PlanResult:
    """``result`` with ``flight`` as the trajectory it is to fly."""
    return dataclasses.replace(
        result,
        flown=flight.points,
        flown_times=flight.times,
        flown_kind=flight.kind,
        flown_ok=flight.ok,
        flown_violations=flight.violations,
    )
