"""A terrain pyramid: the DEM at several resolutions, for multi-resolution planners (HR-MAGA).

Yang, Liu & Li (IEEE CEC 2020, Sects. II-A and IV) plan on "virtual maps of different precision
layers" made "by sampling digital elevation maps at different frequencies"; their first layer
samples the map about 40 times per side (Fig. 1(a)). Each :class:`TerrainLevel` holds two maps on
the same coarse grid (node spacing ``factor`` fine cells):

* ``feasibility``: every coarse node carries the **maximum** of the fine nodes within
  ``factor`` fine cells of it (the support of its bilinear hat function). A point of a coarse
  cell is a convex combination of the cell's four corners, each at least the highest fine node
  of that cell, and the fine bilinear height there is a convex combination of fine nodes of the
  same cell, so ``feasibility.height(x, y) >= fine.height(x, y)`` everywhere (also beyond the
  fine grid, where both clamp to their edge): **a segment that clears the coarse map clears the
  fine one** (property-tested in ``tests/world/test_pyramid.py``).
* ``cost``: the fine map's bilinear heights at the coarse nodes (the map the paper's cost reads
  on that layer: a sampled DEM, not a conservative one).

A terrain with a ceiling's grid (``Terrain.lower``, a reprojected raster) gives every level one
too: the **minimum** of the fine ceiling nodes around each coarse node (so the coarse ceiling is
never above the fine one), and on the cost map the fine ceiling's bilinear heights.

Factors (our choice; the paper gives only the first layer's ~40 samples per side): the first
(coarsest) level's factor makes its longer side about ``first_samples = 40`` cells,
``round((n - 1) / 40)`` for the longer side's ``n`` nodes; the last level is the DEM itself
(factor 1); levels between are geometric, ``round(f_1 ** ((v - l) / (v - 1)))`` for level
``l = 1..v``, kept strictly decreasing where the DEM allows (SPSO's 1,045 x 879 map: 26, 5, 1;
Jacksboro 403 x 344: 10, 3, 1; topobathy 120 x 91: 3, 2, 1). Danger and uncertain areas are
continuous geometry and are the same on every level; which of them a level knows is the
planner's business (HR-MAGA: uncertain areas unknown on the coarse level).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uavplan.world.terrain import Terrain

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class TerrainLevel:
    """One level of a :func:`terrain_pyramid`: node spacing ``factor`` fine cells."""

    factor: int
    feasibility: Terrain  # conservative: never below the fine map
    cost: Terrain  # the fine map's bilinear heights at the coarse nodes


def coarse_nodes(n: int, factor: int) -> int:
    """Nodes of a coarse axis of spacing ``factor`` covering ``n`` fine nodes (the last coarse
    node at or beyond the fine end)."""
    return max(2, math.ceil((n - 1) / factor) + 1)


def conservative_level(terrain: Terrain, factor: int) -> TerrainLevel:
    """The level of node spacing ``factor`` fine cells (see the module docstring)."""
    if factor < 1:
        raise ValueError(f"pyramid factor must be >= 1, got {factor}")
    if factor == 1:
        return TerrainLevel(1, terrain, terrain)
    H = terrain.heights
    ny, nx = H.shape
    mx, my = coarse_nodes(nx, factor), coarse_nodes(ny, factor)
    from scipy.ndimage import maximum_filter  # lazy: 0.2 s of every CLI start

    window = maximum_filter(H, size=2 * factor + 1, mode="nearest")
    ii = np.minimum(np.arange(mx) * factor, nx - 1)
    jj = np.minimum(np.arange(my) * factor, ny - 1)
    dx, dy = terrain.dx * factor, terrain.dy * factor
    low = None
    if terrain.lower is not None:  # the ceiling's grid, conservative the other way
        from scipy.ndimage import minimum_filter

        low = minimum_filter(terrain.lower, size=2 * factor + 1, mode="nearest")[np.ix_(jj, ii)]
    feas = Terrain(window[np.ix_(jj, ii)], terrain.x0, terrain.y0, dx, dy,
                   f"{terrain.name}/max{factor}", dict(terrain.georef), low)  # fmt: skip
    X, Y = np.meshgrid(terrain.x0 + np.arange(mx) * dx, terrain.y0 + np.arange(my) * dy)
    cost = Terrain(terrain.height(X, Y), terrain.x0, terrain.y0, dx, dy,
                   f"{terrain.name}/{factor}", dict(terrain.georef),
                   None if terrain.lower is None else terrain.height_low(X, Y))  # fmt: skip
    return TerrainLevel(factor, feas, cost)


def pyramid_factors(shape: tuple[int, int], levels: int, first_samples: int = 40) -> list[int]:
    """Node spacings (fine cells) of ``levels`` levels, coarsest first, the last 1."""
    if levels < 1:
        raise ValueError(f"a pyramid needs >= 1 level, got {levels}")
    if first_samples < 1:
        raise ValueError(f"first_samples must be >= 1, got {first_samples}")
    n = max(shape) - 1
    f1 = max(1, round(n / first_samples))
    if levels == 1:
        return [1]
    out = [max(1, round(f1 ** ((levels - lv) / (levels - 1)))) for lv in range(1, levels + 1)]
    for k in range(len(out) - 2, -1, -1):  # strictly decreasing where the DEM allows
        if out[k] <= out[k + 1] and out[k + 1] < f1:
            out[k] = out[k + 1] + 1
    out[-1] = 1
    return out


def terrain_pyramid(
    terrain: Terrain, levels: int = 3, first_samples: int = 40
) -> tuple[TerrainLevel, ...]:
    """``levels`` levels of ``terrain``, coarsest first, the last the DEM itself."""
    factors = pyramid_factors(terrain.shape, levels, first_samples)
    return tuple(conservative_level(terrain, f) for f in factors)


def relaxed_near(level: TerrainLevel, points: FloatArray, ring: int = 1) -> Terrain:
    """The level's conservative map, except at the nodes within ``ring`` coarse cells of the
    cells holding ``points`` (n, >= 2), where it takes the sampled map's heights. A path's
    fixed start and goal sit where the *fine* map placed them (e.g. 150 m above it); on a
    conservative coarse map they may be below the ground, which no waypoint can repair, and
    every agent would fail alike. Conservativeness is given up only there, next to the fixed
    ends; the finest level (factor 1) is the DEM itself either way."""
    if level.factor == 1:
        return level.feasibility
    F, C = level.feasibility, level.cost
    H = np.array(F.heights)
    Lo = None if F.lower is None or C.lower is None else np.array(F.lower)
    ny, nx = H.shape
    for p in np.asarray(points, dtype=np.float64).reshape(-1, np.shape(points)[-1]):
        i = int(np.clip(np.floor((p[0] - F.x0) / F.dx), 0, nx - 1))
        j = int(np.clip(np.floor((p[1] - F.y0) / F.dy), 0, ny - 1))
        sl = (slice(max(j - ring, 0), j + ring + 2), slice(max(i - ring, 0), i + ring + 2))
        H[sl] = C.heights[sl]
        if Lo is not None and C.lower is not None:
            Lo[sl] = C.lower[sl]
    return Terrain(H, F.x0, F.y0, F.dx, F.dy, f"{F.name}~ends", dict(F.georef), Lo)
