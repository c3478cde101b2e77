"""The CLI's repair of a fleet's plan (:func:`~uavplan.planners.fleet_plan.plan_all` with
``polish=True`` and a fleet planner; the experiments never polish, so the papers' numbers are
the planners' own). Not from any paper: the single UAV's polish and fallback
(:mod:`uavplan.planners.polish`, :func:`~uavplan.planners.defaults.fallback_planners`) carried
over to a fleet, one UAV at a time, each against the declared flights of **all** the others as
they stand (so whatever is kept stays clear of every other UAV, before and after it in the
priority order), in the plan's priority order:

1. **A UAV whose track crosses itself** (a loop on the map; in the default runs of
   ``benchmarks/default_paths.py`` one UAV of 40 in some seeds of ``dense`` and ``ppswarm2``):
   the loop is cut at the crossing, the polyline shortened by line of sight in the static world
   (:func:`~uavplan.problems.validity.greedy_shortcut`), and the result flown against the
   others (:func:`~uavplan.planners.flight.fly`).
2. **A UAV whose flight fails a check, or whose loop no cut removes** (``dense``: a UAV of 40
   boxed in by the flights of those before it in a narrow passage): re-planned alone with RRT*
   as the single-UAV fallback runs it (informed, tightened, its step scaled to the map,
   polished), shortened, and flown against the others at its planned take-off or, where the
   UAV may wait on the ground (it is not a constant-speed UAV), up to ``max_delays`` steps of
   ``delay_step`` seconds later; up to :data:`RRT_TRIES` RRT* runs.

A new flight is kept only when it passes every check (world, the others, the kinematic limits)
and its track does not cross itself; the UAV's result then says so (``info["repaired"]``) and
the fleet's ``info["repair"]`` lists what changed. A UAV no repair helps keeps its plan, and
the fleet stays infeasible: the CLI says so and exits 1.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.planners.base import separated_problem
from uavplan.planners.flight import declare, flight_validator, fly
from uavplan.planners.results import FleetResult, PlanResult, make_result
from uavplan.problems.validity import greedy_shortcut
from uavplan.world.geometry import track_crosses_itself
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.tolerances import RESERVE_TOL

FloatArray = NDArray[np.float64]

#: How many loops :func:`cut_loops` cuts at most (each cut removes at least one vertex).
MAX_CUTS = 50
#: RRT* runs (independent seeds) tried for a failing UAV: a path found in the static world may
#: fly nowhere (its smoothed curves cut a cylinder, or every take-off time meets another UAV).
RRT_TRIES = 3


def first_crossing(points: FloatArray) -> tuple[int, int, FloatArray] | None:
    """The first pair of non-adjacent segments ``i < j`` of a path whose horizontal tracks
    properly cross (as :func:`~uavplan.world.geometry.track_crosses_itself` counts them), and
    the crossing point on segment ``i`` (its height interpolated along segment ``i``)."""
    P = np.asarray(points, dtype=np.float64)
    n = len(P) - 1
    for i in range(n):
        a, b = P[i, :2], P[i + 1, :2]
        for j in range(i + 2, n):
            c, d = P[j, :2], P[j + 1, :2]
            r, s = b - a, d - c
            den = r[0] * s[1] - r[1] * s[0]
            if den == 0.0:
                continue
            q = c - a
            u = (q[0] * s[1] - q[1] * s[0]) / den  # along i
            v = (q[0] * r[1] - q[1] * r[0]) / den  # along j
            if 0.0 < u < 1.0 and 0.0 < v < 1.0:
                return i, j, P[i] + u * (P[i + 1] - P[i])
    return None


def cut_loops(points: FloatArray) -> FloatArray:
    """The path with every loop of its horizontal track cut out: where segments ``i < j``
    cross, the vertices between them are dropped and the crossing point joins the two."""
    P = np.array(points, dtype=np.float64)
    for _ in range(MAX_CUTS):
        hit = first_crossing(P)
        if hit is None:
            break
        i, j, x = hit
        P = np.vstack([P[: i + 1], x[None], P[j + 1 :]])
    return P


def _others_table(
    scenario: Scenario, results: list[PlanResult], skip: int, margin: float, dt: float
) -> ReservationTable:
    """The reservation table of every UAV's declared flight but ``results[skip]``'s."""
    table = ReservationTable.for_uav(scenario.bounds.lo, scenario.bounds.hi, scenario.uav,
                                     margin, dt=dt)  # fmt: skip
    for k, r in enumerate(results):
        if k == skip:
            continue
        pts, ts = r.flown_trajectory()
        p = np.asarray(pts, dtype=np.float64)
        if p.shape[1] == 2:
            p = np.column_stack([p, np.zeros(len(p))])
        table.add(r.uav_id, p, np.asarray(ts, dtype=np.float64), RESERVE_TOL)
    return table


def _try(
    scenario: Scenario,
    task: Task,
    old: PlanResult,
    path: FloatArray,
    table: ReservationTable,
    opts: dict[str, Any],
    how: str,
) -> PlanResult | None:
    """``path`` flown by ``task`` (its take-off time) against ``table``: the declared result if
    its flight passes every check and its track does not cross itself, else None."""
    if track_crosses_itself(path):
        return None
    problem = separated_problem(scenario, task, table, opts.get("cost"), opts.get("weights"))
    r = make_result(
        problem, path, algorithm=old.algorithm, history=old.history,
        evaluations=old.evaluations, evaluations_history=old.evaluations_history,
        wall_time=old.wall_time, config=old.config, seed=old.seed,
        info={**old.info, "repaired": how},
    )  # fmt: skip
    f = fly(scenario, task, r.waypoints, r.times, table, opts.get("timing", "planned"),
            float(opts.get("step", 5.0)))  # fmt: skip
    if not f.ok:
        return None
    d = declare(r, f)
    cost = d.cost
    if not math.isfinite(cost) and set(r.violations) == {"separation"}:
        # the polyline comes closer than S2 where its flight (a curve) does not: F without F5
        cost = float(problem.evaluate_cv(r.waypoints[None])[0][0])
    return dataclasses.replace(d, cost=cost)


def _rrt_path(scenario: Scenario, task: Task, seed: int) -> FloatArray | None:
    """The task's path alone in the world: RRT* as the single-UAV fallback runs it, polished
    as the CLI polishes a single UAV's path; None when it finds none that flies."""
    from uavplan.planners import get_planner
    from uavplan.planners.defaults import fallback_rrt_options

    planner = get_planner("rrt-star", **fallback_rrt_options(scenario))
    res = planner.plan(scenario, task, seed=seed, polish=True)
    return np.asarray(res.waypoints, dtype=np.float64) if res.flown_feasible else None


