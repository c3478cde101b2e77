"""Exact, batched geometry kernels: segments against circles, cylinders and polygons.

Every kernel takes polylines as ``(pop, n_points, dim)`` arrays and returns one value per
``(path, segment, obstacle)``, or per path where a cost or check only needs their sum or least
(the fused ``*_batch`` kernels, which never build the (P, N - 1, J) array); the hot ones are
Numba-parallel over the population, and each has a plain NumPy or Python reference
(``*_reference``, or the per-pair kernel) that the tests compare against.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.obstacle_index import GRID_MAX_CELLS as GRID_MAX_CELLS  # re-exported
from uavplan.world.obstacle_index import (
    box_grid,
    box_pad,
    by_content,
    disc_grid,
    segment_boxes,
)
from uavplan.world.tolerances import BOUNDS_TOL, SAT_TOL_REL

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------- point-segment 2-D
def point_segment_distance_2d(a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray:
    """Distance from points ``c`` (J, 2) to 2-D segments ``a -> b`` (..., 2); returns (..., J).

    Plain NumPy; the classic clamp-the-projection formula (SPSO's ``DistP2S``).
    """
    a = np.asarray(a, dtype=np.float64)[..., None, :2]
    b = np.asarray(b, dtype=np.float64)[..., None, :2]
    ab = b - a
    ac = np.asarray(c, dtype=np.float64)[..., :2] - a
    den = np.sum(ab * ab, axis=-1)
    t = np.where(den > 0, np.sum(ac * ab, axis=-1) / np.where(den > 0, den, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    d = ac - t[..., None] * ab
    return np.asarray(np.sqrt(np.sum(d * d, axis=-1)))


@njit(cache=True, inline="always")
def _seg_point_dist(ax, ay, bx, by, cx, cy):  # pragma: no cover - numba
    abx = bx - ax
    aby = by - ay
    acx = cx - ax
    acy = cy - ay
    den = abx * abx + aby * aby
    t = 0.0
    if den > 0.0:
        t = (acx * abx + acy * aby) / den
        t = min(max(t, 0.0), 1.0)
    dx = acx - t * abx
    dy = acy - t * aby
    return np.sqrt(dx * dx + dy * dy)


@population_kernel(error_model="numpy")
def segment_cylinder_distance(paths, centers, z_lo, z_hi):  # pragma: no cover - numba
    """Horizontal distance from each cylinder axis to the part of each segment inside the
    cylinder's vertical extent ``[z_lo, z_hi]``; ``inf`` where no part of the segment is at
    those heights. Exact for vertical cylinders, finite or infinite (``z_lo=-inf, z_hi=inf``
    gives SPSO's 2-D point-to-segment distance).

    The segment is ``a + t e``, t in [0, 1]; the heights clip t to ``[t0, t1]``; the closest
    point to the axis is the xy projection parameter clamped to ``[t0, t1]``.

    Args:
        paths: (P, N, 3) float64.
        centers: (J, 2) axis positions; z_lo, z_hi: (J,).
    Returns:
        (P, N - 1, J) float64.
    """
    P, N, _ = paths.shape
    J = centers.shape[0]
    out = np.empty((P, N - 1, J))
    for p in prange(P):
        for s in range(N - 1):
            for j in range(J):
                out[p, s, j] = seg_cyl_dist(paths, p, s, centers, z_lo, z_hi, j)
    return out


@njit(cache=True, inline="always")
def seg_setup(paths, p, s):  # pragma: no cover - numba
    """Segment ``s`` of path ``p`` as :func:`clipped_dist` takes it: its start, its xy
    direction and that direction's inverse squared length, and its height change's inverse
    (``flat``: none)."""
    ax = paths[p, s, 0]
    ay = paths[p, s, 1]
    az = paths[p, s, 2]
    ex = paths[p, s + 1, 0] - ax
    ey = paths[p, s + 1, 1] - ay
    dz = paths[p, s + 1, 2] - az
    ee = ex * ex + ey * ey
    inv_ee = 1.0 / ee if ee > 0.0 else 0.0
    flat = dz == 0.0
    inv_dz = 1.0 / dz if not flat else 0.0
    return ax, ay, az, ex, ey, inv_ee, flat, inv_dz


@njit(cache=True, inline="always")
def clipped_dist(ax, ay, az, ex, ey, inv_ee, flat, inv_dz, cx, cy, lo, hi):  # pragma: no cover
    """:func:`segment_cylinder_distance` of one segment (as :func:`seg_setup` gives it) to the
    cylinder of axis ``(cx, cy)`` and heights ``[lo, hi]``."""
    if flat:
        t0 = 0.0
        t1 = 1.0 if lo <= az <= hi else -1.0
    else:
        ta = (lo - az) * inv_dz
        tb = (hi - az) * inv_dz
        t0 = max(0.0, min(ta, tb))
        t1 = min(1.0, max(ta, tb))
    qx = cx - ax
    qy = cy - ay
    t = (qx * ex + qy * ey) * inv_ee
    t = min(max(t, t0), t1)
    rx = qx - t * ex
    ry = qy - t * ey
    d = np.sqrt(rx * rx + ry * ry)
    return d if t0 <= t1 else np.inf


@njit(cache=True, inline="always")
def seg_cyl_dist(paths, p, s, centers, z_lo, z_hi, j):  # pragma: no cover - numba
    """:func:`segment_cylinder_distance` of segment ``s`` of path ``p`` to cylinder ``j``."""
    ax, ay, az, ex, ey, inv_ee, flat, inv_dz = seg_setup(paths, p, s)
    return clipped_dist(
        ax, ay, az, ex, ey, inv_ee, flat, inv_dz, centers[j, 0], centers[j, 1], z_lo[j], z_hi[j]
    )


#: The fused kernels' floating-point licence: additions may be reassociated (so that the sums
#: and least values over obstacles run in SIMD lanes); inf and NaN keep IEEE meaning (no
#: ``nnan``/``ninf``) and products are not fused into additions (no ``contract``), so results
#: differ from the per-pair kernel's only by the order of additions (tests: 1e-12 relative,
#: the same infinities).
FUSED_MATH = {"reassoc"}


@population_kernel(error_model="numpy", fastmath=FUSED_MATH)
def cylinder_threat_batch(paths, cx, cy, z_lo, z_hi, r_in, r_out, strict):  # pragma: no cover
    """The linear threat cost summed over every segment and cylinder, (P,), in one pass (no
    (P, N - 1, J) distances; cylinders as structure of arrays: axes ``cx``, ``cy``): with d the
    :func:`segment_cylinder_distance`, a pair adds ``inf`` if ``d < r_in`` (``strict``) or
    ``d <= r_in`` (not strict), ``r_out - d`` if ``d <= r_out``, else 0. PPSwarm's Eqs. (4)-(5)
    are ``r_in = R``, ``r_out = R + S1``, not strict; SPSO's J2 is ``r_in = R + drone size``,
    ``r_out = r_in + 10 drone size``, strict. The same terms as
    :func:`uavplan.problems.costs.threat_cost` of the distances, summed in another order
    (:data:`FUSED_MATH`; equal to 1e-12 relative, the same infinities)."""
    P, N, _ = paths.shape
    J = cx.shape[0]
    out = np.empty(P)
    for p in prange(P):
        total = 0.0
        hits = 0
        for s in range(N - 1):
            ax, ay, az, ex, ey, inv_ee, flat, inv_dz = seg_setup(paths, p, s)
            for j in range(J):
                d = clipped_dist(
                    ax, ay, az, ex, ey, inv_ee, flat, inv_dz, cx[j], cy[j], z_lo[j], z_hi[j]
                )
                hits += 1 if (d < r_in[j] or (not strict and d == r_in[j])) else 0
                total += (r_out[j] - d) if d <= r_out[j] else 0.0
        out[p] = total if hits == 0 else np.inf
    return out


@population_kernel(error_model="numpy", fastmath=FUSED_MATH)
def cylinder_overlap_batch(paths, cx, cy, z_lo, z_hi, radii):  # pragma: no cover - numba
    """Per path, in one pass over segments and cylinders (as structure of arrays): the metres
    inside (the sum of ``max(0, R - d)``) and the least clearance ``min(d - R)`` (inf without
    cylinders), d the :func:`segment_cylinder_distance`; (P,) each. A path hits a cylinder iff
    its clearance is negative."""
    P, N, _ = paths.shape
    J = cx.shape[0]
    inside = np.empty(P)
    clearance = np.empty(P)
    for p in prange(P):
        total = 0.0
        least = np.inf
        for s in range(N - 1):
            ax, ay, az, ex, ey, inv_ee, flat, inv_dz = seg_setup(paths, p, s)
            for j in range(J):
                d = clipped_dist(
                    ax, ay, az, ex, ey, inv_ee, flat, inv_dz, cx[j], cy[j], z_lo[j], z_hi[j]
                )
                gap = d - radii[j]
                total += -gap if gap < 0.0 else 0.0
                least = min(least, gap)
        inside[p] = total
        clearance[p] = least
    return inside, clearance


#: :func:`cylinder_threat`: from this many cylinders on, a uniform grid picks the cylinders
#: near each segment (:func:`cylinder_grid`); below it every pair is tested.
GRID_MIN_CYLINDERS = 64


def cylinder_grid(
    cx: FloatArray, cy: FloatArray, reach: FloatArray
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The :mod:`uavplan.world.obstacle_index` grid over the discs of radius ``reach`` around
    the cylinders' axes (:func:`~uavplan.world.obstacle_index.disc_grid`): ``(grid, starts,
    items, first)``, ``first[c] = (i, j)`` the first cell of cylinder ``c``'s box (its lowest
    corner). The cell side is at least the largest disc's diameter (each disc's box meets two
    cells a side, three where rounding widens it; every one of them lists it) and about the
    side that gives one cylinder per cell."""
    grid, starts, items, span = disc_grid(cx, cy, reach)
    return grid, starts, items, np.ascontiguousarray(span[:, :2])


@population_kernel(error_model="numpy")
def cylinder_grid_pass(
    paths, cx, cy, z_lo, z_hi, radii, r_in, r_out, strict, grid, starts, items, first
):  # pragma: no cover - numba
    """:func:`cylinder_threat_batch` and the metres inside and hits of
    :func:`cylinder_overlap_batch`, with the cylinders near each segment taken from the
    :func:`cylinder_grid` over the discs of radius ``max(r_out, radii)`` (``r_in <= r_out``): a
    cylinder whose disc the segment's bounding box misses adds nothing (d > r_out, d > radii),
    so only the cells the box meets are visited; a cylinder listed in several of them is tested
    in the first one its box and the segment's share, so once per segment, with no per-path
    bookkeeping. Returns ``(threat, inside, hit)``, (P,) each (``hit``: some d < radii), the
    same terms as the every-pair kernels in another order."""
    P, N, _ = paths.shape
    x0, y0, h = grid[0], grid[1], grid[2]
    nx, ny = int(grid[3]), int(grid[4])
    threat = np.empty(P)
    inside = np.empty(P)
    hit = np.zeros(P, dtype=np.bool_)
    for p in prange(P):
        total = 0.0
        hits = 0
        metres = 0.0
        for s in range(N - 1):
            ax, ay, az, ex, ey, inv_ee, flat, inv_dz = seg_setup(paths, p, s)
            bx, by = ax + ex, ay + ey
            i0 = max(int(np.floor((min(ax, bx) - x0) / h)), 0)
            i1 = min(int(np.floor((max(ax, bx) - x0) / h)), nx - 1)
            j0 = max(int(np.floor((min(ay, by) - y0) / h)), 0)
            j1 = min(int(np.floor((max(ay, by) - y0) / h)), ny - 1)
            for jj in range(j0, j1 + 1):
                for ii in range(i0, i1 + 1):
                    k = jj * nx + ii
                    for q in range(starts[k], starts[k + 1]):
                        j = items[q]
                        if ii != max(i0, first[j, 0]) or jj != max(j0, first[j, 1]):
                            continue  # tested in the first cell shared with the segment
                        d = clipped_dist(
                            ax, ay, az, ex, ey, inv_ee, flat, inv_dz, cx[j], cy[j], z_lo[j], z_hi[j]
                        )
                        if d < r_in[j] or (not strict and d == r_in[j]):
                            hits += 1
                        elif d <= r_out[j]:
                            total += r_out[j] - d
                        if d < radii[j]:
                            metres += radii[j] - d
                            hit[p] = True
        threat[p] = total if hits == 0 else np.inf
        inside[p] = metres
    return threat, inside, hit


def as_3d(paths: FloatArray) -> FloatArray:
    """Contiguous float64 points or paths (``(..., 2 or 3)``), 2-D ones at z = 0 (what the
    3-D kernels, the reservation table and the Dubins curves read)."""
    p = np.asarray(paths, dtype=np.float64)
    if p.shape[-1] == 2:
        p = np.concatenate([p, np.zeros((*p.shape[:-1], 1))], axis=-1)
    return np.ascontiguousarray(p)


def soa(
    paths: FloatArray, centers: FloatArray, *per_cylinder: FloatArray
) -> tuple[FloatArray, list[FloatArray]]:
    """Paths as :func:`as_3d` gives them, and the axes' x, y and each per-cylinder array as
    contiguous float64 (the fused kernels' structure of arrays)."""
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 2)
    cols = [np.ascontiguousarray(x, dtype=np.float64) for x in (c[:, 0], c[:, 1], *per_cylinder)]
    return as_3d(paths), cols


def gridded(p: FloatArray, n_cylinders: int) -> bool:
    """Whether the grid serves these paths: enough cylinders, and finite coordinates."""
    return n_cylinders >= GRID_MIN_CYLINDERS and bool(np.isfinite(p[..., :2]).all())


def cylinder_threat(
    paths: FloatArray,
    centers: FloatArray,
    z_lo: FloatArray,
    z_hi: FloatArray,
    r_in: FloatArray,
    r_out: FloatArray,
    strict: bool,
) -> FloatArray:
    """:func:`cylinder_threat_batch` of any paths (2-D ones at z = 0 against the cylinders'
    heights, as :func:`cylinder_distances`), (pop,); from :data:`GRID_MIN_CYLINDERS` cylinders
    on, :func:`cylinder_grid_pass`."""
    p, (cx, cy, lo, hi, a, b) = soa(paths, centers, z_lo, z_hi, r_in, r_out)
    if len(cx) == 0:
        return np.zeros(p.shape[0])
    if gridded(p, len(cx)) and bool(np.all(a <= b)):
        g = by_content("cylinder grid", cylinder_grid, cx, cy, b)
        return np.asarray(cylinder_grid_pass(p, cx, cy, lo, hi, a, a, b, bool(strict), *g)[0])
    return np.asarray(cylinder_threat_batch(p, cx, cy, lo, hi, a, b, bool(strict)))


def cylinder_hits(
    paths: FloatArray, centers: FloatArray, z_lo: FloatArray, z_hi: FloatArray, radii: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The metres inside cylinders and whether a path hits one, (pop,) each: what the cylinder
    check and the graded violation need (:func:`cylinder_grid_pass` from
    :data:`GRID_MIN_CYLINDERS` cylinders on, else :func:`cylinder_overlap`)."""
    p, (cx, cy, lo, hi, r) = soa(paths, centers, z_lo, z_hi, radii)
    if len(cx) == 0:
        return np.zeros(p.shape[0]), np.zeros(p.shape[0], dtype=bool)
    if gridded(p, len(cx)):
        g = by_content("cylinder grid", cylinder_grid, cx, cy, r)
        _, inside, hit = cylinder_grid_pass(p, cx, cy, lo, hi, r, r, r, False, *g)
        return np.asarray(inside), np.asarray(hit)
    inside, clearance = cylinder_overlap(p, centers, z_lo, z_hi, radii)
    return inside, clearance < 0.0


def cylinder_overlap(
    paths: FloatArray, centers: FloatArray, z_lo: FloatArray, z_hi: FloatArray, radii: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`cylinder_overlap_batch` of any paths: metres inside and least clearance, (pop,)."""
    p, (cx, cy, lo, hi, r) = soa(paths, centers, z_lo, z_hi, radii)
    if len(cx) == 0:
        return np.zeros(p.shape[0]), np.full(p.shape[0], np.inf)
    inside, clearance = cylinder_overlap_batch(p, cx, cy, lo, hi, r)
    return np.asarray(inside), np.asarray(clearance)


def cylinder_distances(
    paths: FloatArray, centers: FloatArray, z_lo: FloatArray, z_hi: FloatArray
) -> FloatArray:
    """Horizontal distance d_j from each threat axis to each segment, (pop, n - 1, J).

    Only the part of the segment within the cylinder's heights counts (exact); 2-D paths are
    taken at z = 0 against infinitely tall cylinders.
    """
    p = as_3d(paths)
    J = len(centers)
    if J == 0:
        return np.zeros((p.shape[0], p.shape[1] - 1, 0))
    return np.asarray(
        segment_cylinder_distance(
            p,
            np.ascontiguousarray(centers, dtype=np.float64),
            np.ascontiguousarray(z_lo, dtype=np.float64),
            np.ascontiguousarray(z_hi, dtype=np.float64),
        )
    )


def segment_cylinder_distance_reference(
    paths: FloatArray, centers: FloatArray, z_lo: FloatArray, z_hi: FloatArray
) -> FloatArray:
    """NumPy reference for :func:`segment_cylinder_distance` (same maths, no Numba)."""
    p = np.asarray(paths, dtype=np.float64)
    a = p[:, :-1, None, :]
    b = p[:, 1:, None, :]
    dz = b[..., 2] - a[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = (z_lo - a[..., 2]) / dz
        tb = (z_hi - a[..., 2]) / dz
    lo_t = np.where(dz != 0, np.minimum(ta, tb), 0.0)
    hi_t = np.where(dz != 0, np.maximum(ta, tb), 1.0)
    flat_in = (a[..., 2] >= z_lo) & (a[..., 2] <= z_hi)
    t0 = np.where(dz != 0, np.maximum(lo_t, 0.0), 0.0)
    t1 = np.where(dz != 0, np.minimum(hi_t, 1.0), np.where(flat_in, 1.0, -1.0))
    t0c = np.nan_to_num(t0)
    t1c = np.nan_to_num(t1)
    qa = a[..., :2] + t0c[..., None] * (b[..., :2] - a[..., :2])
    qb = a[..., :2] + t1c[..., None] * (b[..., :2] - a[..., :2])
    ab = qb - qa
    ac = centers[None, None, :, :] - qa
    den = np.sum(ab * ab, axis=-1)
    t = np.where(den > 0, np.sum(ac * ab, axis=-1) / np.where(den > 0, den, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    d = ac - t[..., None] * ab
    dist = np.sqrt(np.sum(d * d, axis=-1))
    return np.asarray(np.where(t0 > t1, np.inf, dist))


# ---------------------------------------------------------------------------- chord inside circles
def segment_circle_inside_fraction(
    paths: FloatArray, centers: FloatArray, radii: FloatArray
) -> FloatArray:
    """Fraction of each segment's parameter range whose ground track lies inside each circle.

    Exact (solves the quadratic |a + t (b - a) - c|^2 = r^2 in the xy plane). Multiply by the
    segment's length to get the length inside (HR-MAGA Eq. 9). Returns (P, N - 1, J).
    A point-like segment counts as fully inside when its point is inside.
    """
    return np.asarray(
        _circle_fraction_kernel(
            np.ascontiguousarray(paths, dtype=np.float64),
            np.ascontiguousarray(np.asarray(centers, dtype=np.float64)[:, :2]),
            np.ascontiguousarray(radii, dtype=np.float64),
        )
    )


@population_kernel(error_model="numpy")
def _circle_fraction_kernel(paths, centers, radii):  # pragma: no cover - numba
    P, N, _ = paths.shape
    J = centers.shape[0]
    out = np.zeros((P, N - 1, J))
    for p in prange(P):
        for s in range(N - 1):
            ax = paths[p, s, 0]
            ay = paths[p, s, 1]
            dx = paths[p, s + 1, 0] - ax
            dy = paths[p, s + 1, 1] - ay
            A = dx * dx + dy * dy
            for j in range(J):
                fx = ax - centers[j, 0]
                fy = ay - centers[j, 1]
                C = fx * fx + fy * fy - radii[j] * radii[j]
                if A == 0.0:
                    out[p, s, j] = 1.0 if C < 0.0 else 0.0
                    continue
                B = 2.0 * (fx * dx + fy * dy)
                disc = B * B - 4.0 * A * C
                if disc <= 0.0:
                    continue
                sq = np.sqrt(disc)
                t0 = min(max((-B - sq) / (2.0 * A), 0.0), 1.0)
                t1 = min(max((-B + sq) / (2.0 * A), 0.0), 1.0)
                out[p, s, j] = t1 - t0
    return out


@njit(cache=True, inline="always")
def _chord(fx, fy, dx, dy, A, C):  # pragma: no cover - numba
    """The fraction of segment a -> a + d inside a circle, ``f = a - centre``, ``A = |d|^2 > 0``,
    ``C = |f|^2 - r^2``: the roots of ``|f + t d|^2 = r^2`` clipped to [0, 1]."""
    B = 2.0 * (fx * dx + fy * dy)
    disc = B * B - 4.0 * A * C
    if disc > 0.0:
        sq = np.sqrt(disc)
        t0 = min(max((-B - sq) / (2.0 * A), 0.0), 1.0)
        t1 = min(max((-B + sq) / (2.0 * A), 0.0), 1.0)
        return t1 - t0
    return 0.0


@njit(cache=True, inline="always")
def _seg2d(paths, p, s):  # pragma: no cover - numba
    """The xy ends of segment ``s`` of path ``p``, its xy direction and that one's squared
    length."""
    ax = paths[p, s, 0]
    ay = paths[p, s, 1]
    bx = paths[p, s + 1, 0]
    by = paths[p, s + 1, 1]
    dx = bx - ax
    dy = by - ay
    return ax, ay, bx, by, dx, dy, dx * dx + dy * dy


def circle_grid(
    cx: FloatArray, cy: FloatArray, r: FloatArray
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The obstacle grid (:func:`uavplan.world.obstacle_index.box_grid`) over circles' boxes."""
    pad = box_pad(cx, cy, r)
    return box_grid(cx - r - pad, cy - r - pad, cx + r + pad, cy + r + pad)


def circle_inside_length(paths: FloatArray, centers: FloatArray, radii: FloatArray) -> FloatArray:
    """Per path (pop,), the length inside circles: each segment's chord fraction through each
    circle (:func:`segment_circle_inside_fraction`: the ground track's; a segment with no
    horizontal extent counts whole when its point is inside) times the segment's length (3-D
    for 3-D paths), summed: HR-MAGA's danger-area length (Eq. 9). From
    :data:`GRID_MIN_OBSTACLES` circles on the circles near each segment come from the obstacle
    grid (:func:`circle_inside_grid`); below (or for paths that are not finite), the (pop,
    n - 1, J) fractions are summed."""
    p = np.ascontiguousarray(paths, dtype=np.float64)
    c = np.asarray(centers, dtype=np.float64).reshape(-1, 2)
    r = np.ascontiguousarray(radii, dtype=np.float64)
    if len(r) == 0:
        return np.zeros(p.shape[0])
    if len(r) >= GRID_MIN_OBSTACLES and bool(np.isfinite(p[..., :2]).all()):
        circ = np.ascontiguousarray(np.stack([c[:, 0], c[:, 1], r]))
        g = by_content("circle grid", circle_grid, circ[0], circ[1], r)
        return np.asarray(circle_inside_grid(p, circ, *g))
    d = np.diff(p, axis=1)
    seg = np.sqrt(np.sum(d * d, axis=-1))
    return np.asarray((segment_circle_inside_fraction(p, c, r) * seg[..., None]).sum(axis=(1, 2)))


@population_kernel(error_model="numpy")
def circle_inside_grid(paths, circ, grid, gstarts, gitems, gspan):  # pragma: no cover - numba
    """:func:`circle_inside_length` with the circles (rows ``cx, cy, r`` of ``circ``) near each
    segment taken from their grid (:func:`circle_grid`), each once, in index order."""
    P, N, D = paths.shape
    J = circ.shape[1]
    out = np.zeros(P)
    none = np.empty(0, dtype=np.int64)
    for blk in prange((P + BLOCK - 1) // BLOCK):  # scratch once per block of paths
        buf = np.empty(J, dtype=np.int64)
        cidx = np.empty(J, dtype=np.int64)
        for p in range(blk * BLOCK, min(P, (blk + 1) * BLOCK)):
            total = 0.0
            for s in range(N - 1):
                ax, ay, bx, by, dx, dy, A = _seg2d(paths, p, s)
                L = A
                for q in range(2, D):
                    dz = paths[p, s + 1, q] - paths[p, s, q]
                    L += dz * dz
                L = np.sqrt(L)
                n_c, _ = _grid_candidates(grid, gstarts, gitems, gspan, J, ax, ay, bx, by, buf,
                                          cidx, none)  # fmt: skip
                for m in range(n_c):
                    j = cidx[m]
                    fx = ax - circ[0, j]
                    fy = ay - circ[1, j]
                    C = fx * fx + fy * fy - circ[2, j] * circ[2, j]
                    if A == 0.0:
                        total += L if C < 0.0 else 0.0
                        continue
                    total += _chord(fx, fy, dx, dy, A, C) * L
            out[p] = total
    return out


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
    count. Plain loops: a path has tens of segments."""
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


# ---------------------------------------------------------------------------- moving things
@njit(cache=True)
def _min_dist_linear(px, py, pz, vx, vy, vz, qx, qy, qz, wx, wy, wz, t0, t1):  # pragma: no cover
    """Min over t in [t0, t1] of |(p + v t) - (q + w t)| for two linear motions."""
    rx = px - qx
    ry = py - qy
    rz = pz - qz
    sx = vx - wx
    sy = vy - wy
    sz = vz - wz
    ss = sx * sx + sy * sy + sz * sz
    tm = t0
    if ss > 0.0:
        tm = -(rx * sx + ry * sy + rz * sz) / ss
        tm = min(max(tm, t0), t1)
    dx = rx + sx * tm
    dy = ry + sy * tm
    dz = rz + sz * tm
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@population_kernel()
def timed_path_min_distance(paths, times, obs_t, obs_xyz):  # pragma: no cover - numba
    """Exact minimum distance over continuous time between timed polylines and one moving point.

    Both move linearly between their knots; the path is not present before ``times[:, 0]`` or
    after ``times[:, -1]``; the obstacle holds its first/last position outside its own knots.

    Args:
        paths: (P, N, 3); times: (P, N) non-decreasing seconds.
        obs_t: (K,) increasing seconds; obs_xyz: (K, 3).
    Returns:
        (P, N - 1): the minimum distance during each segment.
    """
    P, N, _ = paths.shape
    K = obs_t.shape[0]
    out = np.empty((P, N - 1))
    for p in prange(P):
        for s in range(N - 1):
            ta = times[p, s]
            tb = times[p, s + 1]
            ax = paths[p, s, 0]
            ay = paths[p, s, 1]
            az = paths[p, s, 2]
            if tb > ta:
                vx = (paths[p, s + 1, 0] - ax) / (tb - ta)
                vy = (paths[p, s + 1, 1] - ay) / (tb - ta)
                vz = (paths[p, s + 1, 2] - az) / (tb - ta)
            else:
                vx = 0.0
                vy = 0.0
                vz = 0.0
            # path position at time t: a + v (t - ta) = (a - v ta) + v t
            px = ax - vx * ta
            py = ay - vy * ta
            pz = az - vz * ta
            best = np.inf
            # walk the obstacle's pieces: (-inf, t_0], [t_k, t_k+1], [t_K-1, inf)
            for k in range(-1, K):
                if k == -1:
                    lo = -np.inf
                    hi = obs_t[0]
                    qx0 = obs_xyz[0, 0]
                    qy0 = obs_xyz[0, 1]
                    qz0 = obs_xyz[0, 2]
                    wx = 0.0
                    wy = 0.0
                    wz = 0.0
                elif k == K - 1:
                    lo = obs_t[K - 1]
                    hi = np.inf
                    qx0 = obs_xyz[K - 1, 0]
                    qy0 = obs_xyz[K - 1, 1]
                    qz0 = obs_xyz[K - 1, 2]
                    wx = 0.0
                    wy = 0.0
                    wz = 0.0
                else:
                    lo = obs_t[k]
                    hi = obs_t[k + 1]
                    dt = hi - lo
                    wx = (obs_xyz[k + 1, 0] - obs_xyz[k, 0]) / dt
                    wy = (obs_xyz[k + 1, 1] - obs_xyz[k, 1]) / dt
                    wz = (obs_xyz[k + 1, 2] - obs_xyz[k, 2]) / dt
                    qx0 = obs_xyz[k, 0] - wx * lo
                    qy0 = obs_xyz[k, 1] - wy * lo
                    qz0 = obs_xyz[k, 2] - wz * lo
                t0 = max(lo, ta)
                t1 = min(hi, tb)
                if t0 > t1:
                    continue
                d = _min_dist_linear(px, py, pz, vx, vy, vz, qx0, qy0, qz0, wx, wy, wz, t0, t1)
                if d < best:
                    best = d
            out[p, s] = best
    return out


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


#: The indexed and blocked kernels: paths per block (the lanes the 2-D scene pass runs its tests
#: in side by side; the block's scratch arrays are allocated once).
BLOCK = 64
#: :func:`scene2d_batch`: from this many circles and polygons together on, a uniform grid
#: (:mod:`uavplan.world.obstacle_index`) picks the obstacles near each segment; below it every
#: pair is tested (the sums over obstacles then keep their order, so results stay bit for bit
#: those of the every-pair pass).
GRID_MIN_OBSTACLES = 64


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


@njit(cache=True, inline="always")
def _sort_head(a, n):  # pragma: no cover - numba
    """Sort ``a[:n]`` in place (insertion sort for the usual handful, else NumPy's)."""
    if n > 32:
        a[:n] = np.sort(a[:n])
        return
    for q in range(1, n):
        key = a[q]
        r = q - 1
        while r >= 0 and a[r] > key:
            a[r + 1] = a[r]
            r -= 1
        a[r + 1] = key


@njit(cache=True, inline="always")
def _grid_candidates(
    grid, gstarts, gitems, gspan, J, ax, ay, bx, by, buf, cidx, kidx
):  # pragma: no cover - numba
    """The circles (into ``cidx``) and polygons (into ``kidx``, as ``item - J``) listed in the
    cells segment a->b crosses (:func:`uavplan.world.obstacle_index.segment_boxes`, into
    ``buf``), each once and in increasing order (so that sums over them keep the every-pair
    order); returns their counts."""
    n = segment_boxes(grid, gstarts, gitems, gspan, ax, ay, bx, by, buf)
    n_c = 0
    n_k = 0
    for q in range(n):
        b = buf[q]
        if b < J:
            cidx[n_c] = b
            n_c += 1
        else:
            kidx[n_k] = b - J
            n_k += 1
    _sort_head(cidx, n_c)
    _sort_head(kidx, n_k)
    return n_c, n_k


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
    p = np.ascontiguousarray(paths, dtype=np.float64)
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
