"""Terrain and altitude-band checks of one trajectory against the bilinear DEM, exact along every
segment (the segment split at grid lines, a quadratic per cell)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import (
    TOL,
    Violation,
    fmt_num,
    fmt_point,
    fmt_points,
    point_at,
    segment_ends,
)
from uavplan.world.obstacles import AltitudeBand
from uavplan.world.terrain import Terrain

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ================================================================================ terrain
@njit(cache=True)
def _terrain_extrema(A, B, H, x0, y0, dx, dy):  # pragma: no cover - numba
    """Exact min and max of ``z - h(x, y)`` along segments ``A[m] -> B[m]`` over the bilinear DEM
    ``H`` (clamped to its edges outside). Returns (m, 4): min, s at min, max, s at max."""
    m = A.shape[0]
    ny, nx = H.shape
    out = np.empty((m, 4))
    for q in range(m):
        u0 = (A[q, 0] - x0) / dx
        u1 = (B[q, 0] - x0) / dx
        v0 = (A[q, 1] - y0) / dy
        v1 = (B[q, 1] - y0) / dy
        za = A[q, 2]
        zb = B[q, 2]
        du = u1 - u0
        dv = v1 - v0
        # next grid line crossed along u and along v (only lines 0..n-1 change the formula)
        if du > 0:
            ku = max(math.floor(u0) + 1, 0)
            su = (ku - u0) / du if ku <= nx - 1 else 2.0
        elif du < 0:
            ku = min(math.ceil(u0) - 1, nx - 1)
            su = (ku - u0) / du if ku >= 0 else 2.0
        else:
            ku = 0
            su = 2.0
        if dv > 0:
            kv = max(math.floor(v0) + 1, 0)
            sv = (kv - v0) / dv if kv <= ny - 1 else 2.0
        elif dv < 0:
            kv = min(math.ceil(v0) - 1, ny - 1)
            sv = (kv - v0) / dv if kv >= 0 else 2.0
        else:
            kv = 0
            sv = 2.0
        cmin = np.inf
        smin = 0.0
        cmax = -np.inf
        smax = 0.0
        sa = 0.0
        while True:
            sb = min(su, sv, 1.0)
            if sb > sa:
                sm = 0.5 * (sa + sb)
                uc = min(max(u0 + du * sm, 0.0), nx - 1.0)
                vc = min(max(v0 + dv * sm, 0.0), ny - 1.0)
                i = min(math.floor(uc), nx - 2)
                j = min(math.floor(vc), ny - 2)
                a0 = min(max(u0 + du * sa, 0.0), nx - 1.0) - i
                a1 = min(max(u0 + du * sb, 0.0), nx - 1.0) - i - a0
                b0 = min(max(v0 + dv * sa, 0.0), ny - 1.0) - j
                b1 = min(max(v0 + dv * sb, 0.0), ny - 1.0) - j - b0
                z0 = za + (zb - za) * sa
                z1 = (zb - za) * (sb - sa)
                h00 = H[j, i]
                p = H[j, i + 1] - h00
                r = H[j + 1, i] - h00
                w = h00 - H[j, i + 1] - H[j + 1, i] + H[j + 1, i + 1]
                # c(t) = z - h along the piece, t in [0, 1]: c0 + c1 t + c2 t^2
                c0 = z0 - (h00 + p * a0 + r * b0 + w * a0 * b0)
                c1 = z1 - (p * a1 + r * b1 + w * (a0 * b1 + a1 * b0))
                c2 = -w * a1 * b1
                e0 = c0
                e1 = c0 + c1 + c2
                if e0 < cmin:
                    cmin = e0
                    smin = sa
                if e0 > cmax:
                    cmax = e0
                    smax = sa
                if e1 < cmin:
                    cmin = e1
                    smin = sb
                if e1 > cmax:
                    cmax = e1
                    smax = sb
                if c2 != 0.0:
                    tv = -c1 / (2.0 * c2)
                    if 0.0 < tv < 1.0:
                        ev = c0 + tv * (c1 + c2 * tv)
                        if c2 > 0.0 and ev < cmin:
                            cmin = ev
                            smin = sa + tv * (sb - sa)
                        elif c2 < 0.0 and ev > cmax:
                            cmax = ev
                            smax = sa + tv * (sb - sa)
            if sb >= 1.0:
                break
            if su <= sb:
                if du > 0:
                    ku += 1
                    su = (ku - u0) / du if ku <= nx - 1 else 2.0
                else:
                    ku -= 1
                    su = (ku - u0) / du if ku >= 0 else 2.0
            if sv <= sb:
                if dv > 0:
                    kv += 1
                    sv = (kv - v0) / dv if kv <= ny - 1 else 2.0
                else:
                    kv -= 1
                    sv = (kv - v0) / dv if kv >= 0 else 2.0
            sa = sb
        out[q, 0] = cmin
        out[q, 1] = smin
        out[q, 2] = cmax
        out[q, 3] = smax
    return out


@njit(cache=True)
def _mark_nodes_read(A, B, x0, y0, dx, dy, ny, nx, mask, r0, c0):  # pragma: no cover - numba
    """Mark in ``mask`` (its node ``[0, 0]`` is the grid's ``[r0, c0]``) every node that
    :func:`_terrain_extrema` reads along ``A[m] -> B[m]`` (the corners of the cells between
    each segment's ends, clamped as it clamps them), and one node more on each side."""
    mr, mc = mask.shape
    for q in range(A.shape[0]):
        u0 = (A[q, 0] - x0) / dx
        u1 = (B[q, 0] - x0) / dx
        v0 = (A[q, 1] - y0) / dy
        v1 = (B[q, 1] - y0) / dy
        i0 = min(math.floor(min(max(min(u0, u1), 0.0), nx - 1.0)), nx - 2) - 1
        i1 = min(math.floor(min(max(max(u0, u1), 0.0), nx - 1.0)), nx - 2) + 2
        j0 = min(math.floor(min(max(min(v0, v1), 0.0), ny - 1.0)), ny - 2) - 1
        j1 = min(math.floor(min(max(max(v0, v1), 0.0), ny - 1.0)), ny - 2) + 2
        for j in range(max(j0 - r0, 0), min(j1 - r0, mr - 1) + 1):
            for i in range(max(i0 - c0, 0), min(i1 - c0, mc - 1) + 1):
                mask[j, i] = True


def nodes_read(
    a: FloatArray, b: FloatArray, terrain: Terrain, cut: tuple[slice, slice]
) -> tuple[IntArray, IntArray]:
    """(rows, columns) of ``terrain``'s grid, within ``cut``: the nodes the clearance kernel
    reads along the segments ``a[m] -> b[m]``, and one more around (a grid that is right at
    these nodes gives the clearances of the whole grid)."""
    mask = np.zeros((cut[0].stop - cut[0].start, cut[1].stop - cut[1].start), dtype=np.bool_)
    ny, nx = np.shape(terrain.heights)
    _mark_nodes_read(np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3),
                     np.ascontiguousarray(b, dtype=np.float64).reshape(-1, 3),
                     float(terrain.x0), float(terrain.y0), float(terrain.dx),
                     float(terrain.dy), ny, nx, mask, cut[0].start, cut[1].start)  # fmt: skip
    rows, cols = np.nonzero(mask)
    return rows + cut[0].start, cols + cut[1].start


def terrain_clearance_extrema(a: FloatArray, b: FloatArray, terrain: Terrain) -> FloatArray:
    """Exact minimum and maximum of ``z - h(x, y)`` along each segment over the bilinear DEM.

    Each segment is split where it crosses the grid lines; on each piece the clearance is a
    quadratic in the segment parameter, whose extrema are taken in closed form. Outside the grid
    the height is that of the nearest edge point (the grid extends its edges).

    Args:
        a, b: (m, 3) segment ends, metres.
        terrain: the DEM (only ``heights, x0, y0, dx, dy`` are read).

    Returns:
        (m, 4): minimum clearance (m), segment parameter of the minimum, maximum clearance (m),
        segment parameter of the maximum.
    """
    A = np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3)
    B = np.ascontiguousarray(b, dtype=np.float64).reshape(-1, 3)
    H = _read_only(terrain.heights)
    return np.asarray(
        _terrain_extrema(
            A, B, H, float(terrain.x0), float(terrain.y0), float(terrain.dx), float(terrain.dy)
        )
    )


