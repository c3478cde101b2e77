"""Replanning in flight: a small mission simulation for any single-UAV planner.

The UAV flies its timed plan (waypoints and arrival times); an uncertain area the planner did
not know (``revealed: false`` in the scenario, HR-MAGA Eq. 2) is revealed when the UAV comes
within ``sensor_range`` of it (horizontal distance from the UAV's position to the rectangle;
the trajectory is sampled every ``sample_step`` seconds). The planner's repair is then called
from the UAV's *predicted* state: the position on the current plan ``latency`` seconds after
the event (the UAV keeps flying its plan while the repair computes; the default latency is one
control period, 0.1 s). The repair's own compute time is measured; it misses the deadline when
it exceeds ``latency``. The flown trajectory is the current plan up to that instant followed by
the repaired plan.

* :meth:`Planner.repair <uavplan.planners.core.base.Planner.repair>` (the default, every planner):
  plan again from scratch, from the predicted state to the goal, on the world as now known (the
  baseline any reader asks for);
* HR-MAGA overrides it: only the segments of the remaining plan that the new area touches are
  re-optimized, on the finest level (:mod:`uavplan.planners.population.hr_maga`).

A revealed area whose interior the remaining plan does not enter needs no repair (the event is
recorded as ``clear``). The mission is checked at the end, as flown, against the world with
every uncertain area revealed (a revealed area is a no-fly zone from then on; the UAV was
outside it before, as it is sensed from outside), by the flight validator here and by the
independent verifier where the caller runs it (``uavplan fly``, the ``hrmaga-replan`` plan).
Algorithms never print: the mission is data.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.planners.core.base import Planner
from uavplan.planners.core.flight import flight_validator
from uavplan.planners.core.results import PlanResult
from uavplan.world.obstacles import UncertainArea
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class RevealEvent:
    """One uncertain area revealed in flight and what the planner did about it."""

    area: int  # index into the scenario's uncertain areas
    time: float  # s, when it came within sensor range
    position: tuple[float, ...]  # the UAV's position then
    action: str  # "clear" (the plan does not enter it), "repair" (the planner's repair)
    compute_time: float = 0.0  # s, the repair's wall time
    deadline_missed: bool = False  # compute_time > latency
    repaired_feasible: bool = True  # the repaired remaining plan passes the checks
    info: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Mission:
    """A simulated flight with replanning: the flown timed polyline, the first plan, the
    events, and the verdict of the flight validator on the fully revealed world."""

    waypoints: FloatArray
    times: FloatArray
    initial: PlanResult
    events: tuple[RevealEvent, ...]
    feasible: bool
    violations: tuple[str, ...]
    latency: float
    sensor_range: float

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())


def revealed_world(scenario: Scenario, areas: set[int] | None = None) -> Scenario:
    """``scenario`` with the uncertain areas ``areas`` (default: all) revealed."""
    return dataclasses.replace(
        scenario,
        uncertain_areas=tuple(
            dataclasses.replace(u, revealed=True) if areas is None or i in areas else u
            for i, u in enumerate(scenario.uncertain_areas)
        ),
    )


def position_at(waypoints: FloatArray, times: FloatArray, t: float) -> FloatArray:
    """The position on a timed polyline at time ``t`` (clamped to its ends)."""
    w = np.asarray(waypoints, dtype=np.float64)
    ts = np.asarray(times, dtype=np.float64)
    return np.array([np.interp(t, ts, w[:, k]) for k in range(w.shape[1])])


def prefix(waypoints: FloatArray, times: FloatArray, t: float) -> tuple[FloatArray, FloatArray]:
    """The timed polyline up to time ``t`` (its last point the position at ``t``)."""
    ts = np.asarray(times, dtype=np.float64)
    k = int(np.searchsorted(ts, t, side="right"))
    p = position_at(waypoints, ts, t)
    pts = np.vstack([np.asarray(waypoints)[:k], p[None]])
    tt = np.concatenate([ts[:k], [t]])
    if len(pts) >= 2 and tt[-1] == tt[-2]:
        pts, tt = pts[:-1], tt[:-1]
    return pts, tt


def rect_distance(points: FloatArray, a: UncertainArea) -> FloatArray:
    """Horizontal distance from points ``(n, >= 2)`` to the rectangle (0 inside)."""
    p = np.asarray(points, dtype=np.float64)
    dx = np.maximum(np.maximum(a.x - p[:, 0], 0.0), p[:, 0] - (a.x + a.width))
    dy = np.maximum(np.maximum(a.y - p[:, 1], 0.0), p[:, 1] - (a.y + a.height))
    return np.asarray(np.hypot(dx, dy))


def first_sighting(
    waypoints: FloatArray,
    times: FloatArray,
    t_from: float,
    areas: dict[int, UncertainArea],
    sensor_range: float,
    sample_step: float,
) -> tuple[float, int] | None:
    """The first time at or after ``t_from`` when an area of ``areas`` is within
    ``sensor_range``, and which (sampled every ``sample_step`` s); None if never."""
    ts = np.asarray(times, dtype=np.float64)
    if not areas or t_from > ts[-1]:
        return None
    grid = np.arange(t_from, ts[-1] + sample_step, sample_step)
    grid = np.minimum(grid, ts[-1])
    pts = np.stack([np.interp(grid, ts, np.asarray(waypoints)[:, k]) for k in range(2)], axis=1)
    best: tuple[float, int] | None = None
    for i, a in areas.items():
        hit = np.flatnonzero(rect_distance(pts, a) <= sensor_range)
        if hit.size and (best is None or grid[hit[0]] < best[0]):
            best = (float(grid[hit[0]]), i)
    return best


def fly_mission(
    planner: Planner,
    scenario: Scenario,
    task: Task | None = None,
    *,
    budget: Budget | int | None = None,
    repair_budget: Budget | int | None = None,
    seed: int | None = None,
    sensor_range: float | None = None,
    latency: float = 0.1,
    sample_step: float = 0.1,
    initial: PlanResult | None = None,
) -> Mission:
    """Plan ``task`` (default: the first) on the world as known, fly it, reveal each unknown
    uncertain area when it comes within ``sensor_range`` (default: 10 s of flight, ``10 v``),
    and repair from the predicted state ``latency`` s later (see the module docstring).
    ``initial``: a plan already made (its planner's repairs follow)."""
    t = task if task is not None else scenario.tasks[0]
    v = scenario.uav.speed
    r_sense = 10.0 * v if sensor_range is None else float(sensor_range)
    if r_sense <= v * latency:
        raise ValueError(
            f"sensor range {r_sense:g} m is not beyond what the UAV flies during the repair "
            f"latency ({v * latency:g} m): it could enter an area before it can react"
        )
    first = initial if initial is not None else planner.plan(scenario, t, budget, seed)
    W, T = np.asarray(first.waypoints), np.asarray(first.times)
    hidden = {i: u for i, u in enumerate(scenario.uncertain_areas) if not u.revealed}
    known: set[int] = set()
    events: list[RevealEvent] = []
    t_now = float(T[0])
    rng = np.random.default_rng(seed)
    while True:
        seen = first_sighting(W, T, t_now, hidden, r_sense, sample_step)
        if seen is None:
            break
        t_e, i = seen
        hidden.pop(i)
        known.add(i)
        world = revealed_world(scenario, known)
        pos_e = position_at(W, T, t_e)
        t_r = min(t_e + latency, float(T[-1]))
        head_w, head_t = prefix(W, T, t_r)
        later = np.greater(T, t_r)
        rest_w = np.vstack([head_w[-1:], W[later]])
        rest_t = np.concatenate([[t_r], T[later]])
        sub_task = dataclasses.replace(t, start=tuple(head_w[-1]), start_time=t_r)
        check = flight_validator(world, sub_task, kinematics=False)
        if len(rest_w) < 2 or bool(check.paths_valid(rest_w[None])[0]):
            events.append(RevealEvent(i, t_e, tuple(pos_e), "clear"))
            t_now = t_e + sample_step
            continue
        t0 = time.perf_counter()
        new_w, info = planner.repair(
            world, sub_task, rest_w, rest_t, i, repair_budget, int(rng.integers(2**31))
        )
        dt = time.perf_counter() - t0
        new_t = t_r + np.concatenate(
            [[0.0], np.cumsum(np.linalg.norm(np.diff(new_w, axis=0), axis=1) / v)]
        )
        ok = bool(check.paths_valid(new_w[None])[0])
        events.append(RevealEvent(i, t_e, tuple(pos_e), "repair", dt, dt > latency, ok, info))
        W = np.vstack([head_w[:-1], new_w])
        T = np.concatenate([head_t[:-1], new_t])
        t_now = t_e + sample_step
    world = revealed_world(scenario)
    check = flight_validator(world, t, kinematics=False)
    b = check.batch(W[None], T[None])
    bad = tuple(k for k, v_ in check.violations(b).items() if bool(v_[0]))
    return Mission(W, T, first, tuple(events), not bad, bad, latency, r_sense)
