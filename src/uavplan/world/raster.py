"""Elevation rasters read through GDAL (rasterio) and placed on a scenario's local frame, with
the floor held above and the ceiling below the raster's own ground.

**Reading** (:func:`read_raster`): any raster GDAL reads (GeoTIFF with any compression or
tiling, SRTM ``.hgt``, Arc/Info ASCII grid, DTED, ...), one band. A sample is the height at its
pixel's centre: GDAL's geotransform maps pixel corners, and for a file written with
``AREA_OR_POINT=Point`` GDAL shifts it by half a pixel on reading, so the sample of pixel
``(row, col)`` is at ``transform * (col + 0.5, row + 0.5)`` either way. Voids: the band's
NoData value (any value, NaN included), the dataset's masks (internal, ``.msk``, alpha) and
non-finite values; a band with neither a NoData value nor a mask also has the usual sentinels
(:data:`VOID_SENTINELS`) and anything below :data:`LOWEST_GROUND` taken as voids, and says so.
The band's scale and offset are applied and heights in feet converted to metres.

**The ground** between samples is the bilinear surface through them, the *source surface*.
A void has no ground; each connected void region is filled, for the floor, with the highest
valid sample on its rim and, for the ceiling, with the lowest (:func:`fill_voids`): the terrain
there is unknown, and ``uavplan plan`` warns for every UAV that flies over it.

**Placing** (:func:`place_raster`) puts the raster on the scenario's local frame (x east, y
north, metres) in one of three ways:

* ``grid``: a raster without a coordinate reference system is a plain grid: node ``(0, 0)``
  (the south-west sample) at ``terrain.origin``, spacing ``cell_size``, else the geotransform's
  pixel size, else 1 m. Heights are the samples themselves.
* ``crs-offset``: a north-up raster in a projected CRS in metres, with no ``cell_size`` and no
  scenario ``origin`` (or one whose ``crs`` is the raster's), keeps its grid: the local frame
  is the raster's CRS, shifted; the scenario's origin is the raster's centre with that
  ``crs``, so positions convert exactly. Heights are the samples.
* ``reprojected``: anything else (a geographic raster, SRTM tiles, a scenario ``origin`` or
  ``cell_size`` given, a rotated or non-metric grid) is reprojected onto a regular local grid
  of the scenario's frame (:class:`~uavplan.world.geo.GeoOrigin`: the azimuthal equidistant
  projection about the origin, or the origin's own projected CRS) over
  ``bounds`` (else the largest local box inside the raster's samples), cell ``cell_size``
  (else the raster's smaller pixel side in whole metres). Every local node is mapped into the
  raster's pixel space by pyproj (no flat-earth step). The terrain's ``heights`` (its floor)
  are the source surface at the nodes raised, node by node, by the largest rise of the source
  surface above the bilinear interpolant of those node values in the node's up to four local
  cells; its ``lower`` (its ceiling) the same lowered by the largest dip
  (:mod:`uavplan.world._raster_kernels` bounds the rise per cell exactly, piece by piece of the
  source grid, with a slack for the map's departure from affine). A local cell's bilinear
  surface is the interpolant plus a convex combination of its corners' raises, so the floor's
  surface is never below the source surface and the ceiling's never above it, anywhere: a
  flight held above ``heights + min`` and below ``lower + max`` is inside the band relative to
  the raster's own ground. The price is the rise itself: where the ground bends between nodes
  (ridges, valleys) the floor stands above and the ceiling below the source; ``uavplan
  scenario show`` prints both, and a smaller ``cell_size`` narrows them.

The terrain's ``georef["raster"]`` records where the samples came from and how the local frame
maps into them, so that :mod:`uavplan.verify` can read the raster again on its own and check a
flight against the source surface itself.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.world import _raster_kernels as rk
from uavplan.world.geo import GeoOrigin
from uavplan.world.terrain import (
    MAX_DEM_CELLS,
    MAX_HEIGHT,
    Terrain,
    TerrainError,
    not_a_regular_file,
)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Values taken as voids in a band that declares neither a NoData value nor a mask: the NoData
#: values GIS tools write most (ArcGIS's and many exports' -9999, SRTM's -32768, -32767,
#: -99999, float32's lowest).
VOID_SENTINELS = (-9999.0, -32767.0, -32768.0, -99999.0, float(np.finfo(np.float32).min))

#: Below this height (metres) a sample is not ground on Earth (the deepest ocean floor is
#: -10,935 m): a void in a band without a NoData value or mask.
LOWEST_GROUND = -12_000.0

#: How far (in source pixels) a local cell's image in the raster's pixel space is taken to
#: reach beyond the box of its four corners' images: a cell's edges map to curves that bulge
#: by well under a micrometre for cells of kilometres; the pad covers that and rounding.
PIXEL_PAD = 1e-6

#: Metres per unit of the band's height unit, by GDAL's unit type (lower case).
HEIGHT_UNITS = {
    "": 1.0, "m": 1.0, "metre": 1.0, "metres": 1.0, "meter": 1.0, "meters": 1.0,
    "ft": 0.3048, "foot": 0.3048, "feet": 0.3048, "international foot": 0.3048,
    "us-ft": 1200.0 / 3937.0, "us survey foot": 1200.0 / 3937.0, "ftus": 1200.0 / 3937.0,
}  # fmt: skip


@dataclass(frozen=True, eq=False)
class RasterSource:
    """An elevation raster's samples as its file gives them.

    Attributes:
        values: (rows, cols) heights in metres, NaN at voids; row 0 is the file's first row
            (the northern one for a north-up raster).
        transform: ``(a, b, c, d, e, f)``: pixel corner ``(col, row)`` is at
            ``X = a col + b row + c``, ``Y = d col + e row + f`` in the raster's CRS (GDAL's
            geotransform, rasterio's ``Affine``).
        crs_wkt: the raster's coordinate reference system (WKT), or None for a plain grid.
        name: a label (the file's name, or the tiles' names joined with ``+``).
        paths: the files, absolute.
        band: the band read (1-based).
        voids_from: what was taken as a void, in words (for messages).
        driver, compression, area_or_point: as GDAL reports them (for ``scenario show``).
        srtm: the samples are a mosaic of SRTM tiles (a missing map part names a tile).
    """

    values: FloatArray
    transform: tuple[float, float, float, float, float, float]
    crs_wkt: str | None
    name: str
    paths: tuple[str, ...]
    band: int = 1
    voids_from: str = ""
    driver: str = ""
    compression: str = ""
    area_or_point: str = "Area"
    srtm: bool = False
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        r, c = self.values.shape
        return int(r), int(c)

    @cached_property
    def void(self) -> BoolArray:
        return np.asarray(np.isnan(self.values))

    @property
    def voids(self) -> int:
        return int(self.void.sum())

    @cached_property
    def filled_high(self) -> FloatArray:
        """The samples with every void region at the highest valid sample on its rim."""
        return fill_voids(self.values, high=True, name=self.name)

    @cached_property
    def filled_low(self) -> FloatArray:
        """The samples with every void region at the lowest valid sample on its rim."""
        return fill_voids(self.values, high=False, name=self.name)

    @cached_property
    def crs(self) -> Any:
        """The pyproj CRS (None for a plain grid)."""
        if self.crs_wkt is None:
            return None
        from pyproj import CRS

        return CRS.from_wkt(self.crs_wkt)

    @property
    def north_up(self) -> bool:
        a, b, _, d, e, _ = self.transform
        return b == 0.0 and d == 0.0 and a > 0.0 and e < 0.0

    def crs_to_samples(self, X: FloatArray, Y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Sample coordinates ``(u, v)`` (column, row; sample ``(r, c)`` at ``(c, r)``) of
        points in the raster's CRS."""
        a, b, c, d, e, f = self.transform
        det = a * e - b * d
        dX, dY = np.asarray(X) - c, np.asarray(Y) - f
        col = (e * dX - b * dY) / det
        row = (-d * dX + a * dY) / det
        return np.asarray(col - 0.5), np.asarray(row - 0.5)

    def samples_to_crs(self, u: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The inverse of :meth:`crs_to_samples`."""
        a, b, c, d, e, f = self.transform
        col, row = np.asarray(u) + 0.5, np.asarray(v) + 0.5
        return np.asarray(a * col + b * row + c), np.asarray(d * col + e * row + f)

    def describe(self) -> str:
        """One line: what the raster is (``scenario show``)."""
        rows, cols = self.shape
        bits = [self.driver or "raster"]
        if self.crs is not None:
            epsg = self.crs.to_epsg()
            bits.append(f"EPSG:{epsg}" if epsg else self.crs.name)
        else:
            bits.append("no CRS")
        if self.compression:
            bits.append(self.compression)
        bits.append(f"pixel is {self.area_or_point.lower()}")
        ok = ~self.void
        span = (f"heights {np.min(self.values[ok]):.6g}..{np.max(self.values[ok]):.6g} m"
                if ok.any() else "no valid height")  # fmt: skip
        voids = f"{self.voids:,} voids ({self.voids_from})" if self.voids else "no voids"
        return f"{self.name} ({', '.join(bits)}): {rows} x {cols} samples, {span}, {voids}"


# ---------------------------------------------------------------------------- reading
def _check_size(rows: int, cols: int, dtype: str, path: Path) -> None:
    if rows * cols > MAX_DEM_CELLS:
        raise TerrainError(
            f"DEM file {str(path)!r}: {rows} x {cols} samples; a DEM has at most "
            f"{MAX_DEM_CELLS:,} nodes (resample it coarser, or cut it to the area)"
        )
    if rows < 2 or cols < 2:
        raise TerrainError(f"DEM file {str(path)!r}: {rows} x {cols} samples; at least 2 x 2")
    if np.dtype(dtype).kind not in "biuf":
        raise TerrainError(
            f"DEM file {str(path)!r}: samples of type {dtype} are not real numbers (heights)"
        )


def read_raster(path: str | Path, band: int = 1) -> RasterSource:
    """Read one band of an elevation raster through GDAL (see the module docstring).

    Raises:
        TerrainError: naming the file and why (not found, not a raster GDAL reads, too large,
            no such band, samples that are not heights, a unit that is not a length).
    """
    p = Path(path)
    why = not_a_regular_file(p)
    if why is not None:
        raise TerrainError(f"DEM file {str(p)!r}: {why}")
    import rasterio
    from rasterio.enums import MaskFlags
    from rasterio.errors import NotGeoreferencedWarning, RasterioIOError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            with rasterio.Env(GDAL_PAM_ENABLED="NO"), rasterio.open(p) as ds:
                if not 1 <= band <= ds.count:
                    raise TerrainError(f"DEM file {str(p)!r}: no band {band} (it has {ds.count})")
                dtype = ds.dtypes[band - 1]
                _check_size(ds.height, ds.width, dtype, p)
                if ds.transform.is_identity and ds.gcps[0]:
                    raise TerrainError(
                        f"DEM file {str(p)!r}: georeferenced by ground control points only; "
                        "warp it onto a grid first (gdalwarp)"
                    )
                raw = ds.read(band, masked=True)
                flags = ds.mask_flag_enums[band - 1]
                nodata = ds.nodatavals[band - 1]
                scale = ds.scales[band - 1] if ds.scales else 1.0
                offset = ds.offsets[band - 1] if ds.offsets else 0.0
                unit = (ds.units[band - 1] or "") if ds.units else ""
                crs_wkt = ds.crs.to_wkt() if ds.crs else None
                local_unit = None
                if ds.crs and not (ds.crs.is_geographic or ds.crs.is_projected):
                    local_unit = ds.crs.linear_units or "unknown"
                    crs_wkt = None  # a local (engineering) CRS: no place on Earth
                t6 = [float(t) for t in ds.transform[:6]]
                transform = (t6[0], t6[1], t6[2], t6[3], t6[4], t6[5])
                driver = ds.driver
                compression = ds.compression.name.upper() if ds.compression else ""
                area = ds.tags().get("AREA_OR_POINT", "Area")
                tiled = bool(ds.profile.get("tiled", False))
    except TerrainError:
        raise
    except RasterioIOError as exc:
        raise TerrainError(f"DEM file {str(p)!r}: not a raster GDAL can read ({exc})") from exc
    except Exception as exc:  # a corrupt file: say which and why
        raise TerrainError(f"cannot read DEM file {str(p)!r}: {exc}") from exc
    factor = HEIGHT_UNITS.get(unit.strip().lower())
    if factor is None:
        raise TerrainError(
            f"DEM file {str(p)!r}: heights in {unit!r}; uavplan reads metres or feet "
            "(convert the band, or set its unit type)"
        )
    data = np.asarray(raw.data, dtype=np.float64)
    nonfinite = ~np.isfinite(data)
    void = np.asarray(np.ma.getmaskarray(raw)) | nonfinite
    said: list[str] = []
    if MaskFlags.all_valid in flags:  # no NoData value, no mask: the usual sentinels
        sentinel = np.isin(data, np.array(VOID_SENTINELS))
        sentinel |= (data * (scale or 1.0) + (offset or 0.0)) * factor < LOWEST_GROUND
        sentinel &= ~void
        if sentinel.any():
            vals = ", ".join(f"{v:g}" for v in np.unique(data[sentinel])[:3])
            said.append(f"{int(sentinel.sum()):,} samples of {vals} with no NoData value in "
                        "the file, taken as voids")  # fmt: skip
            void |= sentinel
        if nonfinite.any():
            said.append(f"{int(nonfinite.sum()):,} non-finite samples")
    else:
        what = []
        if nodata is not None:
            what.append(f"NoData {nodata:g}")
        if MaskFlags.per_dataset in flags or MaskFlags.alpha in flags:
            what.append("the dataset's mask")
        said.append(" and ".join(what) if what else "the band's mask")
    values = data * (scale if scale is not None else 1.0) + (offset or 0.0)
    values = values * factor
    values[void] = np.nan
    ok = ~void
    if ok.any() and (top := float(np.max(np.abs(values[ok])))) > MAX_HEIGHT:
        raise TerrainError(
            f"DEM file {str(p)!r}: heights reach {top:g} m in magnitude; a terrain's heights "
            f"are within {MAX_HEIGHT:,.0f} m (check the NoData value, the units or the file)"
        )
    if not ok.any():
        raise TerrainError(f"DEM file {str(p)!r}: every sample is a void ({'; '.join(said)})")
    info = {"unit": unit or "m", "tiled": tiled, "nodata": nodata, "local_unit": local_unit}
    return RasterSource(
        values, transform, crs_wkt, p.name, (str(p.resolve()),), band, "; ".join(said),
        driver, compression, area or "Area", False, info,
    )  # fmt: skip


def source_from_latlon(
    lats: FloatArray, lons: FloatArray, H: FloatArray, name: str, paths: Sequence[str | Path]
) -> RasterSource:
    """A regular latitude/longitude grid (``lats`` ascending, ``H`` rows south first, NaN =
    void) as a raster on WGS84 (the SRTM tiles' mosaic)."""
    from pyproj import CRS

    dlat, dlon = float(lats[1] - lats[0]), float(lons[1] - lons[0])
    transform = (dlon, 0.0, float(lons[0]) - 0.5 * dlon, 0.0, -dlat, float(lats[-1]) + 0.5 * dlat)
    values = np.ascontiguousarray(H[::-1], dtype=np.float64)
    return RasterSource(
        values, transform, CRS.from_epsg(4326).to_wkt(), name,
        tuple(str(Path(q).resolve()) for q in paths), 1, "SRTM voids (-32768)", "SRTMHGT", "",
        "Point", True,
    )  # fmt: skip


# ---------------------------------------------------------------------------- voids
def fill_voids(values: FloatArray, high: bool, name: str = "the raster") -> FloatArray:
    """``values`` with every connected (8-neighbour) region of NaN set to the highest
    (``high``) or lowest valid value on its rim (the valid samples next to it)."""
    out = np.array(values, dtype=np.float64)
    void = np.isnan(out)
    if not void.any():
        return out
    if void.all():
        raise TerrainError(f"{name}: every sample under the map is a void")
    from scipy import ndimage

    eight = np.ones((3, 3), dtype=bool)
    labels, _ = ndimage.label(void, structure=eight)
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        r0, r1 = max(sl[0].start - 1, 0), sl[0].stop + 1
        c0, c1 = max(sl[1].start - 1, 0), sl[1].stop + 1
        region = labels[r0:r1, c0:c1] == k
        rim = ndimage.binary_dilation(region, structure=eight) & ~void[r0:r1, c0:c1]
        edge = out[r0:r1, c0:c1][rim]
        block = out[r0:r1, c0:c1]
        block[region] = float(edge.max() if high else edge.min())
    return out


# ---------------------------------------------------------------------------- envelopes
def node_rise(rise: FloatArray) -> FloatArray:
    """Per node, the largest of its up to four adjacent cells' ``rise``: (ny, nx)."""
    ny, nx = rise.shape[0] + 1, rise.shape[1] + 1
    out = np.zeros((ny, nx))
    for dj in (0, 1):
        for di in (0, 1):
            sl = (slice(dj, dj + ny - 1), slice(di, di + nx - 1))
            out[sl] = np.maximum(out[sl], rise)
    return out


def node_any(flags: BoolArray) -> BoolArray:
    """Per node, whether any of its up to four adjacent cells is flagged: (ny, nx)."""
    ny, nx = flags.shape[0] + 1, flags.shape[1] + 1
    out = np.zeros((ny, nx), dtype=bool)
    for dj in (0, 1):
        for di in (0, 1):
            out[dj : dj + ny - 1, di : di + nx - 1] |= flags
    return out


def envelopes(
    hi: FloatArray, lo: FloatArray, U: FloatArray, V: FloatArray, map_err: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The floor's and ceiling's grids of the source samples ``hi`` (voids filled high) and
    ``lo`` (filled low) at the local nodes whose sample coordinates are ``U, V`` (ny, nx):
    ``(upper, lower, S_hi, S_lo)``, the last two the source surfaces at the nodes. Each node
    is the source surface there moved up (down) by the largest rise of the source above (dip
    below) the bilinear interpolant in its adjacent cells (:func:`cell_rise`), so that the
    local bilinear surface of ``upper`` is nowhere below the source's and ``lower``'s nowhere
    above it."""
    S_hi = bilinear_samples(hi, U, V)
    S_lo = bilinear_samples(lo, U, V)
    rise = rk.cell_rise(np.ascontiguousarray(hi), U, V, S_hi, map_err)
    dip = rk.cell_rise(np.ascontiguousarray(-lo), U, V, -S_lo, map_err)
    return S_hi + node_rise(rise), S_lo - node_rise(dip), S_hi, S_lo


def bilinear_samples(H: FloatArray, U: FloatArray, V: FloatArray) -> FloatArray:
    """The bilinear surface through the samples ``H`` at sample coordinates ``U, V`` (clamped to
    the edges)."""
    rows, cols = H.shape
    u = np.clip(U, 0.0, cols - 1.0)
    v = np.clip(V, 0.0, rows - 1.0)
    i = np.minimum(np.floor(u).astype(np.intp), cols - 2)
    j = np.minimum(np.floor(v).astype(np.intp), rows - 2)
    s, r = u - i, v - j
    return np.asarray(
        H[j, i] * (1 - s) * (1 - r) + H[j, i + 1] * s * (1 - r)
        + H[j + 1, i] * (1 - s) * r + H[j + 1, i + 1] * s * r
    )  # fmt: skip


# ---------------------------------------------------------------------------- placing
def local_frame(origin: GeoOrigin) -> tuple[str, float, float]:
    """The local frame of ``origin`` as a CRS and a shift: local ``(x, y)`` is at
    ``(x - sx, y - sy)`` in the CRS (``(frame_crs, sx, sy)``; the CRS as PROJ or EPSG text):
    the azimuthal equidistant projection about ``(lat, lon)``, or the origin's own ``crs``."""
    if origin.crs:
        from pyproj import CRS, Transformer

        X0, Y0 = Transformer.from_crs(CRS.from_epsg(4326), CRS.from_user_input(origin.crs),
                                      always_xy=True).transform(origin.lon, origin.lat)  # fmt: skip
        return origin.crs, origin.x - float(X0), origin.y - float(Y0)
    aeqd = (f"+proj=aeqd +lat_0={origin.lat!r} +lon_0={origin.lon!r} +x_0=0 +y_0=0 "
            "+datum=WGS84 +units=m +no_defs")  # fmt: skip
    return aeqd, origin.x, origin.y


def _local_to_samples(
    src: RasterSource, origin: GeoOrigin
) -> Callable[[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
    """Local (x, y) -> the raster's sample coordinates (u, v), through pyproj."""
    from pyproj import CRS, Transformer

    frame, sx, sy = local_frame(origin)
    fwd = Transformer.from_crs(CRS.from_user_input(frame), src.crs, always_xy=True)

    def to_samples(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        X, Y = fwd.transform(np.asarray(x) - sx, np.asarray(y) - sy)
        return src.crs_to_samples(np.asarray(X), np.asarray(Y))

    return to_samples


def _samples_to_local(
    src: RasterSource, origin: GeoOrigin
) -> Callable[[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
    from pyproj import CRS, Transformer

    frame, sx, sy = local_frame(origin)
    inv = Transformer.from_crs(src.crs, CRS.from_user_input(frame), always_xy=True)

    def to_local(u: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
        X, Y = src.samples_to_crs(u, v)
        x, y = inv.transform(X, Y)
        return np.asarray(x) + sx, np.asarray(y) + sy

    return to_local


def raster_centre(src: RasterSource) -> tuple[float, float]:
    """(lat, lon) of the raster's centre sample position."""
    from pyproj import CRS, Transformer

    rows, cols = src.shape
    X, Y = src.samples_to_crs(np.array([(cols - 1) / 2]), np.array([(rows - 1) / 2]))
    lon, lat = Transformer.from_crs(src.crs, CRS.from_epsg(4326), always_xy=True).transform(X, Y)
    return float(np.asarray(lat)[0]), float(np.asarray(lon)[0])


def inner_local_box(src: RasterSource, origin: GeoOrigin) -> tuple[float, float, float, float]:
    """The largest local box ``(xmin, xmax, ymin, ymax)`` inside the raster's outermost
    samples (its edges mapped to the local frame)."""
    rows, cols = src.shape
    to_local = _samples_to_local(src, origin)
    r, c = np.arange(rows, dtype=np.float64), np.arange(cols, dtype=np.float64)
    edges = {
        "west": to_local(np.zeros(rows), r), "east": to_local(np.full(rows, cols - 1.0), r),
        "top": to_local(c, np.zeros(cols)), "bottom": to_local(c, np.full(cols, rows - 1.0)),
    }  # fmt: skip
    xs_w, xs_e = edges["west"][0], edges["east"][0]
    ys = [edges["top"][1], edges["bottom"][1]]
    south, north = (ys[0], ys[1]) if ys[0].mean() < ys[1].mean() else (ys[1], ys[0])
    if xs_w.mean() > xs_e.mean():
        xs_w, xs_e = xs_e, xs_w
    eps = 1e-6
    return (float(xs_w.max()) + eps, float(xs_e.min()) - eps,
            float(south.max()) + eps, float(north.min()) - eps)  # fmt: skip


def pixel_metres(src: RasterSource, origin: GeoOrigin) -> tuple[float, float]:
    """The lengths in local metres of one sample step along the columns and along the rows, at
    the raster's centre."""
    rows, cols = src.shape
    uc, vc = (cols - 1) / 2, (rows - 1) / 2
    to_local = _samples_to_local(src, origin)
    x, y = to_local(np.array([uc, uc + 1, uc]), np.array([vc, vc, vc + 1]))
    return (float(math.hypot(x[1] - x[0], y[1] - y[0])),
            float(math.hypot(x[2] - x[0], y[2] - y[0])))  # fmt: skip


def _is_metric_projected(src: RasterSource) -> bool:
    crs = src.crs
    if crs is None or not crs.is_projected:
        return False
    try:
        unit = crs.axis_info[0].unit_conversion_factor
    except (IndexError, AttributeError):
        return False
    return bool(abs(unit - 1.0) < 1e-12)


def place_raster(
    src: RasterSource,
    *,
    origin: GeoOrigin | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    cell_size: float | None = None,
    grid_origin: tuple[float, float] = (0.0, 0.0),
    beyond: Callable[[float, float], str] | None = None,
) -> tuple[Terrain, GeoOrigin | None]:
    """The raster on the scenario's local frame (see the module docstring) and the geodetic
    origin taken from it (None when ``origin`` was given or the raster has no CRS).

    Args:
        origin: the scenario's geodetic origin, if it gives one.
        bounds: the scenario's horizontal extent ``(xmin, xmax, ymin, ymax)``, if it gives one
            (only a reprojected raster reads it).
        cell_size: the local grid's spacing, metres.
        grid_origin: node (0, 0)'s position for a raster placed by its own grid.
        beyond: what to add to the message when the map reaches past the raster (SRTM: the
            tile to add), given the point's (lat, lon).

    Raises:
        TerrainError: the map reaches past the raster's samples, too many nodes, every sample
            under the map a void.
    """
    if src.crs is None:
        unit = src.info.get("local_unit")
        if (
            unit is not None
            and cell_size is None
            and str(unit).lower() not in ("metre", "meter", "metres", "meters", "m")
        ):
            raise TerrainError(
                f"{src.name}: its CRS is a local one in {unit!r} units (no EPSG code or "
                "projection: GeoTIFF keys incomplete?), so it has no place on Earth and no "
                "metres; fix its georeference (gdal_edit.py -a_srs EPSG:...) or give "
                "terrain.cell_size to read it as a plain grid"
            )
        return _place_grid(src, cell_size, grid_origin), None
    if cell_size is None and src.north_up and _is_metric_projected(src):
        if origin is None:
            return _place_projected(src, grid_origin)
        if origin.crs and src.crs.equals(origin.crs):  # the scenario's frame is the raster's
            return _place_projected(src, None, origin)
    return _reproject(src, origin, bounds, cell_size, beyond)


def _georef(src: RasterSource, frame: dict[str, Any], **more: Any) -> dict[str, Any]:
    block = {"paths": list(src.paths), "band": src.band, "srtm": src.srtm, **frame}
    g: dict[str, Any] = {"file": src.name, "source": src.name, "raster": block,
                         "raster_info": src.describe(), **more}  # fmt: skip
    if src.crs is not None:
        epsg = src.crs.to_epsg()
        if epsg:
            g["epsg"] = int(epsg)
        g["geographic"] = bool(src.crs.is_geographic)
        g["crs"] = src.crs.name
    return g


def _same_grid_terrain(
    src: RasterSource, x0: float, y0: float, dx: float, dy: float, georef: dict[str, Any]
) -> Terrain:
    """The samples on the local grid node for node (rows flipped south first): heights are the
    samples, voids filled high (``heights``) and low (``lower``)."""
    hi = src.filled_high[::-1]
    lo = src.filled_low[::-1] if src.voids else None
    void = src.void[::-1]
    georef.update(voids_filled=int(void.sum()), void_mask=void if void.any() else None,
                  void_samples=src.voids, lift=None)  # fmt: skip
    return Terrain(np.ascontiguousarray(hi), x0, y0, dx, dy, src.name, georef,
                   lower=None if lo is None else np.ascontiguousarray(lo))  # fmt: skip


def _place_grid(src: RasterSource, cell_size: float | None, grid_origin: tuple[float, float]
                ) -> Terrain:  # fmt: skip
    a, b, _, d, e, _ = src.transform
    identity = (a, b, d, e) == (1.0, 0.0, 0.0, 1.0) or (a, b, d, e) == (1.0, 0.0, 0.0, -1.0)
    if cell_size is not None:
        dx = dy = float(cell_size)
    elif not identity and b == 0.0 and d == 0.0:
        dx, dy = abs(a), abs(e)
    else:
        dx = dy = 1.0
    x0, y0 = float(grid_origin[0]), float(grid_origin[1])
    frame = {"frame": "grid", "grid": [x0, y0, dx, dy], "z_offset": 0.0, "bound_m": 0.0}
    return _same_grid_terrain(src, x0, y0, dx, dy, _georef(src, frame))


def _place_projected(
    src: RasterSource,
    grid_origin: tuple[float, float] | None,
    origin: GeoOrigin | None = None,
) -> tuple[Terrain, GeoOrigin | None]:
    """The raster on its own grid. With ``origin`` (whose frame is the raster's CRS) the grid
    sits where that frame puts it and no origin is returned; else node (0, 0) is at
    ``grid_origin`` and the origin returned is the centre node, in the raster's CRS (exact)."""
    from pyproj import CRS, Transformer

    rows, cols = src.shape
    a, _, c, _, e, f = src.transform
    dx, dy = float(a), float(-e)
    # node (j, i) is sample (rows - 1 - j, i), at CRS X = c + (i + 0.5) a,
    # Y = f + (rows - 1 - j + 0.5) e: node (0, 0) at (X0s, Y0s)
    X0s, Y0s = c + 0.5 * a, f + (rows - 0.5) * e
    if origin is not None:
        _, sx, sy = local_frame(origin)
        x0, y0 = X0s + sx, Y0s + sy
    else:
        assert grid_origin is not None
        x0, y0 = float(grid_origin[0]), float(grid_origin[1])
    ox, oy = X0s - x0, Y0s - y0  # local (x, y) is at CRS (x + ox, y + oy)
    frame = {"frame": "crs-offset", "offset": [ox, oy], "z_offset": 0.0, "bound_m": 0.0}
    if origin is not None:
        frame["z_offset"] = origin.alt
    terrain = _same_grid_terrain(src, x0, y0, dx, dy, _georef(src, frame))
    if origin is not None:
        if origin.alt:
            terrain = Terrain(terrain.heights - origin.alt, x0, y0, dx, dy, terrain.name,
                              terrain.georef, None if terrain.lower is None
                              else terrain.lower - origin.alt)  # fmt: skip
        return terrain, None
    epsg = src.crs.to_epsg()
    crs = f"EPSG:{epsg}" if epsg else src.crs.to_wkt()
    xc, yc = x0 + 0.5 * (cols - 1) * dx, y0 + 0.5 * (rows - 1) * dy
    to_wgs = Transformer.from_crs(src.crs, CRS.from_epsg(4326), always_xy=True)
    lon, lat = to_wgs.transform(xc + ox, yc + oy)
    label = f"EPSG:{epsg}" if epsg else src.crs.name
    note = f"the DEM's centre ({src.name}, {label}; heights AMSL; local metres are its grid's)"
    return terrain, GeoOrigin(float(lat), float(lon), 0.0, xc, yc, note, 0.0, crs)


def _reproject(
    src: RasterSource,
    origin: GeoOrigin | None,
    bounds: tuple[float, float, float, float] | None,
    cell_size: float | None,
    beyond: Callable[[float, float], str] | None,
) -> tuple[Terrain, GeoOrigin | None]:
    given = origin is not None
    if origin is None:
        lat, lon = raster_centre(src)
        epsg = src.crs.to_epsg()
        what = f"EPSG:{epsg}" if epsg else src.crs.name
        origin = GeoOrigin(lat, lon, 0.0, note=f"the DEM's centre ({src.name}, {what}; heights "
                           "AMSL)")  # fmt: skip
    box = bounds if bounds is not None else inner_local_box(src, origin)
    if cell_size is None:
        cell = max(1.0, float(round(min(pixel_metres(src, origin)))))
    else:
        cell = float(cell_size)
    xmin, xmax, ymin, ymax = box
    nx = math.floor((xmax - xmin) / cell + 1e-9) + 1
    ny = math.floor((ymax - ymin) / cell + 1e-9) + 1
    if nx < 2 or ny < 2:
        size = f"{xmax - xmin:g} x {ymax - ymin:g} m"
        raise TerrainError(f"{src.name}: the map ({size}) is under 2 cells of {cell:g} m")
    if nx * ny > MAX_DEM_CELLS:
        raise TerrainError(
            f"{src.name}: the map ({xmax - xmin:g} x {ymax - ymin:g} m) in cells of {cell:g} m "
            f"has {nx:,} x {ny:,} nodes; a DEM has at most {MAX_DEM_CELLS:,} (give a larger "
            "cell_size, or smaller bounds)"
        )
    X, Y = np.meshgrid(xmin + cell * np.arange(nx), ymin + cell * np.arange(ny))
    to_samples = _local_to_samples(src, origin)
    U, V = to_samples(X, Y)
    U, V = np.asarray(U, dtype=np.float64), np.asarray(V, dtype=np.float64)
    rows, cols = src.shape
    tol = 1e-9
    outside = (~np.isfinite(U) | ~np.isfinite(V) | (-tol > U) | (-tol > V)
               | (cols - 1 + tol < U) | (rows - 1 + tol < V))  # fmt: skip
    if outside.any():
        k = int(np.argmax(outside.ravel()))
        G = origin.to_geodetic(np.array([[X.ravel()[k], Y.ravel()[k]]]))[0]
        more = beyond(float(G[0]), float(G[1])) if beyond is not None else ""
        raise TerrainError(
            f"the map reaches {G[0]:.5f}, {G[1]:.5f} (local {X.ravel()[k]:g}, "
            f"{Y.ravel()[k]:g} m), beyond the elevation data of {src.name}{more}"
        )
    # the round trip's error, horizontally, in metres (the stated bound of the placement), and
    # how far the exact map strays from the bilinear one through a cell's corners (at its
    # centre, where a smooth map's departure peaks; doubled): both vary smoothly over the map,
    # so a lattice of at most ~200 x 200 cells measures them
    sj, si = max(1, (ny - 1) // 200), max(1, (nx - 1) // 200)
    Xs, Ys, Us, Vs = (A[::sj, ::si] for A in (X, Y, U, V))
    xb, yb = _samples_to_local(src, origin)(Us.ravel(), Vs.ravel())
    h_err = float(np.max(np.hypot(xb - Xs.ravel(), yb - Ys.ravel())))
    cj, ci = np.arange(0, ny - 1, sj), np.arange(0, nx - 1, si)
    J, I = np.meshgrid(cj, ci, indexing="ij")
    Uc, Vc = to_samples(X[J, I] + 0.5 * cell, Y[J, I] + 0.5 * cell)
    mid_u = 0.25 * (U[J, I] + U[J + 1, I] + U[J, I + 1] + U[J + 1, I + 1])
    mid_v = 0.25 * (V[J, I] + V[J + 1, I] + V[J, I + 1] + V[J + 1, I + 1])
    map_err = 2.0 * float(max(np.max(np.abs(Uc - mid_u)), np.max(np.abs(Vc - mid_v))))
    map_err += PIXEL_PAD
    upper, lower, at, at_lo = envelopes(src.filled_high, src.filled_low, U, V, map_err)
    void = node_any(rk.cell_voids(np.ascontiguousarray(src.void), U, V, PIXEL_PAD))
    upper -= origin.alt
    lower -= origin.alt
    at -= origin.alt
    at_lo -= origin.alt
    # the lift: how far the grids stand from the source surface at the nodes
    measured = ~void if not void.all() else np.ones_like(void)  # voids' nodes: unknown ground
    up, down = (upper - at)[measured], (at_lo - lower)[measured]
    lift = {
        "floor_median": float(np.median(up)), "floor_max": float(np.max(up)),
        "ceiling_median": float(np.median(down)), "ceiling_max": float(np.max(down)),
    }  # fmt: skip
    frame_crs, sx, sy = local_frame(origin)
    frame = {
        "frame": "reprojected", "frame_crs": frame_crs, "shift": [sx, sy],
        "z_offset": origin.alt, "bound_m": 0.0, "horizontal_error_m": h_err,
        "map_error_px": map_err,
    }  # fmt: skip
    georef = _georef(
        src, frame, origin=origin.record(), voids_filled=int(void.sum()),
        void_mask=void if void.any() else None, void_samples=src.voids, lift=lift,
        resampling="the source surface at the nodes, raised (floor) and lowered (ceiling) by "
        "its largest rise above and dip below their bilinear interpolant",
    )  # fmt: skip
    if src.srtm:
        georef["srtm"] = [Path(q).name for q in src.paths]
    terrain = Terrain(upper, xmin, ymin, cell, cell, src.name, georef, lower=lower)
    return terrain, (None if given else origin)


def points_over_voids(terrain: Terrain, points: FloatArray) -> int:
    """How many of ``points`` (n, >=2) lie in a terrain cell with a corner whose height came
    from a void of its source (0 for a terrain without voids)."""
    mask = terrain.georef.get("void_mask")
    if mask is None or not np.any(mask):
        return 0
    P = np.asarray(points, dtype=np.float64)
    ny, nx = mask.shape
    j = np.clip(np.floor((P[:, 0] - terrain.x0) / terrain.dx).astype(int), 0, nx - 2)
    i = np.clip(np.floor((P[:, 1] - terrain.y0) / terrain.dy).astype(int), 0, ny - 2)
    hit = mask[i, j] | mask[i + 1, j] | mask[i, j + 1] | mask[i + 1, j + 1]
    return int(hit.sum())


def length_over_voids(terrain: Terrain, points: FloatArray) -> float:
    """About how many metres of the polyline ``points`` (n, >= 2) fly over terrain cells with a
    corner whose height came from a void of its source (sampled at a quarter cell)."""
    mask = terrain.georef.get("void_mask")
    P = np.asarray(points, dtype=np.float64)[:, :2]
    if mask is None or not np.any(mask) or len(P) < 2:
        return 0.0
    step = 0.25 * min(terrain.dx, terrain.dy)
    seg = np.hypot(*(P[1:] - P[:-1]).T)
    k = np.maximum(1, np.ceil(seg / step)).astype(np.int64)
    which = np.repeat(np.arange(len(seg)), k)
    frac = (np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k) + 0.5) / k[which]
    mid = P[which] + frac[:, None] * (P[which + 1] - P[which])
    ny, nx = mask.shape
    i = np.clip(np.floor((mid[:, 0] - terrain.x0) / terrain.dx).astype(int), 0, nx - 2)
    j = np.clip(np.floor((mid[:, 1] - terrain.y0) / terrain.dy).astype(int), 0, ny - 2)
    hit = mask[j, i] | mask[j + 1, i] | mask[j, i + 1] | mask[j + 1, i + 1]
    return float(np.sum((seg[which] / k[which])[hit]))
