"""SRTM ``.hgt`` elevation tiles, mosaicked and resampled onto a scenario's local frame.

A tile ``N36W085.hgt`` covers latitudes 36-37 N and longitudes 85-84 W: big-endian int16
heights (metres above mean sea level), 1201 x 1201 (3 arc-seconds) or 3601 x 3601 (1
arc-second) samples, row 0 the northern edge, the edge rows and columns shared with the
neighbouring tiles, voids -32768. Tiles of one resolution are put on one latitude/longitude
grid (a missing tile is void), and the terrain is resampled onto a local metric grid through
the scenario's :class:`~uavplan.world.geo.GeoOrigin` (pyproj's azimuthal equidistant
projection) as any geographic raster is (:func:`uavplan.world.raster.place_raster`): the
floor's grid never below the tiles' bilinear ground and the ceiling's never above it, each void
region filled with the highest (floor) and lowest (ceiling) valid height on its rim;
:func:`terrain_from_srtm` reports how many local nodes a void touched.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uavplan.world.geo import GeoOrigin
from uavplan.world.raster import place_raster, source_from_latlon
from uavplan.world.terrain import Terrain, TerrainError, not_a_regular_file

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


def _srtm_tile_name(lat: float, lon: float) -> str:
    return (f"{'N' if lat >= 0 else 'S'}{abs(math.floor(lat)):02d}"
            f"{'E' if lon >= 0 else 'W'}{abs(math.floor(lon)):03d}.hgt")  # fmt: skip


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
    src = source_from_latlon(lats, lons, H, "+".join(names), paths)
    terrain, _ = place_raster(
        src, origin=origin, bounds=bounds, cell_size=d,
        beyond=lambda la, lo: f" (the SRTM tiles given): add {_srtm_tile_name(la, lo)}",
    )  # fmt: skip
    return terrain, int(terrain.georef.get("voids_filled", 0))
