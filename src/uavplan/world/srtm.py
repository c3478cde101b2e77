"""SRTM ``.hgt`` elevation tiles, mosaicked and resampled onto a scenario's local frame.

A tile ``N36W085.hgt`` covers latitudes 36-37 N and longitudes 85-84 W: big-endian int16
heights (metres above mean sea level), 1201 x 1201 (3 arc-seconds) or 3601 x 3601 (1
arc-second) samples, row 0 the northern edge, the edge rows and columns shared with the
neighbouring tiles, voids -32768. Tiles of one resolution are put on one latitude/longitude
grid (a missing tile is void), and the terrain is resampled onto a local metric grid through
the scenario's :class:`~uavplan.world.geo.GeoOrigin` (pyproj's azimuthal equidistant
projection): each local node takes the **highest** of the four source samples around its
position, so a node is never below the source's bilinear surface there. A void among them is
skipped; a node with only voids around it takes the highest valid height within growing
neighbourhoods (conservative: a hole is filled high, not low), and :func:`terrain_from_srtm`
reports how many nodes were filled.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uavplan.world.geo import GeoOrigin
from uavplan.world.terrain import Terrain, TerrainError

FloatArray = NDArray[np.float64]
VOID = -32768
SIZES = {1201: 3.0, 3601: 1.0}  # samples per side -> arc-seconds
_NAME = re.compile(r"^([NS])(\d{2})([EW])(\d{3})$", re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class HgtTile:
    """One tile: its south-west corner (degrees), samples per side, heights (n, n) with row 0
    south (NaN = void)."""

    lat: int
    lon: int
    n: int
    heights: FloatArray
    path: Path


def read_hgt(path: str | Path) -> HgtTile:
    """Read one tile; TerrainError naming the file on a bad name or size."""
    p = Path(path)
    m = _NAME.match(p.stem)
    if m is None:
        raise TerrainError(f"{p}: not an SRTM tile name (like N36W085.hgt)")
    lat = int(m.group(2)) * (1 if m.group(1).upper() == "N" else -1)
    lon = int(m.group(4)) * (1 if m.group(3).upper() == "E" else -1)
    if not (-90 <= lat < 90 and -180 <= lon < 180):
        raise TerrainError(f"{p}: tile corner {lat}, {lon} is not on Earth")
    size = p.stat().st_size
    n = round(math.sqrt(size / 2))
    if n not in SIZES or 2 * n * n != size:
        raise TerrainError(
            f"{p}: {size} bytes is not an SRTM tile (1201 x 1201 or 3601 x 3601 int16 samples)"
        )
    raw = np.fromfile(p, dtype=">i2").reshape(n, n)[::-1]
    heights = raw.astype(np.float64)
    heights[raw == VOID] = np.nan
    return HgtTile(lat, lon, n, heights, p)


def mosaic(tiles: list[HgtTile]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The tiles on one grid: ``(lats (m,), lons (k,), heights (m, k))``, rows south first;
    samples of missing tiles are NaN. All tiles must share one resolution."""
    if not tiles:
        raise TerrainError("no SRTM tiles given")
    n = tiles[0].n
    if any(t.n != n for t in tiles):
        names = ", ".join(f"{t.path.name} ({t.n})" for t in tiles)
        raise TerrainError(f"SRTM tiles of different resolutions cannot be mosaicked: {names}")
    lat0, lon0 = min(t.lat for t in tiles), min(t.lon for t in tiles)
    rows = max(t.lat for t in tiles) - lat0 + 1
    cols = max(t.lon for t in tiles) - lon0 + 1
    step = n - 1
    H = np.full((rows * step + 1, cols * step + 1), np.nan)
    for t in tiles:
        i, j = (t.lat - lat0) * step, (t.lon - lon0) * step
        block = H[i : i + n, j : j + n]
        # a shared edge keeps a valid sample over a void one
        H[i : i + n, j : j + n] = np.where(np.isnan(t.heights), block, t.heights)
    lats = lat0 + np.arange(H.shape[0]) / step
    lons = lon0 + np.arange(H.shape[1]) / step
    return lats, lons, H


def _fill_high(Z: FloatArray) -> int:
    """Fill NaN nodes in place with the highest valid height in growing square neighbourhoods;
    returns how many were filled."""
    from scipy.ndimage import maximum_filter

    holes = np.isnan(Z)
    count = int(holes.sum())
    if count == 0:
        return 0
    if holes.all():
        raise TerrainError("the SRTM data under the map is void everywhere")
    work = np.where(holes, -np.inf, Z)
    while np.isnan(Z).any():
        grown = maximum_filter(work, size=3, mode="nearest")
        fill = np.isnan(Z) & np.isfinite(grown)
        Z[fill] = grown[fill]
        work = np.where(np.isnan(Z), -np.inf, Z)
    return count


