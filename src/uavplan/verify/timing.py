"""Timing and box checks of one trajectory: non-decreasing times, the speed limits (maximum and
minimum), the bounds."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import (
    TOL,
    Violation,
    fmt_num,
    fmt_point,
    fmt_points,
)
from uavplan.world.tolerances import VERIFY_ROUNDING, VERIFY_SPEED_RTOL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


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
                (fmt_point(traj.points[k + 1]),),
                t1 - t0,
                0.0,
                f"{traj.id}: times decrease at waypoint {k + 1} ({t0:g} s then {t1:g} s)",
            )
        )
    return out


def check_speed(traj: Trajectory, speed: float, min_speed: float = 0.0) -> list[Violation]:
    """The implied speed ``|dp| / dt`` of every segment must lie in ``[min_speed, speed]`` m/s.

    Maximum: at most ``speed * (1 + 1e-6)`` m/s, plus ``1e-6 (speed + 2)`` m of length slack for
    the rounding of plan files; a segment of zero duration that moves is an instantaneous jump
    (infinitely fast). Minimum (only when ``min_speed > 0``): every segment with ``dt > 0`` at
    least ``min_speed * (1 - 1e-6)`` m/s, less ``1e-6 (min_speed + 2)`` m of length slack; a
    segment that stays put for a while (a hover) flies at 0 m/s. Segments going back in time are
    left to :func:`check_times`. One violation per offending segment."""
    out = []
    d = np.linalg.norm(np.diff(traj.points, axis=0), axis=1)
    dt = np.diff(traj.times)
    allowed = speed * (1 + VERIFY_SPEED_RTOL) * dt + VERIFY_ROUNDING * (speed + 2.0)
    fast = (dt >= 0) & (d > allowed)
    slow = np.zeros_like(fast)
    if min_speed > 0:
        needed = min_speed * (1 - VERIFY_SPEED_RTOL) * dt - VERIFY_ROUNDING * (min_speed + 2.0)
        slow = (dt > 0) & (d < needed)
    for k in np.flatnonzero(fast | slow):
        v = float(d[k] / dt[k]) if dt[k] > 0 else math.inf
        t = float(traj.times[k])
        bound, word = (speed, "limit") if fast[k] else (min_speed, "minimum")
        out.append(
            Violation(
                "speed",
                (traj.id,),
                t,
                (fmt_point(traj.points[k]), fmt_point(traj.points[k + 1])),
                v,
                bound,
                f"{traj.id}: segment {k} at {fmt_num(v)} m/s ({word} {bound:g} m/s): "
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
                (fmt_point(traj.points[k]),),
                float(excess[k]),
                0.0,
                f"{traj.id}: waypoint {k} {fmt_points(traj.points[k])} is {excess[k]:.3f} m "
                f"outside the bounds along {'xyz'[axis]} ({lo[axis]:g}..{hi[axis]:g})",
            )
        )
    return out
