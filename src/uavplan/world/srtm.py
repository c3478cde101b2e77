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
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uavplan.world.geo import GeoOrigin
from uavplan.world.terrain import MAX_DEM_CELLS, Terrain, TerrainError, not_a_regular_file

#: The most samples the SRTM tiles of one scenario may hold (four 1-arc-second tiles, 3601 x
#: 3601 each, or 41 3-arc-second ones): the mosaic is held as float64, 415 MB at most.
MAX_SRTM_SAMPLES = 4 * 3601 * 3601

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
    why = not_a_regular_file(p)
    if why is not None:
        raise TerrainError(f"{p}: {why}")
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


def _srtm_tile_name(lat: float, lon: float) -> str:
    return (f"{'N' if lat >= 0 else 'S'}{abs(math.floor(lat)):02d}"
            f"{'E' if lon >= 0 else 'W'}{abs(math.floor(lon)):03d}.hgt")  # fmt: skip


def resample_latlon(
    lats: FloatArray,
    lons: FloatArray,
    H: FloatArray,
    origin: GeoOrigin,
    bounds: tuple[float, float, float, float],
    cell: float,
    name: str,
    beyond: Callable[[float, float], str] = lambda la, lo: "",
) -> tuple[Terrain, int]:
    """A regular latitude/longitude grid of heights AMSL (``H`` (m, k), rows south first, NaN
    = void) on the local grid over ``bounds = (xmin, xmax, ymin, ymax)`` with ``cell`` metres,
    heights ``AMSL - origin.alt``: each node the highest of the four samples around it, voids
    filled high; the number of filled nodes. ``beyond(lat, lon)`` says what to add when the map
    reaches past the grid."""
    dlat, dlon = float(lats[1] - lats[0]), float(lons[1] - lons[0])
    xmin, xmax, ymin, ymax = bounds
    nx = math.floor((xmax - xmin) / cell + 1e-9) + 1
    ny = math.floor((ymax - ymin) / cell + 1e-9) + 1
    if nx < 2 or ny < 2:
        size = f"{xmax - xmin:g} x {ymax - ymin:g} m"
        raise TerrainError(f"the map ({size}) is under 2 cells of {cell:g} m")
    if nx * ny > MAX_DEM_CELLS:
        raise TerrainError(
            f"the map ({xmax - xmin:g} x {ymax - ymin:g} m) in cells of {cell:g} m has "
            f"{nx:,} x {ny:,} nodes; a DEM has at most {MAX_DEM_CELLS:,} (give a larger "
            "cell_size, or smaller bounds)"
        )
    X, Y = np.meshgrid(xmin + cell * np.arange(nx), ymin + cell * np.arange(ny))
    G = origin.to_geodetic(np.column_stack([X.ravel(), Y.ravel()]))
    la, lo = G[:, 0], G[:, 1]
    fi = (la - lats[0]) / dlat
    fj = (lo - lons[0]) / dlon
    outside = (
        (fi < -1e-9) | (fj < -1e-9) | (fi > len(lats) - 1 + 1e-9) | (fj > len(lons) - 1 + 1e-9)
    )
    if outside.any():
        k = int(np.argmax(outside))
        raise TerrainError(
            f"the map reaches {la[k]:.5f}, {lo[k]:.5f} (local {X.ravel()[k]:g}, "
            f"{Y.ravel()[k]:g} m), beyond the elevation data of {name}{beyond(la[k], lo[k])}"
        )
    i0 = np.clip(np.floor(fi).astype(int), 0, len(lats) - 2)
    j0 = np.clip(np.floor(fj).astype(int), 0, len(lons) - 2)
    corners = np.stack([H[i0, j0], H[i0 + 1, j0], H[i0, j0 + 1], H[i0 + 1, j0 + 1]])
    with warnings.catch_warnings():  # all four corners void: NaN, filled below
        warnings.simplefilter("ignore", RuntimeWarning)
        Z = np.nanmax(corners, axis=0).reshape(ny, nx) - origin.alt
    void = np.isnan(corners).any(axis=0).reshape(ny, nx)  # a node that used a void sample
    filled = _fill_high(Z)
    georef = {
        "source": name, "origin": origin.record(), "voids_filled": filled, "void_mask": void,
        "resampling": "max of the four samples around (conservative)",
    }  # fmt: skip
    return Terrain(Z, xmin, ymin, cell, cell, name, georef), filled


def terrain_from_srtm(
    paths: Sequence[str | Path],
    origin: GeoOrigin,
    bounds: tuple[float, float, float, float],
    cell_size: float | None = None,
) -> tuple[Terrain, int]:
    """The tiles' terrain on the local grid over ``bounds = (xmin, xmax, ymin, ymax)`` with
    ``cell_size`` metres (default: the tiles' spacing north-south, 30 or 90 m), heights in the
    local frame (``AMSL - origin.alt``); and the number of nodes filled over voids.

    Raises:
        TerrainError: a tile is unreadable, or the map reaches beyond the tiles given (naming
            the tile that is missing).
    """
    samples = sum(Path(p).stat().st_size // 2 for p in paths if not_a_regular_file(p) is None)
    if samples > MAX_SRTM_SAMPLES:
        raise TerrainError(
            f"{len(paths)} SRTM tiles hold {samples:,} samples; at most {MAX_SRTM_SAMPLES:,} "
            "are read at once (four 1-arc-second tiles): give only the tiles under the map"
        )
    tiles = [read_hgt(p) for p in paths]
    lats, lons, H = mosaic(tiles)
    d = float(cell_size) if cell_size else 30.0 * SIZES[tiles[0].n]  # 90 m or 30 m
    names = [Path(p).name for p in paths]
    terrain, filled = resample_latlon(
        lats, lons, H, origin, bounds, d, "+".join(names),
        lambda la, lo: f" (the SRTM tiles given): add {_srtm_tile_name(la, lo)}",
    )  # fmt: skip
    terrain.georef["srtm"] = names
    return terrain, filled


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


def geographic_grid(
    tiepoint: list[float], pixel_scale: list[float], shape: tuple[int, int]
) -> tuple[FloatArray, FloatArray]:
    """The latitudes (ascending: rows flipped south first) and longitudes of a geographic
    GeoTIFF's pixel centres (tie point at a pixel's corner, PixelIsArea)."""
    rows, cols = shape
    ti, tj, _, lon0, lat0 = (float(v) for v in tiepoint[:5])
    dlon, dlat = float(pixel_scale[0]), float(pixel_scale[1])
    lons = lon0 + (np.arange(cols) - ti + 0.5) * dlon
    lats = lat0 - (np.arange(rows)[::-1] - tj + 0.5) * dlat
    return lats.astype(np.float64), lons.astype(np.float64)


def inner_box(
    origin: GeoOrigin, lats: FloatArray, lons: FloatArray
) -> tuple[float, float, float, float]:
    """The largest local box ``(xmin, xmax, ymin, ymax)`` inside a lat/lon grid's edges."""

    def local(la: FloatArray, lo: FloatArray) -> FloatArray:
        return origin.to_local(np.column_stack([la, lo, np.full(len(la), origin.alt)]))

    west = local(lats, np.full(len(lats), lons[0]))
    east = local(lats, np.full(len(lats), lons[-1]))
    south = local(np.full(len(lons), lats[0]), lons)
    north = local(np.full(len(lons), lats[-1]), lons)
    eps = 1e-6
    return (float(west[:, 0].max()) + eps, float(east[:, 0].min()) - eps,
            float(south[:, 1].max()) + eps, float(north[:, 1].min()) - eps)  # fmt: skip
