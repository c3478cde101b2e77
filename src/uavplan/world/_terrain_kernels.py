"""Numba kernels for exact terrain queries along straight segments.

The terrain is the bilinear interpolant of a DEM grid. Along a straight segment, inside one DEM
cell, that interpolant is a quadratic in the segment parameter ``t``, so the clearance
``z(t) - h(t)`` is a quadratic too and its minimum over the cell is found exactly (end points and
the stationary point). To avoid walking every cell of every segment, a branch-and-bound over
``t`` prunes any sub-segment whose lowest altitude is above the highest terrain in its bounding
box, read from a max-pyramid of the grid (level ``L`` holds the max over blocks of ``2**L``
cells). The result is the exact minimum clearance (to rounding), not a sampled one.

Coordinates here are *cell coordinates*: ``u = (x - x0) / dx``, ``v = (y - y0) / dy``; node
``(j, i)`` of the grid sits at ``(u, v) = (i, j)`` and cell ``(cj, ci)`` spans
``[ci, ci + 1] x [cj, cj + 1]``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from uavplan.kernel_builds import population_kernel

_STACK = 256


def build_max_pyramid(heights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Max-pyramid over the cells of ``heights`` (ny, nx).

    Returns ``(flat, offsets, shapes)``: level ``L`` is
    ``flat[offsets[L]:offsets[L] + shapes[L, 0] * shapes[L, 1]].reshape(shapes[L])`` and holds, for
    each block of ``2**L x 2**L`` cells, the largest grid value at any corner of those cells.
    """
    h = np.asarray(heights, dtype=np.float64)
    level = np.maximum(np.maximum(h[:-1, :-1], h[1:, :-1]), np.maximum(h[:-1, 1:], h[1:, 1:]))
    levels = [level]
    while level.shape[0] > 1 or level.shape[1] > 1:
        ny, nx = level.shape
        py, px = ny + (ny % 2), nx + (nx % 2)
        padded = np.full((py, px), -np.inf)
        padded[:ny, :nx] = level
        level = padded.reshape(py // 2, 2, px // 2, 2).max(axis=(1, 3))
        levels.append(level)
    shapes = np.array([lv.shape for lv in levels], dtype=np.int64)
    sizes = shapes[:, 0] * shapes[:, 1]
    offsets = np.concatenate(([0], np.cumsum(sizes)[:-1])).astype(np.int64)
    flat = np.concatenate([lv.ravel() for lv in levels])
    return flat, offsets, shapes


@njit(cache=True, inline="always")
def _bilinear_cell(H, ci, cj, s, r):  # pragma: no cover - numba
    h00 = H[cj, ci]
    h10 = H[cj, ci + 1]
    h01 = H[cj + 1, ci]
    h11 = H[cj + 1, ci + 1]
    return h00 + (h10 - h00) * s + (h01 - h00) * r + (h00 - h10 - h01 + h11) * s * r


@njit(cache=True)
def _box_max(flat, offsets, shapes, ci0, ci1, cj0, cj1):  # pragma: no cover - numba
    """Upper bound of the terrain over cells [ci0..ci1] x [cj0..cj1] from the pyramid."""
    L = 0
    nlev = shapes.shape[0]
    while nlev - 1 > L and ((ci1 >> L) - (ci0 >> L) > 1 or (cj1 >> L) - (cj0 >> L) > 1):
        L += 1
    off = offsets[L]
    nx = shapes[L, 1]
    best = -np.inf
    for bj in range(cj0 >> L, (cj1 >> L) + 1):
        for bi in range(ci0 >> L, (ci1 >> L) + 1):
            val = flat[off + bj * nx + bi]
            if val > best:
                best = val
    return best


@njit(cache=True)
def _clip_to_grid(u0, v0, du, dv, ncx, ncy):  # pragma: no cover - numba
    """Parameter interval [ta, tb] of the segment inside the grid rectangle [0,ncx] x [0,ncy]."""
    ta = 0.0
    tb = 1.0
    edge_lo = 0.0
    hx = float(ncx)
    hy = float(ncy)
    if du != 0.0:
        t1 = (edge_lo - u0) / du
        t2 = (hx - u0) / du
        lo = min(t1, t2)
        hi = max(t1, t2)
        ta = max(ta, lo)
        tb = min(tb, hi)
    elif u0 < edge_lo or u0 > hx:
        return 1.0, 0.0
    if dv != 0.0:
        t1 = (edge_lo - v0) / dv
        t2 = (hy - v0) / dv
        lo = min(t1, t2)
        hi = max(t1, t2)
        ta = max(ta, lo)
        tb = min(tb, hi)
    elif v0 < edge_lo or v0 > hy:
        return 1.0, 0.0
    return ta, tb


@njit(cache=True)
def _sort_small(ts, n):  # pragma: no cover - numba
    """``ts[:n]`` sorted in place by insertion (n <= 64: two sorted runs of crossings between
    the ends; as fast as ``np.sort`` there, and it spares every cold start compiling Numba's
    quicksort, about 3 s)."""
    for i in range(1, n):
        x = ts[i]
        j = i - 1
        while j >= 0 and ts[j] > x:
            ts[j + 1] = ts[j]
            j -= 1
        ts[j + 1] = x
    return ts[:n]


@njit(cache=True)
def _leaf_min(H, u0, v0, z0, du, dv, dz, ta, tb, ncx, ncy):  # pragma: no cover - numba
    """Exact minimum of z(t) - h(t) for t in [ta, tb] (the sub-segment spans few cells)."""
    ts = np.empty(64)
    n = 0
    ts[n] = ta
    n += 1
    # integer crossings of u and v inside (ta, tb)
    if du != 0.0:
        ua = u0 + du * ta
        ub = u0 + du * tb
        k0 = int(np.floor(min(ua, ub))) + 1
        k1 = int(np.ceil(max(ua, ub))) - 1
        for k in range(k0, k1 + 1):
            if n < 62:
                ts[n] = (k - u0) / du
                n += 1
    if dv != 0.0:
        va = v0 + dv * ta
        vb = v0 + dv * tb
        k0 = int(np.floor(min(va, vb))) + 1
        k1 = int(np.ceil(max(va, vb))) - 1
        for k in range(k0, k1 + 1):
            if n < 63:
                ts[n] = (k - v0) / dv
                n += 1
    ts[n] = tb
    n += 1
    tsorted = _sort_small(ts, n)
    best = np.inf
    for q in range(n - 1):
        a = tsorted[q]
        b = tsorted[q + 1]
        if b < a:
            continue
        tm = 0.5 * (a + b)
        ci = int(np.floor(u0 + du * tm))
        cj = int(np.floor(v0 + dv * tm))
        ci = min(max(ci, 0), ncx - 1)
        cj = min(max(cj, 0), ncy - 1)
        h00 = H[cj, ci]
        bx = H[cj, ci + 1] - h00
        by = H[cj + 1, ci] - h00
        cc = h00 - H[cj, ci + 1] - H[cj + 1, ci] + H[cj + 1, ci + 1]
        s0 = u0 - ci
        r0 = v0 - cj
        # h(t) = qa + qb t + qc t^2
        qa = h00 + bx * s0 + by * r0 + cc * s0 * r0
        qb = bx * du + by * dv + cc * (s0 * dv + r0 * du)
        qc = cc * du * dv
        # g(t) = z0 + dz t - h(t)
        ga = (z0 - qa) + (dz - qb) * a - qc * a * a
        gb = (z0 - qa) + (dz - qb) * b - qc * b * b
        g = min(ga, gb)
        if qc < 0.0:  # g convex: interior minimum possible
            tstar = (dz - qb) / (2.0 * qc)
            if a < tstar < b:
                gs = (z0 - qa) + (dz - qb) * tstar - qc * tstar * tstar
                if gs < g:
                    g = gs
        if g < best:
            best = g
    return best


@njit(cache=True)
def _segment_min_clearance(
    H, flat, offsets, shapes, u0, v0, z0, u1, v1, z1, cap, stop_below
):  # pragma: no cover - numba
    ncy = H.shape[0] - 1
    ncx = H.shape[1] - 1
    du = u1 - u0
    dv = v1 - v0
    dz = z1 - z0
    ta, tb = _clip_to_grid(u0, v0, du, dv, ncx, ncy)
    if ta > tb:
        return np.inf
    best = np.inf
    stack_a = np.empty(_STACK)
    stack_b = np.empty(_STACK)
    top = 0
    stack_a[0] = ta
    stack_b[0] = tb
    top = 1
    while top > 0:
        top -= 1
        a = stack_a[top]
        b = stack_b[top]
        ua = u0 + du * a
        ub = u0 + du * b
        va = v0 + dv * a
        vb = v0 + dv * b
        ci0 = min(max(int(np.floor(min(ua, ub))), 0), ncx - 1)
        ci1 = min(max(int(np.floor(max(ua, ub))), 0), ncx - 1)
        cj0 = min(max(int(np.floor(min(va, vb))), 0), ncy - 1)
        cj1 = min(max(int(np.floor(max(va, vb))), 0), ncy - 1)
        zmin = min(z0 + dz * a, z0 + dz * b)
        hmax = _box_max(flat, offsets, shapes, ci0, ci1, cj0, cj1)
        bound = zmin - hmax
        if bound >= best or bound >= cap:
            continue
        if (ci1 - ci0 <= 1 and cj1 - cj0 <= 1) or top >= _STACK - 2:
            g = _leaf_min(H, u0, v0, z0, du, dv, dz, a, b, ncx, ncy)
            if g < best:
                best = g
                if stop_below and best < cap:
                    return best
            continue
        m = 0.5 * (a + b)
        stack_a[top] = a
        stack_b[top] = m
        stack_a[top + 1] = m
        stack_b[top + 1] = b
        top += 2
    return best


@population_kernel()
def min_clearance_batch(H, flat, offsets, shapes, u, v, z, cap, stop_below):  # pragma: no cover
    """Min of z - h along every segment of ``(P, N)`` polylines in cell coordinates, (P, N - 1).

    A value ``>= cap`` means "at least ``cap``" (pruned early). With ``stop_below`` the search
    also stops at the first point found below ``cap``: the value is then below ``cap`` but not
    necessarily the minimum (a fast yes/no test). Otherwise values below ``cap`` are exact.
    Parts of a segment outside the grid are ignored (the bounds check covers them).
    """
    P, N = u.shape
    out = np.empty((P, N - 1))
    for p in prange(P):
        for s in range(N - 1):
            out[p, s] = _segment_min_clearance(
                H,
                flat,
                offsets,
                shapes,
                u[p, s],
                v[p, s],
                z[p, s],
                u[p, s + 1],
                v[p, s + 1],
                z[p, s + 1],
                cap,
                stop_below,
            )
    return out


@njit(cache=True, inline="always")
def _interval_mean(H, ncx, ncy, u0, v0, du, dv, a, b):  # pragma: no cover - numba
    """The integral over ``t`` in ``[a, b]`` of the bilinear terrain at ``(u0 + du t, v0 + dv t)``,
    for an interval that lies inside one grid cell (off the grid: clamped to the edge)."""
    tm = 0.5 * (a + b)
    um = u0 + du * tm
    vm = v0 + dv * tm
    ci = min(max(int(np.floor(um)), 0), ncx - 1)
    cj = min(max(int(np.floor(vm)), 0), ncy - 1)
    h00 = H[cj, ci]
    bx = H[cj, ci + 1] - h00
    by = H[cj + 1, ci] - h00
    cc = h00 - H[cj, ci + 1] - H[cj + 1, ci] + H[cj + 1, ci + 1]
    # local coordinates s(t) = s0 + su t, r(t) = r0 + rv t; off the grid the terrain is
    # clamped to the edge (as Terrain.height), so s or r is constant
    s0 = u0 - ci
    su = du
    if um < 0.0 or um > ncx:
        s0 = 0.0 if um < 0.0 else 1.0
        su = 0.0
    r0 = v0 - cj
    rv = dv
    if vm < 0.0 or vm > ncy:
        r0 = 0.0 if vm < 0.0 else 1.0
        rv = 0.0
    qa = h00 + bx * s0 + by * r0 + cc * s0 * r0
    qb = bx * su + by * rv + cc * (s0 * rv + r0 * su)
    qc = cc * su * rv
    return qa * (b - a) + qb * (b * b - a * a) / 2.0 + qc * (b**3 - a**3) / 3.0


@njit(cache=True, inline="always")
def _crossings(x0, dx):  # pragma: no cover - numba
    """First grid line, step and count of the integer crossings of ``x0 + dx t`` for ``t`` in
    (0, 1), in the order of increasing ``t``."""
    if dx == 0.0:
        return 0, 0, 0
    lo = min(x0, x0 + dx)
    hi = max(x0, x0 + dx)
    k_lo = int(np.floor(lo)) + 1
    k_hi = int(np.ceil(hi))
    n = max(k_hi - k_lo, 0)
    if dx > 0.0:
        return k_lo, 1, n
    return k_hi - 1, -1, n


@population_kernel()
def mean_height_batch(H, u, v):  # pragma: no cover - numba
    """Exact mean of the bilinear terrain along the xy projection of each segment, (P, N - 1).

    The mean is over the segment parameter (uniform in xy arc length); a vertical segment gives
    the height at its point. Off the grid the terrain is the nearest edge point's height, as in
    :meth:`Terrain.height`.

    The breakpoints (0, the crossings of the grid lines in u and in v, 1) are walked in order by
    merging the two monotone sequences of crossings, with no allocation or sort per segment; the
    intervals are summed in the same order as :func:`mean_height_batch_reference`, so the two
    give the same bits.
    """
    P, N = u.shape
    ncy = H.shape[0] - 1
    ncx = H.shape[1] - 1
    out = np.empty((P, N - 1))
    for p in prange(P):
        for s in range(N - 1):
            u0 = u[p, s]
            v0 = v[p, s]
            du = u[p, s + 1] - u0
            dv = v[p, s + 1] - v0
            if du == 0.0 and dv == 0.0:
                uc = min(max(u0, 0.0), float(ncx))
                vc = min(max(v0, 0.0), float(ncy))
                ci = min(int(np.floor(uc)), ncx - 1)
                cj = min(int(np.floor(vc)), ncy - 1)
                out[p, s] = _bilinear_cell(H, ci, cj, uc - ci, vc - cj)
                continue
            ku, su, nu = _crossings(u0, du)
            kv, sv, nv = _crossings(v0, dv)
            iu = 0
            iv = 0
            zero = True  # the breakpoint 0 not yet taken
            one = True  # the breakpoint 1 not yet taken
            total = 0.0
            prev = 0.0
            first = True
            for _ in range(nu + nv + 2):
                # the smallest of the four heads (as np.sort would order them)
                best = np.inf
                src = -1
                if zero:
                    best = 0.0
                    src = 0
                if iu < nu:
                    t = (ku + su * iu - u0) / du
                    if src < 0 or t < best:
                        best = t
                        src = 1
                if iv < nv:
                    t = (kv + sv * iv - v0) / dv
                    if src < 0 or t < best:
                        best = t
                        src = 2
                if one and (src < 0 or best > 1.0):
                    best = 1.0
                    src = 3
                if src == 0:
                    zero = False
                elif src == 1:
                    iu += 1
                elif src == 2:
                    iv += 1
                else:
                    one = False
                if not first:
                    total += _interval_mean(H, ncx, ncy, u0, v0, du, dv, prev, best)
                first = False
                prev = best
            out[p, s] = total
    return out


@population_kernel()
def mean_height_lower_batch(Hb, B, slack, u, v):  # pragma: no cover - numba
    """A lower bound of :func:`mean_height_batch`, (P, N - 1): along each segment the mean of
    the block minima ``Hb`` (``Hb[j, i]``: the least node of the block of ``B`` x ``B`` cells
    ``j, i``, its edges' nodes included, so at least the bilinear terrain anywhere in the
    block), walked block by block (``B`` times fewer crossings than the exact mean); off the
    grid the edge's block (the terrain there is the nearest edge point's), less ``slack`` for
    the round-off of an interval's block at a crossing."""
    P, N = u.shape
    nbj = Hb.shape[0]
    nbi = Hb.shape[1]
    out = np.empty((P, N - 1))
    for p in prange(P):
        for s in range(N - 1):
            u0 = u[p, s] / B
            v0 = v[p, s] / B
            du = u[p, s + 1] / B - u0
            dv = v[p, s + 1] / B - v0
            ku, su, nu = _crossings(u0, du)
            kv, sv, nv = _crossings(v0, dv)
            iu = 0
            iv = 0
            prev = 0.0
            total = 0.0
            while True:
                tu = (ku + su * iu - u0) / du if iu < nu else 2.0
                tv = (kv + sv * iv - v0) / dv if iv < nv else 2.0
                t = min(min(tu, tv), 1.0)
                mid = 0.5 * (prev + t)
                i = min(max(int(np.floor(u0 + du * mid)), 0), nbi - 1)
                j = min(max(int(np.floor(v0 + dv * mid)), 0), nbj - 1)
                total += (t - prev) * Hb[j, i]
                prev = t
                if t >= 1.0:
                    break
                if tu <= t:
                    iu += 1
                if tv <= t:
                    iv += 1
            out[p, s] = total - slack
    return out


@population_kernel()
def mean_height_batch_reference(H, u, v):  # pragma: no cover - numba
    """The first form of :func:`mean_height_batch` (breakpoints collected and sorted per
    segment), kept as the reference its tests compare against bit for bit.

    Exact mean of the bilinear terrain along the xy projection of each segment, (P, N - 1).

    The mean is over the segment parameter (uniform in xy arc length); a vertical segment gives
    the height at its point. Off the grid the terrain is the nearest edge point's height, as in
    :meth:`Terrain.height`.
    """
    P, N = u.shape
    ncy = H.shape[0] - 1
    ncx = H.shape[1] - 1
    out = np.empty((P, N - 1))
    for p in prange(P):
        for s in range(N - 1):
            u0 = u[p, s]
            v0 = v[p, s]
            du = u[p, s + 1] - u0
            dv = v[p, s + 1] - v0
            # breakpoints: integer crossings of u and v
            nu = 0
            nv = 0
            if du != 0.0:
                nu = int(abs(np.floor(u0 + du) - np.floor(u0))) + 1
            if dv != 0.0:
                nv = int(abs(np.floor(v0 + dv) - np.floor(v0))) + 1
            ts = np.empty(nu + nv + 2)
            n = 0
            ts[n] = 0.0
            n += 1
            if du != 0.0:
                lo = min(u0, u0 + du)
                hi = max(u0, u0 + du)
                for k in range(int(np.floor(lo)) + 1, int(np.ceil(hi))):
                    ts[n] = (k - u0) / du
                    n += 1
            if dv != 0.0:
                lo = min(v0, v0 + dv)
                hi = max(v0, v0 + dv)
                for k in range(int(np.floor(lo)) + 1, int(np.ceil(hi))):
                    ts[n] = (k - v0) / dv
                    n += 1
            ts[n] = 1.0
            n += 1
            tsorted = np.sort(ts[:n])
            total = 0.0
            for q in range(n - 1):
                total += _interval_mean(H, ncx, ncy, u0, v0, du, dv, tsorted[q], tsorted[q + 1])
            if du == 0.0 and dv == 0.0:
                uc = min(max(u0, 0.0), float(ncx))
                vc = min(max(v0, 0.0), float(ncy))
                ci = min(int(np.floor(uc)), ncx - 1)
                cj = min(int(np.floor(vc)), ncy - 1)
                total = _bilinear_cell(H, ci, cj, uc - ci, vc - cj)
            out[p, s] = total
    return out


@njit(cache=True, inline="always")
def bilinear_one(H, x0, y0, dx, dy, x, y):  # pragma: no cover - numba
    """Bilinear height at one point, clamped to the grid (the arithmetic of
    :meth:`uavplan.world.terrain.Terrain.height_reference`)."""
    ny, nx = H.shape
    u = (x - x0) / dx
    v = (y - y0) / dy
    u = min(max(u, 0.0), nx - 1.0)
    v = min(max(v, 0.0), ny - 1.0)
    i = min(int(np.floor(u)), nx - 2)
    j = min(int(np.floor(v)), ny - 2)
    return _bilinear_cell(H, i, j, u - i, v - j)


@njit(cache=True, inline="always")
def nearest_one(H, x0, y0, dx, dy, x, y):  # pragma: no cover - numba
    """Height of the grid node nearest ``(x, y)``, halves rounded up, clamped to the grid: the
    arithmetic of :meth:`uavplan.world.terrain.Terrain.height_nearest` (SPSO's ``H(round(y),
    round(x))``). A coordinate that is not finite or beyond the int64 range takes node 0, as
    the NumPy form's float-to-int conversion gives on x86 (then clipped)."""
    ny, nx = H.shape
    u = (x - x0) / dx
    v = (y - y0) / dy
    fu = np.floor(u)
    fv = np.floor(v)
    ru = fu + 1.0 if u - fu >= 0.5 else fu
    rv = fv + 1.0 if v - fv >= 0.5 else fv
    i = int(ru) if abs(ru) < 9.2e18 else 0  # NaN fails the test too
    j = int(rv) if abs(rv) < 9.2e18 else 0
    return H[min(max(j, 0), ny - 1), min(max(i, 0), nx - 1)]


@njit(cache=True, inline="always")
def ground_one(H, has_terrain, nearest, x0, y0, dx, dy, x, y):  # pragma: no cover - numba
    """The ground's height at ``(x, y)`` read at the ``nearest`` node or bilinear; 0 without a
    terrain (``has_terrain`` False, ``H`` then a placeholder)."""
    if not has_terrain:
        return 0.0
    if nearest:
        return nearest_one(H, x0, y0, dx, dy, x, y)
    return bilinear_one(H, x0, y0, dx, dy, x, y)


@njit(cache=True)
def bilinear_heights(H, x0, y0, dx, dy, x, y):  # pragma: no cover - numba
    """Bilinear height at the points ``(x[k], y[k])`` (flat float64 arrays), clamped to the grid:
    the same arithmetic, in the same order, as :meth:`uavplan.world.terrain.Terrain.height`'s
    NumPy form (which tests compare it with)."""
    n = x.shape[0]
    out = np.empty(n)
    for k in range(n):
        out[k] = bilinear_one(H, x0, y0, dx, dy, x[k], y[k])
    return out


@njit(cache=True, inline="always")
def snap_one(a, n1, tol):  # pragma: no cover - numba
    """A cell coordinate within ``tol`` of 0 or of ``n1`` put exactly there."""
    if abs(a) <= tol:
        a = 0.0
    if abs(a - n1) <= tol:
        a = float(n1)
    return a


@njit(cache=True)
def snapped_cell_coords(x, y, x0, y0, dx, dy, nx1, ny1, tol_u, tol_v):  # pragma: no cover
    """Cell coordinates ``((x - x0) / dx, (y - y0) / dy)`` of flat arrays, with values within
    ``tol`` of the grid's first or last node put exactly on it (as
    :meth:`uavplan.world.terrain.Terrain._uv_snapped` does in NumPy)."""
    n = x.shape[0]
    u = np.empty(n)
    v = np.empty(n)
    for k in range(n):
        u[k] = snap_one((x[k] - x0) / dx, nx1, tol_u)
        v[k] = snap_one((y[k] - y0) / dy, ny1, tol_v)
    return u, v