def within_reach(
    H: FloatArray, du: float, dv: float, reach: float, highest: bool, how: str = "height",
    cut: tuple[slice, slice] | None = None, nodes: tuple[IntArray, IntArray] | None = None,
) -> FloatArray:  # fmt: skip
    """The verifier's own bound on the ground within ``reach`` horizontally of any point: a
    grid whose bilinear surface at a point is at least (``highest``; at most otherwise) the
    surface of ``H`` (columns ``du``, rows ``dv`` apart, edges extended) anywhere within
    ``reach`` of it. ``how="height"``: each node moved to the highest (lowest) node within
    ``ceil(reach / d) + 1`` nodes per axis (a point within reach lies in a cell whose corners
    are all that close to each corner of the point's own cell). ``how="slope"``: each node
    moved by ``reach`` times the steepest cell gradient within that many cells (a cell's
    gradient is at most the hypot of its larger x-edge and y-edge slopes, and the surface is
    continuous). Either holds alone; the verifier uses the better clearance of the two.
    ``cut``: the rows and columns of the result wanted (the nodes at the cut's edges are the
    whole grid's). ``nodes``: (rows, columns) of the whole grid: the result at those nodes
    alone, a 1-D array (the margins' bisections read a flight's few hundred nodes at many
    reaches: each is a query of :class:`_Extremes`, not a filter of the whole grid)."""
    G = np.asarray(H, dtype=np.float64)
    if reach <= 0:
        if nodes is not None:
            return G[nodes]
        return G if cut is None else G[cut]
    ku = math.ceil(reach / du) + 1
    kv = math.ceil(reach / dv) + 1
    if nodes is not None:
        table = _extremes(H, G, du, dv, highest, how, kv, ku)
        if table is not None:
            near = table.at(nodes[0], nodes[1], kv, ku)
            if how == "height":
                return near
            g = G[nodes]
            return g + reach * near if highest else g - reach * near
        return within_reach(H, du, dv, reach, highest, how)[nodes]
    # the filtered grid depends on the window alone (for "slope", the steepest gradient
    # near each node, which the reach then scales): kept per grid and window
    key = (id(H), ku, kv, bool(highest) if how == "height" else True, how)
    hit = _WITHIN.pop(key, None)
    if hit is not None and hit[0] is H:
        near = hit[1]
        _WITHIN[key] = hit  # the most recently used last
    else:
        from scipy.ndimage import maximum_filter, minimum_filter

        size = (2 * kv + 1, 2 * ku + 1)
        if how == "height":
            f = maximum_filter if highest else minimum_filter
            near = np.asarray(f(G, size=size, mode="nearest"))
        else:
            near = maximum_filter(_steepest(G, du, dv), size=size, mode="constant",
                                  cval=0.0)[: G.shape[0], : G.shape[1]]  # fmt: skip
        while len(_WITHIN) >= 64:  # the least recently used go first
            del _WITHIN[next(iter(_WITHIN))]
        _WITHIN[key] = (H, near)
    if cut is not None:
        G, near = G[cut], near[cut]
    if how == "height":
        return near
    return G + reach * near if highest else G - reach * near


