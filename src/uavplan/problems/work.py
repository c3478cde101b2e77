"""The work a run did, counted where it is done: the paths whose cost a :class:`PathProblem`
computed, and the paths and timed segments a :class:`MotionValidator` checked, as pymoo's
``Evaluator`` counts the evaluations it makes and OMPL's ``SpaceInformation`` the motions its
validity checker is asked about.

The cost functions and the validators add to the counter of the innermost :func:`counting`
block in progress (a context variable: per thread, and a block opened inside another adds its
totals to the outer one when it closes); outside any block nothing is counted. Compiled loops
that check segments without going through a validator's Python entry points (RRT*'s tree
growth and tightening, PPSwarm's fused fleet cost) report what they did with :func:`add`.

This is work, not a budget. A planner's ``evaluations`` keeps its paper's unit, the one its
budget and histories count (a swarm's particles per iteration, an RRT*'s segment checks, an
APF subgoal vector flown once); the counters here also see what the paper's unit leaves out
(SPSO's re-evaluations, the validations of a found path, the checks of a polish), and they
count every planner alike. :meth:`uavplan.planners.core.base.Planner.plan` puts a run's counts
in ``PlanResult.info["work"]``.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import asdict, dataclass


@dataclass
class Work:
    """Counts of one run: ``cost_paths`` paths whose cost terms were computed,
    ``checked_paths`` paths (a segment checked alone is a path of two points) presented to a
    motion validator's checks, and ``checked_segments`` of their segments."""

    cost_paths: int = 0
    checked_paths: int = 0
    checked_segments: int = 0

    def add(self, other: Work) -> None:
        self.cost_paths += other.cost_paths
        self.checked_paths += other.checked_paths
        self.checked_segments += other.checked_segments

    def record(self) -> dict[str, int]:
        return {k: int(v) for k, v in asdict(self).items()}


_CURRENT: ContextVar[Work | None] = ContextVar("uavplan_work", default=None)


@contextmanager
def counting() -> Iterator[Work]:
    """Count the work done inside the block; on leaving, the totals are added to the
    enclosing block's counter, if any."""
    work = Work()
    token = _CURRENT.set(work)
    try:
        yield work
    finally:
        _CURRENT.reset(token)
        outer = _CURRENT.get()
        if outer is not None:
            outer.add(work)


def add(cost_paths: int = 0, checked_paths: int = 0, checked_segments: int = 0) -> None:
    """Add to the counter of the block in progress (nothing outside one)."""
    work = _CURRENT.get()
    if work is not None:
        work.cost_paths += int(cost_paths)
        work.checked_paths += int(checked_paths)
        work.checked_segments += int(checked_segments)


def checked(pop: int, n_points: int) -> None:
    """``pop`` paths of ``n_points`` points each presented to the checks."""
    work = _CURRENT.get()
    if work is not None and pop:
        work.checked_paths += int(pop)
        work.checked_segments += int(pop) * max(int(n_points) - 1, 0)
