"""Obstacle checks of one trajectory, exact: cylinders, circles, polygons (and revealed uncertain
areas), moving obstacles over continuous time."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import (
    TOL,
    Violation,
    fmt_num,
    fmt_points,
    point_at,
    segment_ends,
)
from uavplan.world.obstacles import Cylinder

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ================================================================================ obstacles
def segment_cylinder_distance(
    a: FloatArray, b: FloatArray, center: Sequence[float], z_lo: float, z_hi: float
) -> tuple[FloatArray, FloatArray]:
    """Horizontal distance from a vertical axis to the part of each segment inside a z range.

    Args:
        a, b: (m, 2 or 3) segment ends, metres (2-D segments are never outside the z range).
        center: the axis (x, y); z_lo, z_hi: the z range (may be infinite).

    Returns:
        ``(distance, s)``: (m,) metres (inf where no part of the segment is in the z range) and
        (m,) the segment parameter in [0, 1] of the closest point (nan where none).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    m = a.shape[0]
    lo = np.zeros(m)
    hi = np.ones(m)
    if a.shape[1] == 3:
        za, dz = a[:, 2], b[:, 2] - a[:, 2]
        flat = dz == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            s1 = (z_lo - za) / np.where(flat, 1.0, dz)
            s2 = (z_hi - za) / np.where(flat, 1.0, dz)
        inside = (za >= z_lo) & (za <= z_hi)
        lo = np.where(flat, np.where(inside, 0.0, 2.0), np.maximum(0.0, np.minimum(s1, s2)))
        hi = np.where(flat, np.where(inside, 1.0, -1.0), np.minimum(1.0, np.maximum(s1, s2)))
    c = np.asarray(center, dtype=np.float64)
    ax, ay = a[:, 0] - c[0], a[:, 1] - c[1]
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    dd = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(dd > 0, -(ax * dx + ay * dy) / np.where(dd > 0, dd, 1.0), 0.0)
    s = np.clip(s, lo, np.maximum(lo, hi))
    dist = np.hypot(ax + s * dx, ay + s * dy)
    empty = lo > hi
    return np.where(empty, np.inf, dist), np.where(empty, np.nan, s)


def check_cylinders(traj: Trajectory, cylinders: Sequence[Cylinder]) -> list[Violation]:
    """Every segment clears every cylinder: the part of the segment between ``z_min - margin``
    and ``z_max + margin`` stays at least ``radius + margin`` from the axis (exact)."""
    a, b = segment_ends(traj)
    out = []
    for ci, cyl in enumerate(cylinders):
        r = cyl.effective_radius
        d, s = segment_cylinder_distance(
            a, b, cyl.center, cyl.z_min - cyl.margin, cyl.z_max + cyl.margin
        )
        for k in np.flatnonzero(d < r - TOL):
            p, t = point_at(traj, int(k), float(s[k]))
            out.append(
                Violation(
                    "cylinder",
                    (traj.id,),
                    t,
                    (p,),
                    float(d[k]),
                    r,
                    f"{traj.id}: segment {k} passes {fmt_num(d[k])} m from the axis of cylinder "
                    f"{ci} (radius + margin {r:g} m) at {fmt_points(p)}, t={t:.3f} s",
                )
            )
    return out


def check_circles(traj: Trajectory, circles: Sequence[Any]) -> list[Violation]:
    """Circles are infinite vertical prisms: every segment stays at least ``radius + margin``
    from the centre in the horizontal plane (exact)."""
    a, b = segment_ends(traj)
    out = []
    for ci, circ in enumerate(circles):
        r = float(circ.effective_radius)
        d, s = segment_cylinder_distance(a[:, :2], b[:, :2], circ.center, -math.inf, math.inf)
        for k in np.flatnonzero(d < r - TOL):
            p, t = point_at(traj, int(k), float(s[k]))
            out.append(
                Violation(
                    "circle",
                    (traj.id,),
                    t,
                    (p,),
                    float(d[k]),
                    r,
                    f"{traj.id}: segment {k} passes {fmt_num(d[k])} m from the centre of circle "
                    f"{ci} (radius + margin {r:g} m) at {fmt_points(p)}, t={t:.3f} s",
                )
            )
    return out


def _point_segment_dist2(
    px: FloatArray, py: FloatArray, ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray
) -> FloatArray:
    dx, dy = bx - ax, by - ay
    dd = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(dd > 0, ((px - ax) * dx + (py - ay) * dy) / np.where(dd > 0, dd, 1.0), 0.0)
    s = np.clip(s, 0.0, 1.0)
    ex, ey = ax + s * dx - px, ay + s * dy - py
    return np.asarray(ex * ex + ey * ey)


def _orient(
    ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray, cx: FloatArray, cy: FloatArray
) -> FloatArray:
    return np.asarray((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))


def segment_polygon_distance(a: FloatArray, b: FloatArray, vertices: FloatArray) -> FloatArray:
    """Horizontal distance from each segment to a polygon's boundary.

    Args:
        a, b: (m, >=2) segment ends, metres (only x, y are used).
        vertices: (k, 2) the polygon, in order.

    Returns:
        (m,) metres, 0 where the segment touches or crosses the boundary.
    """
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    ax, ay = a[:, 0:1], a[:, 1:2]
    bx, by = b[:, 0:1], b[:, 1:2]
    cx, cy, ex, ey = v[None, :, 0], v[None, :, 1], w[None, :, 0], w[None, :, 1]
    d2 = np.minimum.reduce(
        [
            _point_segment_dist2(ax, ay, cx, cy, ex, ey),
            _point_segment_dist2(bx, by, cx, cy, ex, ey),
            _point_segment_dist2(cx, cy, ax, ay, bx, by),
            _point_segment_dist2(ex, ey, ax, ay, bx, by),
        ]
    )
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, ex, ey)
    o3 = _orient(cx, cy, ex, ey, ax, ay)
    o4 = _orient(cx, cy, ex, ey, bx, by)
    cross = (o1 * o2 < 0) & (o3 * o4 < 0)
    d2 = np.where(cross, 0.0, d2)
    return np.asarray(np.sqrt(d2.min(axis=1)))


