"""Kinematic checks of one trajectory against the UAV's declared limits: climb and descent
angles (``climb``) and the minimum turn radius of the horizontal track (``turn``). The speed
limits (maximum and minimum) are :func:`uavplan.verify.timing.check_speed`.

A trajectory is a timed polyline flown straight between consecutive points, so its geometry is
known only at its samples: the turn radius is estimated from them (discrete curvature, below),
which is why the check needs samples dense enough (a heading change of at most
:data:`~uavplan.world.tolerances.MAX_SAMPLE_TURN_DEG` per point) and allows the estimate
:data:`~uavplan.world.tolerances.TURN_RTOL` of slack. Written with NumPy only, apart from the
planner's own kinematic checks.

Each check reports one violation per **stretch**: a maximal run of consecutive offending
segments (climb, descent) or points (turn), at its worst segment or point, so that a densely
sampled curve that is too tight gives one line, not hundreds.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import Violation, fmt_point, fmt_points
from uavplan.world.tolerances import (
    ANGLE_TOL_DEG,
    DUPLICATE_TOL,
    MAX_SAMPLE_TURN_DEG,
    TURN_RTOL,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def stretches(bad: BoolArray, key: BoolArray | None = None) -> list[tuple[int, int]]:
    """Maximal runs ``[i, j)`` of consecutive True entries of ``bad`` (a run also ends where
    ``key`` changes, e.g. from climbing to descending)."""
    idx = np.flatnonzero(bad)
    if idx.size == 0:
        return []
    brk = np.diff(idx) != 1
    if key is not None:
        brk |= key[idx[1:]] != key[idx[:-1]]
    starts = np.concatenate([[0], np.flatnonzero(brk) + 1])
    ends = np.concatenate([starts[1:], [idx.size]])
    return [(int(idx[s]), int(idx[e - 1]) + 1) for s, e in zip(starts, ends, strict=True)]


def _span(what: str, i: int, j: int) -> str:
    return f"{what} {i}" if j - i == 1 else f"{what}s {i}-{j - 1}"


# ================================================================================ climb
def segment_angles(points: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Each segment's angle above the horizontal, degrees in [-90, 90] (``atan2(dz, h)``, h the
    horizontal length), and which segments move at all (length above ``DUPLICATE_TOL``)."""
    d = np.diff(np.asarray(points, dtype=np.float64), axis=0)
    h = np.hypot(d[:, 0], d[:, 1])
    dz = d[:, 2]
    moving = np.hypot(h, dz) > DUPLICATE_TOL
    return np.degrees(np.arctan2(dz, h)), moving


def check_climb(
    traj: Trajectory, max_climb: float | None, max_descent: float | None
) -> list[Violation]:
    """No segment climbs more steeply than ``max_climb`` or descends more steeply than
    ``max_descent`` (degrees from the horizontal; None: no limit; slack ``ANGLE_TOL_DEG``).
    3-D only; segments that do not move are skipped. One violation per stretch of consecutive
    offending segments in one direction, at its steepest segment."""
    if traj.dim != 3 or (max_climb is None and max_descent is None):
        return []
    ang, moving = segment_angles(traj.points)
    up = ang > 0
    limit = np.where(
        up,
        math.inf if max_climb is None else max_climb,
        math.inf if max_descent is None else max_descent,
    )
    excess = np.abs(ang) - limit
    bad = moving & (excess > ANGLE_TOL_DEG)
    out = []
    for i, j in stretches(bad, up):
        k = i + int(np.argmax(excess[i:j]))
        word = "climbs" if up[k] else "descends"
        lim = float(limit[k])
        t = float(traj.times[k])
        a, b = traj.points[k], traj.points[k + 1]
        more = f" (steepest of {_span('segment', i, j)})" if j - i > 1 else ""
        out.append(
            Violation(
                "climb",
                (traj.id,),
                t,
                (fmt_point(a), fmt_point(b)),
                float(abs(ang[k])),
                lim,
                f"{traj.id}: segment {k} {word} at {abs(ang[k]):.3f} deg (limit {lim:g} deg)"
                f"{more}: {fmt_points(a)} to {fmt_points(b)} from t={t:g} s",
            )
        )
    return out


# ================================================================================ turn
def turn_estimates(points: FloatArray) -> tuple[IntArray, FloatArray, FloatArray]:
    """The horizontal track's turn at its interior points, from its samples.

    A point at the same x, y as the one before it (horizontal distance at most
    ``DUPLICATE_TOL``) is dropped. At each interior point ``i`` of what is left, with incoming
    and outgoing horizontal segment lengths ``L_a``, ``L_b`` and heading change ``theta`` in
    [0, pi], the curvature estimate is ``kappa = theta / ((L_a + L_b) / 2)`` (1/m). For samples
    of a circular arc of radius rho, ``kappa = (1 / rho) (phi / 2) / sin(phi / 2)`` at equal
    spacing (phi the angle between samples): never below ``1 / rho``, above it by 0.26 % at a
    spacing of rho / 4.

    Returns:
        ``(index, theta, kappa)``: the points' indices in ``points``, the heading changes in
        radians and the curvature estimates (empty when fewer than 3 distinct points remain).
    """
    p = np.asarray(points, dtype=np.float64)[:, :2]
    step = np.hypot(*np.diff(p, axis=0).T)
    idx = np.concatenate([[0], np.flatnonzero(step > DUPLICATE_TOL) + 1]).astype(np.int64)
    if idx.size < 3:
        empty = np.zeros(0)
        return np.zeros(0, dtype=np.int64), empty, empty
    d = np.diff(p[idx], axis=0)
    length = np.hypot(d[:, 0], d[:, 1])
    da, db = d[:-1], d[1:]
    cross = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    dot = da[:, 0] * db[:, 0] + da[:, 1] * db[:, 1]
    theta = np.abs(np.arctan2(cross, dot))
    kappa = theta / (0.5 * (length[:-1] + length[1:]))
    return idx[1:-1], theta, kappa