def polish_fleet(
    scenario: Scenario,
    fleet: FleetResult,
    seed: int | None,
    config: dict[str, Any] | None = None,
) -> FleetResult:
    """``fleet`` with its looping and failing UAVs repaired where a repair flies (module
    docstring). ``config``: the planner's (``separation_margin``, ``dt``, ``max_delays``,
    ``delay_step``, ``cost``, ``weights``, ``smooth_timing``, ``smooth_step``; defaults
    otherwise). Deterministic for a ``seed`` (RRT*'s draws come from it)."""
    t0 = time.perf_counter()
    cfg = dict(config or {})
    results = list(fleet.results)
    if not results or any(r.flown is None for r in results):
        return fleet  # nothing declared to fly: nothing this pass can check
    margin, dt = float(cfg.get("separation_margin", 0.0)), float(cfg.get("dt", 1.0))
    uav = scenario.uav
    may_wait = not (uav.min_speed > 0 and uav.min_speed >= uav.v_max)
    delays = int(cfg.get("max_delays", 24)) if may_wait else 0
    delay_step = float(cfg.get("delay_step", 5.0))
    opts = {"cost": cfg.get("cost"), "weights": cfg.get("weights"),
            "timing": cfg.get("smooth_timing", "planned"),
            "step": cfg.get("smooth_step", 5.0)}  # fmt: skip
    tasks = {t.id: t for t in scenario.tasks}
    index = {r.uav_id: k for k, r in enumerate(results)}
    order = [u for u in fleet.priority if u in index] or list(index)
    rngs = np.random.SeedSequence(seed).spawn(len(results))
    repaired: dict[str, str] = {}
    for uid in order:
        k = index[uid]
        r = results[k]
        loops = track_crosses_itself(r.waypoints)
        if r.flown_feasible and not loops:
            continue
        table = _others_table(scenario, results, k, margin, dt)
        static = flight_validator(scenario, tasks[uid], None, kinematics=False)
        task = dataclasses.replace(tasks[uid], start_time=float(r.times[0]))
        new: PlanResult | None = None
        if loops:
            cut, _, _ = greedy_shortcut(static, cut_loops(r.waypoints))
            new = _try(scenario, task, r, cut, table, opts, "loop cut")
        for a, ss in enumerate(rngs[k].spawn(RRT_TRIES) if new is None else ()):
            path = _rrt_path(scenario, tasks[uid], int(ss.generate_state(1)[0]))
            if path is None:
                continue
            path, _, _ = greedy_shortcut(static, path)
            base = tasks[uid].start_time
            for w in range(delays + 1):
                later = dataclasses.replace(tasks[uid], start_time=base + w * delay_step)
                how = f"RRT* (try {a + 1})" + (
                    f", taking off {w * delay_step:g} s later" if w else ""
                )
                new = _try(scenario, later, r, path, table, opts, how)
                if new is not None:
                    break
            if new is not None:
                break
        if new is not None:
            results[k] = new
            repaired[uid] = str(new.info["repaired"])
    spent = time.perf_counter() - t0  # the user waits for it: it is planning time
    info = {**fleet.info, "repair": repaired, "repair_time": spent}
    if not repaired:
        return dataclasses.replace(fleet, wall_time=fleet.wall_time + spent, info=info)
    out = tuple(results)
    feasible = all(r.flown_feasible for r in out)
    total = float(sum(r.cost for r in out))
    return dataclasses.replace(
        fleet,
        results=out,
        cost=total if feasible and math.isfinite(total) else math.inf,
        feasible=feasible,
        planned_feasible=all(r.feasible for r in out),
        wall_time=fleet.wall_time + spent,
        info=info,
    )
