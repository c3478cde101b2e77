"""Segments against polygons: distances, the fraction inside, point-in-polygon, convexity and
hulls, and whether a track crosses itself."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.geometry.cylinders import _seg_point_dist

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------- polygons
def pack_polygons(polygons: list[FloatArray]) -> tuple[FloatArray, NDArray[np.int64]]:
    """Pack ragged polygons into ``(vertices (V, 2), starts (K + 1,))`` for the kernels."""
    if not polygons:
        return np.zeros((0, 2)), np.zeros(1, dtype=np.int64)
    verts = np.concatenate([np.asarray(p, dtype=np.float64)[:, :2] for p in polygons])
    starts = np.concatenate(([0], np.cumsum([len(p) for p in polygons]))).astype(np.int64)
    return verts, starts


@njit(cache=True, inline="always")
def _cross(ax, ay, bx, by):  # pragma: no cover - numba
    return ax * by - ay * bx


@njit(cache=True)
def _point_in_polygon(px, py, verts, v0, v1):  # pragma: no cover - numba
    """Even-odd rule; points on the boundary may go either way (callers handle edges)."""
    inside = False
    n = v1 - v0
    j = v1 - 1
    for i in range(v0, v1):
        xi = verts[i, 0]
        yi = verts[i, 1]
        xj = verts[j, 0]
        yj = verts[j, 1]
        if (yi > py) != (yj > py):
            xint = xj + (py - yj) * (xi - xj) / (yi - yj)
            if px < xint:
                inside = not inside
        j = i
    _ = n
    return inside


@njit(cache=True)
def _seg_seg_param(ax, ay, bx, by, cx, cy, dx, dy):  # pragma: no cover - numba
    """Parameter t on a->b where it crosses segment c->d, or -1 (parallel or no crossing)."""
    rx = bx - ax
    ry = by - ay
    sx = dx - cx
    sy = dy - cy
    den = _cross(rx, ry, sx, sy)
    if den == 0.0:
        return -1.0
    qx = cx - ax
    qy = cy - ay
    t = _cross(qx, qy, sx, sy) / den
    u = _cross(qx, qy, rx, ry) / den
    if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0:
        return t
    return -1.0


@njit(cache=True)
def _seg_seg_distance(ax, ay, bx, by, cx, cy, dx, dy):  # pragma: no cover - numba
    if _seg_seg_param(ax, ay, bx, by, cx, cy, dx, dy) >= 0.0:
        return 0.0
    d1 = _seg_point_dist(ax, ay, bx, by, cx, cy)
    d2 = _seg_point_dist(ax, ay, bx, by, dx, dy)
    d3 = _seg_point_dist(cx, cy, dx, dy, ax, ay)
    d4 = _seg_point_dist(cx, cy, dx, dy, bx, by)
    return min(min(d1, d2), min(d3, d4))


@njit(cache=True)
def _polygon_boxes(verts, starts):  # pragma: no cover - numba
    """(K, 4) bounding boxes xmin, ymin, xmax, ymax of the packed polygons."""
    K = starts.shape[0] - 1
    box = np.empty((K, 4))
    for k in range(K):
        box[k, 0] = np.inf
        box[k, 1] = np.inf
        box[k, 2] = -np.inf
        box[k, 3] = -np.inf
        for i in range(starts[k], starts[k + 1]):
            box[k, 0] = min(box[k, 0], verts[i, 0])
            box[k, 1] = min(box[k, 1], verts[i, 1])
            box[k, 2] = max(box[k, 2], verts[i, 0])
            box[k, 3] = max(box[k, 3], verts[i, 1])
    return box


@njit(cache=True, inline="always")
def _box_gap(ax, ay, bx, by, box, k):  # pragma: no cover - numba
    """Distance between the segment's bounding box and polygon k's (a lower bound of the
    segment-polygon distance; 0 when the boxes overlap)."""
    gx = max(0.0, max(min(ax, bx) - box[k, 2], box[k, 0] - max(ax, bx)))
    gy = max(0.0, max(min(ay, by) - box[k, 3], box[k, 1] - max(ay, by)))
    return np.sqrt(gx * gx + gy * gy)


@population_kernel()
def segment_polygon_distance(paths, verts, starts, cap=np.inf):  # pragma: no cover - numba
    """Distance between each 2-D segment and each polygon (0 when they touch or overlap).

    Exact for convex and non-convex simple polygons. Returns (P, N - 1, K). With a finite
    ``cap``, a pair whose bounding boxes are at least ``cap`` apart reports that box distance (a
    lower bound, ``>= cap``) instead of the exact distance: enough for a clearance test.
    """
    P, N, _ = paths.shape
    K = starts.shape[0] - 1
    out = np.empty((P, N - 1, K))
    box = _polygon_boxes(verts, starts)
    for p in prange(P):
        for s in range(N - 1):
            ax = paths[p, s, 0]
            ay = paths[p, s, 1]
            bx = paths[p, s + 1, 0]
            by = paths[p, s + 1, 1]
            for k in range(K):
                gap = _box_gap(ax, ay, bx, by, box, k)
                if gap >= cap:
                    out[p, s, k] = gap
                    continue
                v0 = starts[k]
                v1 = starts[k + 1]
                if _point_in_polygon(ax, ay, verts, v0, v1):
                    out[p, s, k] = 0.0
                    continue
                best = np.inf
                j = v1 - 1
                for i in range(v0, v1):
                    d = _seg_seg_distance(
                        ax, ay, bx, by, verts[j, 0], verts[j, 1], verts[i, 0], verts[i, 1]
                    )
                    if d < best:
                        best = d
                        if best == 0.0:
                            break
                    j = i
                out[p, s, k] = best
    return out


@njit(cache=True)
def _inside_pieces(ax, ay, rx, ry, verts, v0, v1, ts, n):  # pragma: no cover - numba
    """Fraction of segment a -> a + r inside polygon verts[v0:v1], given ``ts[:n]``: 0 and the
    crossing parameters in (0, 1) in any order. Appends 1, sorts, and sums the pieces whose
    midpoint is inside."""
    ts[n] = 1.0
    n += 1
    for q in range(1, n):  # insertion sort in place (few crossings)
        key = ts[q]
        r = q - 1
        while r >= 0 and ts[r] > key:
            ts[r + 1] = ts[r]
            r -= 1
        ts[r + 1] = key
    frac = 0.0
    for q in range(n - 1):
        a = ts[q]
        b = ts[q + 1]
        if b <= a:
            continue
        m = 0.5 * (a + b)
        if _point_in_polygon(ax + m * rx, ay + m * ry, verts, v0, v1):
            frac += b - a
    return frac


@njit(cache=True)
def _inside_fraction_one(ax, ay, bx, by, verts, v0, v1, ts):  # pragma: no cover - numba
    """Exact fraction of segment a->b inside the polygon verts[v0:v1]: split at the edge
    crossings, test each piece's midpoint. ``ts``: scratch of length >= v1 - v0 + 2."""
    n = 0
    ts[n] = 0.0
    n += 1
    j = v1 - 1
    for i in range(v0, v1):
        t = _seg_seg_param(ax, ay, bx, by, verts[j, 0], verts[j, 1], verts[i, 0], verts[i, 1])
        if t > 0.0 and t < 1.0:
            ts[n] = t
            n += 1
        j = i
    return _inside_pieces(ax, ay, bx - ax, by - ay, verts, v0, v1, ts, n)


