"""The 2-D scene pass: circles and polygons together, in blocks of paths side by side, every
pair or on the obstacle grid."""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.geometry._grid import BLOCK, GRID_MIN_OBSTACLES, _grid_candidates
from uavplan.world.geometry.circles import _chord, _seg2d
from uavplan.world.geometry.polygons import (
    _convex_clip,
    _inside_fraction_and_touch,
    _inside_fraction_one,
    _point_in_polygon,
    _seg_seg_distance,
    convex_hulls,
    polygon_convexity,
)
from uavplan.world.kernel_arrays import writable
from uavplan.world.obstacle_index import (
    box_grid,
    box_pad,
)
from uavplan.world.tolerances import BOUNDS_TOL, SAT_TOL_REL

FloatArray = NDArray[np.float64]


def hull_edges(
    verts: FloatArray, starts: NDArray[np.int64]
) -> tuple[FloatArray, NDArray[np.int64]]:
    """The edges of the polygons' counter-clockwise convex hulls (:func:`convex_hulls`), packed
    with starts (K + 1,): per edge ``q`` (from hull vertex ``q - 1`` to ``q``, cyclic in each
    hull) its outward normal ``(nx, ny)`` (the edge turned clockwise, as long as the edge), its
    offset ``c = n . v`` and ``|nx| + |ny|``, (E, 4)."""
    hull_v, hull_s = convex_hulls(verts, starts)
    edges = np.zeros((len(hull_v), 4))
    for k in range(len(hull_s) - 1):
        v = hull_v[hull_s[k] : hull_s[k + 1]]
        prev = np.roll(v, 1, axis=0)
        e = v - prev
        n = np.c_[e[:, 1], -e[:, 0]]
        edges[hull_s[k] : hull_s[k + 1]] = np.c_[n, np.sum(n * prev, axis=1), np.abs(n).sum(axis=1)]
    return edges, hull_s


def scene_prep(
    centers: FloatArray,
    radii: FloatArray,
    verts: FloatArray,
    starts: NDArray[np.int64],
    margins: FloatArray,
    gridded: bool | None = None,
) -> tuple[Any, ...]:
    """What :func:`scene2d_kernel` needs of a world's circles and polygons besides their
    vertices, worked out once per world (NumPy/Python): the circles as rows ``(cx, cy, r)``
    (3, C); per polygon the rows ``(x_min, y_min, x_max, y_max, margin, margin^2, scale)``
    (7, K) (``scale``: 1 + the largest vertex coordinate's magnitude); convexity (K,); the
    convex hulls' edges (:func:`hull_edges`); the most vertices of one polygon; and from
    :data:`GRID_MIN_OBSTACLES` obstacles on (or as ``gridded`` says) the grid over the circles'
    boxes (items ``0..C-1``) and the polygons' boxes grown by their margins (items
    ``C..C+K-1``), else an empty one."""
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 2)
    r = np.asarray(radii, dtype=np.float64)
    circ = np.ascontiguousarray(np.stack([c[:, 0], c[:, 1], r]))
    K = len(starts) - 1
    m = np.maximum(np.asarray(margins, dtype=np.float64), 0.0)
    if K > 0:
        box = [
            np.minimum.reduceat(verts[:, 0], starts[:-1]),
            np.minimum.reduceat(verts[:, 1], starts[:-1]),
            np.maximum.reduceat(verts[:, 0], starts[:-1]),
            np.maximum.reduceat(verts[:, 1], starts[:-1]),
        ]
        scale = 1.0 + np.maximum.reduceat(np.abs(verts).max(axis=1), starts[:-1])
    else:
        box = [np.zeros(0)] * 4
        scale = np.zeros(0)
    raw = np.asarray(margins, dtype=np.float64)
    poly = np.ascontiguousarray(np.stack([*box, raw, m * m, scale]))
    convex = polygon_convexity(verts, starts)
    edges, hull_s = hull_edges(verts, starts)
    maxv = int(np.diff(starts).max()) if K > 0 else 0
    J = len(r)
    if gridded is None:
        gridded = J + K >= GRID_MIN_OBSTACLES
    if gridded and J + K > 0:
        pc = box_pad(c[:, 0], c[:, 1], r)
        pp = box_pad(*box) + m if K > 0 else np.zeros(0)
        g = box_grid(
            np.r_[c[:, 0] - r - pc, box[0] - pp],
            np.r_[c[:, 1] - r - pc, box[1] - pp],
            np.r_[c[:, 0] + r + pc, box[2] + pp],
            np.r_[c[:, 1] + r + pc, box[3] + pp],
        )
    else:
        g = (np.zeros(5), np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64),
             np.zeros((0, 4), dtype=np.int64))  # fmt: skip
    return (circ, poly, convex, edges, hull_s, maxv, *g)


