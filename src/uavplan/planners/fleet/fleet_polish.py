"""The CLI's repair of a fleet's plan (:func:`~uavplan.planners.fleet.fleet_plan.plan_all` with
``polish=True`` and a fleet planner; the experiments never polish, so the papers' numbers are
the planners' own). Not from any paper: the single UAV's polish and fallback
(:mod:`uavplan.planners.polish`, the fallbacks of :mod:`uavplan.strategy`) carried
over to a fleet, one UAV at a time, each against the declared flights of all the others that
pass every check as they stand (so whatever is kept stays clear of every other UAV that is
flown, before and after it in the priority order; a UAV whose flight fails and is not repaired
fails the fleet), in the plan's priority order:

1. **A UAV whose track crosses itself** (a loop on the map; in the default runs of
   ``benchmarks/default_paths.py`` one UAV of 40 in some seeds of ``dense`` and ``ppswarm2``):
   the loop is cut at the crossing, the polyline shortened by line of sight in the static world
   (:func:`~uavplan.problems.validity.greedy_shortcut`), and the result flown against the
   others (:func:`~uavplan.planners.core.flight.fly`).
2. **A UAV whose flight fails a check, or whose loop no cut removes** (``dense``: a UAV of 40
   boxed in by the flights of those before it in a narrow passage): first its own path taking
   off later (as below), then re-planned alone with RRT*
   as the single-UAV fallback runs it (informed, tightened, its step scaled to the map,
   polished), shortened (and, if the shortcut flies nowhere, as polished: its flight passed
   alone), and flown against the others at its planned take-off or, where the
   UAV may wait on the ground (it is not a constant-speed UAV), up to ``max_delays`` steps of
   ``delay_step`` seconds later, then at the first free step of ``delay_step`` before every
   other UAV has landed (where separation is the only check that reads time: batched table
   queries), and, last, after every other UAV has landed (whatever the execution model lets
   the schedules drift: no other flight is left to meet); up to :data:`RRT_TRIES` RRT* runs
   (none among moving obstacles, which RRT* cannot plan around: there the UAV is left
   unrepaired, and the fleet refused).

A new flight is kept only when it passes every check (world, the others, the kinematic limits)
and its track does not cross itself; the UAV's result then says so (``info["repaired"]``) and
the fleet's ``info["repair"]`` lists what changed. A UAV no repair helps keeps its plan, and
the fleet stays infeasible: the CLI says so and exits 1.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.planners.core.base import separated_problem
from uavplan.planners.core.flight import (
    Flight,
    candidate_flights,
    check_flights,
    declare,
    first_clear,
    flight_validator,
    fly,
    only_separation_reads_time,
)
from uavplan.planners.core.results import FleetResult, PlanResult, make_result
from uavplan.planners.polish import polished
from uavplan.problems.validity import TIME_CHECKS, greedy_shortcut
from uavplan.world.geometry import as_3d, track_crosses_itself
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.tolerances import RESERVE_TOL

FloatArray = NDArray[np.float64]

#: How many loops :func:`cut_loops` cuts at most (each cut removes at least one vertex).
MAX_CUTS = 50
#: RRT* runs (independent seeds) tried for a failing UAV: a path found in the static world may
#: fly nowhere (its smoothed curves cut a cylinder, or every take-off time meets another UAV).
#: Among the widened cylinders of a dense map about half of the rescue paths fly, so three
#: tries left one UAV in eight unrepaired; a failed try mostly costs a tenth of a second.
RRT_TRIES = 8
#: more RRT* runs for a UAV none of whose :data:`RRT_TRIES` paths flies even alone (the seeds
#: continue the same sequence, so the first tries and every UAV they repair are unchanged):
#: where the room for the flight's curves is tight, a path whose smoothing passes is found by
#: few seeds (on the 1,000-UAV PPSwarm maps under the fleet's tracking error, three of four
#: such UAVs had one among the next eight).
RRT_MORE = 8
#: take-off times checked against the reserved flights in one table query
SLOT_CHUNK = 64


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
    scenario: Scenario,
    results: list[PlanResult],
    skip: int,
    margin: float,
    dt: float,
    passing_only: bool = False,
) -> ReservationTable:
    """The reservation table of every UAV's declared flight but ``results[skip]``'s (only
    the flights that pass every check, with ``passing_only``)."""
    table = ReservationTable.for_scenario(scenario, margin, dt=dt)
    for k, r in enumerate(results):
        if k == skip or (passing_only and not r.flown_feasible):
            continue
        _reserve(table, r)
    return table


def _reserve(table: ReservationTable, r: PlanResult) -> None:
    pts, ts = r.flown_trajectory()
    table.add(r.uav_id, as_3d(pts), np.asarray(ts, dtype=np.float64), RESERVE_TOL)


def _after_all(table: ReservationTable) -> float:
    """The first whole second at which a UAV can take off and meet none of the flights in
    ``table`` whatever its own and their schedules drift within the table's execution model:
    when all of them have landed at the latest, plus the take-off error. The last resort of a
    UAV that may wait on the ground; its flight is checked like any other."""
    return float(math.floor(max(table.clear_time(), 0.0) + table.delta0) + 1.0)


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
    r0 = make_result(problem, path, algorithm=old.algorithm, history=old.history,
                     evaluations=old.evaluations, evaluations_history=old.evaluations_history,
                     wall_time=old.wall_time)  # fmt: skip
    f = fly(scenario, task, r0.waypoints, r0.times, table, opts.get("timing", "planned"),
            float(opts.get("step", 5.0)))  # fmt: skip
    return _declared(scenario, task, old, path, table, opts, f, how, problem) if f.ok else None


def _declared(
    scenario: Scenario,
    task: Task,
    old: PlanResult,
    path: FloatArray,
    table: ReservationTable,
    opts: dict[str, Any],
    flight: Flight,
    how: str,
    problem: Any = None,
) -> PlanResult:
    """``path`` as ``task``'s result against ``table``, ``flight`` declared as what it flies
    (a flight that passed every check), saying it was repaired (``how``); ``problem``: the
    separated problem of ``task`` against ``table`` when the caller has made it."""
    if problem is None:
        problem = separated_problem(scenario, task, table, opts.get("cost"), opts.get("weights"))
    r = make_result(
        problem, path, algorithm=old.algorithm, history=old.history,
        evaluations=old.evaluations, evaluations_history=old.evaluations_history,
        wall_time=old.wall_time, config=old.config, seed=old.seed,
        info={**old.info, "repaired": how},
    )  # fmt: skip
    d = declare(r, flight)
    cost = d.cost
    if not math.isfinite(cost) and set(r.violations) == {"separation"}:
        # the polyline comes closer than S2 where its flight (a curve) does not: F without F5
        cost = float(problem.evaluate_cv(r.waypoints[None])[0][0])
    return dataclasses.replace(d, cost=cost)


def _first_slot(
    scenario: Scenario,
    task: Task,
    old: PlanResult,
    path: FloatArray,
    table: ReservationTable,
    opts: dict[str, Any],
    starts: list[float],
    how: Callable[[float], str],
    flights: list[Flight] | None = None,
    fill: float | None = None,
) -> PlanResult | None:
    """``path`` flown by ``task`` taking off at the first of ``starts`` (s, ascending) where its
    flight passes every check, declared; None if at none. The flights are made and checked
    against the world and the kinematic limits once (a take-off time moves the schedule, not
    the curves); per take-off only the checks that read time run, and a flight that passes
    them is checked in full. ``how(wait)``: what the result says was done. ``flights``: the
    flights to try (at the task's take-off time; made from ``path`` when None). ``fill``
    (s): where separation is the only check that reads time, the starts between the last two
    of ``starts`` every ``fill`` seconds too (each start of a chunk of :data:`SLOT_CHUNK` is
    one path of one table query), so the first free slot before the last start is found."""
    if track_crosses_itself(path) or not starts:
        return None
    first = dataclasses.replace(task, start_time=starts[0])
    world = flight_validator(scenario, first, None)
    short = flight_validator(scenario, first, None, kinematics=False)
    r0 = make_result(
        separated_problem(scenario, first, None, opts.get("cost"), opts.get("weights")), path,
        algorithm=old.algorithm, history=old.history, evaluations=old.evaluations,
        evaluations_history=old.evaluations_history, wall_time=old.wall_time,
    )  # fmt: skip
    if flights is None:
        timing = "constant" if scenario.moving_obstacles else str(opts.get("timing", "planned"))
        made = candidate_flights(scenario, r0.waypoints, r0.times, timing,
                                 float(opts.get("step", 5.0)), shortcut=short)  # fmt: skip
        if not made:
            made = [Flight(r0.waypoints, r0.times, "polyline", "polyline", ())]
    else:  # flights given at the task's take-off: at the first of starts
        made = [dataclasses.replace(f, times=f.times + starts[0] - task.start_time)
                for f in flights]  # fmt: skip
    flights = sorted((f for f in check_flights(world, made) if f.ok), key=lambda f: f.length)
    if fill is not None and len(starts) > 1 and only_separation_reads_time(scenario, first, table):
        # every step between the last of the delays and the take-off after all have landed:
        # each is one path of a batched table query, and a UAV waits only as long as it must
        more = np.arange(starts[-2] + fill, starts[-1], fill)
        starts = [*starts[:-1], *(float(x) for x in more), starts[-1]]
    found = first_clear(
        scenario,
        table,
        flights,
        [x - starts[0] for x in starts],
        lambda i: dataclasses.replace(task, start_time=starts[i]),
        SLOT_CHUNK,
    )
    if found is None:
        return None
    i, _, later, flight = found
    return _declared(scenario, later, old, path, table, opts, flight,
                     how(starts[i] - task.start_time))  # fmt: skip


def _rrt_path(scenario: Scenario, task: Task, seed: int) -> FloatArray | None:
    """The task's path alone in the world: RRT* as the single-UAV fallback runs it, polished
    as the CLI polishes a single UAV's path; None when it finds none that flies."""
    from uavplan.planners import get_planner
    from uavplan.planners.sampling.rrt_star import map_scaled_options

    planner = get_planner("rrt-star", **map_scaled_options(scenario))
    res = planner.plan(scenario, task, seed=seed, polish=polished)
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
    margin = float(cfg.get("separation_margin") or 0.0)
    dt = float(cfg.get("dt") or 1.0)
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
    unrepaired: dict[str, str] = {}  # what was tried for each UAV no repair helped
    # a failing UAV is repaired against the flights that pass (a failing one is replaced, or
    # the fleet fails anyway): one table for all of them, each repaired flight added to it
    passing: ReservationTable | None = None
    for uid in order:
        k = index[uid]
        r = results[k]
        loops = track_crosses_itself(r.waypoints)
        if r.flown_feasible and not loops:
            continue
        if r.flown_feasible:  # a looping UAV that passes: every other flight but its own
            table = _others_table(scenario, results, k, margin, dt)
        else:
            if passing is None:
                passing = _others_table(scenario, results, k, margin, dt, passing_only=True)
            table = passing
        static = flight_validator(scenario, tasks[uid], None, kinematics=False)
        task = dataclasses.replace(tasks[uid], start_time=float(r.times[0]))
        base = tasks[uid].start_time
        starts = [base + w * delay_step for w in range(delays + 1)]
        last = _after_all(table)
        if delays and last > starts[-1]:
            starts.append(last)

        def how(what: str, wait: float, last: float = last - base) -> str:
            later = f", taking off {wait:g} s later" if wait else ""
            after = ", after every other UAV has landed" if wait == last else ""
            return f"{what}{later}{after}"

        new: PlanResult | None = None
        tried: list[str] = []  # what was tried, for a UAV left unrepaired
        if loops:
            cut, _, _ = greedy_shortcut(static, cut_loops(r.waypoints))
            new = _try(scenario, task, r, cut, table, opts, "loop cut")
            tried.append("the loop cut")
        elif not r.flown_feasible and len(starts) > 1:  # its own flight, later (no search)
            tried.append(f"its own path at {len(starts) - 1} later take-offs: none flies")
            own = None
            if r.flown is not None and set(r.flown_violations) <= TIME_CHECKS:
                own = [Flight(np.asarray(r.flown), np.asarray(r.flown_times) - r.times[0]
                              + tasks[uid].start_time, r.flown_kind, "declared", ())]  # fmt: skip
            new = _first_slot(scenario, tasks[uid], r, r.waypoints, table, opts, starts[1:],
                              functools.partial(how, "its own path"), own,
                              fill=delay_step)  # fmt: skip
        alone = 0  # RRT* tries whose path flies nowhere, even alone
        tries = 0
        searches = rngs[k].spawn(RRT_TRIES + RRT_MORE) if new is None else ()
        if new is None and scenario.moving_obstacles:  # RRT*'s graph has no time
            searches = ()
            tried.append("no RRT* path: it cannot plan around moving obstacles")
        for a, ss in enumerate(searches):
            if a == RRT_TRIES and alone < RRT_TRIES:
                break  # some path flew alone: its take-offs were tried, and none flies
            tries += 1
            found = _rrt_path(scenario, tasks[uid], int(ss.generate_state(1)[0]))
            if found is None:
                alone += 1
                continue
            short, _, _ = greedy_shortcut(static, found)
            # the shortcut first; then the path as RRT*'s polish left it, whose flight passed
            # (a shortcut's curves can take a flight where its polyline does not go: over a
            # ceiling that falls steeply beside a vertex)
            paths = [short] if np.array_equal(short, found) else [short, found]
            for path in paths:
                new = _first_slot(scenario, tasks[uid], r, path, table, opts, starts,
                                  functools.partial(how, f"RRT* (try {a + 1})"),
                                  fill=delay_step)  # fmt: skip
                if new is not None:
                    break
            if new is not None:
                break
        if new is None and not r.flown_feasible:
            if alone < tries:
                tried.append(f"{tries - alone} RRT* path(s): none flies at any take-off tried")
            if alone:
                tried.append(f"{alone} RRT* tries: no path whose flight passes even alone")
            unrepaired[uid] = "; ".join(tried)
        if new is not None:
            results[k] = new
            repaired[uid] = str(new.info["repaired"])
            if table is passing:
                _reserve(passing, new)
            else:  # a passing flight changed: the shared table is rebuilt when next needed
                passing = None
    spent = time.perf_counter() - t0  # the user waits for it: it is planning time
    info = {**fleet.info, "repair": repaired, "repair_time": spent}
    if unrepaired:
        info["unrepaired"] = unrepaired
    if not repaired:
        return dataclasses.replace(fleet, wall_time=fleet.wall_time + spent, info=info)
    out = tuple(results)
    flown = all(r.flown_feasible for r in out)
    total = float(sum(r.cost for r in out))
    return dataclasses.replace(
        fleet,
        results=out,
        cost=total if flown and math.isfinite(total) else math.inf,
        flown_feasible=flown,
        planned_feasible=all(r.feasible for r in out),
        wall_time=fleet.wall_time + spent,
        info=info,
    )
