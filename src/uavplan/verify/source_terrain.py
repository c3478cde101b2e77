"""The terrain and the altitude band checked against the elevation raster itself.

When the scenario's terrain was read from a raster (``terrain.georef["raster"]``: the files, the
band, and how the local frame maps into them), the verifier reads the raster again through GDAL
with its own code, not the planner's grid, and checks every flown segment against the raster's
own ground: the bilinear surface through its samples (``S``).

* **Reading** (:func:`read_source`): the band's NoData value (any, NaN), the dataset's masks and
  non-finite samples are voids; a band with neither a NoData value nor a mask also has
  -9999, -32767, -32768, -99999, float32's lowest and anything below -12,000 m as voids (the
  convention of ``docs/scenario-format.md``); scale and offset applied, feet converted. Several
  files (SRTM tiles) are merged by rasterio. Each connected void region stands at the highest
  valid sample on its rim for the floor and the lowest for the ceiling (no ground is known
  there: a flight over one is warned about).
* **Mapping** local ``(x, y)`` into the raster's sample coordinates: ``grid`` (a plain grid at
  ``x0, y0, dx, dy``, row 0 the file's first, i.e. northern, row) and ``crs-offset`` (the
  raster's CRS is the local frame shifted) are affine, so a segment stays straight there; the
  ``reprojected`` frame (the scenario's azimuthal equidistant projection about its origin, or
  its origin's projected CRS, to the raster's CRS) goes through pyproj, and each segment is
  cut into pieces of at most a quarter of the raster's smaller pixel side, whose ends are
  mapped exactly (a piece's image bends from the straight line between its ends by under a
  micrometre).
* **Checking**: on each straight piece in sample space the clearance ``z - S`` is a quadratic
  per raster cell (the same closed form as :mod:`uavplan.verify.terrain`), so its minimum
  (the floor: ``terrain`` at 0, a ground band's ``min``) and maximum (the band's ``max``) are
  exact. A point beyond the raster's outermost samples is a ``terrain`` violation (no data).
* **The planner's terrain** is compared with ``S`` at every point checked: its floor's grid
  below ``S`` or its ceiling's above it by more than the bound the terrain states is reported
  as a warning (the raster was misread): the flight's verdict comes from ``S`` either way.
"""

from __future__ import annotations

import math
import os
import warnings
import weakref
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import TOL, Violation, fmt_num, fmt_points, point_at
from uavplan.verify.terrain import bilinear_height, terrain_clearance_extrema, within_reach
from uavplan.world.obstacles import AltitudeBand
from uavplan.world.terrain import Terrain

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_SENTINELS = np.array([-9999.0, -32767.0, -32768.0, -99999.0, float(np.finfo(np.float32).min)])
_BELOW_EARTH = -12_000.0
_US_FOOT = 1200.0 / 3937.0
_FEET = {"ft": 0.3048, "foot": 0.3048, "feet": 0.3048, "international foot": 0.3048,
         "us-ft": _US_FOOT, "us survey foot": _US_FOOT, "ftus": _US_FOOT}  # fmt: skip


class SourceError(ValueError):
    """The raster a terrain names cannot be read again."""