@njit(cache=True, inline="always")
def _hull_missed(ax, ay, bx, by, edges, e0, e1, tol):  # pragma: no cover - numba
    """True if segment a->b misses the convex hull whose edges ``edges[e0:e1]`` describes
    (:func:`hull_edges`), grown by ``tol`` times each edge normal's 1-norm (Cyrus-Beck,
    stopping as soon as the interval empties): a conservative rejection, never of a segment
    that touches the polygon, whatever the rounding."""
    rx = bx - ax
    ry = by - ay
    t_in = 0.0
    t_out = 1.0
    for q in range(e0, e1):
        nx = edges[q, 0]
        ny = edges[q, 1]
        num = nx * ax + ny * ay - edges[q, 2] - tol * edges[q, 3]  # > 0: a outside this edge
        den = nx * rx + ny * ry
        if den == 0.0:
            if num > 0.0:
                return True
        elif den < 0.0:
            t_in = max(t_in, -num / den)
        else:
            t_out = min(t_out, -num / den)
        if t_in > t_out:
            return True
    return False


@njit(cache=True, inline="always")
def _box_gap2(sx0, sy0, sx1, sy1, poly, k):  # pragma: no cover - numba
    """The squared distance between the box ``[sx0, sx1] x [sy0, sy1]`` and polygon k's."""
    gx = max(0.0, max(sx0 - poly[2, k], poly[0, k] - sx1))
    gy = max(0.0, max(sy0 - poly[3, k], poly[1, k] - sy1))
    return gx * gx + gy * gy


@njit(cache=True, inline="always")
def _polygon_exact(
    ax, ay, bx, by, A, L, verts, starts, poly, convex, edges, hull_s, k, gap2, phit, ts
):  # pragma: no cover - numba
    """Segment a->b (``A = |b - a|^2``, ``L = |b - a|``) and polygon k (:func:`scene_prep`'s
    data) whose box is within its margin of the segment's (``gap2``: the boxes' squared
    distance): whether the segment touches the polygon or comes closer than its margin, and the
    length of segment inside. Without a margin, a convex polygon is clipped (Cyrus-Beck); a
    non-convex one is skipped when the segment misses its convex hull, else split at the edge
    crossings. With a margin (or a zero-length segment) the clearance is measured unless
    ``phit`` (already known for this path). ``ts``: scratch of the most vertices + 2."""
    v0 = starts[k]
    v1 = starts[k + 1]
    margin = poly[4, k]
    if margin <= 0.0 and A > 0.0:
        if convex[k] != 0:
            t_in, t_out = _convex_clip(ax, ay, bx, by, verts, v0, v1, convex[k])
            if t_in <= t_out:
                return True, (t_out - t_in) * L
            return False, 0.0
        seg_scale = 1.0 + max(max(abs(ax), abs(bx)), max(abs(ay), abs(by)))
        g = SAT_TOL_REL * (seg_scale + poly[6, k])
        if _hull_missed(ax, ay, bx, by, edges, hull_s[k], hull_s[k + 1], g):
            return False, 0.0  # clear of the convex hull, so of the polygon
        frac, touch = _inside_fraction_and_touch(ax, ay, bx, by, verts, v0, v1, ts)
        return touch, frac * L
    hit = False
    if not phit:  # clearance: touching or closer than the margin
        if _point_in_polygon(ax, ay, verts, v0, v1):
            hit = True
        else:
            jj = v1 - 1
            for i in range(v0, v1):
                d = _seg_seg_distance(ax, ay, bx, by, verts[jj, 0], verts[jj, 1], verts[i, 0],
                                      verts[i, 1])  # fmt: skip
                if d <= 0.0 or d < margin:
                    hit = True
                    break
                jj = i
    if gap2 > 0.0 or A == 0.0:
        return hit, 0.0
    return hit, _inside_fraction_one(ax, ay, bx, by, verts, v0, v1, ts) * L


