"""Path cost terms, one function per term, each evaluating a whole population at once.

Shapes: ``paths`` is ``(pop, n_points, dim)`` float64 metres (start and goal included, dim 2 or
3, x east, y north, z up); every term returns ``(pop,)``. Infinite values mark violated hard
constraints where the paper does so (PPSwarm "penalize it with a cost of infinity").

References:
    PPSwarm: Meng, Chen, Qu, "PPSwarm", Drones 2024, Eqs. (2)-(13).
    SPSO: Phung & Ha, Applied Soft Computing 107 (2021), reference MATLAB ``MyCost.m``.
    HR-MAGA: Yang, Liu, Li, Eqs. (4)-(9).
    RGG-PSO+: Liu et al. 2024, Sect. 3 (path length as the cost; collisions infeasible).
"""

from __future__ import annotations

import numpy as np
from numba import prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.geometry import (
    circle_inside_length,
    segment_circle_inside_fraction,
    segment_polygon_inside_fraction,
)

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------- length
def segment_lengths(paths: FloatArray) -> FloatArray:
    """Euclidean length of every segment, (pop, n_points - 1) (PPSwarm Eq. 3)."""
    d = np.diff(np.asarray(paths, dtype=np.float64), axis=1)
    return np.asarray(np.sqrt(np.sum(d * d, axis=-1)))


def length_cost(paths: FloatArray) -> FloatArray:
    """PPSwarm Eqs. (2)-(3), HR-MAGA Eq. (7), RGG-PSO+ cost: total path length, (pop,).

    Works for 2-D and 3-D paths alike (the 2-D length of the RGG-PSO+ scenes).
    """
    return np.asarray(segment_lengths(paths).sum(axis=1))


# ---------------------------------------------------------------------------- threats
def threat_cost(dist: FloatArray, radius: FloatArray, s1: float) -> FloatArray:
    """PPSwarm Eqs. (4)-(5): sum over segments and threats of
    0 if d > S1 + R; (S1 + R) - d if R < d <= S1 + R; inf if d <= R.

    Args:
        dist: (pop, n - 1, J) distances d_j (see :func:`cylinder_distances`).
        radius: (J,) radii R_j (including any safety margin).
        s1: the safety band S1 (metres).
    """
    R = np.asarray(radius, dtype=np.float64)
    band = np.where(dist > R + s1, 0.0, (R + s1) - dist)
    tr = np.where(dist <= R, np.inf, band)
    return np.asarray(tr.sum(axis=(1, 2)))


def threat_cost_spso(
    dist: FloatArray, radius: FloatArray, drone_size: float | FloatArray = 1.0
) -> FloatArray:
    """SPSO's threat cost J2 (``MyCost.m``): d is the 2-D point-to-segment distance to the
    threat's centre (threats infinitely tall); collision (inf) if ``d < R + drone_size``; a linear
    penalty ``(R + drone_size + danger) - d`` inside the danger band ``danger = 10 drone_size``.
    ``drone_size`` may be given per threat, (J,)."""
    drone_size = np.asarray(drone_size, dtype=np.float64)
    R = np.asarray(radius, dtype=np.float64) + drone_size
    danger = 10.0 * drone_size
    cost = np.where(dist > R + danger, 0.0, (R + danger) - dist)
    cost = np.where(dist < R, np.inf, cost)
    return np.asarray(cost.sum(axis=(1, 2)))


# ---------------------------------------------------------------------------- altitude
def altitude_cost(h: FloatArray, h_min: float, h_max: float) -> FloatArray:
    """PPSwarm Eqs. (6)-(7): sum over nodes of |h_i - (h_max + h_min)/2| inside the band, inf
    outside. ``h``: (pop, n) altitudes in the band's reference (above ground or absolute)."""
    mid = 0.5 * (h_max + h_min)
    cost = np.where((h >= h_min) & (h <= h_max), np.abs(h - mid), np.inf)
    return np.asarray(cost.sum(axis=1))