@dataclass(frozen=True, eq=False)
class SourceGround:
    """A raster's ground as the verifier reads it.

    Attributes:
        name: the files' names.
        hi, lo: (rows, cols) samples in the local frame's heights (``AMSL - z_offset``), voids
            at the highest (``hi``) and lowest (``lo``) valid sample on their region's rim.
        void: (rows, cols) the voids.
        to_samples: local ``(x, y)`` arrays -> sample coordinates ``(u, v)`` (column, row).
        piece: the longest piece of a segment mapped as straight, local metres (inf: the
            mapping is affine).
        bound: how far the planner's terrain may stand from ``S`` (metres) as its placement
            states.
    """

    name: str
    hi: FloatArray
    lo: FloatArray
    void: BoolArray
    to_samples: Callable[[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]
    piece: float
    bound: float


def _read_band(paths: tuple[str, ...], band: int) -> tuple[FloatArray, Any, Any]:
    """(values with voids NaN, geotransform, crs) of the files, merged when several."""
    import rasterio
    from rasterio.enums import MaskFlags
    from rasterio.errors import NotGeoreferencedWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        if len(paths) > 1:
            from rasterio.merge import merge

            sets = [rasterio.open(p) for p in paths]
            try:
                arr, transform = merge(sets, indexes=[band], dtype="float64", nodata=np.nan)
                crs = sets[0].crs
            finally:
                for d in sets:
                    d.close()
            return np.asarray(arr[0], dtype=np.float64), transform, crs
        with rasterio.open(paths[0]) as ds:
            raw = ds.read(band, masked=True)
            flags = ds.mask_flag_enums[band - 1]
            scale, offset = ds.scales[band - 1], ds.offsets[band - 1]
            unit = (ds.units[band - 1] or "").strip().lower() if ds.units else ""
            transform, crs = ds.transform, ds.crs
    vals = np.asarray(raw.data, dtype=np.float64)
    bad = np.asarray(np.ma.getmaskarray(raw)) | ~np.isfinite(vals)
    factor = _FEET.get(unit, 1.0)
    metres = (vals * (scale if scale is not None else 1.0) + (offset or 0.0)) * factor
    if MaskFlags.all_valid in flags:
        bad |= np.isin(vals, _SENTINELS) | (metres < _BELOW_EARTH)
    metres[bad] = np.nan
    return metres, transform, crs


def _rim_fill(values: FloatArray, high: bool) -> FloatArray:
    """Each connected region of NaN at the highest (``high``) or lowest valid value next to it."""
    from scipy import ndimage

    out = values.copy()
    holes = np.isnan(out)
    if not holes.any():
        return out
    if holes.all():
        raise SourceError("every sample is a void")
    labels, count = ndimage.label(holes, structure=np.ones((3, 3), dtype=bool))
    # a rim sample takes the labels of the holes around it: look at the 8 neighbours in turn
    rows, cols = out.shape
    best = np.full(count + 1, -np.inf if high else np.inf)
    padded = np.pad(labels, 1)
    valid = ~holes
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr == 0 and dc == 0:
                continue
            near = padded[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols]
            hit = valid & (near > 0)
            if high:
                np.maximum.at(best, near[hit], out[hit])
            else:
                np.minimum.at(best, near[hit], out[hit])
    out[holes] = best[labels[holes]]
    return out


def _inverse(transform: Any) -> Callable[[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
    a, b, c, d, e, f = (float(v) for v in tuple(transform)[:6])
    det = a * e - b * d

    def inv(X: FloatArray, Y: FloatArray) -> tuple[FloatArray, FloatArray]:
        dX, dY = np.asarray(X) - c, np.asarray(Y) - f
        return (e * dX - b * dY) / det - 0.5, (-d * dX + a * dY) / det - 0.5

    return inv


@lru_cache(maxsize=8)
def _load(key: tuple[Any, ...], stamp: tuple[int, ...]) -> SourceGround:
    """The raster of ``key``, read once per process while its files' times (``stamp``) stay."""
    paths, band, frame, params, z_offset, bound = key
    values, transform, crs = _read_band(paths, band)
    rows, cols = values.shape
    name = "+".join(os.path.basename(p) for p in paths)
    hi, lo = _rim_fill(values, True) - z_offset, _rim_fill(values, False) - z_offset
    to_pix = _inverse(transform)
    piece = math.inf
    if frame == "grid":
        x0, y0, dx, dy = params

        def to_samples(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
            return (np.asarray(x) - x0) / dx, (rows - 1) - (np.asarray(y) - y0) / dy

    elif frame == "crs-offset":
        ox, oy = params

        def to_samples(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
            return to_pix(np.asarray(x) + ox, np.asarray(y) + oy)

    elif frame == "reprojected":
        from pyproj import CRS, Transformer

        frame_crs, ox, oy = params
        local = CRS.from_user_input(frame_crs)
        fwd = Transformer.from_crs(local, CRS.from_user_input(crs), always_xy=True)

        def to_samples(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
            X, Y = fwd.transform(np.asarray(x, dtype=np.float64) - ox,
                                 np.asarray(y, dtype=np.float64) - oy)  # fmt: skip
            return to_pix(X, Y)

        # a quarter of the smaller pixel side, measured in local metres at the centre
        back = Transformer.from_crs(CRS.from_user_input(crs), local, always_xy=True)
        a, b, c, d, e, f = (float(v) for v in tuple(transform)[:6])
        cu, cv = cols / 2.0, rows / 2.0
        px = np.array([a * cu + b * cv + c, a * (cu + 1) + b * cv + c, a * cu + b * (cv + 1) + c])
        py = np.array([d * cu + e * cv + f, d * (cu + 1) + e * cv + f, d * cu + e * (cv + 1) + f])
        lx, ly = back.transform(px, py)
        side = min(math.hypot(lx[1] - lx[0], ly[1] - ly[0]),
                   math.hypot(lx[2] - lx[0], ly[2] - ly[0]))  # fmt: skip
        piece = 0.25 * side
    else:
        raise SourceError(f"unknown raster frame {frame!r}")
    return SourceGround(name, np.ascontiguousarray(hi), np.ascontiguousarray(lo),
                        np.isnan(values), to_samples, piece, float(bound))  # fmt: skip


def read_source(terrain: Terrain | None) -> SourceGround | None:
    """The raster behind ``terrain`` as the verifier reads it (None: the terrain names none)."""
    if terrain is None:
        return None
    block = terrain.georef.get("raster")
    if not block:
        return None
    frame = str(block["frame"])
    params: tuple[Any, ...]
    if frame == "grid":
        params = tuple(float(v) for v in block["grid"])
    elif frame == "crs-offset":
        params = tuple(float(v) for v in block["offset"])
    else:
        sx, sy = (float(v) for v in block["shift"])
        params = (str(block["frame_crs"]), sx, sy)
    paths = tuple(str(p) for p in block["paths"])
    stamp = tuple(os.stat(p).st_mtime_ns for p in paths)
    key = (paths, int(block.get("band", 1)), frame, params, float(block.get("z_offset", 0.0)),
           float(block.get("bound_m", 0.0)))  # fmt: skip
    try:
        return _load(key, stamp)
    except SourceError:
        raise
    except Exception as exc:
        raise SourceError(f"cannot read the terrain's raster {', '.join(paths)}: {exc}") from exc


Pieces = tuple[FloatArray, FloatArray, NDArray[np.int64], FloatArray]


def _pieces(a: FloatArray, b: FloatArray, piece: float) -> Pieces:
    """The segments ``a -> b`` cut into pieces of at most ``piece`` metres horizontally:
    (piece starts, piece ends, segment index, (parameter of the piece's start, its span))."""
    m = len(a)
    if not math.isfinite(piece):
        k = np.ones(m, dtype=np.int64)
    else:
        k = np.maximum(1, np.ceil(np.hypot(*(b[:, :2] - a[:, :2]).T) / piece)).astype(np.int64)
    seg = np.repeat(np.arange(m), k)
    first = np.repeat(np.cumsum(k) - k, k)
    idx = np.arange(int(k.sum())) - first
    K = k[seg].astype(np.float64)
    s0, s1 = idx / K, (idx + 1) / K
    d = b[seg] - a[seg]
    return a[seg] + s0[:, None] * d, a[seg] + s1[:, None] * d, seg, np.column_stack([s0, s1 - s0])


def _source_extrema(traj: Trajectory, source: SourceGround) -> tuple[Any, ...]:
    """The flight's pieces in the raster and the exact clearance extrema on each: ``(pa, pb,
    seg, span, ua, va, ub, vb, lo_ext, hi_ext)``, ``lo_ext`` over the floor's samples (its
    column 0 the least ``z - S``), ``hi_ext`` over the ceiling's (column 2 the largest)."""
    a, b = traj.points[:-1], traj.points[1:]
    pa, pb, seg, span = _pieces(a, b, source.piece)
    ua, va = source.to_samples(pa[:, 0], pa[:, 1])
    ub, vb = source.to_samples(pb[:, 0], pb[:, 1])
    A = np.column_stack([ua, va, pa[:, 2]])
    B = np.column_stack([ub, vb, pb[:, 2]])
    lo_ext = terrain_clearance_extrema(A, B, Terrain(source.hi, 0.0, 0.0, 1.0, 1.0, source.name))
    hi_ext = terrain_clearance_extrema(A, B, Terrain(source.lo, 0.0, 0.0, 1.0, 1.0, source.name))
    return pa, pb, seg, span, ua, va, ub, vb, lo_ext, hi_ext


def _cut_at_cells(pa: FloatArray, pb: FloatArray, source: SourceGround) -> tuple[FloatArray, ...]:
    """The pieces ``pa -> pb`` (each at most a sample long) cut where they cross a row or a
    column of samples, so that each lies in one cell (to within the mapping's bend): the bound
    of the ground within reach then reads only the cells a line from the piece can enter."""
    ua, va = source.to_samples(pa[:, 0], pa[:, 1])
    ub, vb = source.to_samples(pb[:, 0], pb[:, 1])
    cuts = [np.zeros(len(pa)), np.ones(len(pa))]
    for x0, x1 in ((ua, ub), (va, vb)):
        k = np.floor(np.maximum(x0, x1))
        crosses = (np.minimum(x0, x1) < k) & (k < np.maximum(x0, x1))
        with np.errstate(divide="ignore", invalid="ignore"):
            cuts.append(np.where(crosses, (k - x0) / (x1 - x0), np.nan))
    t = np.sort(np.column_stack(cuts), axis=1)  # nan last
    t0, t1 = t[:, :-1], t[:, 1:]
    keep = np.isfinite(t1) & (t1 > t0)
    rows = np.nonzero(keep)[0]
    d = pb - pa
    return pa[rows] + t0[keep][:, None] * d[rows], pa[rows] + t1[keep][:, None] * d[rows]


_VIEWS: dict[int, tuple[Any, FloatArray, FloatArray, Terrain]] = {}


def _views(grid: FloatArray) -> tuple[FloatArray, FloatArray, Terrain]:
    """The raster's x-edges (rows, cols - 1) and y-edges (rows - 1, cols), signed height
    differences, and the grid as a terrain in sample coordinates, made once per grid (a
    flight's bounds ask for them at every step of a margin's bisection); kept while the grid
    lives."""
    got = _VIEWS.get(id(grid))
    if got is None or got[0]() is not grid:
        for key in [k for k, v in _VIEWS.items() if v[0]() is None]:
            del _VIEWS[key]
        got = _VIEWS[id(grid)] = (weakref.ref(grid), np.diff(grid, axis=1), np.diff(grid, axis=0),
                                  Terrain(grid, 0.0, 0.0, 1.0, 1.0, "samples"))  # fmt: skip
    return got[1], got[2], got[3]


#: :func:`_directional_change`: the directions a straight line may take, in arcs of 2 pi / this.
DIRECTIONS = 32


def _arc_range(lo: FloatArray, hi: FloatArray, f: Callable[[Any], Any]) -> tuple[Any, Any]:
    """The least and largest of ``f`` (cos or sin) over each arc ``[lo, hi]`` (radians,
    shorter than a quarter turn): at its ends, or where the arc holds an extremum."""
    a, b = f(lo), f(hi)
    least, most = np.minimum(a, b), np.maximum(a, b)
    for k in range(-1, 5):  # the extrema of cos at k pi, of sin at k pi + pi / 2
        at = k * math.pi + (0.0 if f is np.cos else 0.5 * math.pi)
        inside = (lo <= at) & (at <= hi)
        value = f(at)
        least = np.where(inside, np.minimum(least, value), least)
        most = np.where(inside, np.maximum(most, value), most)
    return least, most


def _slab(c_lo: Any, c_hi: Any, p_lo: Any, p_hi: Any, k: Any) -> tuple[Any, Any, Any]:
    """A straight line from a point in ``[p_lo, p_hi]`` (samples along one axis) whose speed
    along that axis (samples per metre) lies in ``[c_lo, c_hi]``: the least length at which it
    can enter the slab ``[k, k + 1]``, the largest at which it can leave it, and whether it can
    reach it at all (lengths in metres)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ahead = k - p_hi  # > 0: the slab lies ahead along +
        behind = p_lo - (k + 1.0)  # > 0: the slab lies ahead along -
        t_in = np.where(
            ahead > 0,
            ahead / np.where(c_hi > 0, c_hi, 1.0),
            np.where(behind > 0, behind / np.where(c_lo < 0, -c_lo, 1.0), 0.0),
        )
        reach = ~(((ahead > 0) & (c_hi <= 0)) | ((behind > 0) & (c_lo >= 0)))
        out_pos = (k + 1.0 - p_lo) / np.where(c_lo > 0, c_lo, 1.0)
        out_neg = (p_hi - k) / np.where(c_hi < 0, -c_hi, 1.0)
        t_out = np.where(c_lo > 0, out_pos, np.where(c_hi < 0, out_neg, np.inf))
    return t_in, t_out, reach & (t_out > 0)


def _speed(J: FloatArray, D: FloatArray, row: int, cos: tuple[Any, Any], sin: tuple[Any, Any]
           ) -> tuple[Any, Any]:  # fmt: skip
    """The range of sample axis ``row``'s speed (samples per metre) along the metric
    directions of each arc (``cos``, ``sin``: their ranges, (K,)), the map's Jacobian within
    ``J`` +- ``D`` (n, 2, 2): interval arithmetic, (n, K) each."""
    lo = np.zeros((J.shape[0], len(cos[0])))
    hi = np.zeros_like(lo)
    for col, (a, b) in enumerate((cos, sin)):
        j = J[:, row, col][:, None]
        lo += np.minimum(j * a, j * b)
        hi += np.maximum(j * a, j * b)
        spread = D[:, row, col][:, None] * np.maximum(np.abs(a), np.abs(b))
        lo -= spread
        hi += spread
    return lo, hi


def _directional_change(
    grid: FloatArray, box: tuple[FloatArray, ...], cells: tuple[FloatArray, ...],
    ok: BoolArray, J: FloatArray, D: FloatArray, reach: float, up: bool,
) -> FloatArray:  # fmt: skip
    """How far the bilinear surface ``grid`` (samples) can fall (rise, ``up``) along a
    straight line of at most ``reach`` metres from a point of each piece's box ``(u_min,
    u_max, v_min, v_max)`` (n,) in samples, through the cells ``(ii, jj, x0, x1, y0, y1)`` (9,
    n) (the cell's column and row, and the box grown by the reach in the cell's own
    coordinates), those with ``ok``; the map from metres to samples has its Jacobian within
    ``J`` +- ``D`` (n, 2, 2). A line has one direction: per arc of :data:`DIRECTIONS` metric
    directions, the line's speed along each sample axis has a range (:func:`_speed`), the
    surface's rate along the line is linear in that speed and, in a cell, affine in the point
    (the x-slope interpolates the two x-edges along y, the y-slope the y-edges along x), so its
    largest is at a corner of the cell's part and an end of each speed's range; the line's
    length inside a cell is bounded by where it can enter and leave the cell's column and row
    (:func:`_slab`). The bound: the rates times those lengths summed, or the largest rate
    times ``reach``, the smaller; the largest over the arcs."""
    u_min, u_max, v_min, v_max = box
    ii, jj, x0, x1, y0, y1 = cells
    K = DIRECTIONS
    half = math.pi / K
    phi = (np.arange(K, dtype=np.float64) + 0.5) * (2.0 * math.pi / K)
    cos = _arc_range(phi - half, phi + half, np.cos)
    sin = _arc_range(phi - half, phi + half, np.sin)
    su = _speed(J, D, 0, cos, sin)
    sv = _speed(J, D, 1, cos, sin)
    ex, ey, _ = _views(grid)
    sign = 1.0 if up else -1.0
    total = np.zeros((len(u_min), K))
    steepest = np.zeros((len(u_min), K))
    for c in range(ii.shape[0]):
        i, j = ii[c], jj[c]
        rate = np.zeros((len(u_min), K))
        for fy in (y0[c], y1[c]):
            gx = sign * ((1.0 - fy) * ex[j, i] + fy * ex[j + 1, i])
            for fx in (x0[c], x1[c]):
                gy = sign * ((1.0 - fx) * ey[j, i] + fx * ey[j, i + 1])
                for a in su:
                    for b in sv:
                        rate = np.maximum(rate, gx[:, None] * a + gy[:, None] * b)
        tu_in, tu_out, ru = _slab(*su, u_min[:, None], u_max[:, None], i[:, None])
        tv_in, tv_out, rv = _slab(*sv, v_min[:, None], v_max[:, None], j[:, None])
        inside = np.minimum(np.minimum(tu_out, tv_out), reach)
        inside = np.maximum(inside - np.maximum(tu_in, tv_in), 0.0)
        inside = np.where(ru & rv & ok[c][:, None], inside, 0.0)
        total += rate * inside
        steepest = np.maximum(steepest, np.where(inside > 0, rate, 0.0))
    return np.asarray(np.minimum(total, steepest * reach).max(axis=1))


def _piece_bounds(
    pa: FloatArray, pb: FloatArray, source: SourceGround, reach: float,
    want: tuple[float, float] = (math.inf, -math.inf), directional: bool = True,
) -> tuple[FloatArray, ...] | None:  # fmt: skip
    """Per piece ``pa -> pb`` (each in one cell, at most a sample long): bounds of the least
    height above the highest ground within ``reach`` metres of it and of the largest above the
    lowest; None where a neighbourhood would reach past the adjacent cells
    (:func:`_piece_reach_bound`). The directional bound (unless not ``directional``) only where
    the first misses ``want``, the least and largest heights wanted (by default everywhere)."""
    ua, va = source.to_samples(pa[:, 0], pa[:, 1])
    ub, vb = source.to_samples(pb[:, 0], pb[:, 1])
    ends = np.zeros((2, len(pa), 2, 2))  # the map's Jacobian at each end, signed
    for e, (p, (u0, v0)) in enumerate(((pa, (ua, va)), (pb, (ub, vb)))):
        for col, (ddx, ddy) in enumerate(((1.0, 0.0), (0.0, 1.0))):
            u1, v1 = source.to_samples(p[:, 0] + ddx, p[:, 1] + ddy)
            ends[e, :, 0, col] = u1 - u0
            ends[e, :, 1, col] = v1 - v0
    J = 1.1 * np.abs(ends).max(axis=0)
    # the signed Jacobian across the piece: between its ends' values, give or take a tenth
    J_mid = ends.mean(axis=0)
    J_spread = 0.5 * np.abs(ends[0] - ends[1]) + (J - np.abs(ends).max(axis=0))
    r = reach * np.sqrt(np.max(np.sum(J * J, axis=1), axis=1))  # the reach in samples, at most
    if np.any(r > 0.5):
        return None
    rows, cols = source.hi.shape
    i0 = np.clip(np.floor(np.minimum(ua, ub) - r), 0, cols - 2).astype(np.int64)
    i1 = np.clip(np.floor(np.maximum(ua, ub) + r), 0, cols - 2).astype(np.int64)
    j0 = np.clip(np.floor(np.minimum(va, vb) - r), 0, rows - 2).astype(np.int64)
    j1 = np.clip(np.floor(np.maximum(va, vb) + r), 0, rows - 2).astype(np.int64)
    if np.any(i1 - i0 > 2) or np.any(j1 - j0 > 2):
        return None
    A = np.column_stack([ua, va, pa[:, 2]])
    B = np.column_stack([ub, vb, pb[:, 2]])
    box = (np.minimum(ua, ub), np.maximum(ua, ub), np.minimum(va, vb), np.maximum(va, vb))
    cells = np.zeros((6, 9, len(pa)))
    ok = np.zeros((9, len(pa)), dtype=bool)
    for c in range(9):
        dj, di = divmod(c, 3)
        ok[c] = (j0 + dj <= j1) & (i0 + di <= i1)
        jj, ii = np.minimum(j0 + dj, rows - 2), np.minimum(i0 + di, cols - 2)
        # the piece's neighbourhood in this cell, in the cell's own [0, 1] coordinates
        cells[:, c] = (ii, jj, np.clip(box[0] - r - ii, 0.0, 1.0),
                       np.clip(box[1] + r - ii, 0.0, 1.0), np.clip(box[2] - r - jj, 0.0, 1.0),
                       np.clip(box[3] + r - jj, 0.0, 1.0))  # fmt: skip
    ii, jj, x0, x1, y0, y1 = cells
    ii, jj = ii.astype(np.int64), jj.astype(np.int64)
    # where the neighbourhood stays on the raster, a line's one direction bounds it too
    on = (box[0] - r >= 0) & (box[1] + r <= cols - 1) & (box[2] - r >= 0) & (box[3] + r <= rows - 1)
    out = []
    for grid, col in ((source.hi, 0), (source.lo, 2)):
        ex, ey, samples = _views(grid)
        per_m = np.zeros(len(pa))
        for c in range(9):
            # the x-slope at height y interpolates the cell's two x-edges, the y-slope at
            # x its two y-edges; the bound is convex in the point, so its largest over the
            # neighbourhood's box is at one of the box's corners
            for fy in (y0[c], y1[c]):
                gx = np.abs((1.0 - fy) * ex[jj[c], ii[c]] + fy * ex[jj[c] + 1, ii[c]])
                for fx in (x0[c], x1[c]):
                    gy = np.abs((1.0 - fx) * ey[jj[c], ii[c]] + fx * ey[jj[c], ii[c] + 1])
                    at = np.hypot(J[:, 0, 0] * gx + J[:, 1, 0] * gy,
                                  J[:, 0, 1] * gx + J[:, 1, 1] * gy)  # fmt: skip
                    per_m = np.where(ok[c], np.maximum(per_m, at), per_m)
        change = reach * per_m
        ext = terrain_clearance_extrema(A, B, samples)
        side = 1.0 if col == 2 else -1.0
        # the directional bound (costlier) where the first misses its target
        miss = on & (side * (ext[:, col] + side * change) > side * want[col // 2])
        if directional and miss.any():
            s = np.flatnonzero(miss)
            along = _directional_change(
                grid, tuple(b[s] for b in box), (ii[:, s], jj[:, s], x0[:, s], x1[:, s],
                y0[:, s], y1[:, s]), ok[:, s], J_mid[s], J_spread[s], reach, up=col == 0,
            )  # fmt: skip
            change[s] = np.minimum(change[s], along)
        out.append(ext[:, col] + side * change)
    return out[0], out[1]


#: :func:`_piece_reach_bound`: rounds of refinement and the pieces cut per round (each into
#: eight).
REFINE_ROUNDS, REFINE_PIECES = 2, 32


def _probe(
    pa: FloatArray, pb: FloatArray, source: SourceGround, reach: float
) -> tuple[float, float]:
    """The least height of the pieces' ends above the highest ground and the largest above the
    lowest, read at the ends and at 16 points ``reach`` metres around each: heights a flight
    within its reach really has (so the true extremes are at least this far out)."""
    ang = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    off = np.concatenate([[[0.0, 0.0]], reach * np.column_stack([np.cos(ang), np.sin(ang)])])
    p = np.concatenate([pa, pb])
    x = (p[:, None, 0] + off[None, :, 0]).ravel()
    y = (p[:, None, 1] + off[None, :, 1]).ravel()
    z = np.repeat(p[:, 2], len(off))
    u, v = source.to_samples(x, y)
    rows, cols = source.hi.shape
    on = (u >= 0) & (u <= cols - 1) & (v >= 0) & (v <= rows - 1)
    if not on.any():
        return math.inf, -math.inf
    hi = _views(source.hi)[2].height(u[on], v[on])
    lo = _views(source.lo)[2].height(u[on], v[on])
    return float(np.min(z[on] - hi)), float(np.max(z[on] - lo))


def _piece_reach_bound(
    traj: Trajectory, source: SourceGround, reach: float, piece: float,
    targets: tuple[float, float] | None = None,
) -> tuple[float, float]:  # fmt: skip
    """The least and largest height above the ground within ``reach`` metres of the flight,
    bounded per piece of at most a sample cut where it crosses a row or column of samples
    (:func:`_cut_at_cells`): the exact extrema over the ground under the piece, less (plus)
    how far the ground can rise (fall) within the reach of it, the smaller of two bounds:

    * the steepest the ground can be in metres along any direction in the piece's
      neighbourhood (the piece's box grown by the reach) times the reach. In a cell the
      bilinear surface's slope per sample along x at height ``y`` interpolates its two
      x-edge differences, along y at ``x`` its two y-edge differences; the map from metres to
      samples has the Jacobian ``J`` (measured at the piece's ends, the larger of each entry,
      times 1.1 for its change across the piece), so a metre moves the ground by at most
      ``hypot(|J00| |gx| + |J10| |gy|, |J01| |gx| + |J11| |gy|)``, a convex function of the
      point: its largest over the neighbourhood's part of each cell is at a corner of that
      part;
    * along one direction at a time (:func:`_directional_change`): a line from the piece
      enters only the cells ahead of it, and falls there only where the ground falls that way
      (a valley floor under the flight is not charged the far slope's steepness).

    A long piece's bound pairs its highest point with the steepest ground anywhere near it:
    with ``targets`` (the least and largest heights the flight must keep), the pieces whose
    bounds miss them are cut into eight, the worst :data:`REFINE_PIECES` per round for up to
    :data:`REFINE_ROUNDS` rounds, until every bound meets its target or points within the
    reach of the flight (:func:`_probe`) show that it cannot. Tight where the reach is a small
    part of a sample, as a tracking error of metres is on a coarse raster; (-inf, inf) (no
    bound) where the neighbourhood would reach past the adjacent cells."""
    if not math.isfinite(piece):
        return -math.inf, math.inf
    a, b = traj.points[:-1], traj.points[1:]
    pa, pb, _, _ = _pieces(a, b, piece)
    pa, pb = _cut_at_cells(pa, pb, source)
    if targets is None:  # both bounds everywhere
        got = _piece_bounds(pa, pb, source, reach)
        return (-math.inf, math.inf) if got is None else (float(got[0].min()), float(got[1].max()))
    want_low, want_high = targets
    got = _piece_bounds(pa, pb, source, reach, targets, directional=False)
    if got is None:
        return -math.inf, math.inf
    low, high = got
    # the first bound alone, then the directional one where it misses
    miss = np.flatnonzero((low < want_low) | (high > want_high))
    if not miss.size:
        return float(np.min(low)), float(np.max(high))
    worst = np.union1d(np.argsort(low)[:REFINE_PIECES], np.argsort(-high)[:REFINE_PIECES])
    probe = _probe(pa[worst], pb[worst], source, reach)
    if probe[0] < want_low or probe[1] > want_high:  # the flight really misses them
        return float(np.min(low)), float(np.max(high))
    more = _piece_bounds(pa[miss], pb[miss], source, reach, targets)
    if more is None:
        return -math.inf, math.inf
    low[miss], high[miss] = more
    for _ in range(REFINE_ROUNDS):
        cut_low = np.argsort(low)[:REFINE_PIECES]
        cut_low = cut_low[low[cut_low] < want_low]
        cut_high = np.argsort(-high)[:REFINE_PIECES]
        cut_high = cut_high[high[cut_high] > want_high]
        probe = _probe(pa[np.r_[cut_low, cut_high]], pb[np.r_[cut_low, cut_high]], source, reach)
        if probe[0] < want_low:  # the flight really comes this close: cutting cannot help
            cut_low = cut_low[:0]
        if probe[1] > want_high:
            cut_high = cut_high[:0]
        cut = np.union1d(cut_low, cut_high)
        if not cut.size:
            break
        t = np.linspace(0.0, 1.0, 9)
        d = pb[cut] - pa[cut]
        qa = (pa[cut][:, None] + t[:-1, None] * d[:, None]).reshape(-1, pa.shape[1])
        qb = (pa[cut][:, None] + t[1:, None] * d[:, None]).reshape(-1, pa.shape[1])
        more = _piece_bounds(qa, qb, source, reach, targets)
        if more is None:
            break
        keep = np.setdiff1d(np.arange(len(pa)), cut)
        pa, pb = np.concatenate([pa[keep], qa]), np.concatenate([pb[keep], qb])
        low = np.concatenate([low[keep], more[0]])
        high = np.concatenate([high[keep], more[1]])
    return float(np.min(low)), float(np.max(high))


def source_clearance(
    traj: Trajectory, source: SourceGround, reach: float = 0.0,
    targets: tuple[float, float] | None = None,
) -> tuple[float, float]:  # fmt: skip
    """The least and the largest height above the raster's own ground along the flight (over
    the floor's and the ceiling's void fills), metres; with ``reach`` > 0, above the highest
    and lowest ground within ``reach`` metres horizontally of the flight (a bound: the best of
    :func:`_piece_reach_bound`, refined toward ``targets``, the least and largest heights the
    flight must keep, and the samples moved to the highest and lowest within the reach in
    samples, the local metres' largest stretch into samples about the flight, measured, times
    1.1)."""
    if traj.dim != 3 or len(traj.points) < 2:
        return math.inf, -math.inf
    if reach > 0:
        P = traj.points
        u0, v0 = source.to_samples(P[:, 0], P[:, 1])
        stretch = 0.0
        for ddx, ddy in ((1.0, 0.0), (0.0, 1.0)):
            u1, v1 = source.to_samples(P[:, 0] + ddx, P[:, 1] + ddy)
            stretch = max(stretch, float(np.max(np.hypot(u1 - u0, v1 - v0))))
        # both unit steps' images bound the map's stretch within sqrt(2) in any direction
        r = 1.1 * math.sqrt(2.0) * stretch * reach
        # each bounds the ground within reach: the best of them
        low, high = _piece_reach_bound(traj, source, reach, min(source.piece, 1.0 / stretch),
                                       targets)  # fmt: skip
        for how in ("height", "slope"):
            s = replace(source, hi=within_reach(source.hi, 1.0, 1.0, r, True, how),
                        lo=within_reach(source.lo, 1.0, 1.0, r, False, how))  # fmt: skip
            ext = _source_extrema(traj, s)
            low = max(low, float(np.min(ext[8][:, 0])))
            high = min(high, float(np.max(ext[9][:, 2])))
        return low, high
    ext = _source_extrema(traj, source)
    return float(np.min(ext[8][:, 0])), float(np.max(ext[9][:, 2]))


def check_source_terrain(
    traj: Trajectory, source: SourceGround, band: AltitudeBand | None, terrain: Terrain | None
) -> tuple[list[Violation], list[str]]:
    """The terrain (``z - S >= 0``) and a ground band (``min <= z - S <= max``) along every
    segment against the raster's own ground, and the planner's terrain compared with it.
    Returns the violations and the warnings."""
    if traj.dim != 3 or len(traj.points) < 2:
        return [], []
    pa, pb, seg, span, ua, va, ub, vb, lo_ext, hi_ext = _source_extrema(traj, source)
    rows, cols = source.hi.shape
    grid = Terrain(source.hi, 0.0, 0.0, 1.0, 1.0, source.name)
    low = Terrain(source.lo, 0.0, 0.0, 1.0, 1.0, source.name)
    out: list[Violation] = []
    said: list[str] = []
    ground = band is not None and band.reference == "ground"
    uu, vv = np.concatenate([ua, ub[-1:]]), np.concatenate([va, vb[-1:]])
    beyond = (uu < -TOL) | (vv < -TOL) | (uu > cols - 1 + TOL) | (vv > rows - 1 + TOL)
    if beyond.any():
        q = int(np.argmax(beyond))
        k = int(seg[min(q, len(seg) - 1)])
        p, t = point_at(traj, k, 0.0 if q < len(seg) else 1.0)
        out.append(Violation("terrain", (traj.id,), t, (p,), math.nan, 0.0,
                             f"{traj.id}: flies beyond the elevation data of {source.name} at "
                             f"{fmt_points(p)}, t={t:.3f} s (no ground known there)"))  # fmt: skip

    checks: list[tuple[FloatArray, int, float, str, str]] = [(lo_ext[:, 0], 1, 0.0, "terrain", "")]
    if ground:
        assert band is not None
        checks.append((lo_ext[:, 0], 1, band.min, "altitude", "below"))
        checks.append((hi_ext[:, 2], 3, band.max, "altitude", "above"))
    for col_vals, col_s, bound, kind, word in checks:
        bad = col_vals > bound + TOL if word == "above" else col_vals < bound - TOL
        if not bad.any():
            continue
        # one violation per segment, at its worst piece
        for k in np.unique(seg[bad]):
            rows_k = np.flatnonzero(bad & (seg == k))
            pick = rows_k[np.argmax(col_vals[rows_k]) if word == "above"
                          else np.argmin(col_vals[rows_k])]  # fmt: skip
            ext = lo_ext if col_s == 1 else hi_ext
            s = float(span[pick, 0] + ext[pick, col_s] * span[pick, 1])
            p, t = point_at(traj, int(k), s)
            v = float(col_vals[pick])
            if kind == "terrain":
                msg = (f"{traj.id}: segment {int(k)} goes {fmt_num(-v)} m under the ground of "
                       f"{source.name} at {fmt_points(p)}, t={t:.3f} s")  # fmt: skip
            else:
                assert band is not None
                msg = (f"{traj.id}: segment {int(k)} at {fmt_num(v)} m above the ground of "
                       f"{source.name}, {word} the band [{band.min:g}, {band.max:g}] m, at "
                       f"{fmt_points(p)}, t={t:.3f} s")  # fmt: skip
            out.append(Violation(kind, (traj.id,), t, (p,), v, bound, msg))
    # voids under the flight
    ui = np.clip(np.floor(uu).astype(np.int64), 0, cols - 2)
    vi = np.clip(np.floor(vv).astype(np.int64), 0, rows - 2)
    over = (source.void[vi, ui] | source.void[vi + 1, ui] | source.void[vi, ui + 1]
            | source.void[vi + 1, ui + 1])  # fmt: skip
    if over.any():
        said.append(f"{traj.id}: {int(over.sum())} of the {len(over)} points checked are over "
                    f"voids (no data) of {source.name}: checked against the highest (floor) and "
                    "lowest (ceiling) valid height on each void's rim; the ground there is "
                    "unknown")  # fmt: skip
    # the planner's terrain against the source surface at the points checked
    if terrain is not None:
        P = np.concatenate([pa, pb[-1:]])
        s_hi = bilinear_height(grid, uu, vv)
        s_lo = bilinear_height(low, uu, vv)
        floor = bilinear_height(terrain, P[:, 0], P[:, 1])
        ceil_grid = (
            terrain
            if terrain.lower is None
            else Terrain(
                terrain.lower, terrain.x0, terrain.y0, terrain.dx, terrain.dy, terrain.name
            )
        )
        ceiling = bilinear_height(ceil_grid, P[:, 0], P[:, 1])
        xmin, xmax, ymin, ymax = terrain.extent
        inside = ((P[:, 0] >= xmin) & (P[:, 0] <= xmax) & (P[:, 1] >= ymin)
                  & (P[:, 1] <= ymax) & ~beyond)  # fmt: skip
        under = np.where(inside, s_hi - floor, -np.inf)
        over_c = np.where(inside, ceiling - s_lo, -np.inf)
        lim = source.bound + 1e-6
        pairs = ((under, "floor's grid is {} m below"), (over_c, "ceiling's grid is {} m above"))
        for gap, what in pairs:
            q = int(np.argmax(gap))
            if gap[q] > lim:
                said.append(f"{traj.id}: the scenario's terrain disagrees with {source.name}: "
                            f"its {what.format(fmt_num(gap[q]))} the raster's ground at "
                            f"{fmt_points(P[q])} (its stated bound {source.bound:g} m): the "
                            "raster was misread")  # fmt: skip
    return out, said
