"""Timed paths against moving obstacles: the least distance over each segment's time."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel

FloatArray = NDArray[np.float64]


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