def altitude_cost_spso(z_rel: FloatArray, z_min: float, z_max: float) -> FloatArray:
    """SPSO's J3 (``MyCost.m``): over the free nodes, inf if below ground (z_rel < 0), else
    |z_rel - (z_max + z_min)/2|. ``z_rel``: (pop, n_free) heights above the terrain."""
    mid = 0.5 * (z_max + z_min)
    cost = np.where(z_rel < 0, np.inf, np.abs(z_rel - mid))
    return np.asarray(cost.sum(axis=1))


# ---------------------------------------------------------------------------- smoothness
def turn_angles(paths: FloatArray) -> FloatArray:
    """Turning angle at each interior node, radians in [0, pi], (pop, n - 2).

    PPSwarm Eq. (8) prints arctan(|a x b| / (|a| |b|)), which is arctan(sin(theta)): it is not
    monotone (a U-turn would score 0). We use the angle it intends, atan2(|a x b|, a . b).
    """
    p = np.asarray(paths, dtype=np.float64)
    a = p[:, 1:-1] - p[:, :-2]
    b = p[:, 2:] - p[:, 1:-1]
    if p.shape[-1] == 2:
        cross = np.abs(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])
    else:
        cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    return np.asarray(np.arctan2(cross, dot))


def climb_angles(paths: FloatArray) -> FloatArray:
    """PPSwarm Eq. (9): arctan((z_{i+1} - z_i) / |P_i P_{i+1}|) per segment, (pop, n - 1)."""
    p = np.asarray(paths, dtype=np.float64)
    dz = np.diff(p[..., 2], axis=1)
    L = segment_lengths(p)
    return np.asarray(np.arctan2(dz, L))


def smoothness_cost(paths: FloatArray, a1: float = 1.0, a2: float = 1.0) -> FloatArray:
    """PPSwarm Eq. (10): a1 * sum of turning angles + a2 * sum of |climb angle changes|
    (radians). 2-D paths have no climb term."""
    cost = a1 * turn_angles(paths).sum(axis=1)
    if np.shape(paths)[-1] == 3:
        psi = climb_angles(paths)
        cost = cost + a2 * np.abs(np.diff(psi, axis=1)).sum(axis=1)
    return np.asarray(cost)


def smoothness_cost_spso(
    paths: FloatArray, turning_max: float = 45.0, climb_max: float = 45.0
) -> FloatArray:
    """SPSO's J4 (``MyCost.m``), in degrees: at each interior node, the turning angle between the
    xy projections of the adjacent segments (a zero-length projection is replaced by the nearest
    non-zero one before it / after it, as the reference loops do) and the change of climb angle
    atan2(dz, |projection|); each adds its absolute value when it exceeds its 45-degree limit."""
    p = np.ascontiguousarray(paths, dtype=np.float64)
    return np.asarray(_smoothness_spso_kernel(p, float(turning_max), float(climb_max)))


@population_kernel()
def _smoothness_spso_kernel(p, turning_max, climb_max):  # pragma: no cover - numba
    P, N, _ = p.shape
    out = np.zeros(P)
    deg = 180.0 / np.pi
    for q in prange(P):
        total = 0.0
        for i in range(N - 2):
            # segment1: last non-zero xy projection among segments i, i-1, ..., 0 (else 0)
            j1 = i
            while j1 > 0 and p[q, j1 + 1, 0] == p[q, j1, 0] and p[q, j1 + 1, 1] == p[q, j1, 1]:
                j1 -= 1
            # segment2: first non-zero among segments i+1, ..., N-2 (else N-2)
            j2 = i + 1
            while j2 < N - 2 and p[q, j2 + 1, 0] == p[q, j2, 0] and p[q, j2 + 1, 1] == p[q, j2, 1]:
                j2 += 1
            ax = p[q, j1 + 1, 0] - p[q, j1, 0]
            ay = p[q, j1 + 1, 1] - p[q, j1, 1]
            bx = p[q, j2 + 1, 0] - p[q, j2, 0]
            by = p[q, j2 + 1, 1] - p[q, j2, 1]
            n1 = np.sqrt(ax * ax + ay * ay)
            n2 = np.sqrt(bx * bx + by * by)
            climb1 = np.arctan2(p[q, i + 1, 2] - p[q, i, 2], n1) * deg
            climb2 = np.arctan2(p[q, i + 2, 2] - p[q, i + 1, 2], n2) * deg
            turning = abs(np.arctan2(abs(ax * by - ay * bx), ax * bx + ay * by) * deg)
            if turning > turning_max:
                total += turning
            dclimb = abs(climb2 - climb1)
            if dclimb > climb_max:
                total += dclimb
        out[q] = total
    return out


