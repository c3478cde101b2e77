"""One Numba pass over a batch of 3-D paths for the world's static checks.

:meth:`uavplan.problems.validity.MotionValidator.passing` (the yes/no question every planner
asks most) runs the bounds, cylinder, circle, polygon, terrain and altitude-band checks of a
3-D world (and the segments' climb angles where the validator checks them) in this single
kernel, path by path, stopping at a path's first failure, instead of one NumPy pass per check.
It calls the same scalar functions as the per-check kernels
(:func:`uavplan.world.geometry.seg_cyl_dist`, the 2-D scene pass's
:func:`~uavplan.world.geometry.scene2d.segment_scene_hit`, the terrain's branch-and-bound
``_segment_min_clearance``, :func:`uavplan.world._terrain_kernels.ground_one`), so its
verdicts are those of :meth:`~uavplan.problems.validity.MotionValidator.violations`; the tests
compare the two on random batches.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from uavplan.kernel_builds import population_kernel
from uavplan.world._terrain_kernels import _segment_min_clearance, ground_one, snap_one
from uavplan.world.geometry import seg_cyl_dist
from uavplan.world.geometry.scene2d import segment_scene_hit
from uavplan.world.tolerances import ANGLE_TOL_DEG


# compiled once as its own function (see :func:`uavplan.world.reservations.path_query_from`)
@njit(cache=True)
def static_path_ok(paths, p, args, waypoint_band=True):  # pragma: no cover - numba
    """Whether path ``p`` of ``paths`` (P, N, 3) passes bounds, cylinders, circles, polygons,
    terrain and the band (:func:`static_world_ok`'s test of one path; the fleet's fused
    objective calls it too).
    ``args``: the tuple ``(lo, hi, bounds_tol, cyl_c, cyl_r, cyl_lo, cyl_hi, has_terrain, H,
    flat, off, shp, nH, nflat, noff, nshp, grid, need, has_band, band_ground, nearest, bmin, bmax,
    band_tol, strict, max_climb, max_descent, *scene)``
    (:meth:`~uavplan.problems.validity.MotionValidator.static_kernel_args`; the climb and
    descent limits in degrees, inf where not checked, as
    :func:`~uavplan.problems.validity.climb_violations` tests them).
    ``waypoint_band=False``: the caller knows every waypoint to be inside the band (without
    the tolerance), so the band is checked along the segments only.

    ``grid``: (x0, y0, dx, dy, nx - 1, ny - 1, tol_u, tol_v) of the terrain; ``H``/``flat``/
    ``off``/``shp`` its heights and max-pyramid, ``nH``/... those of its negated ceiling grid
    (``Terrain.ceiling_heights``: the band's ceiling at the waypoints and along
    segments); ``need``: the least clearance above the terrain; the band
    ``[bmin, bmax]`` above ground (``band_ground``; at the waypoints the ground is read at the
    ``nearest`` node, else bilinear) or absolute, within ``band_tol``, and along whole segments
    when ``strict`` (ground band over terrain only); ``scene``: ``verts, starts, circ, poly,
    convex, edges, hull_s, maxv``, the circles and polygons whose ground tracks it tests
    (:func:`uavplan.world.geometry.scene2d.segment_scene_hit`, empty where the validator
    leaves them to the 2-D scene pass), flattened into ``args``: Numba's parallel build
    cannot pass a tuple nested in a tuple argument to its parallel loop.
    """
    (lo, hi, bounds_tol, cyl_c, cyl_r, cyl_lo, cyl_hi, has_terrain, H, flat, off, shp, nH,
     nflat, noff, nshp, grid, need, has_band, band_ground, nearest, bmin, bmax, band_tol, strict,
     max_climb, max_descent, verts, starts, circ, poly, convex, edges, hull_s,
     maxv) = args  # fmt: skip
    N = paths.shape[1]
    J = cyl_c.shape[0]
    x0, y0, dx, dy = grid[0], grid[1], grid[2], grid[3]
    nx1, ny1, tol_u, tol_v = grid[4], grid[5], grid[6], grid[7]
    ceiling = -(bmax + band_tol)
    ok = True
    for k in range(N):  # bounds at the waypoints
        for d in range(3):
            c = paths[p, k, d]
            if not (c >= lo[d] - bounds_tol and c <= hi[d] + bounds_tol):
                ok = False
    if ok and (max_climb < np.inf or max_descent < np.inf):  # the segments' climb angles
        for s in range(N - 1):
            ex = paths[p, s + 1, 0] - paths[p, s, 0]
            ey = paths[p, s + 1, 1] - paths[p, s, 1]
            ez = paths[p, s + 1, 2] - paths[p, s, 2]
            h = np.hypot(ex, ey)
            if h > 0 or ez != 0:
                ang = np.degrees(np.arctan2(ez, h))
                if ang > max_climb + ANGLE_TOL_DEG or -ang > max_descent + ANGLE_TOL_DEG:
                    ok = False
                    break
    if ok and has_band and waypoint_band:  # the band at the waypoints
        for k in range(N):
            z = paths[p, k, 2]
            h = z
            hc = z
            if band_ground:
                x, y = paths[p, k, 0], paths[p, k, 1]
                h = z - ground_one(H, has_terrain, nearest, x0, y0, dx, dy, x, y)
                hc = z + ground_one(nH, has_terrain, nearest, x0, y0, dx, dy, x, y)
            if h < bmin - band_tol or hc > bmax + band_tol:
                ok = False
                break
    if ok:  # cylinders along the segments
        for s in range(N - 1):
            for j in range(J):
                if seg_cyl_dist(paths, p, s, cyl_c, cyl_lo, cyl_hi, j) < cyl_r[j]:
                    ok = False
                    break
            if not ok:
                break
    if ok and (circ.shape[1] > 0 or starts.shape[0] > 1):  # circles and polygons (ground track)
        ts = np.empty(maxv + 2)
        for s in range(N - 1):
            if segment_scene_hit(paths[p, s, 0], paths[p, s, 1], paths[p, s + 1, 0],
                                 paths[p, s + 1, 1], verts, starts, circ, poly, convex, edges,
                                 hull_s, ts):  # fmt: skip
                ok = False
                break
    if ok and has_terrain:  # the terrain, and the band's ceiling, along the segments
        for s in range(N - 1):
            u0 = snap_one((paths[p, s, 0] - x0) / dx, nx1, tol_u)
            v0 = snap_one((paths[p, s, 1] - y0) / dy, ny1, tol_v)
            u1 = snap_one((paths[p, s + 1, 0] - x0) / dx, nx1, tol_u)
            v1 = snap_one((paths[p, s + 1, 1] - y0) / dy, ny1, tol_v)
            z0 = paths[p, s, 2]
            z1 = paths[p, s + 1, 2]
            m = _segment_min_clearance(H, flat, off, shp, u0, v0, z0, u1, v1, z1, need, True)
            if not m >= need:
                ok = False
                break
            if strict:
                m = _segment_min_clearance(
                    nH, nflat, noff, nshp, u0, v0, -z0, u1, v1, -z1, ceiling, True
                )
                if not m >= ceiling:
                    ok = False
                    break
    return ok


@population_kernel()
def static_world_ok(paths, args):  # pragma: no cover - numba
    """(P,) whether each path (P, N, 3) passes bounds, cylinders, circles, polygons, terrain and
    the band (:func:`static_path_ok` of each, with its ``args``)."""
    P = paths.shape[0]
    out = np.zeros(P, dtype=np.bool_)
    for p in prange(P):
        out[p] = static_path_ok(paths, p, args, True)  # the fused objective's signature
    return out