def _steepest(G: FloatArray, du: float, dv: float) -> FloatArray:
    """(ny + 1, nx + 1): at node (r, c) the bound on the gradient of the cell whose far corner
    it is (zero on the border rows and columns): the hypot of the cell's larger x-edge and
    larger y-edge slopes."""
    ny, nx = G.shape
    su = np.abs(G[:, 1:] - G[:, :-1]) / du
    sv = np.abs(G[1:, :] - G[:-1, :]) / dv
    steep = np.zeros((ny + 1, nx + 1))
    steep[1:ny, 1:nx] = np.sqrt(np.maximum(su[1:], su[:-1]) ** 2
                                + np.maximum(sv[:, 1:], sv[:, :-1]) ** 2)  # fmt: skip
    return steep


_WITHIN: dict[tuple[int, int, int, bool, str], tuple[FloatArray, FloatArray]] = {}

#: The most memory the window tables of :func:`within_reach` may hold (bytes); a grid whose
#: table would need more is filtered whole per window instead.
TABLE_BYTES = 768 * 2**20


def _read_only(a: FloatArray) -> FloatArray:
    """``a`` as a C-contiguous, read-only float64 view: a grid reaches its kernel with one
    signature whether the caller's copy is writable or not (each other signature is a
    compilation; the planner's side does the same, ``uavplan.world.kernel_arrays``, which the
    verifier does not import)."""
    v = np.ascontiguousarray(a, dtype=np.float64).view()
    v.setflags(write=False)
    return v