@population_kernel()
def segment_polygon_inside_fraction(paths, verts, starts):  # pragma: no cover - numba
    """Fraction of each segment's parameter range inside each polygon, exact. (P, N - 1, K)."""
    P, N, _ = paths.shape
    K = starts.shape[0] - 1
    out = np.zeros((P, N - 1, K))
    maxv = 0
    for k in range(K):
        maxv = max(maxv, starts[k + 1] - starts[k])
    box = _polygon_boxes(verts, starts)
    for p in prange(P):
        ts = np.empty(maxv + 2)
        for s in range(N - 1):
            ax = paths[p, s, 0]
            ay = paths[p, s, 1]
            bx = paths[p, s + 1, 0]
            by = paths[p, s + 1, 1]
            for k in range(K):
                if _box_gap(ax, ay, bx, by, box, k) > 0.0:
                    continue  # boxes apart: nothing inside (out is zero-filled)
                out[p, s, k] = _inside_fraction_one(
                    ax, ay, bx, by, verts, starts[k], starts[k + 1], ts
                )
    return out


def track_crosses_itself(points: FloatArray) -> bool:
    """Whether a path's horizontal track crosses itself: two non-adjacent segments properly
    intersect (a loop, as a user sees it on a map). Touching and collinear overlaps do not
    count. Compiled (a fleet's flight checks ask it of every candidate: hundreds of thousands
    of orientation tests); :func:`track_crosses_itself_reference` is the plain loops."""
    P = np.ascontiguousarray(np.asarray(points, dtype=np.float64)[:, :2])
    return bool(_crosses(P))


