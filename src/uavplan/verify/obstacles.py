"""Obstacle checks of one trajectory, exact: cylinders, circles, polygons (and revealed uncertain
areas), moving obstacles over continuous time.

Broad phase: from :data:`INDEX_MIN` obstacles of a kind on, a uniform grid over the obstacles'
boxes (:mod:`uavplan.world.obstacle_index`, which imports none of the planner's geometry) gives
each obstacle the segments near it, and the exact tests below (the narrow phase, the verifier's
own) run on those alone; below it, or for a trajectory with coordinates that are not finite,
every obstacle is tested against every segment. The broad phase is conservative: a segment
whose box misses an obstacle's box (grown by its margin) cannot violate it."""

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
from uavplan.world.obstacle_index import box_grid, box_pad, segment_candidates
from uavplan.world.obstacles import Cylinder

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: From this many obstacles of one kind on, the grid picks the segments near each obstacle.
INDEX_MIN = 64
#: The grids of the last few obstacle tuples (by identity: a verification asks for the same
#: world's obstacles once per trajectory; the tuple is kept, so its identity is not reused).
_GRIDS: dict[int, tuple[Any, Any]] = {}


def _grid(obstacles: Sequence[Any], boxes: Any) -> Any:
    key = id(obstacles)
    hit = _GRIDS.get(key)
    if hit is None or hit[0] is not obstacles:
        if len(_GRIDS) >= 8:
            _GRIDS.pop(next(iter(_GRIDS)))
        hit = _GRIDS[key] = (obstacles, box_grid(*boxes(obstacles)))
    return hit[1]


def near_segments(
    a: FloatArray, b: FloatArray, obstacles: Sequence[Any], boxes: Any
) -> list[tuple[int, IntArray]]:
    """``(obstacle index, segment indices)`` for every obstacle that segments ``a -> b`` may
    violate, both in increasing order: the broad phase (see the module). ``boxes(obstacles)``
    gives ``(x_lo, y_lo, x_hi, y_hi)`` arrays of boxes that hold everything a segment must keep
    out of."""
    n, m = len(obstacles), len(a)
    if n < INDEX_MIN or not (np.isfinite(a[:, :2]).all() and np.isfinite(b[:, :2]).all()):
        every = np.arange(m)
        return [(i, every) for i in range(n)]
    seg, box = segment_candidates(_grid(obstacles, boxes), a, b)
    cut = np.flatnonzero(np.diff(box)) + 1
    groups = zip(np.split(box, cut), np.split(seg, cut), strict=True)
    return [(int(g[0]), s) for g, s in groups if len(g)]


def _disc_boxes(obstacles: Sequence[Any]) -> tuple[FloatArray, ...]:
    """Boxes around discs of radius ``effective_radius`` (cylinders, circles)."""
    c = np.array([o.center for o in obstacles], dtype=np.float64).reshape(-1, 2)
    r = np.array([o.effective_radius for o in obstacles], dtype=np.float64)
    pad = box_pad(c[:, 0], c[:, 1], r)
    return c[:, 0] - r - pad, c[:, 1] - r - pad, c[:, 0] + r + pad, c[:, 1] + r + pad


def _polygon_boxes(polygons: Sequence[Any]) -> tuple[FloatArray, ...]:
    """Boxes around polygons grown by their margins."""
    lo = np.array([np.min(np.asarray(p.vertices, dtype=np.float64), axis=0) for p in polygons])
    hi = np.array([np.max(np.asarray(p.vertices, dtype=np.float64), axis=0) for p in polygons])
    m = np.maximum(np.array([float(p.margin) for p in polygons]), 0.0)
    pad = box_pad(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]) + m
    return lo[:, 0] - pad, lo[:, 1] - pad, hi[:, 0] + pad, hi[:, 1] + pad


