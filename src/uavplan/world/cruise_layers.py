"""Cruise altitude layers by heading: aviation's semicircular rule for a fleet of UAVs.

Aircraft flying under instrument rules cruise at levels chosen by their track (ICAO Annex 2,
Appendix 3, tables of cruising levels: magnetic tracks 000-179 degrees at odd, 180-359 at even
flight levels; the United Kingdom's former quadrantal rule used four sectors of 90 degrees), so
that two aircraft on crossing or opposite tracks are a layer apart where their tracks meet, and
aircraft sharing a layer fly roughly the same way. A fleet planned with PPSwarm's altitude cost
(Eqs. 6-7: every node pulled toward the middle of the altitude band) has the opposite: every
UAV cruises at the same height, and where many tracks cross (the middle of a map whose tasks
cross it) each flight must wait for the others. Under an execution model the flights are tubes
whose time windows grow along the flight (:mod:`uavplan.world.execution`), and a fleet pulled
into one layer then takes off over most of an hour.

The rule here: the band ``[min, max]`` (in its own reference: above the ground or absolute) is
split into ``k`` layers of equal thickness; a UAV whose course over the ground (from its start
to its goal, degrees clockwise from north, the +y axis) lies in sector ``floor(course / (360 /
k))`` cruises at the middle of the layer of that number (sectors in clockwise order, layers
from the bottom up). The layer is a preference, not a constraint: it replaces the band's middle
in the altitude cost (:attr:`uavplan.world.scenario.Task.cruise`); the band, the terrain and the
separation are checked as before, so a UAV that must climb over a hill, or leave its layer to
pass another, still may. Which layer a UAV is in is a pure function of its task, so the same
fleet gets the same layers in every restart and every run.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from uavplan.world.obstacles import AltitudeBand
from uavplan.world.scenario import Task

FloatArray = NDArray[np.float64]


def layer_heights(band: AltitudeBand, k: int) -> FloatArray:
    """The middles of ``k`` layers of equal thickness splitting ``band``, bottom up, (k,)."""
    if k < 1:
        raise ValueError(f"layers must be >= 1, got {k}")
    step = (band.max - band.min) / k
    return np.asarray(band.min + step * (np.arange(k) + 0.5), dtype=np.float64)


def course(task: Task) -> float:
    """The task's course over the ground, degrees in [0, 360) clockwise from north (+y): 0 for
    a task whose goal is straight above or below its start."""
    dx = task.goal[0] - task.start[0]
    dy = task.goal[1] - task.start[1]
    if dx == 0.0 and dy == 0.0:
        return 0.0
    return math.degrees(math.atan2(dx, dy)) % 360.0


def sector(task: Task, k: int) -> int:
    """The heading sector of ``task`` among ``k`` sectors of ``360 / k`` degrees, 0 ... k-1."""
    return min(int(course(task) // (360.0 / k)), k - 1)


def layered(tasks: tuple[Task, ...], band: AltitudeBand | None, k: int) -> tuple[Task, ...]:
    """``tasks`` each with its cruise layer's height (:attr:`Task.cruise`) by heading among
    ``k`` layers of ``band``; unchanged when ``k`` is 1 or there is no band."""
    if band is None or k <= 1:
        return tasks
    heights = layer_heights(band, k)
    return tuple(replace(t, cruise=float(heights[sector(t, k)])) for t in tasks)