def terrain_from_srtm(
    paths: Sequence[str | Path],
    origin: GeoOrigin,
    bounds: tuple[float, float, float, float],
    cell_size: float | None = None,
) -> tuple[Terrain, int]:
    """The terrain on the local grid over ``bounds = (xmin, xmax, ymin, ymax)`` with
    ``cell_size`` metres (default: the tiles' spacing north-south, 30 or 90 m), heights in the
    local frame (``AMSL - origin.alt``); and the number of nodes filled over voids.

    Raises:
        TerrainError: a tile is unreadable, or the map reaches beyond the tiles given (naming
            the tile that is missing).
    """
    tiles = [read_hgt(p) for p in paths]
    lats, lons, H = mosaic(tiles)
    step_deg = 1.0 / (tiles[0].n - 1)
    d = float(cell_size) if cell_size else 30.0 * SIZES[tiles[0].n]  # 90 m or 30 m
    xmin, xmax, ymin, ymax = bounds
    nx = math.floor((xmax - xmin) / d + 1e-9) + 1
    ny = math.floor((ymax - ymin) / d + 1e-9) + 1
    if nx < 2 or ny < 2:
        size = f"{xmax - xmin:g} x {ymax - ymin:g} m"
        raise TerrainError(f"the map ({size}) is under 2 cells of {d:g} m")
    X, Y = np.meshgrid(xmin + d * np.arange(nx), ymin + d * np.arange(ny))
    G = origin.to_geodetic(np.column_stack([X.ravel(), Y.ravel()]))
    la, lo = G[:, 0], G[:, 1]
    fi = (la - lats[0]) / step_deg
    fj = (lo - lons[0]) / step_deg
    outside = (fi < 0) | (fj < 0) | (fi > len(lats) - 1) | (fj > len(lons) - 1)
    if outside.any():
        k = int(np.argmax(outside))
        tile = (f"{'N' if la[k] >= 0 else 'S'}{abs(math.floor(la[k])):02d}"
                f"{'E' if lo[k] >= 0 else 'W'}{abs(math.floor(lo[k])):03d}.hgt")  # fmt: skip
        raise TerrainError(
            f"the map reaches {la[k]:.5f}, {lo[k]:.5f} (local {X.ravel()[k]:g}, "
            f"{Y.ravel()[k]:g} m), beyond the SRTM tiles given: add {tile}"
        )
    i0 = np.clip(np.floor(fi).astype(int), 0, len(lats) - 2)
    j0 = np.clip(np.floor(fj).astype(int), 0, len(lons) - 2)
    corners = np.stack([H[i0, j0], H[i0 + 1, j0], H[i0, j0 + 1], H[i0 + 1, j0 + 1]])
    with warnings.catch_warnings():  # all four corners void: NaN, filled below
        warnings.simplefilter("ignore", RuntimeWarning)
        Z = np.nanmax(corners, axis=0).reshape(ny, nx) - origin.alt
    void = np.isnan(corners).any(axis=0).reshape(ny, nx)  # a node that used a void sample
    filled = _fill_high(Z)
    names = [Path(p).name for p in paths]
    georef = {"srtm": names, "origin": origin.record(), "voids_filled": filled, "void_mask": void,
              "resampling": "max of the four source samples (conservative)"}  # fmt: skip
    return Terrain(Z, xmin, ymin, d, d, "+".join(names), georef), filled


def points_over_voids(terrain: Terrain, points: FloatArray) -> int:
    """How many of ``points`` (n, >=2) lie in a terrain cell with a corner filled over an SRTM
    void (0 for a terrain without voids)."""
    mask = terrain.georef.get("void_mask")
    if mask is None or not np.any(mask):
        return 0
    P = np.asarray(points, dtype=np.float64)
    ny, nx = mask.shape
    j = np.clip(np.floor((P[:, 0] - terrain.x0) / terrain.dx).astype(int), 0, nx - 2)
    i = np.clip(np.floor((P[:, 1] - terrain.y0) / terrain.dy).astype(int), 0, ny - 2)
    hit = mask[i, j] | mask[i + 1, j] | mask[i, j + 1] | mask[i + 1, j + 1]
    return int(hit.sum())