# ================================================================================ obstacles
def segment_cylinder_distance(
    a: FloatArray, b: FloatArray, center: Sequence[float], z_lo: float, z_hi: float
) -> tuple[FloatArray, FloatArray]:
    """Horizontal distance from a vertical axis to the part of each segment inside a z range.

    Args:
        a, b: (m, 2 or 3) segment ends, metres (2-D segments are never outside the z range).
        center: the axis (x, y), or one per segment (m, 2); z_lo, z_hi: the z range (may be
            infinite), or one per segment (m,).

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
    ax, ay = a[:, 0] - c[..., 0], a[:, 1] - c[..., 1]
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    dd = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(dd > 0, -(ax * dx + ay * dy) / np.where(dd > 0, dd, 1.0), 0.0)
    s = np.clip(s, lo, np.maximum(lo, hi))
    dist = np.hypot(ax + s * dx, ay + s * dy)
    empty = lo > hi
    return np.where(empty, np.inf, dist), np.where(empty, np.nan, s)


def _disc_distances(
    a: FloatArray, b: FloatArray, discs: Sequence[Any], z_lo: FloatArray, z_hi: FloatArray
) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """:func:`segment_cylinder_distance` of every (disc, segment) pair the broad phase keeps,
    in one call: the discs' indices, the segments' rows (disc by disc, rows in order), the
    distances and the closest points' parameters. ``z_lo``, ``z_hi``: each disc's z range."""
    near = near_segments(a, b, discs, _disc_boxes)
    if not near:
        none = np.zeros(0, dtype=np.intp)
        return none, none, np.zeros(0), np.zeros(0)
    ci = np.concatenate([np.full(len(rows), i, dtype=np.intp) for i, rows in near])
    rows = np.concatenate([rows for _, rows in near]).astype(np.intp)
    centers = np.array([o.center for o in discs], dtype=np.float64).reshape(-1, 2)
    d, s = segment_cylinder_distance(a[rows], b[rows], centers[ci], z_lo[ci], z_hi[ci])
    return ci, rows, d, s


def check_cylinders(traj: Trajectory, cylinders: Sequence[Cylinder]) -> list[Violation]:
    """Every segment clears every cylinder: the part of the segment between ``z_min - margin``
    and ``z_max + margin`` stays at least ``radius + margin`` from the axis (exact)."""
    a, b = segment_ends(traj)
    z_lo = np.array([c.z_min - c.margin for c in cylinders], dtype=np.float64)
    z_hi = np.array([c.z_max + c.margin for c in cylinders], dtype=np.float64)
    radius = np.array([c.effective_radius for c in cylinders], dtype=np.float64)
    found = _disc_distances(a, b, cylinders, z_lo, z_hi)
    return _disc_violations(traj, "cylinder", "the axis of cylinder", radius, *found)


def check_circles(traj: Trajectory, circles: Sequence[Any]) -> list[Violation]:
    """Circles are infinite vertical prisms: every segment stays at least ``radius + margin``
    from the centre in the horizontal plane (exact)."""
    a, b = segment_ends(traj)
    unbounded = np.full(len(circles), math.inf)
    radius = np.array([float(c.effective_radius) for c in circles], dtype=np.float64)
    found = _disc_distances(a[:, :2], b[:, :2], circles, -unbounded, unbounded)
    return _disc_violations(traj, "circle", "the centre of circle", radius, *found)


def _disc_violations(
    traj: Trajectory,
    kind: str,
    what: str,
    radius: FloatArray,
    ci: IntArray,
    rows: IntArray,
    d: FloatArray,
    s: FloatArray,
) -> list[Violation]:
    """A violation for each (disc, segment) pair of :func:`_disc_distances` closer than the
    disc's radius plus margin."""
    out = []
    for q in np.flatnonzero(d < radius[ci] - TOL):
        k, r = rows[q], float(radius[ci[q]])
        p, t = point_at(traj, int(k), float(s[q]))
        out.append(
            Violation(
                kind,
                (traj.id,),
                t,
                (p,),
                float(d[q]),
                r,
                f"{traj.id}: segment {k} passes {fmt_num(d[q])} m from {what} {ci[q]} "
                f"(radius + margin {r:g} m) at {fmt_points(p)}, t={t:.3f} s",
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
    a_all, b_all = segment_ends(traj)
    out = []
    for pi, rows in near_segments(a_all, b_all, polygons, _polygon_boxes):
        poly = polygons[pi]
        a, b = a_all[rows], b_all[rows]
        verts = np.asarray(poly.vertices, dtype=np.float64)
        margin = float(poly.margin)
        dist = segment_polygon_distance(a, b, verts)
        # A segment that does not touch the boundary is wholly inside or wholly outside.
        start_inside = point_in_polygon(a[:, 0], a[:, 1], verts)
        suspects = (dist <= TOL) | start_inside | (dist < margin - TOL)
        for q in (int(i) for i in np.flatnonzero(suspects)):
            k = int(rows[q])
            if dist[q] > TOL:
                if start_inside[q]:
                    s, depth = (
                        0.5,
                        _midpoint_depth(a[q], b[q], verts),
                    )
                elif dist[q] < margin - TOL:
                    s, depth = _closest_to_polygon(a[q], b[q], verts), -float(dist[q])
                else:
                    continue
            else:
                s, depth = _deepest_inside(a[q], b[q], verts)
                if math.isnan(s):
                    if margin <= TOL:
                        continue
                    s, depth = _closest_to_polygon(a[q], b[q], verts), 0.0
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