@njit(cache=True, inline="always")
def _circle_pair(ax, ay, dx, dy, A, inv_a, L, cx, cy, r):  # pragma: no cover - numba
    """Segment a -> a + d (``A = |d|^2``, ``inv_a = 1 / A`` or 0, ``L = |d|``) and the circle
    ``(cx, cy, r)``: whether the segment comes closer than ``r`` to the centre, and the length
    of its chord inside the circle (scalars only: no array to count references of)."""
    fx = ax - cx
    fy = ay - cy
    # squared distance from the centre to the segment
    t = min(max(-(fx * dx + fy * dy) * inv_a, 0.0), 1.0)
    qx = fx + t * dx
    qy = fy + t * dy
    if qx * qx + qy * qy >= r * r:
        return False, 0.0  # the segment stays out of the open disc: no hit, no chord
    if A == 0.0:
        return True, 0.0
    return True, _chord(fx, fy, dx, dy, A, fx * fx + fy * fy - r * r) * L


# compiled once as its own function (see :func:`uavplan.world.reservations.path_query_from`)
@njit(cache=True)
def segment_scene_hit(
    ax, ay, bx, by, verts, starts, circ, poly, convex, edges, hull_s, ts
):  # pragma: no cover - numba
    """Whether the ground track a->b of one segment comes closer than its radius to a circle's
    centre, or touches a polygon or comes closer than its margin (:func:`scene_prep`'s data;
    ``ts``: scratch of the most vertices + 2): one segment's ``circle_hit | polygon_hit`` of
    :func:`scene2d_kernel`, by the same box test and :func:`_polygon_exact`, for the fused
    static kernel of 3-D paths (:mod:`uavplan.problems._validity_kernels`)."""
    dx = bx - ax
    dy = by - ay
    A = dx * dx + dy * dy
    inv_a = 1.0 / A if A > 0.0 else 0.0
    L = np.sqrt(A)
    for j in range(circ.shape[1]):
        if _circle_pair(ax, ay, dx, dy, A, inv_a, L, circ[0, j], circ[1, j], circ[2, j])[0]:
            return True
    sx0, sx1 = min(ax, bx), max(ax, bx)
    sy0, sy1 = min(ay, by), max(ay, by)
    for k in range(starts.shape[0] - 1):
        g2 = _box_gap2(sx0, sy0, sx1, sy1, poly, k)
        if g2 > 0.0 and g2 >= poly[5, k]:
            continue
        hit = _polygon_exact(
            ax, ay, bx, by, A, L, verts, starts, poly, convex, edges, hull_s, k, g2, False, ts
        )[0]
        if hit:
            return True
    return False


