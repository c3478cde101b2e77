"""The CLI's polish of a single UAV's found polyline (``Planner.plan(polish=polished)``; the
experiments never polish, so the papers' numbers are the optimizers' own). Not from any paper:
cheap post-processing that planning tools commonly apply, each step judged by the
straight-segment validator of the UAV's flight (the altitude band along whole segments,
:func:`~uavplan.planners.core.flight.flight_validator`) and by the planner's own problem:

1. **terrain following** when that validator rejects the path
   (:func:`~uavplan.problems.validity.band_repair`: points moved or added vertically until
   every segment holds the band; the horizontal track unchanged);
2. **shortcuts** by line of sight (:func:`~uavplan.problems.validity.greedy_shortcut`);
3. **tightening** (:func:`tighten`): each interior vertex pulled towards the midpoint of its
   neighbours while the problem's cost falls and both its segments stay valid (a discrete
   string pulling), then shortcuts again (a pulled-straight vertex drops out);
4. **climb limits** when a segment climbs or descends more steeply than the UAV may
   (:func:`~uavplan.problems.validity.limit_climb`: interior heights moved the least a greedy
   pass can, the track unchanged; kept when every segment stays valid). A sampling planner's
   edges and a shortcut's know nothing of the climb angle (RRT* can join a vertex 15 m from
   the start to it at 40 degrees), and no smoothing of the corners flies such a segment.

The result is kept when the problem finds it feasible, it is no less flyable than the found
path, and it costs no more unless it flies where the found path did not. The flight is checked
again after this (:func:`~uavplan.planners.core.flight.fly`), so the verdict stays the flight's.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.planners.core.flight import flight_validator
from uavplan.problems.path_problem import PathProblem
from uavplan.problems.validity import (
    MotionValidator,
    band_repair,
    climb_violations,
    greedy_shortcut,
    limit_climb,
)
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]

#: :func:`tighten`: the shares of the way to the neighbours' midpoint tried per vertex move.
PULL = (1.0, 0.5, 0.25)
#: :func:`tighten`: sweeps over the vertices at most, and the longest path it works on (each
#: sweep costs a cost evaluation per vertex in Python, where RRT*'s elastic band, a Numba
#: kernel that checks clearance only, sweeps up to ``rrt_star.BAND_SWEEPS`` times).
POLISH_SWEEPS, POLISH_MAX_POINTS = 40, 200


def tighten(
    problem: PathProblem,
    validator: MotionValidator,
    path: FloatArray,
    rounds: int = POLISH_SWEEPS,
) -> FloatArray:
    """Pull each interior vertex of ``path`` towards the midpoint of its two neighbours (by the
    shares :data:`PULL`, in one batch per vertex), keeping the move that lowers the problem's
    cost the most among those whose two segments ``validator`` accepts and that the problem
    finds feasible; sweep until no vertex moves or ``rounds`` sweeps. Start and goal are kept;
    the cost never rises (only strictly lower costs are taken)."""
    P = np.array(path, dtype=np.float64)
    if len(P) < 3 or len(P) > POLISH_MAX_POINTS:
        return P
    ev = problem.evaluate(P[None])
    best = float(ev.cost[0]) if bool(ev.feasible[0]) else np.inf
    if not np.isfinite(best):
        return P
    share = np.asarray(PULL)[:, None]
    for _ in range(rounds):
        moved = False
        for i in range(1, len(P) - 1):
            cand = np.repeat(P[None], len(PULL), axis=0)
            cand[:, i] = P[i] + share * (0.5 * (P[i - 1] + P[i + 1]) - P[i])
            a = np.concatenate([np.broadcast_to(P[i - 1], cand[:, i].shape), cand[:, i]])
            b = np.concatenate([cand[:, i], np.broadcast_to(P[i + 1], cand[:, i].shape)])
            ok = validator.segments_valid(a, b).reshape(2, -1).all(axis=0)
            if not ok.any():
                continue
            e = problem.evaluate(cand[ok])
            cost = np.where(e.feasible, e.cost, np.inf)
            k = int(np.argmin(cost))
            if cost[k] < best - 1e-12 * max(1.0, abs(best)):
                P, best, moved = cand[ok][k], float(cost[k]), True
        if not moved:
            break
    return P


def polished(
    scenario: Scenario, task: Task, problem: PathProblem, path: FloatArray
) -> tuple[FloatArray, dict[str, Any]]:
    """``path`` polished (see the module docstring) and a note of what changed (``points``
    before and after, ``cost`` before and after, ``steps``), or ``path`` itself and ``{}``."""
    v = flight_validator(scenario, task, kinematics=False)
    flies = bool(v.paths_valid(path[None])[0])
    cand, steps = path, []
    if not flies:
        repaired = band_repair(v, path)
        if repaired is not None:
            cand, steps = repaired, ["terrain following"]
    short, _, _ = greedy_shortcut(v, cand)
    if len(short) < len(cand):
        cand, steps = short, [*steps, "shortcut"]
    if bool(v.paths_valid(cand[None])[0]):
        tight = tighten(problem, v, cand)
        if not np.array_equal(tight, cand):
            cand, steps = greedy_shortcut(v, tight)[0], [*steps, "tightening"]
    cand_valid = bool(v.paths_valid(cand[None])[0])
    steep = _steep(scenario, cand)
    if steep and cand_valid:
        eased = _eased(scenario, cand)
        if eased is not None and bool(v.paths_valid(eased[None])[0]):
            cand, steps, steep = eased, [*steps, "climb limits"], False
    if not steps:
        return path, {}
    before, after = problem.evaluate(path[None]), problem.evaluate(cand[None])
    c0, c1 = float(before.cost[0]), float(after.cost[0])
    cand_flies = cand_valid and not steep
    flies = flies and not _steep(scenario, path)
    if not bool(after.feasible[0]) or (flies and not cand_flies):
        return path, {}
    if bool(before.feasible[0]) and c1 > c0 and (flies or not cand_flies):
        return path, {}  # a higher cost only buys a path that flies where ``path`` did not
    return cand, {"points": [len(path), len(cand)], "cost": [c0, c1], "steps": steps}


def _steep(scenario: Scenario, path: FloatArray) -> bool:
    """Whether a segment of ``path`` climbs or descends more steeply than the UAV may."""
    uav = scenario.uav
    if scenario.dim != 3 or (uav.max_climb_angle is None and uav.max_descent_angle is None):
        return False
    return bool(climb_violations(path[None], uav.max_climb_angle, uav.max_descent_angle)[0])


def _eased(scenario: Scenario, path: FloatArray) -> FloatArray | None:
    """``path`` within the UAV's climb and descent limits (:func:`limit_climb`), or None."""
    uav = scenario.uav
    return limit_climb(path, uav.max_climb_angle, uav.max_descent_angle)
