"""Segments against vertical cylinders (and 2-D point-segment distances): the per-pair kernel,
the fused threat and overlap passes, the cylinder grid, and their references."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.obstacle_index import (
    by_content,
    disc_grid,
)

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
    """Contiguous, writable float64 points or paths (``(..., 2 or 3)``), 2-D ones at z = 0
    (what the 3-D kernels, the reservation table and the Dubins curves read;
    :mod:`uavplan.world.kernel_arrays`)."""
    from uavplan.world.kernel_arrays import writable

    p = np.asarray(paths, dtype=np.float64)
    if p.shape[-1] == 2:
        p = np.concatenate([p, np.zeros((*p.shape[:-1], 1))], axis=-1)
    return writable(p)


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