def scene2d_batch(
    paths: FloatArray,
    centers: FloatArray,
    radii: FloatArray,
    verts: FloatArray,
    starts: NDArray[np.int64],
    margins: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    prep: tuple[Any, ...] | None = None,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
    """One pass over every (path, segment, obstacle) of a scene of circles and polygons, with
    the world's :func:`scene_prep` (given, as a world keeps it, or worked out here): on the
    obstacle grid when the world has one (:func:`scene2d_grid_kernel`; paths with coordinates
    that are not finite test every pair), else testing every pair (:func:`scene2d_kernel`).
    The two return the same bits.

    The fused form of :func:`segment_circle_inside_fraction`,
    :func:`segment_polygon_inside_fraction`, :func:`segment_cylinder_distance` (infinite, for
    circles), :func:`segment_polygon_distance` and the bounds test that the 2-D cost and
    feasibility need, without the (P, N - 1, J) intermediates. Only the xy coordinates of
    ``paths`` (P, N, >= 2) are used; ``lo``, ``hi``: the (2,) box, with a 1e-9 tolerance.

    Returns:
        length: (P,) xy path length;
        inside: (P,) length of path inside circles and polygons;
        circle_hit: (P,) bool, some segment closer than ``radii`` to a circle's centre;
        polygon_hit: (P,) bool, some segment touching a polygon or closer than its margin;
        outside: (P,) bool, some node outside the box.
    """
    if prep is None:
        prep = scene_prep(centers, radii, verts, starts, margins)
    p = writable(paths)
    if prep[-4][3] > 0 and np.isfinite(p[..., :2]).all():
        return scene2d_grid_kernel(p, verts, starts, lo, hi, *prep)
    return scene2d_kernel(p, verts, starts, lo, hi, *prep[:-4])


@njit(cache=True)
def _scene_outputs(P):  # pragma: no cover - numba
    """The 2-D scene pass's outputs for P paths, zeroed (see :func:`scene2d_batch`)."""
    flags = np.zeros((3, P), dtype=np.bool_)
    return np.zeros(P), np.zeros(P), flags[0], flags[1], flags[2]


@population_kernel(error_model="numpy")
def scene2d_kernel(
    paths, verts, starts, lo, hi, circ, poly, convex, edges, hull_s, maxv
):  # pragma: no cover - numba
    """:func:`scene2d_batch` testing every pair, in blocks of :data:`BLOCK` paths whose
    coordinates are laid out side by side: per segment index, each circle's distance test and
    each polygon's box test run over the block's paths at once (loops without branches, in SIMD
    lanes), then the exact work for the pairs that pass (the circle's chord,
    :func:`_polygon_exact`). Each path's sums take its segments in order and, per segment, its
    circles then its polygons in index order; a repeated node (a zero-length segment after the
    first) is skipped, its point tested as the previous segment's end."""
    P, N, _ = paths.shape
    J = circ.shape[1]
    K = starts.shape[0] - 1
    length, inside, circle_hit, polygon_hit, outside = _scene_outputs(P)
    tol = BOUNDS_TOL
    for blk in prange((P + BLOCK - 1) // BLOCK):
        p0 = blk * BLOCK
        m = min(P, p0 + BLOCK) - p0
        xs = np.empty((N, m))
        ys = np.empty((N, m))
        for q in range(m):
            for s in range(N):
                xs[s, q] = paths[p0 + q, s, 0]
                ys[s, q] = paths[p0 + q, s, 1]
        ts = np.empty(maxv + 2)
        total = np.zeros(m)
        plen = np.zeros(m)
        chit = np.zeros(m, dtype=np.bool_)
        phit = np.zeros(m, dtype=np.bool_)
        out = np.zeros(m, dtype=np.bool_)
        dx = np.empty(m)
        dy = np.empty(m)
        A = np.empty(m)
        inv_a = np.empty(m)
        L = np.empty(m)
        near = np.empty(m, dtype=np.bool_)
        gap2 = np.empty(m)
        for s in range(N):
            x = xs[s]
            y = ys[s]
            for q in range(m):
                out[q] |= (
                    (x[q] < lo[0] - tol)
                    | (x[q] > hi[0] + tol)
                    | (y[q] < lo[1] - tol)
                    | (y[q] > hi[1] + tol)
                )
        for s in range(N - 1):
            ax = xs[s]
            ay = ys[s]
            bx = xs[s + 1]
            by = ys[s + 1]
            first = s == 0
            for q in range(m):
                d0 = bx[q] - ax[q]
                d1 = by[q] - ay[q]
                aa = d0 * d0 + d1 * d1
                dx[q] = d0
                dy[q] = d1
                A[q] = aa
                ll = np.sqrt(aa)
                L[q] = ll
                plen[q] += ll  # + 0 for a zero-length segment
                inv_a[q] = 1.0 / aa if aa > 0.0 else 0.0
            for j in range(J):
                cx = circ[0, j]
                cy = circ[1, j]
                r2 = circ[2, j] * circ[2, j]
                n_near = 0
                for q in range(m):  # the distance tests side by side
                    fx = ax[q] - cx
                    fy = ay[q] - cy
                    t = min(max(-(fx * dx[q] + fy * dy[q]) * inv_a[q], 0.0), 1.0)
                    qx = fx + t * dx[q]
                    qy = fy + t * dy[q]
                    c = (not (qx * qx + qy * qy >= r2)) & ((A[q] != 0.0) | first)
                    near[q] = c
                    n_near += c
                if n_near == 0:
                    continue
                for q in range(m):  # inside the open disc: a hit, and the chord
                    if near[q]:
                        chit[q] = True
                        if A[q] > 0.0:
                            fx = ax[q] - cx
                            fy = ay[q] - cy
                            C = fx * fx + fy * fy - r2
                            total[q] += _chord(fx, fy, dx[q], dy[q], A[q], C) * L[q]
            for k in range(K):
                n_near = 0
                for q in range(m):  # the box tests side by side
                    gx = max(
                        0.0, max(min(ax[q], bx[q]) - poly[2, k], poly[0, k] - max(ax[q], bx[q]))
                    )
                    gy = max(
                        0.0, max(min(ay[q], by[q]) - poly[3, k], poly[1, k] - max(ay[q], by[q]))
                    )
                    g2 = gx * gx + gy * gy
                    c = (not ((g2 > 0.0) & (g2 >= poly[5, k]))) & ((A[q] != 0.0) | first)
                    gap2[q] = g2
                    near[q] = c
                    n_near += c
                if n_near == 0:
                    continue
                for q in range(m):
                    if near[q]:
                        h, add = _polygon_exact(ax[q], ay[q], bx[q], by[q], A[q], L[q], verts,
                                                starts, poly, convex, edges, hull_s, k, gap2[q],
                                                phit[q], ts)  # fmt: skip
                        phit[q] |= h
                        total[q] += add
        for q in range(m):
            length[p0 + q] = plen[q]
            inside[p0 + q] = total[q]
            circle_hit[p0 + q] = chit[q]
            polygon_hit[p0 + q] = phit[q]
            outside[p0 + q] = out[q]
    return length, inside, circle_hit, polygon_hit, outside


@population_kernel(error_model="numpy")
def scene2d_grid_kernel(
    paths,
    verts,
    starts,
    lo,
    hi,
    circ,
    poly,
    convex,
    edges,
    hull_s,
    maxv,
    grid,
    gstarts,
    gitems,
    gspan,
):  # pragma: no cover - numba
    """:func:`scene2d_batch` on the obstacle grid (paths with finite coordinates): each
    segment's circles and polygons are those listed in the cells it crosses
    (:func:`_grid_candidates`), each once and in index order, so the sums and verdicts are
    :func:`scene2d_kernel`'s bit for bit."""
    P, N, _ = paths.shape
    J = circ.shape[1]
    K = starts.shape[0] - 1
    length, inside, circle_hit, polygon_hit, outside = _scene_outputs(P)
    tol = BOUNDS_TOL
    for blk in prange((P + BLOCK - 1) // BLOCK):  # scratch once per block of paths
        ts = np.empty(maxv + 2)
        buf = np.empty(J + K, dtype=np.int64)
        cidx = np.empty(J, dtype=np.int64)
        kidx = np.empty(K, dtype=np.int64)
        for p in range(blk * BLOCK, min(P, (blk + 1) * BLOCK)):
            total = 0.0
            plen = 0.0
            chit = False
            phit = False
            out = False
            for s in range(N):
                x = paths[p, s, 0]
                y = paths[p, s, 1]
                if x < lo[0] - tol or x > hi[0] + tol or y < lo[1] - tol or y > hi[1] + tol:
                    out = True
            for s in range(N - 1):
                ax, ay, bx, by, dx, dy, A = _seg2d(paths, p, s)
                if A == 0.0 and s > 0:
                    continue  # a repeated node: the point was tested as the previous segment's end
                L = np.sqrt(A)
                plen += L
                inv_a = 1.0 / A if A > 0.0 else 0.0
                n_c, n_k = _grid_candidates(grid, gstarts, gitems, gspan, J, ax, ay, bx, by, buf,
                                            cidx, kidx)  # fmt: skip
                for i in range(n_c):
                    j = cidx[i]
                    h, add = _circle_pair(ax, ay, dx, dy, A, inv_a, L, circ[0, j], circ[1, j],
                                          circ[2, j])  # fmt: skip
                    chit = chit or h
                    total += add
                sx0 = min(ax, bx)
                sy0 = min(ay, by)
                sx1 = max(ax, bx)
                sy1 = max(ay, by)
                for i in range(n_k):
                    k = kidx[i]
                    gap2 = _box_gap2(sx0, sy0, sx1, sy1, poly, k)
                    if gap2 > 0.0 and gap2 >= poly[5, k]:
                        continue  # clear of polygon k, and nothing inside it
                    h, add = _polygon_exact(ax, ay, bx, by, A, L, verts, starts, poly, convex,
                                            edges, hull_s, k, gap2, phit, ts)  # fmt: skip
                    phit = phit or h
                    total += add
            length[p] = plen
            inside[p] = total
            circle_hit[p] = chit
            polygon_hit[p] = phit
            outside[p] = out
    return length, inside, circle_hit, polygon_hit, outside
