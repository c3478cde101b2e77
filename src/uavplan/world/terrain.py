"""Terrain: a DEM grid with bilinear height lookup, exact segment clearance, built-in maps.

Frame: x east, y north, z up, metres. Grid node ``heights[j, i]`` sits at
``(x0 + i * dx, y0 + j * dy)``; row 0 is the southern edge (y grows with the row index).
"""

from __future__ import annotations

import math
import os
import stat
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uavplan.world import _terrain_kernels as tk

FloatArray = NDArray[np.float64]

#: Mean Earth metres per degree of latitude (WGS84 mean meridional), for the built-in lon/lat DEMs.
METRES_PER_DEGREE = 111_195.0

BUILTIN_TERRAINS = ("spso", "jacksboro", "topobathy", "virtual")


class TerrainError(ValueError):
    """A DEM file or array that cannot be used, with the reason."""


#: The largest height a terrain may have in magnitude, metres (ten times Everest: a height
#: beyond it is a unit mistake or a corrupt file, and flight altitudes above it lose meaning).
MAX_HEIGHT = 100_000.0


@dataclass(frozen=True, eq=False)
class Terrain:
    """A digital elevation model sampled on a regular grid.

    Attributes:
        heights: (ny, nx) float64 metres; ``heights[j, i]`` at ``(x0 + i*dx, y0 + j*dy)``.
        x0, y0: position of node (0, 0), metres.
        dx, dy: grid spacing, metres (> 0).
        name: a label (the built-in name or the file it came from).
        georef: optional metadata on where the grid sits on Earth (CRS name, origin), kept for
            mission export; the planner works in the local metric frame only. A terrain read
            from a raster keeps ``georef["raster"]``: the files and how the local frame maps
            into them (:mod:`uavplan.world.raster`), which the verifier reads on its own.
        lower: the ceiling's grid, (ny, nx) at most ``heights`` node for node, or None (the
            same as ``heights``). A raster resampled onto the local grid has two surfaces: the
            floor's (``heights``, never below the source's ground) and the ceiling's
            (``lower``, never above it); every check of the altitude band's ceiling reads
            ``lower`` (:meth:`height_low`, :meth:`max_clearance`, :meth:`stays_within`), every
            other use ``heights``.
    """

    heights: FloatArray
    x0: float = 0.0
    y0: float = 0.0
    dx: float = 1.0
    dy: float = 1.0
    name: str = "terrain"
    georef: dict[str, Any] = field(default_factory=dict)
    lower: FloatArray | None = None

    def __post_init__(self) -> None:
        h = np.ascontiguousarray(self.heights, dtype=np.float64)
        if h.ndim != 2 or h.shape[0] < 2 or h.shape[1] < 2:
            raise TerrainError(f"heights must be a 2-D grid of at least 2x2, got shape {h.shape}")
        if not np.all(np.isfinite(h)):
            raise TerrainError(f"heights contain {int((~np.isfinite(h)).sum())} non-finite values")
        if h.size and (top := float(np.abs(h).max())) > MAX_HEIGHT:
            raise TerrainError(
                f"heights reach {top:g} m in magnitude; a terrain's heights are within "
                f"{MAX_HEIGHT:,.0f} m (Earth's are within 11 km: check the units or the file)"
            )
        if not (self.dx > 0 and self.dy > 0 and np.isfinite(self.dx) and np.isfinite(self.dy)):
            raise TerrainError(
                f"cell size must be positive and finite, got dx={self.dx}, dy={self.dy}"
            )
        h.setflags(write=False)
        object.__setattr__(self, "heights", h)
        if self.lower is not None:
            lo = np.ascontiguousarray(self.lower, dtype=np.float64)
            if lo.shape != h.shape:
                raise TerrainError(f"lower has shape {lo.shape}, heights {h.shape}")
            if not np.all(np.isfinite(lo)):
                raise TerrainError(f"lower contains {int((~np.isfinite(lo)).sum())} non-finite "
                                   "values")  # fmt: skip
            if np.any(lo > h):
                raise TerrainError("lower is above heights at some node (the ceiling's grid "
                                   "must be at most the floor's)")  # fmt: skip
            lo.setflags(write=False)
            object.__setattr__(self, "lower", lo)

    @property
    def ceiling_heights(self) -> FloatArray:
        """The grid the altitude band's ceiling is held against: ``lower``, else ``heights``."""
        return self.heights if self.lower is None else self.lower

    # ------------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        ny, nx = self.heights.shape
        return int(ny), int(nx)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) of the grid nodes, metres."""
        ny, nx = self.heights.shape
        return (self.x0, self.x0 + (nx - 1) * self.dx, self.y0, self.y0 + (ny - 1) * self.dy)

    @property
    def cell_size(self) -> float:
        return float(min(self.dx, self.dy))

    def _uv(self, x: ArrayLike, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
        u = (np.asarray(x, dtype=np.float64) - self.x0) / self.dx
        v = (np.asarray(y, dtype=np.float64) - self.y0) / self.dy
        return u, v

    def _uv_snapped(self, x: ArrayLike, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Cell coordinates with points on the grid's edge, up to rounding, put exactly on it
        (``(ymax - y0) / dy`` can come out as ``ny - 1 + 4e-15``: still on the edge)."""
        u, v = self._uv(x, y)
        ny, nx = self.heights.shape
        return _snap_edges(u, nx - 1), _snap_edges(v, ny - 1)

    def height(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """Bilinear terrain height at any array of points (broadcast ``x`` with ``y``).

        Points outside the grid take the height of the nearest edge point. Numba
        (:func:`~uavplan.world._terrain_kernels.bilinear_heights`); :meth:`height_reference` is
        the same arithmetic in NumPy.
        """
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        if self.heights.shape[0] < 2 or self.heights.shape[1] < 2:
            return self.height_reference(xa, ya)
        out = tk.bilinear_heights(
            self.heights, float(self.x0), float(self.y0), float(self.dx), float(self.dy),
            np.ascontiguousarray(xa).reshape(-1), np.ascontiguousarray(ya).reshape(-1),
        )  # fmt: skip
        return np.asarray(out).reshape(xa.shape)

    def height_low(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """:meth:`height` of the ceiling's grid (:attr:`ceiling_heights`)."""
        if self.lower is None:
            return self.height(x, y)
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        out = tk.bilinear_heights(
            self.lower, float(self.x0), float(self.y0), float(self.dx), float(self.dy),
            np.ascontiguousarray(xa).reshape(-1), np.ascontiguousarray(ya).reshape(-1),
        )  # fmt: skip
        return np.asarray(out).reshape(xa.shape)

    def lookup_low(self, x: ArrayLike, y: ArrayLike, method: str = "bilinear") -> FloatArray:
        """:meth:`lookup` of the ceiling's grid."""
        if self.lower is None:
            return self.lookup(x, y, method)
        if method == "nearest":
            return self._nearest(self.lower, x, y)
        if method == "bilinear":
            return self.height_low(x, y)
        raise ValueError(f"unknown terrain lookup method {method!r}")

    def height_reference(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """:meth:`height` in NumPy (the reference the kernel is tested against)."""
        u, v = self._uv(x, y)
        u, v = np.broadcast_arrays(u, v)
        ny, nx = self.heights.shape
        u = np.clip(u, 0.0, nx - 1.0)
        v = np.clip(v, 0.0, ny - 1.0)
        i = np.minimum(np.floor(u).astype(np.intp), nx - 2)
        j = np.minimum(np.floor(v).astype(np.intp), ny - 2)
        s = u - i
        r = v - j
        H = self.heights
        h00 = H[j, i]
        h10 = H[j, i + 1]
        h01 = H[j + 1, i]
        h11 = H[j + 1, i + 1]
        return np.asarray(h00 + (h10 - h00) * s + (h01 - h00) * r + (h00 - h10 - h01 + h11) * s * r)

    def height_nearest(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """Height of the nearest grid node, rounding halves up as MATLAB's ``round`` does for
        positive indices (SPSO's ``H(round(y), round(x))``)."""
        return self._nearest(self.heights, x, y)

    def _nearest(self, grid: FloatArray, x: ArrayLike, y: ArrayLike) -> FloatArray:
        u, v = self._uv(x, y)
        u, v = np.broadcast_arrays(u, v)
        ny, nx = grid.shape
        i = np.clip(_round_half_up(u), 0, nx - 1)
        j = np.clip(_round_half_up(v), 0, ny - 1)
        return np.asarray(grid[j, i])

    def lookup(self, x: ArrayLike, y: ArrayLike, method: str = "bilinear") -> FloatArray:
        """Height by ``method``: ``"bilinear"`` (default) or ``"nearest"``."""
        if method == "bilinear":
            return self.height(x, y)
        if method == "nearest":
            return self.height_nearest(x, y)
        raise ValueError(f"unknown terrain lookup method {method!r}")

    # ------------------------------------------------------------------ segment queries
    @cached_property
    def _pyramid(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return tk.build_max_pyramid(self.heights)

    @cached_property
    def _neg(self) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        neg = np.ascontiguousarray(-self.ceiling_heights)
        neg.setflags(write=False)  # as the heights: one kernel signature, compiled once
        return neg, tk.build_max_pyramid(neg)

    def min_clearance(self, paths: ArrayLike, cap: float = np.inf) -> FloatArray:
        """Exact minimum of ``z - h(x, y)`` along every segment of a batch of polylines.

        Args:
            paths: (pop, n_points, 3) metres.
            cap: values at or above ``cap`` may be reported as any number ``>= cap`` (the search
                prunes there); values below ``cap`` are exact.

        Returns:
            (pop, n_points - 1) metres. Segment parts outside the grid are not checked.
        """
        return self._min_clearance(paths, cap, False)

    def clears(self, paths: ArrayLike, clearance: float = 0.0) -> NDArray[np.bool_]:
        """Whether every point of every segment is at least ``clearance`` above the terrain.

        The fast yes/no form of :meth:`min_clearance` (it stops at the first violation found).
        Returns (pop, n_points - 1) bool.
        """
        return np.asarray(self._min_clearance(paths, clearance, True) >= clearance)

    def _uv_fast(self, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        """:meth:`_uv_snapped` of the points ``p[..., :2]`` (Numba, the same values)."""
        ny, nx = self.heights.shape
        eps = 64.0 * np.finfo(np.float64).eps
        x = np.ascontiguousarray(p[..., 0]).reshape(-1)
        y = np.ascontiguousarray(p[..., 1]).reshape(-1)
        u, v = tk.snapped_cell_coords(
            x, y, float(self.x0), float(self.y0), float(self.dx), float(self.dy),
            nx - 1, ny - 1, eps * max(1.0, float(nx - 1)), eps * max(1.0, float(ny - 1)),
        )  # fmt: skip
        return u.reshape(p.shape[:-1]), v.reshape(p.shape[:-1])

    def _min_clearance(self, paths: ArrayLike, cap: float, stop_below: bool) -> FloatArray:
        p = np.asarray(paths, dtype=np.float64)
        u, v = self._uv_fast(p)
        flat, off, shp = self._pyramid
        return np.asarray(
            tk.min_clearance_batch(
                self.heights,
                flat,
                off,
                shp,
                np.ascontiguousarray(u),
                np.ascontiguousarray(v),
                np.ascontiguousarray(p[..., 2]),
                float(cap),
                bool(stop_below),
            )
        )

    def max_clearance(self, paths: ArrayLike) -> FloatArray:
        """Exact maximum of ``z - h(x, y)`` along every segment over the ceiling's grid
        (:attr:`ceiling_heights`), (pop, n_points - 1) metres."""
        p = np.asarray(paths, dtype=np.float64)
        u, v = self._uv_snapped(p[..., 0], p[..., 1])
        neg, (flat, off, shp) = self._neg
        out = tk.min_clearance_batch(
            neg,
            flat,
            off,
            shp,
            np.ascontiguousarray(u),
            np.ascontiguousarray(v),
            np.ascontiguousarray(-p[..., 2]),
            np.inf,
            False,
        )
        return np.asarray(-out)

    def stays_within(self, paths: ArrayLike, clearance: float) -> NDArray[np.bool_]:
        """Whether every point of every segment is at most ``clearance`` above the terrain's
        ceiling grid (:attr:`ceiling_heights`): the yes/no form of :meth:`max_clearance` (the
        search prunes every block of cells that is clearly below the ceiling). Returns
        (pop, n_points - 1) bool."""
        p = np.asarray(paths, dtype=np.float64)
        u, v = self._uv_fast(p)
        neg, (flat, off, shp) = self._neg
        cap = -float(clearance)
        out = tk.min_clearance_batch(
            neg,
            flat,
            off,
            shp,
            np.ascontiguousarray(u),
            np.ascontiguousarray(v),
            np.ascontiguousarray(-p[..., 2]),
            cap,
            True,
        )
        return np.asarray(out >= cap)

    def mean_height(self, paths: ArrayLike) -> FloatArray:
        """Exact mean terrain height under each segment's ground track, (pop, n_points - 1)."""
        p = np.asarray(paths, dtype=np.float64)
        u, v = self._uv(p[..., 0], p[..., 1])
        return np.asarray(
            tk.mean_height_batch(self.heights, np.ascontiguousarray(u), np.ascontiguousarray(v))
        )

    #: :meth:`mean_height_lower`: the blocks' side, in cells.
    LOWER_BLOCK = 8

    @cached_property
    def _block_min(self) -> FloatArray:
        """The least node of each block of ``LOWER_BLOCK`` x ``LOWER_BLOCK`` cells, its edges'
        nodes included (read-only)."""
        B = self.LOWER_BLOCK
        H = self.heights
        out = H
        for axis in (0, 1):
            n = out.shape[axis]
            starts = np.arange(0, max(n - 1, 1), B)
            m = np.minimum.reduceat(out, starts, axis=axis)
            nxt = np.take(out, np.minimum(starts[1:], n - 1), axis=axis)  # the far edge's nodes
            if axis == 0:
                m[:-1] = np.minimum(m[:-1], nxt)
            else:
                m[:, :-1] = np.minimum(m[:, :-1], nxt)
            out = m
        out = np.ascontiguousarray(out)
        out.setflags(write=False)
        return out

    @cached_property
    def _lower_slack(self) -> float:
        """What :meth:`mean_height_lower` gives up for the round-off at a block's edge."""
        return 1e-9 * (1.0 + float(np.max(np.abs(self.heights))))

    def mean_height_lower(self, paths: ArrayLike) -> FloatArray:
        """A lower bound of :meth:`mean_height` at a ``LOWER_BLOCK``-th of its cost (the
        mean of the terrain's block minima under each segment), (pop, n_points - 1): what lets
        a search skip the exact mean where even the bound is too high."""
        p = np.asarray(paths, dtype=np.float64)
        u, v = self._uv(p[..., 0], p[..., 1])
        return np.asarray(tk.mean_height_lower_batch(
            self._block_min, float(self.LOWER_BLOCK), self._lower_slack, np.ascontiguousarray(u),
            np.ascontiguousarray(v),
        ))  # fmt: skip

    def downsample(self, factor: int) -> Terrain:
        """Every ``factor``-th node (a coarser map for multi-resolution planners)."""
        if factor < 1:
            raise ValueError("factor must be >= 1")
        return Terrain(
            self.heights[::factor, ::factor],
            self.x0,
            self.y0,
            self.dx * factor,
            self.dy * factor,
            f"{self.name}/{factor}",
            dict(self.georef),
            None if self.lower is None else self.lower[::factor, ::factor],
        )

    # ------------------------------------------------------------------ loading
    @classmethod
    def builtin(cls, name: str) -> Terrain:
        """One of the built-in maps: ``spso``, ``jacksboro``, ``topobathy``, ``virtual``."""
        if name == "spso":
            return _spso_terrain()
        if name == "jacksboro":
            return _jacksboro_terrain()
        if name == "topobathy":
            return _topobathy_terrain()
        if name == "virtual":
            return _virtual_terrain()
        raise TerrainError(f"unknown built-in terrain {name!r}; choose from {BUILTIN_TERRAINS}")

    @classmethod
    def from_file(
        cls,
        path: str | Path,
        *,
        cell_size: float | None = None,
        origin: tuple[float, float] = (0.0, 0.0),
        key: str | None = None,
    ) -> Terrain:
        """Load a DEM file: ``.npy`` or ``.npz``, or any raster GDAL reads (GeoTIFF, ``.hgt``,
        ASCII grid, ...).

        A raster is read and placed by :mod:`uavplan.world.raster` (its NoData, masks,
        pixel-is-point, CRS) with no scenario origin: a plain grid at ``origin`` with
        ``cell_size``, a projected one on its own grid, anything else reprojected about its
        centre; a scenario file places it with the scenario's origin and bounds
        (:mod:`uavplan.io.scenario_file.build`).
        ``.npy``: a 2-D array, rows south to north. ``.npz``: the array under ``key`` (or
        ``heights``/``elevation``/``topo``), with optional scalars ``dx``, ``dy``, ``x0``, ``y0``.
        """
        p = Path(path)
        why = not_a_regular_file(p)
        if why is not None:
            raise TerrainError(f"DEM file {str(p)!r}: {why}")
        suffix = p.suffix.lower()
        if suffix not in (".npy", ".npz"):
            from uavplan.world.raster import place_raster, read_raster

            terrain, _ = place_raster(read_raster(p), cell_size=cell_size, grid_origin=origin)
            return terrain
        try:
            if suffix == ".npy":
                with p.open("rb") as f:
                    _check_grid(_npy_shape(f), _npy_dtype(f), p)
                arr = np.load(p, allow_pickle=False)
                d = cell_size or 1.0
                return cls(arr, origin[0], origin[1], d, d, p.name)
            with np.load(p, allow_pickle=False) as z:
                names = [key] if key else ["heights", "elevation", "topo"]
                found = next((n for n in names if n in z.files), None)
                if found is None:
                    raise TerrainError(f"{p}: no array named {' or '.join(names)} (has {z.files})")
                with z.zip.open(f"{found}.npy") as f:
                    _check_grid(_npy_shape(f), _npy_dtype(f), p)
                arr = z[found]
                dx = float(z["dx"]) if "dx" in z.files else (cell_size or 1.0)
                dy = float(z["dy"]) if "dy" in z.files else dx
                x0 = float(z["x0"]) if "x0" in z.files else origin[0]
                y0 = float(z["y0"]) if "y0" in z.files else origin[1]
            return cls(arr, x0, y0, dx, dy, p.name)
        except TerrainError:
            raise
        except Exception as exc:  # a corrupt or foreign file: say which and why
            raise TerrainError(f"cannot read DEM file {str(p)!r}: {exc}") from exc


def not_a_regular_file(path: str | Path) -> str | None:
    """Why ``path`` (links followed) is not a regular file a user's input may name, or None:
    missing, a directory, a FIFO (reading it would wait for a writer), a device (``/dev/zero``
    never ends), a socket, a link loop."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return "not found"
    except OSError as exc:
        return f"cannot read: {exc.strerror or exc}"
    if stat.S_ISREG(st.st_mode):
        return None
    if stat.S_ISDIR(st.st_mode):
        return "is a directory"
    kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(st.st_mode)
            else "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode)
            else "a socket" if stat.S_ISSOCK(st.st_mode) else "not a regular file")  # fmt: skip
    return f"is {kind}, not a regular file"


def _snap_edges(u: FloatArray, n: int) -> FloatArray:
    tol = 64.0 * np.finfo(np.float64).eps * max(1.0, float(n))
    u = np.where(np.abs(u) <= tol, 0.0, u)
    return np.asarray(np.where(np.abs(u - n) <= tol, float(n), u))


def _round_half_up(u: FloatArray) -> NDArray[np.intp]:
    """Round halves away from zero for u >= 0 (MATLAB ``round``), exact for every float
    (``floor(u + 0.5)`` is not: 0.49999999999999994 + 0.5 rounds to 1.0)."""
    f = np.floor(u)
    return np.asarray((f + (u - f >= 0.5)).astype(np.intp))


#: The most grid nodes a DEM may have, in its file and once resampled onto the local grid
#: (SRTM tiles, a geographic GeoTIFF): 25 million (5,000 x 5,000) float64 heights are 200 MB,
#: and the clearance pyramid, the cost maps and HR-MAGA's pyramid add about three times that.
#: ``docs/scenario-format.md``, "Limits".
MAX_DEM_CELLS = 25_000_000


def _check_grid(shape: tuple[int, ...], dtype: np.dtype[Any] | None, path: Path) -> None:
    """A DEM's declared grid, refused before its data is read: too many nodes, or samples that
    are not real numbers."""
    cells = math.prod(int(n) for n in shape[:2]) if shape else 0
    if cells > MAX_DEM_CELLS:
        raise TerrainError(
            f"DEM file {str(path)!r}: {' x '.join(str(int(n)) for n in shape)} samples; a DEM "
            f"has at most {MAX_DEM_CELLS:,} nodes (resample it coarser, or cut it to the area)"
        )
    if dtype is not None and dtype.kind not in "biuf":
        raise TerrainError(
            f"DEM file {str(path)!r}: samples of type {dtype} are not real numbers (heights)"
        )


def _npy_header(f: Any) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    version = np.lib.format.read_magic(f)
    if version == (1, 0):
        return np.lib.format.read_array_header_1_0(f)
    return np.lib.format.read_array_header_2_0(f)


def _npy_shape(f: Any) -> tuple[int, ...]:
    """The shape an .npy stream declares (its header only; the stream is rewound)."""
    pos = f.tell()
    try:
        return tuple(_npy_header(f)[0])
    finally:
        f.seek(pos)


def _npy_dtype(f: Any) -> np.dtype[Any]:
    pos = f.tell()
    try:
        return _npy_header(f)[2]
    finally:
        f.seek(pos)


def _data_path(name: str) -> Path:
    return Path(str(resources.files("uavplan") / "data" / name))


def _spso_terrain() -> Terrain:
    """The SPSO benchmark map (Phung & Ha 2021; ``data/ChrismasTerrain.tif``, BSD licence).

    Taken exactly as the authors' MATLAB code reads it: one cell per metre, node (1, 1) of the
    file at x = y = 1, row index = y (so no north flip), negative heights clipped to 0.
    """
    import rasterio

    with rasterio.open(_data_path("ChrismasTerrain.tif")) as ds:  # its samples, as they are
        arr = np.asarray(ds.read(1), dtype=np.float64)
    arr = np.maximum(arr, 0.0)
    return Terrain(arr, 1.0, 1.0, 1.0, 1.0, "spso", {"source": "ChrismasTerrain.tif (SPSO)"})


def _jacksboro_terrain() -> Terrain:
    """Jacksboro fault DEM (Tennessee), from matplotlib's sample data; 3 arc-second cells
    converted to metres at the map's mean latitude, rows flipped so that +y is north."""
    from matplotlib import cbook

    d: Any = cbook.get_sample_data("jacksboro_fault_dem.npz")
    elev = np.asarray(d["elevation"], dtype=np.float64)
    # The file's ymin (36.733) is the northern edge: row 0 is north. Flip to south-first.
    lat_n, lat_s = float(d["ymin"]), float(d["ymax"])
    lat0 = 0.5 * (lat_n + lat_s)
    dx = float(d["dx"]) * METRES_PER_DEGREE * np.cos(np.radians(lat0))
    dy = float(d["dy"]) * METRES_PER_DEGREE
    georef = {
        "source": "matplotlib jacksboro_fault_dem.npz",
        "lon0": float(d["xmin"]),
        "lat0": min(lat_n, lat_s),
        "units": "elevation metres",
    }
    return Terrain(elev[::-1].copy(), 0.0, 0.0, dx, dy, "jacksboro", georef)


def _topobathy_terrain() -> Terrain:
    """Topography/bathymetry off the Pacific Northwest coast, from matplotlib's sample data.

    Longitude/latitude cells converted to metres at the mean latitude. The sea surface is what a
    UAV must clear, so heights below 0 (bathymetry) are raised to 0.
    """
    from matplotlib import cbook

    d: Any = cbook.get_sample_data("topobathy.npz")
    topo = np.asarray(d["topo"], dtype=np.float64)
    lon = np.asarray(d["longitude"], dtype=np.float64)
    lat = np.asarray(d["latitude"], dtype=np.float64)
    if lat[0] > lat[-1]:
        topo, lat = topo[::-1], lat[::-1]
    if lon[0] > lon[-1]:
        topo, lon = topo[:, ::-1], lon[::-1]
    lat0 = float(lat.mean())
    dx = float(np.mean(np.diff(lon))) * METRES_PER_DEGREE * np.cos(np.radians(lat0))
    dy = float(np.mean(np.diff(lat))) * METRES_PER_DEGREE
    georef = {
        "source": "matplotlib topobathy.npz",
        "lon0": float(lon[0]) - 360.0,
        "lat0": float(lat[0]),
        "sea_level_clipped": True,
    }
    return Terrain(np.maximum(topo, 0.0), 0.0, 0.0, dx, dy, "topobathy", georef)


#: The ``virtual`` map's mountains: centre x, y (km), height (m), spread (km).
_VIRTUAL_HILLS = (
    (4.0, 14.0, 900.0, 2.2), (6.5, 6.0, 700.0, 1.8), (9.5, 11.5, 1100.0, 2.0),
    (13.0, 4.5, 650.0, 1.6), (14.5, 15.5, 950.0, 2.4), (17.0, 9.0, 800.0, 1.7),
    (11.0, 17.5, 600.0, 1.5), (2.5, 3.0, 500.0, 1.4),
)  # fmt: skip


def _virtual_terrain() -> Terrain:
    """A synthetic 20 km x 20 km map (100 m cells) of eight Gaussian mountains (500-1,100 m)
    on a gently tilted plain with ridges, the stand-in for HR-MAGA's "virtual map" (Fig. 7(c)),
    whose formula the paper does not give. Deterministic: a formula, no random numbers."""
    x = np.arange(201) * 0.1  # km
    X, Y = np.meshgrid(x, x)
    H = 100.0 + 8.0 * X + 5.0 * Y + 40.0 * np.sin(X / 1.3) * np.cos(Y / 1.7)
    for cx, cy, h, s in _VIRTUAL_HILLS:
        H += h * np.exp(-((X - cx) ** 2 + (Y - cy) ** 2) / (2 * s * s))
    return Terrain(H, 0.0, 0.0, 100.0, 100.0, "virtual", {"source": "synthetic (uavplan)"})
