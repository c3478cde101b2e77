"""What planners return: :class:`PlanResult` per UAV, :class:`FleetResult` per fleet, and
:func:`make_result`, the one place a PlanResult is assembled (one fresh evaluation of the path)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems.path_problem import PathProblem

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PlanResult:
    """One UAV's planned path and how it was found.

    Attributes:
        uav_id: the task id.
        waypoints: (n, dim) metres, start and goal included.
        times: (n,) seconds at the UAV's speed from the task's start time.
        cost: total cost under the planner's cost model; terms: each term's raw value.
        feasible: decided on continuous segments by the motion validator.
        evaluations, iterations, wall_time (s), history: best-so-far cost per iteration.
        algorithm, config, seed, cost_model: what produced it.
        violations: the checks the path fails (and planner reasons such as ``no_path``).
        feasible_history: best cost among feasible candidates so far, per iteration (inf
            before the first feasible one); empty when the planner did not track it.
        evaluations_history: evaluations used after each iteration (for plots against
            evaluations, the fair axis between algorithms).
        first_feasible_iteration: the 1-based iteration in which a feasible candidate was first
            evaluated (RGG-PSO+'s F-Measure counts the iterations before it), None if never or
            not tracked.
        info: planner-specific figures of the run (edge checks, tree size, merge kind, ...).
        smoothed, smoothed_times, smoothed_ok, smoothed_violations: a flyable version of
            ``waypoints`` (Dubins-smoothed dense polyline (m, dim) and its times (m,)), whether
            it keeps every clearance and what it breaks (None: not smoothed).
        flown, flown_times, flown_kind, flown_ok, flown_violations: the trajectory the UAV is
            to fly and that the plan guarantees (``"smoothed"`` or ``"polyline"``), whether it
            passes every check, kinematic limits included, and what it breaks (None: not
            declared; the planned polyline is then what is flown).
    """

    uav_id: str
    waypoints: FloatArray
    times: FloatArray
    cost: float
    terms: dict[str, float]
    feasible: bool
    evaluations: int
    iterations: int
    wall_time: float
    history: FloatArray
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    cost_model: str = ""
    violations: tuple[str, ...] = ()
    feasible_history: FloatArray = field(default_factory=lambda: np.zeros(0))
    first_feasible_iteration: int | None = None
    evaluations_history: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64)
    )
    info: dict[str, Any] = field(default_factory=dict)
    smoothed: FloatArray | None = None
    smoothed_times: FloatArray | None = None
    smoothed_ok: bool | None = None
    smoothed_violations: tuple[str, ...] = ()
    flown: FloatArray | None = None
    flown_times: FloatArray | None = None
    flown_kind: str = "polyline"
    flown_ok: bool | None = None
    flown_violations: tuple[str, ...] = ()

    def flown_trajectory(self) -> tuple[FloatArray, FloatArray]:
        """The trajectory this UAV is to fly, points (m, dim) and times (m,): :attr:`flown`
        when declared, else the planned polyline."""
        if self.flown is None or self.flown_times is None:
            return self.waypoints, self.times
        return self.flown, self.flown_times

    @property
    def flown_feasible(self) -> bool:
        """What the plan guarantees of the flown trajectory (the polyline's verdict until a
        flight is declared)."""
        return self.feasible if self.flown_ok is None else bool(self.flown_ok)

    @property
    def length(self) -> float:
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))


@dataclass(frozen=True)
class FleetResult:
    """A whole fleet's plan from a :class:`FleetPlanner`.

    Attributes:
        results: one :class:`PlanResult` per task, in the scenario's task order.
        priority: task ids in the order they were planned in the kept solution.
        cost: total cost (sum of the UAVs' costs; inf where what the planner guarantees fails).
        flown_feasible: every UAV's flown trajectory passes every check: the world, the
            separation from every other UAV's flown trajectory, the kinematic limits (the
            plan's guarantee; :attr:`PlanResult.flown_feasible` of each UAV). ``feasible``
            always means a polyline's verdict (:attr:`PlanResult.feasible`), ``flown_``
            a flight's.
        planned_feasible: every UAV's planned polyline is feasible, separation included from
            what the UAVs planned before it reserved (``info["separated"]``: their polylines in
            PPSwarm's mode, its criterion; their flights where flights are planned in the loop,
            and then two polylines may come closer than S2: only the flights are kept apart).
        history: the fleet's cost per low-level iteration (see the planner's docs).
        restart_costs: the fleet cost after each restart.
        wall_time: seconds; info: planner-specific figures (timings, smoothing report).
    """

    results: tuple[PlanResult, ...]
    priority: tuple[str, ...]
    cost: float
    flown_feasible: bool
    planned_feasible: bool
    history: FloatArray
    restart_costs: FloatArray
    wall_time: float
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    info: dict[str, Any] = field(default_factory=dict)


def first_finite(history: Sequence[float] | FloatArray) -> int | None:
    """1-based index of the first finite entry, or None."""
    finite = np.flatnonzero(np.isfinite(np.asarray(history, dtype=np.float64)))
    return int(finite[0]) + 1 if len(finite) else None


def make_result(
    problem: PathProblem,
    path: FloatArray,
    *,
    algorithm: str,
    history: Sequence[float] | FloatArray,
    evaluations: int,
    evaluations_history: Sequence[int] | NDArray[np.int64],
    wall_time: float,
    feasible_history: Sequence[float] | FloatArray = (),
    config: dict[str, Any] | None = None,
    seed: int | None = None,
    reasons: tuple[str, ...] = (),
    info: dict[str, Any] | None = None,
) -> PlanResult:
    """The :class:`PlanResult` of ``path`` (n, dim): evaluated once on ``problem`` (cost, terms,
    feasibility, violations), timed at the UAV's speed; ``reasons`` (e.g. ``"no_path"``) make
    it infeasible and join its violations. Every planner's result is assembled here."""
    p = np.asarray(path, dtype=np.float64)
    ev = problem.evaluate(p[None])
    fh = np.asarray(feasible_history, dtype=np.float64)
    return PlanResult(
        uav_id=problem.task.id,
        waypoints=p,
        times=problem.times(p[None])[0],
        cost=float(ev.cost[0]),
        terms={k: float(v[0]) for k, v in ev.terms.items()},
        feasible=bool(ev.feasible[0]) and not reasons,
        evaluations=int(evaluations),
        iterations=len(history),
        wall_time=float(wall_time),
        history=np.asarray(history, dtype=np.float64),
        algorithm=algorithm,
        config=dict(config or {}),
        seed=seed,
        cost_model=problem.cost_name,
        violations=tuple(k for k, v in ev.violations.items() if v[0]) + tuple(reasons),
        feasible_history=fh,
        first_feasible_iteration=first_finite(fh),
        evaluations_history=np.asarray(evaluations_history, dtype=np.int64),
        info=dict(info or {}),
    )
