"""Elevation rasters written the way GIS tools write them (rasterio, GDAL), for the tests of
reading, placing and verifying terrain: a landscape known in closed form, NoData of any kind,
pixel-is-point or -area, compression and tiling, geographic or projected."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: The hill scene: geographic pixels of 3 arc-seconds, 120 x 160, north-west corner here.
LON0, LAT0, STEP = -84.40, 36.70, 1.0 / 1200.0


def landscape(lat: FloatArray, lon: FloatArray) -> FloatArray:
    """Heights AMSL, metres: a tilted plain, a ridge and a hill of 600 m (steep enough that
    every cell bends)."""
    x = (lon - LON0) / STEP
    y = (LAT0 - lat) / STEP
    hill = 600.0 * np.exp(-((x - 80.0) ** 2 + (y - 60.0) ** 2) / (2 * 14.0**2))
    ridge = 150.0 * np.exp(-((x - 0.4 * y - 30.0) ** 2) / (2 * 6.0**2))
    wave = 12.0 * np.sin(x / 3.0) * np.cos(y / 4.0)
    return np.asarray(300.0 + 0.8 * x + 0.5 * y + hill + ridge + wave)


def hill_samples(rows: int = 120, cols: int = 160) -> tuple[FloatArray, Any]:
    """The landscape at the pixel centres of the geographic grid (row 0 north) and its
    geotransform (pixel corners)."""
    from rasterio.transform import Affine

    lat = LAT0 - (np.arange(rows) + 0.5) * STEP
    lon = LON0 + (np.arange(cols) + 0.5) * STEP
    H = landscape(lat[:, None], lon[None, :])
    return H, Affine(STEP, 0.0, LON0, 0.0, -STEP, LAT0)


def peak_block(H: FloatArray, half: int = 12) -> tuple[slice, slice]:
    """A square of samples around the highest one."""
    j, i = np.unravel_index(int(np.argmax(H)), H.shape)
    return slice(max(j - half, 0), j + half), slice(max(i - half, 0), i + half)


def write(
    path: Path,
    values: FloatArray,
    transform: Any,
    crs: str | None = "EPSG:4326",
    *,
    dtype: str = "float32",
    nodata: float | None = None,
    void: tuple[slice, slice] | None = None,
    void_value: float | None = None,
    point: bool = False,
    **profile: Any,
) -> Path:
    """Write ``values`` (row 0 north) as a GeoTIFF; the samples in ``void`` set to
    ``void_value`` (else ``nodata``); ``point``: AREA_OR_POINT=Point with the same pixel
    centres (GDAL writes the tie point at the first pixel's centre); ``profile``: rasterio's
    creation options (``compress``, ``tiled``, ``blockxsize``, ...)."""
    import rasterio

    data = np.array(values, dtype=np.float64)
    if void is not None:
        data[void] = nodata if void_value is None else void_value
    rows, cols = data.shape
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=cols,
        height=rows,
        count=1,
        dtype=dtype,
        crs=crs,
        transform=transform,
        nodata=nodata,
        **profile,
    ) as f:
        if point:
            f.update_tags(AREA_OR_POINT="Point")
        f.write(data.astype(dtype), 1)
    return path


def utm_hill(rows: int = 100, cols: int = 140, cell: float = 30.0) -> tuple[FloatArray, Any]:
    """The landscape's shape on a UTM 16N grid (metres) near the geographic scene."""
    from rasterio.transform import Affine

    E0, N0 = 730_000.0, 4_066_000.0
    x = np.arange(cols) + 0.5
    y = np.arange(rows) + 0.5
    X, Y = np.meshgrid(x, y)
    H = 300.0 + 0.5 * X + 0.3 * Y + 500.0 * np.exp(-((X - 90) ** 2 + (Y - 45) ** 2) / 300.0)
    H += 10.0 * np.sin(X / 2.5) * np.cos(Y / 3.5)
    return H, Affine(cell, 0.0, E0, 0.0, -cell, N0)


def source_ground(path: Path, origin: Any, x: FloatArray, y: FloatArray) -> FloatArray:
    """The raster's own ground at local points, by the tests' own route: rasterio's masked
    samples, pyproj from the origin's azimuthal equidistant frame (``origin``: lat, lon, alt,
    x, y) to the raster's CRS, the bilinear surface through the pixel centres; NaN where a
    cell corner is a void or the point is beyond the samples. Heights in the local frame."""
    import rasterio
    from pyproj import CRS, Transformer

    with rasterio.open(path) as ds:
        m = ds.read(1, masked=True)
        crs, tr = ds.crs, ds.transform
    H = np.where(np.ma.getmaskarray(m), np.nan, np.asarray(m.data, dtype=np.float64))
    if getattr(origin, "crs", ""):  # the local frame is that CRS, shifted
        local = CRS.from_user_input(origin.crs)
        X0, Y0 = Transformer.from_crs(CRS.from_epsg(4326), local, always_xy=True).transform(
            origin.lon, origin.lat
        )
    else:
        local = CRS.from_proj4(
            f"+proj=aeqd +lat_0={origin.lat!r} +lon_0={origin.lon!r} +datum=WGS84 +units=m"
        )
        X0 = Y0 = 0.0
    X, Y = Transformer.from_crs(local, CRS.from_user_input(crs), always_xy=True).transform(
        X0 + np.asarray(x) - origin.x, Y0 + np.asarray(y) - origin.y
    )
    a, b, c, d, e, f = tr[:6]
    det = a * e - b * d
    dX, dY = np.asarray(X) - c, np.asarray(Y) - f
    u = (e * dX - b * dY) / det - 0.5
    v = (-d * dX + a * dY) / det - 0.5
    rows, cols = H.shape
    out = np.full(u.shape, np.nan)
    ok = (u >= 0) & (v >= 0) & (u <= cols - 1) & (v <= rows - 1)
    i = np.minimum(np.floor(u[ok]).astype(int), cols - 2)
    j = np.minimum(np.floor(v[ok]).astype(int), rows - 2)
    s, r = u[ok] - i, v[ok] - j
    out[ok] = (
        H[j, i] * (1 - s) * (1 - r)
        + H[j, i + 1] * s * (1 - r)
        + H[j + 1, i] * (1 - s) * r
        + H[j + 1, i + 1] * s * r
    )
    return out - origin.alt