@njit(cache=True)
def _orient(ax, ay, bx, by, cx, cy):  # pragma: no cover - numba
    return np.sign((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))


@njit(cache=True)
def _crosses(P):  # pragma: no cover - numba
    n = P.shape[0] - 1
    for i in range(n):
        ax, ay, bx, by = P[i, 0], P[i, 1], P[i + 1, 0], P[i + 1, 1]
        for j in range(i + 2, n):
            cx, cy, dx, dy = P[j, 0], P[j, 1], P[j + 1, 0], P[j + 1, 1]
            if (
                _orient(ax, ay, bx, by, cx, cy) * _orient(ax, ay, bx, by, dx, dy) < 0
                and _orient(cx, cy, dx, dy, ax, ay) * _orient(cx, cy, dx, dy, bx, by) < 0
            ):
                return True
    return False


def track_crosses_itself_reference(points: FloatArray) -> bool:
    """:func:`track_crosses_itself` in plain Python loops (the reference the tests compare)."""
    P = np.asarray(points, dtype=np.float64)[:, :2]

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> float:
        return float(np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])))

    n = len(P) - 1
    for i in range(n):
        for j in range(i + 2, n):
            a, b, c, d = P[i], P[i + 1], P[j], P[j + 1]
            if orient(a, b, c) * orient(a, b, d) < 0 and orient(c, d, a) * orient(c, d, b) < 0:
                return True
    return False


