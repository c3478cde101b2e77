"""One planning run: the :class:`Termination` (iterations, evaluations, wall time, the callback),
the :class:`Tracker` a planner records into, the :class:`Run` its ``_plan`` gets and the
:class:`Outcome` it may return."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.compile_clock import Stopwatch
from uavplan.optimizers.base import Budget
from uavplan.problems.path_problem import PathProblem
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]

#: Progress callback: (iteration, best cost so far) -> True to stop early.
ProgressCallback = Callable[[int, float], bool | None]


@dataclass
class Termination:
    """When a run stops (OMPL's ``PlannerTerminationCondition``): any limit reached, or the
    callback asking to stop. ``max_iterations`` None: no iteration limit. ``max_time`` counts
    planning time as results report it: ``clock``'s wall seconds less kernel compilation."""

    max_iterations: int | None
    max_evaluations: int | None = None
    max_time: float | None = None
    callback: ProgressCallback | None = None
    clock: Stopwatch = field(default_factory=Stopwatch)

    def reached(self, iterations: int, evaluations: int, best: float) -> bool:
        """Called once per iteration; the callback is always called first."""
        stop = bool(self.callback(iterations, best)) if self.callback is not None else False
        if self.max_iterations is not None and iterations >= self.max_iterations:
            stop = True
        if self.max_evaluations is not None and evaluations >= self.max_evaluations:
            stop = True
        if self.max_time is not None and self.clock.elapsed >= self.max_time:
            stop = True
        return stop


class Tracker:
    """What a run records: evaluations, the incumbent (the best path offered, a feasible one
    before any infeasible one, then the lowest cost), and per iteration the best cost so far,
    the best feasible cost so far (when tracked) and the evaluations used."""

    def __init__(self, termination: Termination, track_feasibility: bool = True) -> None:
        self.termination = termination
        self.track_feasibility = track_feasibility
        self.evaluations = 0
        self.history: list[float] = []
        self.feasible_history: list[float] = []
        self.evaluations_history: list[int] = []
        self.path: FloatArray | None = None
        self.cost = math.inf
        self.feasible = False

    def offer(self, path: FloatArray, cost: float, feasible: bool) -> bool:
        """A candidate result; kept if it beats the incumbent (feasible first, then cost)."""
        if (feasible, -cost) > (self.feasible, -self.cost):
            self.path, self.cost, self.feasible = np.asarray(path), float(cost), bool(feasible)
            return True
        return False

    def end_iteration(self, best: float | None = None, feasible_best: float | None = None) -> bool:
        """Close an iteration: record ``best`` (default: the incumbent's cost) and
        ``feasible_best`` (default: the incumbent's cost if it is feasible) as running minima,
        and the evaluations; True when the run must stop."""
        b = self.cost if best is None else float(best)
        self.history.append(min(self.history[-1], b) if self.history else b)
        if self.track_feasibility:
            if feasible_best is None:
                feasible_best = self.cost if self.feasible else math.inf
            prev = self.feasible_history[-1] if self.feasible_history else math.inf
            self.feasible_history.append(min(prev, float(feasible_best)))
        self.evaluations_history.append(self.evaluations)
        return self.termination.reached(len(self.history), self.evaluations, self.history[-1])

    def end_iterations(self, k: int) -> bool:
        """Close ``k`` iterations in which the incumbent did not change, asking the termination
        once, after the last (for planners that run iterations in compiled batches that stop
        at their iteration limit; a run with a callback or an evaluation limit closes one at a
        time, so that the callback sees every iteration). True when the run must stop."""
        if k <= 0:
            return False
        b = self.cost
        self.history.extend([min(self.history[-1], b) if self.history else b] * k)
        if self.track_feasibility:
            fb = self.cost if self.feasible else math.inf
            prev = self.feasible_history[-1] if self.feasible_history else math.inf
            self.feasible_history.extend([min(prev, fb)] * k)
        self.evaluations_history.extend([self.evaluations] * k)
        return self.termination.reached(len(self.history), self.evaluations, self.history[-1])

    def amend(self, best: float, feasible_best: float) -> None:
        """Fold a result found after the last iteration closed into that iteration's record."""
        self.history[-1] = min(self.history[-1], float(best))
        if self.track_feasibility:
            self.feasible_history[-1] = min(self.feasible_history[-1], float(feasible_best))
        self.evaluations_history[-1] = self.evaluations


@dataclass
class Run:
    """Everything ``_plan`` works with: the scenario, the task, its problem, the seed, the
    budget, the resolved iteration limit, the termination and the tracker."""

    scenario: Scenario
    task: Task
    problem: PathProblem
    seed: int | None
    budget: Budget
    max_iterations: int | None
    tracker: Tracker
    #: other UAVs' flights the run keeps clear of (planners with ``supports_reservations``)
    reservations: ReservationTable | None = None

    @property
    def termination(self) -> Termination:
        return self.tracker.termination


@dataclass(frozen=True)
class Outcome:
    """What ``_plan`` may return instead of a bare path: the path (None: the tracker's
    incumbent, or the straight start-goal segment if there is none), ``reasons`` that make it
    infeasible (``"no_path"``...), and ``info`` (planner figures for :attr:`PlanResult.info`)."""

    path: FloatArray | None = None
    reasons: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)
