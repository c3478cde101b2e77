"""An obstacle index: a uniform grid over the obstacles' bounding boxes, so that a segment is
tested only against the obstacles near it.

One structure serves every obstacle kind: whatever a check needs of an obstacle (a disc of
threat, a circle, a polygon grown by its margin) is given to :func:`box_grid` as an
axis-aligned box that contains it, each box listed in every cell it meets. The planner's kernels
(:mod:`uavplan.world.geometry`: the 2-D scene pass, the cylinder passes) walk the cells a
segment crosses with the inlined helpers below; the verifier's broad phase
(:mod:`uavplan.verify.obstacles`) and Python callers take the candidate pairs from
:func:`segment_candidates`. Both are *conservative*: every obstacle whose box the segment
meets is a candidate (plus some that are merely near it); the exact test stays the caller's.
This module imports none of the planner's geometry, so the independent verifier may use it
(only for the broad phase: it keeps its own exact narrow phase).

**The grid.** ``grid = (x0, y0, h, nx, ny)`` (float64), square cells of side ``h``; cell
``(i, j)`` is ``[x0 + i h, x0 + (i + 1) h) x [y0 + j h, ...)`` and has the flat index
``k = j nx + i``; the boxes listed in it are ``items[starts[k]:starts[k + 1]]``, in increasing
order; ``span[b] = (i0, j0, i1, j1)`` is the rectangle of cells box ``b`` is listed in. The cell
side is the larger of ``cell`` (default: the 90th percentile of the boxes' sides) and the side
that gives one box per cell on average, so a typical box meets a few cells and a larger one is
listed in every cell it meets; at most :data:`GRID_MAX_CELLS` cells a side.

**A segment's cells.** Not its bounding box (a long diagonal segment's box holds quadratically
many cells) but the cells it passes through, row by row: in each row of cells the segment
meets, the columns between where it enters and leaves the row, each widened by ``1e-9`` of a
cell (so rounding never drops a cell the segment touches, borders and corners included; a
zero-length segment is a point). The rows and columns are clipped to the grid; paths must have
finite coordinates (callers test every pair otherwise).

**Each box once per segment.** A box listed in several visited cells is taken in the first of
them in the walking order (rows upwards, columns rightwards): at cell ``(ii, jj)`` box ``b`` is
taken iff ``ii`` is the first column of row ``jj`` it shares with the segment and no earlier
visited row shares a column with it (:func:`segment_boxes`). No per-segment bookkeeping.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: :func:`box_grid`: at most this many cells a side.
GRID_MAX_CELLS = 1024
#: The widening of a segment's rows and columns, in cells (rounding never drops a cell).
WALK_PAD = 1e-9

Grid = tuple[FloatArray, IntArray, IntArray, IntArray]


def box_pad(*scales: FloatArray) -> FloatArray:
    """A growth for boxes whose edges are computed in floating point: 1e-9 of the magnitudes
    involved (plus 1e-9 m), far above any rounding and far below any obstacle."""
    acc: Any = 1.0
    for s in scales:
        acc = acc + np.abs(np.asarray(s, dtype=np.float64))
    return np.asarray(1e-9 * acc)


def box_grid(
    x_lo: FloatArray,
    y_lo: FloatArray,
    x_hi: FloatArray,
    y_hi: FloatArray,
    cell: float | None = None,
) -> Grid:
    """The uniform grid over boxes ``[x_lo, x_hi] x [y_lo, y_hi]`` (n,): ``(grid, starts, items,
    span)`` as the module describes. ``cell``: the least cell side (default: the 90th
    percentile of the boxes' widths and heights)."""
    x_lo, y_lo, x_hi, y_hi = (np.asarray(a, dtype=np.float64) for a in (x_lo, y_lo, x_hi, y_hi))
    n = len(x_lo)
    if n == 0:
        raise ValueError("box_grid needs at least one box")
    x0, y0 = float(x_lo.min()), float(y_lo.min())
    w, hgt = float(x_hi.max()) - x0, float(y_hi.max()) - y0
    if cell is None:
        cell = float(np.percentile(np.r_[x_hi - x_lo, y_hi - y_lo], 90))
    h = max(float(cell), float(np.sqrt(max(w * hgt, 1e-300) / n)))
    h = max(h, w / GRID_MAX_CELLS, hgt / GRID_MAX_CELLS, 1e-9)
    nx, ny = int(w // h) + 1, int(hgt // h) + 1
    i0 = np.floor((x_lo - x0) / h).astype(np.int64)
    i1 = np.minimum(np.floor((x_hi - x0) / h).astype(np.int64), nx - 1)
    j0 = np.floor((y_lo - y0) / h).astype(np.int64)
    j1 = np.minimum(np.floor((y_hi - y0) / h).astype(np.int64), ny - 1)
    wide = i1 - i0 + 1
    count = wide * (j1 - j0 + 1)
    item = np.repeat(np.arange(n, dtype=np.int64), count)
    off = np.arange(int(count.sum()), dtype=np.int64) - np.repeat(np.cumsum(count) - count, count)
    cell_of = (np.repeat(j0, count) + off // np.repeat(wide, count)) * nx + (
        np.repeat(i0, count) + off % np.repeat(wide, count)
    )
    order = np.lexsort((item, cell_of))
    starts = np.searchsorted(cell_of[order], np.arange(nx * ny + 1)).astype(np.int64)
    grid = np.array([x0, y0, h, nx, ny], dtype=np.float64)
    span = np.ascontiguousarray(np.c_[i0, j0, i1, j1], dtype=np.int64)
    return grid, starts, np.ascontiguousarray(item[order], dtype=np.int64), span


def disc_grid(cx: FloatArray, cy: FloatArray, reach: FloatArray) -> Grid:
    """:func:`box_grid` over the discs of radius ``reach`` around ``(cx, cy)`` (boxes grown by
    :func:`box_pad`), with the cell side at least the largest disc's diameter (each disc meets
    two cells a side, three where rounding widens its box)."""
    r = np.asarray(reach, dtype=np.float64)
    pad = box_pad(cx, cy, r)
    x_lo, x_hi, y_lo, y_hi = cx - r - pad, cx + r + pad, cy - r - pad, cy + r + pad
    return box_grid(x_lo, y_lo, x_hi, y_hi, cell=2.0 * float((r + pad).max()))


# ------------------------------------------------------------------------------ the walk
@njit(cache=True, inline="always")
def _cell_coord(v, n):  # pragma: no cover - numba
    """floor(v) clipped to [-1, n] (so that the int conversion never overflows)."""
    return int(np.floor(min(max(v, -1.0), float(n))))


@njit(cache=True, inline="always")
def segment_walk(grid, ax, ay, bx, by):  # pragma: no cover - numba
    """Segment a->b in cell units, as :func:`row_columns` takes it: ``(ua, ub, va, vb,
    inv_dv)`` (``inv_dv = 1 / (vb - va)``, 0 for a horizontal segment), and the rows
    ``j_lo..j_hi`` it meets, clipped to the grid (empty when ``j_lo > j_hi``)."""
    ny = int(grid[4])
    inv_h = 1.0 / grid[2]
    ua = (ax - grid[0]) * inv_h
    ub = (bx - grid[0]) * inv_h
    va = (ay - grid[1]) * inv_h
    vb = (by - grid[1]) * inv_h
    dv = vb - va
    inv_dv = 1.0 / dv if dv != 0.0 else 0.0
    j_lo = max(_cell_coord(min(va, vb) - WALK_PAD, ny), 0)
    j_hi = min(_cell_coord(max(va, vb) + WALK_PAD, ny), ny - 1)
    return ua, ub, va, vb, inv_dv, j_lo, j_hi


@njit(cache=True, inline="always")
def row_columns(nx, ua, ub, va, vb, inv_dv, jj):  # pragma: no cover - numba
    """The columns ``i_lo..i_hi`` of row ``jj`` that the segment (:func:`segment_walk`) passes
    through, widened by :data:`WALK_PAD` cells (and by as much again of its length, for the
    rounding of its entry and exit), clipped to the grid's ``nx`` columns."""
    u_min = min(ua, ub)
    u_max = max(ua, ub)
    if inv_dv != 0.0:
        t1 = (jj - WALK_PAD - va) * inv_dv
        t2 = (jj + 1.0 + WALK_PAD - va) * inv_dv
        t_lo = max(0.0, min(t1, t2))
        t_hi = min(1.0, max(t1, t2))
        u1 = ua + t_lo * (ub - ua)
        u2 = ua + t_hi * (ub - ua)
        slack = WALK_PAD * (1.0 + abs(ub - ua))
        u_min = max(u_min, min(u1, u2) - slack)
        u_max = min(u_max, max(u1, u2) + slack)
    i_lo = max(_cell_coord(u_min - WALK_PAD, nx), 0)
    i_hi = min(_cell_coord(u_max + WALK_PAD, nx), nx - 1)
    return i_lo, i_hi


@njit(cache=True, inline="always")
def segment_boxes(grid, starts, items, span, ax, ay, bx, by, out):  # pragma: no cover - numba
    """The boxes listed in the cells segment a->b crosses, each once, into ``out`` (room for
    every box); returns how many. Box ``b`` is taken at visited cell ``(ii, jj)`` iff ``ii``
    is the first column of row ``jj`` it shares with the segment and no earlier visited row of
    it shares a column (the module's rule)."""
    nx = int(grid[3])
    ua, ub, va, vb, inv_dv, j_lo, j_hi = segment_walk(grid, ax, ay, bx, by)
    n = 0
    for jj in range(j_lo, j_hi + 1):
        i_lo, i_hi = row_columns(nx, ua, ub, va, vb, inv_dv, jj)
        for ii in range(i_lo, i_hi + 1):
            k = jj * nx + ii
            for q in range(starts[k], starts[k + 1]):
                bb = items[q]
                if ii != max(i_lo, span[bb, 0]):
                    continue  # taken in an earlier column of this row
                first = True
                for r in range(max(j_lo, span[bb, 1]), jj):
                    c_lo, c_hi = row_columns(nx, ua, ub, va, vb, inv_dv, r)
                    if c_lo <= span[bb, 2] and c_hi >= span[bb, 0]:
                        first = False  # taken in an earlier row
                        break
                if first:
                    out[n] = bb
                    n += 1
    return n


@njit(cache=True)
def _candidates(grid, starts, items, span, a, b, count_only, seg_out, box_out):  # pragma: no cover
    buf = np.empty(span.shape[0], dtype=np.int64)
    n = 0
    for s in range(a.shape[0]):
        m = segment_boxes(grid, starts, items, span, a[s, 0], a[s, 1], b[s, 0], b[s, 1], buf)
        if not count_only:
            seg_out[n : n + m] = s
            box_out[n : n + m] = buf[:m]
        n += m
    return n


def segment_candidates(grid: Grid, a: FloatArray, b: FloatArray) -> tuple[IntArray, IntArray]:
    """The candidate pairs of segments ``a[s] -> b[s]`` ((m, >= 2), finite; x, y used) and boxes
    of ``grid``: ``(segment, box)`` index arrays, each pair once, every box the segment meets
    included (conservative: a few that are only near it too), sorted by box then segment."""
    A = np.ascontiguousarray(np.asarray(a, dtype=np.float64)[:, :2])
    B = np.ascontiguousarray(np.asarray(b, dtype=np.float64)[:, :2])
    if not (np.isfinite(A).all() and np.isfinite(B).all()):
        raise ValueError("segment_candidates needs finite coordinates")
    g, starts, items, span = grid
    none = np.zeros(0, dtype=np.int64)
    n = _candidates(g, starts, items, span, A, B, True, none, none)
    seg = np.empty(n, dtype=np.int64)
    box = np.empty(n, dtype=np.int64)
    _candidates(g, starts, items, span, A, B, False, seg, box)
    order = np.lexsort((seg, box))
    return seg[order], box[order]


# ------------------------------------------------------------------------------ kept builds
_BUILT: dict[tuple[str, bytes], Any] = {}


def by_content(kind: str, build: Callable[..., Any], *arrays: Any) -> Any:
    """``build(*arrays)``, kept for the last few distinct inputs of each ``kind`` (keyed by the
    arrays' bytes, which cost far less to hash than the structure to build): a planner asks for
    the same world's grid or polygon data at every iteration and every validator, the verifier
    for every trajectory."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
        h.update(b"|")
    key = (kind, h.digest())
    out = _BUILT.get(key)
    if out is None:
        if len(_BUILT) >= 16:
            _BUILT.pop(next(iter(_BUILT)))
        out = _BUILT[key] = build(*arrays)
    return out