def check_turn(traj: Trajectory, turn_radius: float) -> list[Violation]:
    """The horizontal track turns no tighter than ``turn_radius`` m (0: no limit).

    At every interior point (see :func:`turn_estimates`; the first and last points have no
    constraint) the heading change must be at most ``MAX_SAMPLE_TURN_DEG`` (a sharper turn at
    one point cannot be checked from samples and fails) and the curvature estimate at most
    ``(1 + TURN_RTOL) / turn_radius``. One violation per stretch of consecutive offending
    points: at its sharpest point if any turns too sharply at one point, else at its tightest.
    """
    if turn_radius <= 0:
        return []
    idx, theta, kappa = turn_estimates(traj.points)
    if idx.size == 0:
        return []
    deg = np.degrees(theta)
    sharp = deg > MAX_SAMPLE_TURN_DEG
    bad = sharp | (kappa > (1 + TURN_RTOL) / turn_radius)
    out = []
    for i, j in stretches(bad):
        if sharp[i:j].any():
            m = i + int(np.argmax(np.where(sharp[i:j], deg[i:j], -1.0)))
        else:
            m = i + int(np.argmax(kappa[i:j]))
        k = int(idx[m])
        radius = 1.0 / kappa[m] if kappa[m] > 0 else math.inf
        t = float(traj.times[k])
        p = traj.points[k]
        what = (
            f"a turn of {deg[m]:.1f} deg at one point (at most {MAX_SAMPLE_TURN_DEG:g} deg can "
            "be checked from samples)"
            if sharp[m]
            else f"an estimated turn radius of {radius:.3f} m"
        )
        first, last = int(idx[i]), int(idx[j - 1])
        more = f" (worst of points {first}-{last})" if j - i > 1 else ""
        out.append(
            Violation(
                "turn",
                (traj.id,),
                t,
                (fmt_point(p),),
                float(radius),
                float(turn_radius),
                f"{traj.id}: point {k} has {what}, minimum radius {turn_radius:g} m{more}, at "
                f"{fmt_points(p)}, t={t:g} s",
            )
        )
    return out


# ================================================================================ heights in wind
def _opens(left: float, up: float, down: float, plan: float) -> float:
    """The gap a plan of slope ``plan`` opens over ``left`` metres beyond a UAV on it that
    climbs at most ``up`` and descends at most ``down`` per metre."""
    if plan > up:
        return (up - plan) * left
    return (-down - plan) * left if plan < -down else 0.0


def heights_in_wind(
    traj: Trajectory, wind: float, max_climb: float | None, max_descent: float | None
) -> FloatArray:
    """(n,) the height a fixed wing flies at each point of ``traj`` less the planned one, with
    ``wind`` m/s behind it: on a segment flown at ``v`` m/s over the ground its height changes
    at most ``(v - wind) / v`` times the tangent of its climb (descent) limit per metre, and
    it steers toward the planned height (up while below it, down while above, on it while the
    plan's slope allows). The verifier's own walk, one segment at a time: from the gap at the
    segment's start, the distance to where the gap closes, then the gap the rest of the
    segment opens (the planner's vectorized ``uavplan.world.execution.height_lag`` answers
    the same, tested against this)."""
    p = np.asarray(traj.points, dtype=np.float64)
    t = np.asarray(traj.times, dtype=np.float64)
    tan_up = math.inf if max_climb is None else math.tan(math.radians(max_climb))
    tan_down = math.inf if max_descent is None else math.tan(math.radians(max_descent))
    out = np.zeros(len(p))
    if len(p) < 2:
        return out
    # the gap stays 0 up to the first segment steeper than the UAV can fly there
    d = np.diff(p, axis=0)
    h_all = np.hypot(d[:, 0], d[:, 1])
    dt_all = np.diff(t)
    with np.errstate(divide="ignore", invalid="ignore"):
        v_all = np.where(dt_all > 0, h_all / dt_all, np.inf)
        share_all = np.where(np.isfinite(v_all), np.clip((v_all - wind) / v_all, 0.0, 1.0), 1.0)
        slope_all = np.where(h_all > 0, d[:, 2] / h_all, 0.0)
        steep = (slope_all > share_all * tan_up) | (slope_all < -share_all * tan_down)
    steep |= (h_all <= 0) & (d[:, 2] != 0)
    if not steep.any():
        return out
    gap = 0.0
    for k in range(int(np.argmax(steep)), len(p) - 1):
        h = float(h_all[k])
        if h <= 0.0:  # a step straight up or down: no height changes without a distance flown
            gap -= float(d[k, 2])
            out[k + 1] = gap
            continue
        up, down = float(share_all[k]) * tan_up, float(share_all[k]) * tan_down
        plan = float(slope_all[k])
        # the gap's rate while it closes (or grows): the UAV at its limit toward the plan
        rate = (-down - plan) if gap > 0 else (up - plan) if gap < 0 else 0.0
        if gap == 0.0:
            gap = _opens(h, up, down, plan)
        elif gap * rate < 0.0 and -gap / rate < h:
            gap = _opens(h + gap / rate, up, down, plan)
        else:
            gap += rate * h
        out[k + 1] = gap
    return out
