"""Segments against circles in 2-D: the length of a path inside them (chords), every pair or on
a grid."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.geometry._grid import BLOCK, GRID_MIN_OBSTACLES, _grid_candidates
from uavplan.world.obstacle_index import (
    box_grid,
    box_pad,
    by_content,
)

FloatArray = NDArray[np.float64]


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