class _Extremes:
    """A sparse table of a grid's extremes over square blocks: ``S[k, r, c]`` is the largest
    (smallest) value over rows ``r .. r + 2^k - 1`` and columns ``c .. c + 2^k - 1`` (cut at the
    grid's end). Any window's extreme is that of a few blocks of the largest size that fits
    its shorter side (overlaps change nothing in a maximum): the same value as the filter's,
    bit for bit, read at a few nodes in microseconds. Built up to the level the windows ask."""

    def __init__(self, base: FloatArray, highest: bool, levels: int) -> None:
        self.highest = highest
        self.S = _extreme_levels(_read_only(base), levels, highest)

    @property
    def levels(self) -> int:
        return int(self.S.shape[0])

    def at(self, rows: IntArray, cols: IntArray, kv: int, ku: int) -> FloatArray:
        """The extreme over rows ``rows -kv .. +kv`` and columns ``cols -ku .. +ku`` (cut at the
        grid's edges; a filter's ``nearest`` edge adds no other value)."""
        out = np.empty(rows.shape[0])
        _window_extremes(self.S, rows, cols, kv, ku, self.highest, out)
        return out


def _levels_for(ny: int, nx: int, kv: int, ku: int) -> int:
    """The levels a window of half-sizes ``kv``, ``ku`` needs on a ``ny`` x ``nx`` grid."""
    side = min(2 * kv + 1, 2 * ku + 1, ny, nx)
    return math.floor(math.log2(side)) + 1


def _extremes(
    H: FloatArray, G: FloatArray, du: float, dv: float, highest: bool, how: str, kv: int, ku: int
) -> _Extremes | None:
    """The table for ``within_reach``'s windows over ``H`` (its nodes' heights for ``height``,
    the steepest gradients for ``slope``), kept per grid; None when it would need more than
    :data:`TABLE_BYTES`."""
    high = bool(highest) if how == "height" else True
    key = (id(H), high, how)
    hit = _TABLES.get(key)
    ny, nx = G.shape if how == "height" else (G.shape[0] + 1, G.shape[1] + 1)
    need = _levels_for(ny, nx, kv, ku)
    if hit is not None and hit[0] is H and hit[1].levels >= need:
        return hit[1]
    # built to the deepest level any window on this grid can use (one build per grid) when
    # that fits beside the other grids' tables; else to this window's, the others dropped
    size = ny * nx * 8
    others = sum(t.S.nbytes for k, (_, t) in _TABLES.items() if k != key)
    levels = _levels_for(ny, nx, ny, nx)
    if levels * size + others > TABLE_BYTES:
        levels = need
    if levels * size > TABLE_BYTES:
        return None
    if levels * size + others > TABLE_BYTES:
        _TABLES.clear()
    base = G if how == "height" else _steepest(G, du, dv)
    table = _Extremes(base, high, levels)
    _TABLES[key] = (H, table)
    return table


_TABLES: dict[tuple[int, bool, str], tuple[FloatArray, _Extremes]] = {}


@njit(cache=True)
def _extreme_levels(G, levels, highest):  # pragma: no cover - numba
    """``S[k]``: the extreme of ``G`` over each 2^k x 2^k block (cut at the grid's end)."""
    ny, nx = G.shape
    S = np.empty((levels, ny, nx))
    S[0] = G
    for k in range(1, levels):
        h = 1 << (k - 1)
        for r in range(ny):
            r2 = min(r + h, ny - 1)
            for c in range(nx):
                c2 = min(c + h, nx - 1)
                a = S[k - 1, r, c]
                b = S[k - 1, r2, c]
                d = S[k - 1, r, c2]
                e = S[k - 1, r2, c2]
                if highest:
                    S[k, r, c] = max(max(a, b), max(d, e))
                else:
                    S[k, r, c] = min(min(a, b), min(d, e))
    return S


@njit(cache=True)
def _window_extremes(S, rows, cols, kv, ku, highest, out):  # pragma: no cover - numba
    """``out[n]``: the extreme of the table's grid over rows ``rows[n] -kv .. +kv`` and columns
    ``cols[n] -ku .. +ku`` (cut at the edges), from blocks of the largest size that fits."""
    ny, nx = S.shape[1], S.shape[2]
    for n in range(rows.shape[0]):
        r0 = max(rows[n] - kv, 0)
        r1 = min(rows[n] + kv, ny - 1)
        c0 = max(cols[n] - ku, 0)
        c1 = min(cols[n] + ku, nx - 1)
        side = min(r1 - r0 + 1, c1 - c0 + 1)
        a = 0
        while (2 << a) <= side:
            a += 1
        s = 1 << a
        best = S[a, r0, c0]
        rr = r0
        while True:
            cc = c0
            while True:
                v = S[a, rr, cc]
                best = max(best, v) if highest else min(best, v)
                if cc + s - 1 >= c1:
                    break
                cc = min(cc + s, c1 - s + 1)
            if rr + s - 1 >= r1:
                break
            rr = min(rr + s, r1 - s + 1)
        out[n] = best