def point_in_polygon(points: FloatArray, vertices: FloatArray) -> NDArray[np.bool_]:
    """Even-odd point-in-polygon for (..., 2) points against one polygon (k, 2). NumPy."""
    pts = np.asarray(points, dtype=np.float64)
    v = np.asarray(vertices, dtype=np.float64)
    x = pts[..., 0, None]
    y = pts[..., 1, None]
    xi, yi = v[:, 0], v[:, 1]
    xj, yj = np.roll(xi, 1), np.roll(yi, 1)
    cond = (yi > y) != (yj > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = xj + (y - yj) * (xi - xj) / (yi - yj)
    crossings = np.sum(cond & (x < xint), axis=-1)
    return np.asarray(crossings % 2 == 1)


@njit(cache=True)
def _inside_fraction_and_touch(ax, ay, bx, by, verts, v0, v1, ts):  # pragma: no cover - numba
    """For a segment of positive length and the closed polygon verts[v0:v1]: the exact fraction
    of the segment inside (as :func:`_inside_fraction_one`) and whether the two touch (distance
    0, as :func:`_seg_seg_distance` <= 0 on some edge or the segment inside), from one pass over
    the edges: a crossing (``_seg_seg_param`` >= 0, end points included) touches; a parallel edge
    is measured; otherwise the segment touches iff some piece between crossings is inside."""
    n = 0
    ts[n] = 0.0
    n += 1
    touch = False
    rx = bx - ax
    ry = by - ay
    j = v1 - 1
    for i in range(v0, v1):
        cx = verts[j, 0]
        cy = verts[j, 1]
        sx = verts[i, 0] - cx
        sy = verts[i, 1] - cy
        den = _cross(rx, ry, sx, sy)
        if den == 0.0:
            if not touch and (
                _seg_seg_distance(ax, ay, bx, by, cx, cy, verts[i, 0], verts[i, 1]) <= 0.0
            ):
                touch = True
        else:
            qx = cx - ax
            qy = cy - ay
            tn = _cross(qx, qy, sx, sy)
            un = _cross(qx, qy, rx, ry)
            # t = tn / den, u = un / den: reject by signs and a 2x bound without dividing
            # (never rejects what the tests below accept after rounding)
            if den > 0.0:
                if tn < 0.0 or un < 0.0 or tn > 2.0 * den or un > 2.0 * den:
                    j = i
                    continue
            elif tn > 0.0 or un > 0.0 or tn < 2.0 * den or un < 2.0 * den:
                j = i
                continue
            t = tn / den
            u = un / den
            if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0:
                touch = True
                if t > 0.0 and t < 1.0:
                    ts[n] = t
                    n += 1
        j = i
    frac = _inside_pieces(ax, ay, rx, ry, verts, v0, v1, ts, n)
    if frac > 0.0:
        touch = True
    return frac, touch


def polygon_convexity(verts: FloatArray, starts: NDArray[np.int64]) -> NDArray[np.int64]:
    """(K,) +1 for a convex counter-clockwise polygon, -1 for a convex clockwise one, 0 for a
    non-convex one: every turn between consecutive edges of one sign and the turns summing to
    one full turn (a pentagram's turns share a sign but sum to two). NumPy, once per world."""
    K = len(starts) - 1
    out = np.zeros(K, dtype=np.int64)
    for k in range(K):
        v = verts[starts[k] : starts[k + 1]]
        e = np.roll(v, -1, axis=0) - v  # edge q: vertex q to q + 1
        f = np.roll(e, -1, axis=0)  # the next edge
        c = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
        turn = float(np.arctan2(c, e[:, 0] * f[:, 0] + e[:, 1] * f[:, 1]).sum())
        if abs(abs(turn) - 2.0 * np.pi) > 1e-6:
            continue
        pos, neg = bool((c > 0.0).any()), bool((c < 0.0).any())
        out[k] = 1 if pos and not neg else -1 if neg and not pos else 0
    return out


@njit(cache=True, inline="always")
def _convex_clip(ax, ay, bx, by, verts, v0, v1, orient):  # pragma: no cover - numba
    """Cyrus-Beck: the parameter interval [t_in, t_out] of segment a->b inside the closed
    convex polygon verts[v0:v1] (``orient`` +1 counter-clockwise, -1 clockwise); empty when
    t_in > t_out. Its length is the exact inside fraction; non-empty means the two touch."""
    rx = bx - ax
    ry = by - ay
    t_in = 0.0
    t_out = 1.0
    j = v1 - 1
    for i in range(v0, v1):
        # outward normal of edge j -> i: (ey, -ex) for a counter-clockwise polygon
        ex = verts[i, 0] - verts[j, 0]
        ey = verts[i, 1] - verts[j, 1]
        nx = orient * ey
        ny = -orient * ex
        num = nx * (ax - verts[j, 0]) + ny * (ay - verts[j, 1])  # > 0: a outside this edge
        den = nx * rx + ny * ry
        if den == 0.0:
            if num > 0.0:
                return 1.0, 0.0
        elif den < 0.0:
            t_in = max(t_in, -num / den)
        else:
            t_out = min(t_out, -num / den)
        if t_in > t_out:
            return t_in, t_out
        j = i
    return t_in, t_out


def convex_hulls(
    verts: FloatArray, starts: NDArray[np.int64]
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Counter-clockwise convex hulls (Andrew's monotone chain, collinear points dropped) of the
    packed polygons, packed the same way: ``(hull vertices (H, 2), hull starts (K + 1,))``.
    Plain Python, once per world."""
    K = len(starts) - 1
    hv: list[tuple[float, float]] = []
    hs = np.zeros(K + 1, dtype=np.int64)
    for k in range(K):
        pts = sorted(map(tuple, verts[starts[k] : starts[k + 1]].tolist()))
        h: list[tuple[float, float]] = []
        for chain in (pts, pts[::-1]):  # lower chain left to right, then upper right to left
            base = len(h)
            for px, py in chain:
                while len(h) - base >= 2:
                    (ax, ay), (bx, by) = h[-2], h[-1]
                    if (bx - ax) * (py - ay) - (by - ay) * (px - ax) > 0.0:
                        break
                    h.pop()
                h.append((px, py))
            h.pop()  # the chain's last point starts the other chain
        hv.extend(h)
        hs[k + 1] = len(hv)
    return np.array(hv, dtype=np.float64).reshape(-1, 2), hs
