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
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world._terrain_kernels import ground_one
from uavplan.world.geometry import (
    circle_inside_length,
    clipped_dist,
    seg_setup,
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
def altitude_target(h_min: float, h_max: float, cruise: float | None = None) -> float:
    """The height PPSwarm's altitude cost pulls toward: the band's middle (Eq. 7), or a UAV's
    cruise layer (:attr:`uavplan.world.scenario.Task.cruise`) when it has one."""
    return float(cruise) if cruise is not None else 0.5 * (h_max + h_min)


def altitude_cost(
    h: FloatArray, h_min: float, h_max: float, cruise: float | None = None
) -> FloatArray:
    """PPSwarm Eqs. (6)-(7): sum over nodes of |h_i - (h_max + h_min)/2| inside the band, inf
    outside. ``h``: (pop, n) altitudes in the band's reference (above ground or absolute).
    ``cruise``: a cruise layer's height to pull toward instead (:func:`altitude_target`)."""
    mid = altitude_target(h_min, h_max, cruise)
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


@njit(cache=True, inline="always")
def _spso_projections(p, q, i):  # pragma: no cover - numba
    """The xy projections J4 compares at interior node ``i + 1`` of path ``q``: the last non-zero
    one among segments i, i-1, ..., 0 (else segment 0's) and the first non-zero one among
    segments i+1, ..., N-2 (else segment N-2's), as ``MyCost.m``'s loops find them."""
    N = p.shape[1]
    j1 = i
    while j1 > 0 and p[q, j1 + 1, 0] == p[q, j1, 0] and p[q, j1 + 1, 1] == p[q, j1, 1]:
        j1 -= 1
    j2 = i + 1
    while j2 < N - 2 and p[q, j2 + 1, 0] == p[q, j2, 0] and p[q, j2 + 1, 1] == p[q, j2, 1]:
        j2 += 1
    ax = p[q, j1 + 1, 0] - p[q, j1, 0]
    ay = p[q, j1 + 1, 1] - p[q, j1, 1]
    bx = p[q, j2 + 1, 0] - p[q, j2, 0]
    by = p[q, j2 + 1, 1] - p[q, j2, 1]
    return ax, ay, bx, by


@njit(cache=True, inline="always")
def _spso_node_smoothness(p, q, i, turning_max, climb_max):  # pragma: no cover - numba
    """J4's two additions at interior node ``i + 1`` of path ``q`` (see
    :func:`smoothness_cost_spso`): the turning angle and the climb change, each 0 within its
    limit; the caller adds them in that order."""
    ax, ay, bx, by = _spso_projections(p, q, i)
    n1 = np.sqrt(ax * ax + ay * ay)
    n2 = np.sqrt(bx * bx + by * by)
    deg = 180.0 / np.pi
    climb1 = np.arctan2(p[q, i + 1, 2] - p[q, i, 2], n1) * deg
    climb2 = np.arctan2(p[q, i + 2, 2] - p[q, i + 1, 2], n2) * deg
    turning = abs(np.arctan2(abs(ax * by - ay * bx), ax * bx + ay * by) * deg)
    dclimb = abs(climb2 - climb1)
    return (turning if turning > turning_max else 0.0), (dclimb if dclimb > climb_max else 0.0)


@population_kernel()
def _smoothness_spso_kernel(p, turning_max, climb_max):  # pragma: no cover - numba
    P, N, _ = p.shape
    out = np.zeros(P)
    for q in prange(P):
        total = 0.0
        for i in range(N - 2):
            turn, climb = _spso_node_smoothness(p, q, i, turning_max, climb_max)
            total += turn
            total += climb
        out[q] = total
    return out


# ---------------------------------------------------------------------------- SPSO, fused
#: :func:`path_cost_batch`'s columns of terms (SPSO's names; PPSwarm's F1-F4 are the same four)
SPSO_TERMS = ("length", "threat", "altitude", "smoothness")
#: :func:`path_cost_batch`, SPSO: an angle is taken as within its limit without computing it when
#: the limit's test, made on the vectors, holds with this relative margin (far above the
#: rounding of the vectors' products and of ``arctan2``, so the decision is the reference's)
ANGLE_MARGIN = 1e-9


@njit(cache=True, inline="always")
def _spso_node_smoothness_fast(p, q, i, turning_max, climb_max):  # pragma: no cover - numba
    """:func:`_spso_node_smoothness` with the angles computed only where they may exceed their
    limits (the same values where it matters, so the same additions): with the 45-degree limits
    of SPSO, the turning angle ``atan2(c, d)`` is below 45 degrees when ``c < d`` and the climb
    change, the angle between ``(n1, dz1)`` and ``(n2, dz2)``, when ``|dz2 n1 - dz1 n2| <
    n1 n2 + dz1 dz2``; each test is made with :data:`ANGLE_MARGIN` and otherwise the angles
    are computed as the reference does."""
    ax, ay, bx, by = _spso_projections(p, q, i)
    deg = 180.0 / np.pi
    turn = 0.0
    c = abs(ax * by - ay * bx)
    d = ax * bx + ay * by
    if not (turning_max == 45.0 and c < d * (1.0 - ANGLE_MARGIN)):
        turning = abs(np.arctan2(c, d) * deg)
        if turning > turning_max:
            turn = turning
    n1 = np.sqrt(ax * ax + ay * ay)
    n2 = np.sqrt(bx * bx + by * by)
    dz1 = p[q, i + 1, 2] - p[q, i, 2]
    dz2 = p[q, i + 2, 2] - p[q, i + 1, 2]
    climb = 0.0
    cross = abs(dz2 * n1 - dz1 * n2)
    dot = n1 * n2 + dz1 * dz2
    scale = (n1 + abs(dz1)) * (n2 + abs(dz2))
    if not (climb_max == 45.0 and n1 > 0.0 and n2 > 0.0 and cross < dot - ANGLE_MARGIN * scale):
        dclimb = abs(np.arctan2(dz2, n2) * deg - np.arctan2(dz1, n1) * deg)
        if dclimb > climb_max:
            climb = dclimb
    return turn, climb


@njit(cache=True, inline="always")
def _ppswarm_node_turn(p, q, i):  # pragma: no cover - numba
    """PPSwarm's turning angle at interior node ``i + 1`` of path ``q`` (:func:`turn_angles`,
    3-D, the same operations)."""
    a0 = p[q, i + 1, 0] - p[q, i, 0]
    a1 = p[q, i + 1, 1] - p[q, i, 1]
    a2 = p[q, i + 1, 2] - p[q, i, 2]
    b0 = p[q, i + 2, 0] - p[q, i + 1, 0]
    b1 = p[q, i + 2, 1] - p[q, i + 1, 1]
    b2 = p[q, i + 2, 2] - p[q, i + 1, 2]
    c0 = a1 * b2 - a2 * b1
    c1 = a2 * b0 - a0 * b2
    c2 = a0 * b1 - a1 * b0
    dot = 0.0 + a0 * b0  # from +0, as NumPy's sum: a zero segment's dot is +0 (angle 0, not pi)
    return np.arctan2(np.sqrt(c0 * c0 + c1 * c1 + c2 * c2), dot + a1 * b1 + a2 * b2)


#: :func:`path_cost_batch`'s cost models
SPSO, PPSWARM = 0, 1


@population_kernel(error_model="numpy")
def path_cost_batch(
    model,
    p,
    cx,
    cy,
    z_lo,
    z_hi,
    r_in,
    r_out,
    threat,
    moving,
    H,
    has_terrain,
    nearest,
    x0,
    y0,
    dx,
    dy,
    has_band,
    ground_ref,
    z_min,
    z_max,
    z_mid,
    weights,
    early,
):  # pragma: no cover - numba
    """A whole cost of four terms -- length J1, threat J2, altitude J3, smoothness J4 -- of every
    path in one pass over the population: ``(total, terms)``, (P,) and (P, 4), ``total = ((w0
    J1 + w1 J2) + w2 J3) + w3 J4`` as :class:`~uavplan.problems.path_problem.PathProblem` adds
    the terms. ``model``: :data:`SPSO` (``MyCost.m``, the terms of :data:`SPSO_TERMS`) or
    :data:`PPSWARM` (PPSwarm's F1-F4, Eqs. 2-10).

    The same terms as the separate ones (the references the tests compare it with), per path one
    loop over its segments for J1 and J2, one over its nodes for J3 and one over its interior
    nodes for J4:

    * J2: cylinders as structure of arrays, ``r_in``, ``r_out`` as
      :func:`uavplan.world.geometry.cylinder_threat_batch` takes them (SPSO strict, PPSwarm
      not); ``threat``: empty to compute it here from every pair, or each path's static J2
      computed apart (the indexed pass); ``moving``: empty, or PPSwarm's moving-obstacle term
      per path, added to it (empty arrays rather than None: one signature, one compilation,
      whichever of them a problem has).
    * J3: heights of the terrain ``H`` (when ``has_terrain``) read at the ``nearest`` node or
      bilinear; SPSO: over the free nodes, inf below ground, else the distance to the band's
      middle; PPSwarm (``has_band``): over every node, in the band's reference
      (``ground_ref``: above ground), inf outside the band, else the distance to ``z_mid``
      (its middle, or the UAV's cruise layer, :attr:`uavplan.world.scenario.Task.cruise`).
    * J4: SPSO's limited angles in degrees (:func:`_spso_node_smoothness_fast`); PPSwarm's
      turning angles and climb-angle changes in radians (Eq. 10 with a1 = a2 = 1).

    ``early``: a path with an infinite J2 or J3 (so an infinite total) skips what is left once
    every coordinate is known finite (so that NaN stays NaN), its terms left where they were:
    for the total alone.
    """
    P, N, _ = p.shape
    J = cx.shape[0]
    total = np.empty(P)
    terms = np.zeros((P, 4))
    psi = np.empty((P, max(N - 1, 1)))  # PPSwarm's climb angle per segment
    mid = 0.5 * (z_max + z_min) if model == SPSO else z_mid
    strict = model == SPSO
    for q in prange(P):
        finite = True
        if early:
            for s in range(N):
                for c in range(3):
                    finite = finite and np.isfinite(p[q, s, c])
        # J1 and J2: segments
        j1 = 0.0
        j2 = 0.0
        hits = 0
        for s in range(N - 1):
            ax, ay, az, ex, ey, inv_ee, flat, inv_dz = seg_setup(p, q, s)
            dz = p[q, s + 1, 2] - az
            length = np.sqrt(ex * ex + ey * ey + dz * dz)
            j1 += length
            if model == PPSWARM:
                psi[q, s] = np.arctan2(dz, length)
            if threat.shape[0] == 0:
                for j in range(J):
                    d = clipped_dist(
                        ax, ay, az, ex, ey, inv_ee, flat, inv_dz, cx[j], cy[j], z_lo[j], z_hi[j]
                    )
                    hits += 1 if (d < r_in[j] or (not strict and d == r_in[j])) else 0
                    j2 += (r_out[j] - d) if d <= r_out[j] else 0.0
        if threat.shape[0] > 0:
            j2 = threat[q]
        elif hits > 0:
            j2 = np.inf
        if moving.shape[0] > 0:
            j2 = j2 + moving[q]
        # J3: nodes
        j3 = 0.0
        first, last = (1, N - 1) if model == SPSO else (0, N)
        if (model == SPSO or has_band) and not (early and finite and np.isinf(j2)):
            for s in range(first, last):
                h = p[q, s, 2]
                if model == SPSO or ground_ref:
                    h = h - ground_one(
                        H, has_terrain, nearest, x0, y0, dx, dy, p[q, s, 0], p[q, s, 1]
                    )
                inside = (not h < 0) if model == SPSO else (h >= z_min and h <= z_max)
                if inside:
                    j3 += abs(h - mid)
                else:
                    j3 += np.inf
                    if early and finite:
                        break
        # J4: interior nodes
        j4 = 0.0
        if not (early and finite and (np.isinf(j2) or np.isinf(j3))):
            if model == SPSO:
                for i in range(N - 2):
                    turn, climb = _spso_node_smoothness_fast(p, q, i, 45.0, 45.0)
                    j4 += turn
                    j4 += climb
            else:
                turns = 0.0
                climbs = 0.0
                for i in range(N - 2):
                    turns += _ppswarm_node_turn(p, q, i)
                    climbs += abs(psi[q, i + 1] - psi[q, i])
                j4 = 1.0 * turns
                j4 = j4 + 1.0 * climbs
        terms[q, 0] = j1
        terms[q, 1] = j2
        terms[q, 2] = j3
        terms[q, 3] = j4
        t = 0.0 + weights[0] * j1
        t = t + weights[1] * j2
        t = t + weights[2] * j3
        total[q] = t + weights[3] * j4
    return total, terms


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