# ---------------------------------------------------------------------------- HR-MAGA
def hrmaga_altitude_cost(mean_heights: FloatArray) -> FloatArray:
    """HR-MAGA Eq. (8): sum over segments of the mean terrain height under the segment.

    ``mean_heights``: (pop, n - 1) from :meth:`uavplan.world.terrain.Terrain.mean_height` (the
    exact mean of the bilinear terrain along the ground track; the paper averages the map cells
    the segment crosses)."""
    return np.asarray(np.asarray(mean_heights).sum(axis=1))


def danger_length_cost(paths: FloatArray, centers: FloatArray, radii: FloatArray) -> FloatArray:
    """HR-MAGA Eq. (9): total length of path inside the cylindrical danger areas, (pop,).

    Exact: the chord of each segment's ground track through each circle, scaled to the
    segment's 3-D length.
    """
    return circle_inside_length(paths, centers, radii)  # indexed from 64 areas on


# ---------------------------------------------------------------------------- 2-D scenes
def inside_length_2d(
    paths: FloatArray,
    circle_centers: FloatArray,
    circle_radii: FloatArray,
    poly_verts: FloatArray,
    poly_starts: NDArray[np.int64],
) -> FloatArray:
    """Length of path inside circles and polygons (exact), (pop,). Zero iff collision-free
    (up to touching)."""
    p = np.ascontiguousarray(paths, dtype=np.float64)
    L = segment_lengths(p)
    total = np.zeros(p.shape[0])
    if len(circle_radii):
        total += (
            segment_circle_inside_fraction(p, circle_centers, circle_radii) * L[..., None]
        ).sum(axis=(1, 2))
    if len(poly_starts) > 1:
        frac = segment_polygon_inside_fraction(p, poly_verts, poly_starts)
        total += (frac * L[..., None]).sum(axis=(1, 2))
    return total


def penalized_length_cost(
    length: FloatArray, inside: FloatArray, beta: float = 100.0
) -> FloatArray:
    """Length with a collision penalty, L (1 + beta V), V = inside length / L (the classic PSO
    path-planning form, e.g. Yarpiz's; RGG-PSO+ leaves the penalty unspecified).

    Computed as ``L + beta * inside``, the same value: the inside length is part of the length,
    so ``inside = 0`` whenever ``L = 0``, and no division is needed.
    """
    return np.asarray(length + beta * np.asarray(inside))


# ---------------------------------------------------------------------------- timing
def path_times(paths: FloatArray, speed: float, start_time: float = 0.0) -> FloatArray:
    """Arrival time at each node flying at constant ``speed``, (pop, n) seconds."""
    L = segment_lengths(paths)
    t = np.concatenate([np.zeros((L.shape[0], 1)), np.cumsum(L, axis=1)], axis=1) / speed
    return np.asarray(t + start_time)


def moving_threat_cost(min_dist: FloatArray, radius: FloatArray, s1: float) -> FloatArray:
    """PPSwarm's Eq. (5) form applied to moving obstacles: ``min_dist`` (pop, n - 1, K) is the
    exact minimum distance over time between each segment and each moving obstacle."""
    return threat_cost(min_dist, radius, s1)