def bilinear_height(terrain: Terrain, x: FloatArray, y: FloatArray) -> FloatArray:
    """The verifier's own bilinear lookup (nearest edge outside the grid), metres."""
    H = np.asarray(terrain.heights, dtype=np.float64)
    ny, nx = H.shape
    u = np.clip((np.asarray(x, dtype=np.float64) - terrain.x0) / terrain.dx, 0.0, nx - 1.0)
    v = np.clip((np.asarray(y, dtype=np.float64) - terrain.y0) / terrain.dy, 0.0, ny - 1.0)
    i = np.minimum(np.floor(u).astype(np.intp), nx - 2)
    j = np.minimum(np.floor(v).astype(np.intp), ny - 2)
    s, r = u - i, v - j
    return np.asarray(
        H[j, i] * (1 - s) * (1 - r)
        + H[j, i + 1] * s * (1 - r)
        + H[j + 1, i] * (1 - s) * r
        + H[j + 1, i + 1] * s * r
    )


def check_terrain(
    traj: Trajectory, terrain: Terrain | None, band: AltitudeBand | None = None
) -> list[Violation]:
    """Terrain and altitude band along every segment (3-D only).

    * ``terrain``: the clearance ``z - h`` must stay >= 0 (exact, bilinear DEM);
    * ``altitude``, ground reference: ``z - h`` in ``[band.min, band.max]`` along the segment
      (exact min and max; ground is 0 without terrain);
    * ``altitude``, absolute reference: ``z`` in ``[band.min, band.max]`` at every waypoint
      (``z`` is linear along a segment).
    """
    if traj.dim != 3:
        return []
    a, b = segment_ends(traj)
    out: list[Violation] = []
    ground = band is not None and band.reference == "ground"
    ext: FloatArray | None = None
    if terrain is not None:
        ext = terrain_clearance_extrema(a, b, terrain)
    elif ground:  # flat ground at z = 0: z - h is linear
        za, zb = a[:, 2], b[:, 2]
        ext = np.stack(
            [
                np.minimum(za, zb),
                np.where(za <= zb, 0.0, 1.0),
                np.maximum(za, zb),
                np.where(za >= zb, 0.0, 1.0),
            ],
            axis=1,
        )
    if terrain is not None and ext is not None:
        for k in (int(i) for i in np.flatnonzero(ext[:, 0] < -TOL)):
            p, t = point_at(traj, k, float(ext[k, 1]))
            out.append(
                Violation(
                    "terrain",
                    (traj.id,),
                    t,
                    (p,),
                    float(ext[k, 0]),
                    0.0,
                    f"{traj.id}: segment {k} goes {fmt_num(-ext[k, 0])} m under the terrain at "
                    f"{fmt_points(p)}, t={t:.3f} s",
                )
            )
    if band is None:
        return out
    if ground and ext is not None:
        for k in range(a.shape[0]):
            for col, bad, bound, word in (
                (0, ext[k, 0] < band.min - TOL, band.min, "below"),
                (2, ext[k, 2] > band.max + TOL, band.max, "above"),
            ):
                if not bad:
                    continue
                p, t = point_at(traj, k, float(ext[k, col + 1]))
                out.append(
                    Violation(
                        "altitude",
                        (traj.id,),
                        t,
                        (p,),
                        float(ext[k, col]),
                        bound,
                        f"{traj.id}: segment {k} at {fmt_num(ext[k, col])} m above ground, {word} "
                        f"the band [{band.min:g}, {band.max:g}] m, at {fmt_points(p)}, t={t:.3f} s",
                    )
                )
    elif not ground:
        z = traj.points[:, 2]
        for w in np.flatnonzero((z < band.min - TOL) | (z > band.max + TOL)):
            k = int(w)
            zk = float(z[k])
            bound = band.min if zk < band.min else band.max
            out.append(
                Violation(
                    "altitude",
                    (traj.id,),
                    float(traj.times[k]),
                    (fmt_point(traj.points[k]),),
                    zk,
                    bound,
                    f"{traj.id}: waypoint {k} at altitude {fmt_num(zk)} m, outside the band "
                    f"[{band.min:g}, {band.max:g}] m",
                )
            )
    return out
