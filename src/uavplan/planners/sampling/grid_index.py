"""A uniform-grid spatial index over points added one at a time (2-D or 3-D): exact nearest and
near(r) queries without a full scan (RRT*'s tree; PPSwarm Alg. 1 lines 4 and 7).

``cKDTree`` cannot insert, and a query from Python costs about 10 us, so a growing tree wants a
grid hash in Numba: ``benchmarks/rrt_star_nn.py`` measures it against a brute-force scan
(:func:`nearest_brute`, :func:`near_brute`, the references the tests compare with).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Most cells of a :class:`GridIndex` (the cell grows to stay below it).
MAX_CELLS = 1 << 21


@njit(cache=True)
def _cell(x: float, lo: float, cell: float) -> int:
    return int(np.floor((x - lo) / cell))


@njit(cache=True)
def _clamp(c: int, n: int) -> int:
    if c < 0:
        return 0
    if c >= n:
        return n - 1
    return c


@njit(cache=True)
def _grid_insert(pts, i, head, nxt, lo, cell, dims):
    a = _clamp(_cell(pts[i, 0], lo[0], cell), dims[0])
    b = _clamp(_cell(pts[i, 1], lo[1], cell), dims[1])
    c = _clamp(_cell(pts[i, 2], lo[2], cell), dims[2])
    k = (a * dims[1] + b) * dims[2] + c
    nxt[i] = head[k]
    head[k] = i


@njit(cache=True)
def _grid_rebuild(pts, n, head, nxt, lo, cell, dims):
    head[:] = -1
    for i in range(n):
        _grid_insert(pts, i, head, nxt, lo, cell, dims)


@njit(cache=True)
def _scan(pts, head, nxt, k, q0, q1, q2, best, bd2):
    j = head[k]
    while j >= 0:
        dx = pts[j, 0] - q0
        dy = pts[j, 1] - q1
        dz = pts[j, 2] - q2
        d2 = dx * dx + dy * dy + dz * dz
        if d2 < bd2 or (d2 == bd2 and j < best):
            best = j
            bd2 = d2
        j = nxt[j]
    return best, bd2


@njit(cache=True)
def _box_cells(ci, k, dims):
    """Cells of the grid within Chebyshev index distance k of ``ci`` (0 for k < 0)."""
    if k < 0:
        return 0
    out = 1
    for a in range(3):
        w = min(ci[a] + k, dims[a] - 1) - max(ci[a] - k, 0) + 1
        if w <= 0:
            return 0
        out *= w
    return out


@njit(cache=True)
def _grid_nearest(pts, n, head, nxt, lo, cell, dims, q, limit):
    """Nearest point to ``q``: rings of cells of Chebyshev index distance k = 0, 1, ... around
    q's (unclamped) cell; stop once the best distance is <= k cell + (q's distance to its own
    cell's faces), a lower bound on any point in a farther ring. If the rings would visit more
    than ``limit`` cells, scan the ``n`` points instead (cheaper then; same answer)."""
    ci = np.empty(3, dtype=np.int64)
    dface = np.inf
    kmax = 0
    for a in range(3):
        ci[a] = _cell(q[a], lo[a], cell)
        f = (q[a] - lo[a]) - ci[a] * cell
        dface = min(dface, f, cell - f)
        kmax = max(kmax, abs(ci[a]), abs(dims[a] - 1 - ci[a]))
    dface = max(dface, 0.0)
    best = -1
    bd2 = np.inf
    visited = 0
    for k in range(kmax + 1):
        visited += _box_cells(ci, k, dims) - _box_cells(ci, k - 1, dims)
        if visited > limit:
            best = -1
            bd2 = np.inf
            for j in range(n):
                dx = pts[j, 0] - q[0]
                dy = pts[j, 1] - q[1]
                dz = pts[j, 2] - q[2]
                d2 = dx * dx + dy * dy + dz * dz
                if d2 < bd2:
                    best = j
                    bd2 = d2
            return best, bd2
        a0, a1 = max(ci[0] - k, 0), min(ci[0] + k, dims[0] - 1)
        b0, b1 = max(ci[1] - k, 0), min(ci[1] + k, dims[1] - 1)
        c0, c1 = max(ci[2] - k, 0), min(ci[2] + k, dims[2] - 1)
        for a in range(a0, a1 + 1):
            for b in range(b0, b1 + 1):
                base = (a * dims[1] + b) * dims[2]
                if abs(a - ci[0]) == k or abs(b - ci[1]) == k:
                    for c in range(c0, c1 + 1):
                        best, bd2 = _scan(pts, head, nxt, base + c, q[0], q[1], q[2], best, bd2)
                else:
                    c = ci[2] - k
                    if 0 <= c < dims[2]:
                        best, bd2 = _scan(pts, head, nxt, base + c, q[0], q[1], q[2], best, bd2)
                    c = ci[2] + k
                    if k > 0 and 0 <= c < dims[2]:
                        best, bd2 = _scan(pts, head, nxt, base + c, q[0], q[1], q[2], best, bd2)
        if best >= 0:
            bound = k * cell + dface
            if bd2 <= bound * bound:
                break
    return best, bd2


@njit(cache=True)
def _grid_near(pts, head, nxt, lo, cell, dims, q, r, out):
    """Points within ``r`` of ``q`` (cells within ceil(r / cell) of q's cell: the 27 neighbours
    while r <= cell) into ``out``; returns how many there are (may exceed ``len(out)``)."""
    m = max(int(np.ceil(r / cell)), 1)
    r2 = r * r
    count = 0
    ci0 = _cell(q[0], lo[0], cell)
    ci1 = _cell(q[1], lo[1], cell)
    ci2 = _cell(q[2], lo[2], cell)
    for a in range(max(ci0 - m, 0), min(ci0 + m, dims[0] - 1) + 1):
        for b in range(max(ci1 - m, 0), min(ci1 + m, dims[1] - 1) + 1):
            base = (a * dims[1] + b) * dims[2]
            for c in range(max(ci2 - m, 0), min(ci2 + m, dims[2] - 1) + 1):
                j = head[base + c]
                while j >= 0:
                    dx = pts[j, 0] - q[0]
                    dy = pts[j, 1] - q[1]
                    dz = pts[j, 2] - q[2]
                    if dx * dx + dy * dy + dz * dz <= r2:
                        if count < out.shape[0]:
                            out[count] = j
                        count += 1
                    j = nxt[j]
    return count


def pad3(p: FloatArray) -> FloatArray:
    out = np.zeros(3)
    v = np.asarray(p, dtype=np.float64).ravel()
    out[: len(v)] = v
    return out


class GridIndex:
    """Nearest and near(r) queries over points added one at a time (2-D or 3-D).

    A uniform grid of cubic cells over a box (``lo``..``hi``; points outside go to the border
    cells, so they are found but may make ``nearest`` inexact: keep them inside), one linked list
    of point indices per cell (``head`` per cell, ``nxt`` per point), point arrays that grow by
    doubling. 2-D points get z = 0 and a grid one cell thick. :meth:`set_cell` rebuilds the grid
    with another cell size (at most :data:`MAX_CELLS` cells: the cell grows to respect it);
    :meth:`balance` shrinks the cell as the points get denser.

    ``nearest`` searches rings of cells outwards; when the rings would visit more cells than
    ``scan_limit`` times the number of points (a young tree in a fine grid, or a query far from
    every point), scanning the points is cheaper and gives the same answer, so it does that
    (``scan_limit = inf``: rings only).
    """

    def __init__(self, lo: FloatArray, hi: FloatArray, cell: float, capacity: int = 1024) -> None:
        self.dim = len(np.ravel(lo))
        if self.dim not in (2, 3):
            raise ValueError(f"GridIndex is 2-D or 3-D, got {self.dim}")
        self._box_lo = pad3(lo)
        self._box_hi = pad3(hi)
        if np.any(self._box_hi < self._box_lo):
            raise ValueError("GridIndex needs lo <= hi")
        #: the points' storage (capacity, 3), 2-D points with z = 0; rows ``0..n-1`` are the
        #: points (kernels that index points by number read it directly)
        self.buffer = np.zeros((max(int(capacity), 1), 3))
        self._nxt = np.full(len(self.buffer), -1, dtype=np.int64)
        self.n = 0
        self.scan_limit = 1.0
        self.set_cell(cell)

    @property
    def points(self) -> FloatArray:
        """The points so far, (n, dim) (a view)."""
        return self.buffer[: self.n, : self.dim]

    @property
    def n_cells(self) -> int:
        return int(np.prod(self._dims))

    @property
    def measure(self) -> float:
        """Length, area or volume of the box (its first ``dim`` sides)."""
        return float(np.prod((self._box_hi - self._box_lo)[: self.dim]))

    def balance(self, r: float) -> None:
        """Shrink the cell to ``max(r, (measure / n)^(1/dim))`` (``r``: the radius of the near
        queries to come; the second term keeps about one point per cell of a uniform set) when
        that is below half the current cell; never grows it."""
        target = max(float(r), (self.measure / max(self.n, 1)) ** (1.0 / self.dim))
        if 0 < target < 0.5 * self.cell:
            self.set_cell(target)

    def set_cell(self, cell: float) -> None:
        """Rebuild the grid with cubic cells of side ``cell`` (or larger, see the class)."""
        if not (np.isfinite(cell) and cell > 0):
            raise ValueError(f"cell must be finite and > 0, got {cell}")
        extent = self._box_hi - self._box_lo
        pad = 1e-6 * (1.0 + float(extent.max()))
        lo = self._box_lo - pad
        span = extent + 2 * pad
        while True:
            dims = np.floor(span / cell).astype(np.int64) + 1
            if self.dim == 2:
                dims[2] = 1
            if int(np.prod(dims)) <= MAX_CELLS:
                break
            cell *= 1.25
        self.cell = float(cell)
        self._lo = lo
        self._dims = dims
        self._head = np.full(int(np.prod(dims)), -1, dtype=np.int64)
        _grid_rebuild(self.buffer, self.n, self._head, self._nxt, self._lo, self.cell, self._dims)

    def reserve(self) -> None:
        """Make room for one more point (the storage doubles when full)."""
        if self.n == len(self.buffer):
            cap = 2 * len(self.buffer)
            pts = np.zeros((cap, 3))
            pts[: self.n] = self.buffer
            nxt = np.full(cap, -1, dtype=np.int64)
            nxt[: self.n] = self._nxt
            self.buffer, self._nxt = pts, nxt

    def add(self, p: FloatArray) -> int:
        """Add a point; returns its index."""
        self.reserve()
        i = self.n
        self.buffer[i] = pad3(p)
        _grid_insert(self.buffer, i, self._head, self._nxt, self._lo, self.cell, self._dims)
        self.n += 1
        return i

    def nearest(self, q: FloatArray) -> tuple[int, float]:
        """Index of the nearest point (lowest index among ties) and its distance."""
        if self.n == 0:
            raise ValueError("nearest of an empty GridIndex")
        limit = self.scan_limit * self.n
        i, d2 = _grid_nearest(
            self.buffer,
            self.n,
            self._head,
            self._nxt,
            self._lo,
            self.cell,
            self._dims,
            pad3(q),
            float(min(limit, 1e18)),
        )
        return int(i), math.sqrt(d2)

    def near(self, q: FloatArray, r: float) -> IntArray:
        """Indices of the points within ``r`` of ``q`` (distance <= r), ascending."""
        qq = pad3(q)
        out = np.empty(64, dtype=np.int64)
        while True:
            k = _grid_near(
                self.buffer, self._head, self._nxt, self._lo, self.cell, self._dims, qq, float(r),
                out,
            )  # fmt: skip
            if k <= len(out):
                return np.sort(out[:k])
            out = np.empty(2 * k, dtype=np.int64)


def nearest_brute(points: FloatArray, q: FloatArray) -> tuple[int, float]:
    """Reference for :meth:`GridIndex.nearest`: a scan of every point (same arithmetic)."""
    p = np.asarray(points, dtype=np.float64)
    d = p - np.asarray(q, dtype=np.float64)
    d2 = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]
    if p.shape[1] == 3:
        d2 = d2 + d[:, 2] * d[:, 2]
    i = int(np.argmin(d2))
    return i, math.sqrt(float(d2[i]))


def near_brute(points: FloatArray, q: FloatArray, r: float) -> IntArray:
    """Reference for :meth:`GridIndex.near`: a scan of every point (same arithmetic)."""
    p = np.asarray(points, dtype=np.float64)
    d = p - np.asarray(q, dtype=np.float64)
    d2 = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]
    if p.shape[1] == 3:
        d2 = d2 + d[:, 2] * d[:, 2]
    return np.asarray(np.flatnonzero(d2 <= r * r), dtype=np.int64)