def point_in_polygon(x: FloatArray, y: FloatArray, vertices: FloatArray) -> NDArray[np.bool_]:
    """Even-odd ray casting; points on the boundary may go either way (callers test the
    distance to the boundary separately)."""
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    px = np.asarray(x, dtype=np.float64)[..., None]
    py = np.asarray(y, dtype=np.float64)[..., None]
    y0, y1 = v[:, 1], w[:, 1]
    straddle = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = v[:, 0] + (py - y0) * (w[:, 0] - v[:, 0]) / (y1 - y0)
    hits = straddle & (px < xc)
    return np.asarray(np.count_nonzero(hits, axis=-1) % 2 == 1)


def _boundary_dist(x: FloatArray, y: FloatArray, vertices: FloatArray) -> FloatArray:
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    px, py = np.asarray(x)[..., None], np.asarray(y)[..., None]
    d2 = _point_segment_dist2(px, py, v[:, 0], v[:, 1], w[:, 0], w[:, 1])
    return np.asarray(np.sqrt(d2.min(axis=-1)))


def _deepest_inside(a: FloatArray, b: FloatArray, vertices: FloatArray) -> tuple[float, float]:
    """For one segment that touches a polygon's boundary: the segment parameter of the deepest
    point found strictly inside (midpoints of the pieces between boundary crossings) and its
    depth, or ``(nan, 0)`` if no piece enters the interior."""
    v = np.asarray(vertices, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    d = b[:2] - a[:2]
    e = w - v
    den = d[0] * e[:, 1] - d[1] * e[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = ((v[:, 0] - a[0]) * e[:, 1] - (v[:, 1] - a[1]) * e[:, 0]) / den
        u = ((v[:, 0] - a[0]) * d[1] - (v[:, 1] - a[1]) * d[0]) / den
    ok = (den != 0) & (u >= -1e-12) & (u <= 1 + 1e-12) & (s > 0) & (s < 1)
    cuts = np.unique(np.concatenate([[0.0, 1.0], s[ok]]))
    mids = 0.5 * (cuts[:-1] + cuts[1:])
    px, py = a[0] + mids * d[0], a[1] + mids * d[1]
    depth = _boundary_dist(px, py, v)
    inside = point_in_polygon(px, py, v) & (depth > TOL)
    if not np.any(inside):
        return math.nan, 0.0
    k = int(np.argmax(np.where(inside, depth, -1.0)))
    return float(mids[k]), float(depth[k])


def check_polygons(traj: Trajectory, polygons: Sequence[Any]) -> list[Violation]:
    """Polygons are infinite vertical prisms: no segment enters the interior, and every segment
    keeps at least ``margin`` from the boundary (exact; touching with no margin is allowed).

    ``value`` is the signed horizontal distance at the reported point (negative inside)."""
    a, b = segment_ends(traj)
    out = []
    for pi, poly in enumerate(polygons):
        verts = np.asarray(poly.vertices, dtype=np.float64)
        margin = float(poly.margin)
        dist = segment_polygon_distance(a, b, verts)
        # A segment that does not touch the boundary is wholly inside or wholly outside.
        start_inside = point_in_polygon(a[:, 0], a[:, 1], verts)
        suspects = (dist <= TOL) | start_inside | (dist < margin - TOL)
        for k in (int(i) for i in np.flatnonzero(suspects)):
            if dist[k] > TOL:
                if start_inside[k]:
                    s, depth = (
                        0.5,
                        _midpoint_depth(a[k], b[k], verts),
                    )
                elif dist[k] < margin - TOL:
                    s, depth = _closest_to_polygon(a[k], b[k], verts), -float(dist[k])
                else:
                    continue
            else:
                s, depth = _deepest_inside(a[k], b[k], verts)
                if math.isnan(s):
                    if margin <= TOL:
                        continue
                    s, depth = _closest_to_polygon(a[k], b[k], verts), 0.0
            p, t = point_at(traj, k, s)
            value = -depth
            inside = value < 0
            text = (
                f"enters polygon {pi} ({fmt_num(-value)} m deep)"
                if inside
                else f"passes {fmt_num(value)} m from polygon {pi} (margin {margin:g} m)"
            )
            out.append(
                Violation(
                    "polygon",
                    (traj.id,),
                    t,
                    (p,),
                    value,
                    margin,
                    f"{traj.id}: segment {k} {text} at {fmt_points(p)}, t={t:.3f} s",
                )
            )
    return out


def _midpoint_depth(a: FloatArray, b: FloatArray, verts: FloatArray) -> float:
    m = 0.5 * (a[:2] + b[:2])
    return float(_boundary_dist(m[0:1], m[1:2], verts)[0])


def _closest_to_polygon(a: FloatArray, b: FloatArray, verts: FloatArray) -> float:
    """Segment parameter of a point of segment ``a``-``b`` closest to the polygon boundary
    (sampled finely; only used to say where a margin violation happens)."""
    s = np.linspace(0.0, 1.0, 1025)
    x = a[0] + s * (b[0] - a[0])
    y = a[1] + s * (b[1] - a[1])
    return float(s[int(np.argmin(_boundary_dist(x, y, verts)))])
