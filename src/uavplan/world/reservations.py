"""Reservation table: a time-indexed spatial hash of the trajectories already planned.

Prioritized planning (PPSwarm, Meng, Chen & Qu 2024, Drones 8:192, Sect. 4.3 and Alg. 3 line 11)
keeps a "dynamic obstacle list" of the higher-priority UAVs' paths, discretized in time (Alg. 5),
and rejects a candidate path that comes closer than the UAV-UAV safety distance ``S2`` to one of
them. Comparing positions only at sampled instants misses two UAVs that pass through each other
between samples (at 20 m/s each they close 40 m per second, four times ``S2 = 10 m``), so this
table keeps the exact motion:

* every trajectory is piecewise linear in time (constant speed along each segment); it is cut at
  the multiples of ``dt`` into **pieces**, each inside one time bucket ``k = floor(t / dt)`` and
  at most ``speed * dt`` long (Alg. 5 cuts at one step of ``v_uav``; we cut in time);
* each reserved piece is entered in every cell of a 3-D grid (side ``cell``) that its bounding
  box, grown by ``separation``, touches, under the key ``(k, cell)``;
* a candidate piece looks up only the cells its own bounding box touches in its own bucket, and
  for every reserved piece found there computes the exact minimum distance over the common time
  interval (relative motion is linear there, so it is the minimum of a quadratic).

A conflict found this way is real, and every real conflict is found: if two pieces come closer
than ``separation`` at time ``t``, the candidate's position at ``t`` lies in one of its own cells
and inside the reserved piece's grown box, so that cell holds the reserved piece. The cost of a
query is proportional to the candidate's own pieces (and the reserved pieces sharing its cells),
not to the number of UAVs in the table.

**Per-axis separation** (the RSCDWOA paper, Sect. 5: "the minimal distance between UAVs ... is
[50, 50, 20]^T m"): two UAVs conflict when they are closer than ``S_x`` in x *and* ``S_y`` in y
*and* ``S_z`` in z, an axis-aligned box. The table then measures the scaled Chebyshev distance
``S_ref max_i |r_i| / S_i`` with ``S_ref = max_i S_i`` (metres in the widest axes), which is below
``S_ref`` exactly when the offset is inside the box. Over a common time interval the relative
offset ``r(s) = r0 + s dr`` is linear, so this distance is convex and piecewise linear in ``s``;
its minimum lies at an end or at a kink (a zero of some ``r_i``, or where two scaled components
are equal in magnitude), and is taken exactly over those at most 11 candidates. Cells are grown
by ``S_ref`` on every axis, which holds the whole box.

A UAV is in the air only between its first and last time (it takes off at its start and lands at
its goal): before and after it is no hazard. :mod:`uavplan.verify` checks the same
semantics independently, pair by pair.

**Under an execution model** (:mod:`uavplan.world.execution`: take-off error ``delta0``, speed
error ``rho``), a table made with ``timing=(delta0, rho)`` keeps every UAV's *window*: the
point ``tau`` of a trajectory taking off at ``t0`` can be flown at any actual time in
``[t0 - delta0 + (tau - t0) / (1 + rho), t0 + delta0 + (tau - t0) / (1 - rho)]``. A reserved
piece is entered in its own time bucket, as without a model; a candidate piece whose window
is ``[w_lo, w_hi]`` looks in the buckets of every path time whose window can meet it, which is
``[(1 - rho)(w_lo - delta0) + rho t_min, (1 + rho)(w_hi + delta0) - rho t_min]`` for
trajectories taking off at ``t_min`` or later: a dozen buckets or more once the drift has
grown, so such a table keys its entries by cell and sorts each cell's entries by bucket (one
lookup per cell, then a bisection to the first bucket), and skips a reserved piece whose own
window does not meet the candidate's; two pieces are compared by the least distance
between their points over the pairs of path times whose windows meet
(:func:`window_min_dist2`: a convex quadratic over a convex polygon, minimised exactly), after
a test of their boxes. What the tracking error takes away is in the table's separation
(:meth:`ReservationTable.for_scenario`). Every pair of pieces that can come within the
separation is compared: the reserved piece's path times lie in the buckets looked in, and its
grown box holds the candidate's point.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.world.kernel_arrays import writable

if TYPE_CHECKING:
    from uavplan.world.scenario import Scenario

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_EMPTY = np.int64(-1)
#: a timed table's entry key: ``cell * _NB + _OFF + bucket`` (buckets -_OFF .. _NB - _OFF - 1)
_NB = np.int64(1 << 21)
_OFF = np.int64(1 << 20)


def split_pieces(points: FloatArray, times: FloatArray, dt: float) -> tuple[FloatArray, ...]:
    """Cut one timed polyline into pieces that each lie in one time bucket of length ``dt``.

    Args:
        points: (n, 3) metres; times: (n,) non-decreasing seconds.
    Returns:
        p0, p1 (m, 3) piece end positions, t0, t1 (m,) their times (t1 > t0), k (m,) buckets.
    """
    P = np.asarray(points, dtype=np.float64)
    T = np.asarray(times, dtype=np.float64)
    return _split(writable(P), writable(T), float(dt))


@njit(cache=True)
def _split(P, T, dt):  # pragma: no cover - numba
    n = P.shape[0]
    cap = 16
    for s in range(n - 1):
        if T[s + 1] > T[s]:
            cap += int(np.floor(T[s + 1] / dt) - np.floor(T[s] / dt)) + 1
    p0 = np.empty((cap, 3))
    p1 = np.empty((cap, 3))
    t0 = np.empty(cap)
    t1 = np.empty(cap)
    kk = np.empty(cap, dtype=np.int64)
    m = 0
    for s in range(n - 1):
        ta = T[s]
        tb = T[s + 1]
        if not tb > ta:
            continue
        k = int(np.floor(ta / dt))
        lo = ta
        while lo < tb:
            hi = min((k + 1) * dt, tb)
            if hi > lo:
                fa = (lo - ta) / (tb - ta)
                fb = (hi - ta) / (tb - ta)
                for d in range(3):
                    p0[m, d] = P[s, d] + fa * (P[s + 1, d] - P[s, d])
                    p1[m, d] = P[s, d] + fb * (P[s + 1, d] - P[s, d])
                t0[m] = lo
                t1[m] = hi
                kk[m] = k
                m += 1
            lo = hi
            k += 1
    return p0[:m], p1[:m], t0[:m], t1[:m], kk[:m]


def simplify_timed(
    points: FloatArray, times: FloatArray, tolerance: float, max_window: int = 64
) -> tuple[NDArray[np.int64], FloatArray]:
    """The vertices of a timed polyline to keep so that each kept segment, flown linearly in
    time between its ends, stays within ``tolerance`` metres of the trajectory at every instant.

    Returns ``(keep, pad)``: indices into the points (first and last included) and, per kept
    segment, its largest deviation (<= ``tolerance``). The deviation is exact: both motions are
    linear in time between the original samples, so their distance is largest at a sample.
    At most ``max_window`` original segments merge into one; a segment of zero duration is
    never merged across.
    """
    return _simplify(writable(points), writable(times), float(tolerance), int(max_window))


@njit(cache=True)
def _simplify(P, T, tol, max_window):  # pragma: no cover - numba
    n = P.shape[0]
    keep = np.empty(max(n, 1), dtype=np.int64)
    pad = np.zeros(max(n, 1))
    keep[0] = 0
    m = 0
    i = 0
    while i < n - 1:
        j = i + 1
        dev_j = 0.0
        while j + 1 < n and j + 1 - i <= max_window and T[j + 1] > T[i] and T[j] > T[i]:
            jj = j + 1
            dev = 0.0
            for k in range(i + 1, jj):
                f = (T[k] - T[i]) / (T[jj] - T[i])
                d = 0.0
                for c in range(P.shape[1]):
                    e = P[k, c] - (P[i, c] + f * (P[jj, c] - P[i, c]))
                    d += e * e
                dev = max(dev, d)
            dev = np.sqrt(dev)
            if dev > tol:
                break
            j = jj
            dev_j = dev
        pad[m] = dev_j
        m += 1
        keep[m] = j
        i = j
    return keep[: m + 1], pad[:m]


def _piece_pads(seg_times: FloatArray, seg_pad: FloatArray, piece_t0: FloatArray) -> FloatArray:
    """Each piece's pad: that of the segment it was cut from (the segment whose time interval
    holds the piece's start)."""
    if not seg_pad.size or not np.any(seg_pad):
        return np.zeros(piece_t0.shape[0])
    s = np.searchsorted(seg_times, piece_t0, side="right") - 1
    return np.asarray(seg_pad[np.clip(s, 0, seg_pad.size - 1)], dtype=np.float64)


@njit(cache=True)
def _hash(key, mask):  # pragma: no cover - numba
    h = (key * np.int64(-7046029254386353131)) ^ (key >> np.int64(29))
    return h & mask


@njit(cache=True)
def _cell_range(a, b, grow, origin, cell, n):  # pragma: no cover - numba
    """First and last grid index (clamped to [0, n)) that the interval [min(a, b) - grow,
    max(a, b) + grow] touches along one axis."""
    lo = min(max(int(np.floor((min(a, b) - grow - origin) / cell)), 0), n - 1)
    hi = min(max(int(np.floor((max(a, b) + grow - origin) / cell)), 0), n - 1)
    return lo, hi


@njit(cache=True)
def _cell_keys(p0, p1, k, grow, origin, cell, dims, by_cell):  # pragma: no cover - numba
    """(entry key, piece index) for every cell that each piece's box grown by ``grow[i]``
    touches: bucket-major, or with ``by_cell`` cell-major (``cell * _NB + _OFF + k``)."""
    m = p0.shape[0]
    nx, ny, nz = dims[0], dims[1], dims[2]
    count = 0
    for i in range(m):
        c = 1
        for d in range(3):
            a, b = _cell_range(p0[i, d], p1[i, d], grow[i], origin[d], cell, dims[d])
            c *= b - a + 1
        count += c
    keys = np.empty(count, dtype=np.int64)
    idx = np.empty(count, dtype=np.int64)
    e = 0
    for i in range(m):
        ix0, ix1 = _cell_range(p0[i, 0], p1[i, 0], grow[i], origin[0], cell, nx)
        iy0, iy1 = _cell_range(p0[i, 1], p1[i, 1], grow[i], origin[1], cell, ny)
        iz0, iz1 = _cell_range(p0[i, 2], p1[i, 2], grow[i], origin[2], cell, nz)
        for ix in range(ix0, ix1 + 1):
            for iy in range(iy0, iy1 + 1):
                for iz in range(iz0, iz1 + 1):
                    if by_cell:
                        keys[e] = ((ix * ny + iy) * nz + iz) * _NB + _OFF + k[i]
                    else:
                        keys[e] = (((k[i] + 1) * nx + ix) * ny + iy) * nz + iz
                    idx[e] = i
                    e += 1
    return keys, idx


@njit(cache=True)
def _build_table(sorted_keys):  # pragma: no cover - numba
    """Open-addressing table over the distinct keys of ``sorted_keys``: slot -> (key, start,
    count) into the sorted entry arrays."""
    n = sorted_keys.shape[0]
    distinct = 0
    for i in range(n):
        if i == 0 or sorted_keys[i] != sorted_keys[i - 1]:
            distinct += 1
    size = 16
    while size < 2 * distinct:
        size *= 2
    mask = np.int64(size - 1)
    tkey = np.full(size, -1, dtype=np.int64)
    tstart = np.zeros(size, dtype=np.int64)
    tcount = np.zeros(size, dtype=np.int64)
    i = 0
    while i < n:
        j = i
        while j < n and sorted_keys[j] == sorted_keys[i]:
            j += 1
        h = _hash(sorted_keys[i], mask)
        while tkey[h] != -1:
            h = (h + 1) & mask
        tkey[h] = sorted_keys[i]
        tstart[h] = i
        tcount[h] = j - i
        i = j
    return tkey, tstart, tcount


@njit(cache=True)
def _lookup(key, tkey, mask):  # pragma: no cover - numba
    h = _hash(key, mask)
    while True:
        kk = tkey[h]
        if kk == key:
            return h
        if kk == -1:
            return -1
        h = (h + 1) & mask


@njit(cache=True, inline="always")
def _relative_motion(a0, a1, ta0, ta1, b0, b1, tb0, tb1):  # pragma: no cover - numba
    """The offset of two linear motions over their common time: ``(ok, r0 (3 floats), dr (3
    floats))``, the offset at the start and its change to the end (``ok`` False: no common
    time). Scalar arithmetic: no temporary arrays in the innermost loop."""
    lo = max(ta0, tb0)
    hi = min(ta1, tb1)
    if lo > hi:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    fa0 = (lo - ta0) / (ta1 - ta0)
    fa1 = (hi - ta0) / (ta1 - ta0)
    fb0 = (lo - tb0) / (tb1 - tb0)
    fb1 = (hi - tb0) / (tb1 - tb0)
    # relative offset at lo (r0) and at hi (r0 + dr); it moves linearly in between
    ex = a1[0] - a0[0]
    ey = a1[1] - a0[1]
    ez = a1[2] - a0[2]
    gx = b1[0] - b0[0]
    gy = b1[1] - b0[1]
    gz = b1[2] - b0[2]
    r0x = (a0[0] + fa0 * ex) - (b0[0] + fb0 * gx)
    r0y = (a0[1] + fa0 * ey) - (b0[1] + fb0 * gy)
    r0z = (a0[2] + fa0 * ez) - (b0[2] + fb0 * gz)
    drx = ((a0[0] + fa1 * ex) - (b0[0] + fb1 * gx)) - r0x
    dry = ((a0[1] + fa1 * ey) - (b0[1] + fb1 * gy)) - r0y
    drz = ((a0[2] + fa1 * ez) - (b0[2] + fb1 * gz)) - r0z
    return True, r0x, r0y, r0z, drx, dry, drz


@njit(cache=True)
def _piece_min_dist2(a0, a1, ta0, ta1, b0, b1, tb0, tb1):  # pragma: no cover - numba
    """Squared minimum distance between two linear motions over their common time, or inf."""
    ok, r0x, r0y, r0z, drx, dry, drz = _relative_motion(a0, a1, ta0, ta1, b0, b1, tb0, tb1)
    if not ok:
        return np.inf
    dd = drx * drx + dry * dry + drz * drz
    s = 0.0
    if dd > 0.0:
        s = -(r0x * drx + r0y * dry + r0z * drz) / dd
        s = min(max(s, 0.0), 1.0)
    x = r0x + s * drx
    y = r0y + s * dry
    z = r0z + s * drz
    return x * x + y * y + z * z


@njit(cache=True)
def _cheb_at(r0x, r0y, r0z, drx, dry, drz, w, s):  # pragma: no cover - numba
    return max(w[0] * abs(r0x + s * drx), max(w[1] * abs(r0y + s * dry), w[2] * abs(r0z + s * drz)))


@njit(cache=True)
def _piece_min_box(a0, a1, ta0, ta1, b0, b1, tb0, tb1, w):  # pragma: no cover - numba
    """Minimum over the common time of two linear motions of the scaled Chebyshev distance
    ``max_i w_i |r_i|`` of their offset, or inf (the per-axis separation; see the module
    docstring). Exact: the minimum of a convex piecewise-linear function over candidates."""
    ok, r0x, r0y, r0z, drx, dry, drz = _relative_motion(a0, a1, ta0, ta1, b0, b1, tb0, tb1)
    if not ok:
        return np.inf
    r0 = (r0x, r0y, r0z)
    dr = (drx, dry, drz)
    best = min(
        _cheb_at(r0x, r0y, r0z, drx, dry, drz, w, 0.0),
        _cheb_at(r0x, r0y, r0z, drx, dry, drz, w, 1.0),
    )
    for i in range(3):
        if dr[i] != 0.0:
            s = -r0[i] / dr[i]
            if 0.0 < s < 1.0:
                best = min(best, _cheb_at(r0x, r0y, r0z, drx, dry, drz, w, s))
        for j in range(i + 1, 3):
            for sign in (1.0, -1.0):
                # w_i (r0_i + s dr_i) = sign w_j (r0_j + s dr_j)
                den = w[i] * dr[i] - sign * w[j] * dr[j]
                if den != 0.0:
                    s = (sign * w[j] * r0[j] - w[i] * r0[i]) / den
                    if 0.0 < s < 1.0:
                        best = min(best, _cheb_at(r0x, r0y, r0z, drx, dry, drz, w, s))
    return best


@njit(cache=True, inline="always")
def _half_plane_clip(L, own, x0, y0, dx, dy, tol):  # pragma: no cover - numba
    """The parameter interval of the line ``(x0, y0) + t (dx, dy)`` inside every half-plane
    ``L[k, 0] + L[k, 1] x + L[k, 2] y >= 0`` but ``own`` (the line's own): ``(lo, hi)``, empty
    when ``lo > hi``."""
    lo = -np.inf
    hi = np.inf
    for k in range(L.shape[0]):
        if k == own:
            continue
        l0 = L[k, 0] + L[k, 1] * x0 + L[k, 2] * y0
        l1 = L[k, 1] * dx + L[k, 2] * dy
        if l1 == 0.0:
            if l0 < -tol:
                return 1.0, 0.0
            continue
        t = -l0 / l1
        if l1 > 0.0:
            lo = max(lo, t - tol / abs(l1))
        else:
            hi = min(hi, t + tol / abs(l1))
    return lo, hi


@njit(cache=True)
def window_min_dist2(
    a0, a1, ta0, ta1, b0, b1, tb0, tb1, t0a, da, ra, t0b, db, rb
):  # pragma: no cover - numba
    """The least squared distance between ``A``'s segment ``a0 -> a1`` (path times
    ``ta0..ta1``) and ``B``'s ``b0 -> b1`` (``tb0..tb1``) over the pairs of path times whose
    windows meet (:mod:`uavplan.world.execution`: ``A`` takes off at ``t0a`` with take-off error
    ``da`` and speed error ``ra``; ``B`` likewise), or inf when none do. In the segments'
    parameters ``(u, w)`` the pairs form the unit square cut by two half-planes (a convex
    polygon) and the squared distance is a convex quadratic: its minimum is the unconstrained
    one when inside, else on an edge, where it is a quadratic in one variable."""
    LA = ta1 - ta0
    LB = tb1 - tb0
    L = np.empty((6, 3))
    L[0, 0], L[0, 1], L[0, 2] = 0.0, 1.0, 0.0
    L[1, 0], L[1, 1], L[1, 2] = 1.0, -1.0, 0.0
    L[2, 0], L[2, 1], L[2, 2] = 0.0, 0.0, 1.0
    L[3, 0], L[3, 1], L[3, 2] = 1.0, 0.0, -1.0
    # A's earliest time at u before B's latest at w; B's earliest before A's latest
    k0 = (t0a - da + (ta0 - t0a) / (1.0 + ra)) - (t0b + db + (tb0 - t0b) / (1.0 - rb))
    L[4, 0], L[4, 1], L[4, 2] = -k0, -LA / (1.0 + ra), LB / (1.0 - rb)
    m0 = (t0b - db + (tb0 - t0b) / (1.0 + rb)) - (t0a + da + (ta0 - t0a) / (1.0 - ra))
    L[5, 0], L[5, 1], L[5, 2] = -m0, LA / (1.0 - ra), -LB / (1.0 + rb)
    scale = 1.0 + abs(ta0) + abs(tb0) + abs(ta1) + abs(tb1)
    tol = 1e-12 * scale
    r0x, r0y, r0z = a0[0] - b0[0], a0[1] - b0[1], a0[2] - b0[2]
    ex, ey, ez = a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]
    gx, gy, gz = b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]
    c = r0x * r0x + r0y * r0y + r0z * r0z
    cu = 2.0 * (r0x * ex + r0y * ey + r0z * ez)
    cw = -2.0 * (r0x * gx + r0y * gy + r0z * gz)
    cuu = ex * ex + ey * ey + ez * ez
    cuw = -2.0 * (ex * gx + ey * gy + ez * gz)
    cww = gx * gx + gy * gy + gz * gz
    best = np.inf
    det = 4.0 * cuu * cww - cuw * cuw
    if det > 1e-12 * (1.0 + cuu * cww):
        u = (-cu * 2.0 * cww + cw * cuw) / det
        w = (-cw * 2.0 * cuu + cu * cuw) / det
        inside = True
        for k in range(6):
            if L[k, 0] + L[k, 1] * u + L[k, 2] * w < -tol:
                inside = False
                break
        if inside:
            best = c + cu * u + cw * w + cuu * u * u + cuw * u * w + cww * w * w
            return max(best, 0.0)
    for k in range(6):
        nu, nw = L[k, 1], L[k, 2]
        nn = nu * nu + nw * nw
        if nn == 0.0:
            continue
        x0 = -L[k, 0] * nu / nn
        y0 = -L[k, 0] * nw / nn
        dx, dy = -nw, nu
        lo, hi = _half_plane_clip(L, k, x0, y0, dx, dy, tol)
        if not lo <= hi or not (math.isfinite(lo) and math.isfinite(hi)):
            continue
        # the quadratic along the line: q0 + q1 t + q2 t^2
        q0 = c + cu * x0 + cw * y0 + cuu * x0 * x0 + cuw * x0 * y0 + cww * y0 * y0
        q1 = (cu + 2.0 * cuu * x0 + cuw * y0) * dx + (cw + cuw * x0 + 2.0 * cww * y0) * dy
        q2 = cuu * dx * dx + cuw * dx * dy + cww * dy * dy
        t = lo
        if q2 > 0.0:
            t = min(max(-q1 / (2.0 * q2), lo), hi)
        v = q0 + t * (q1 + q2 * t)
        v = min(v, q0 + lo * (q1 + q2 * lo), q0 + hi * (q1 + q2 * hi))
        if v < best:
            best = v
    return max(best, 0.0) if best < np.inf else np.inf


@njit(cache=True, inline="always")
def _box_gap2(a0, a1, b0, b1):  # pragma: no cover - numba
    """The squared distance between the boxes of segments ``a0 -> a1`` and ``b0 -> b1``."""
    g = 0.0
    for d in range(3):
        e = max(min(a0[d], a1[d]) - max(b0[d], b1[d]), min(b0[d], b1[d]) - max(a0[d], a1[d]))
        if e > 0.0:
            g += e * e
    return g


@njit(cache=True, inline="always")
def path_query(paths, times, p, args):  # pragma: no cover - numba
    """:func:`_query` of path ``p`` of ``paths`` (P, N, 3) at ``times`` (P, N): the smallest
    distance to a reserved piece found within the searched cells, less the piece's pad (inf if
    none), stopping at the first one below ``sep`` unless ``want_min``
    (:func:`path_query_from` from the first segment)."""
    return path_query_from(paths, times, p, args, 0)[0]


# compiled once as its own function, not inlined at Numba's IR level into each kernel that
# calls it: a cold PPSwarm plan compiled 36 % less, at the same run time
@njit(cache=True)
def path_query_from(paths, times, p, args, first):  # pragma: no cover - numba
    """:func:`path_query` with the segments searched from segment ``first`` on (then from 0,
    round to ``first``), and the segment where it stopped below ``sep`` (-1 if it did not):
    ``(distance, segment)``. Whether a path comes closer than ``sep`` does not depend on
    ``first`` (each segment is searched the same way whatever the order); a caller that asks
    the same path at nearby take-off times starts where the last conflict was found, most
    often found again at once. ``args``: the tuple
    ``(dt, origin, cell, dims, sep, tkey, tstart, tcount, e_idx, rp0, rp1, rt0, rt1, rpad,
    want_min, box, w, timed, delta0, rho, rtake, take_min, ekeys, qgrow)``
    (:meth:`ReservationTable.query_args`; ``timed``: the pieces are compared under the
    execution model's windows, ``rtake`` the take-off time of each reserved piece's
    trajectory, ``take_min`` the earliest of them, the path's its first time; ``qgrow``: per
    segment of the path (an empty array: none) how much farther than ``sep`` it is held,
    subtracted from its distances as a reserved piece's pad is, the cells searched around it
    grown by as much: :meth:`ReservationTable.held_off`)."""
    (
        dt,
        origin,
        cell,
        dims,
        sep,
        tkey,
        tstart,
        tcount,
        e_idx,
        rp0,
        rp1,
        rt0,
        rt1,
        rpad,
        want_min,
        box,
        w,
        timed,
        delta0,
        rho,
        rtake,
        take_min,
        ekeys,
        qgrow,
    ) = args
    N = paths.shape[1]
    t0 = times[p, 0]
    nx, ny, nz = dims[0], dims[1], dims[2]
    mask = np.int64(tkey.shape[0] - 1)
    best = np.inf
    a0 = np.empty(3)
    a1 = np.empty(3)
    done = False
    found = -1
    s0 = first if first >= 0 and first < N - 1 else 0
    for j in range(N - 1):
        if done:
            break
        s = s0 + j
        if s >= N - 1:
            s -= N - 1
        ta = times[p, s]
        tb = times[p, s + 1]
        if not tb > ta:
            continue
        g = qgrow[s] if qgrow.shape[0] > s else 0.0
        k = int(np.floor(ta / dt))
        lo = ta
        while lo < tb and not done:
            hi = min((k + 1) * dt, tb)
            if hi > lo:
                fa = (lo - ta) / (tb - ta)
                fb = (hi - ta) / (tb - ta)
                for d in range(3):
                    a0[d] = paths[p, s, d] + fa * (paths[p, s + 1, d] - paths[p, s, d])
                    a1[d] = paths[p, s, d] + fb * (paths[p, s + 1, d] - paths[p, s, d])
                ix0, ix1 = _cell_range(a0[0], a1[0], g, origin[0], cell, nx)
                iy0, iy1 = _cell_range(a0[1], a1[1], g, origin[1], cell, ny)
                iz0, iz1 = _cell_range(a0[2], a1[2], g, origin[2], cell, nz)
                k0 = k
                k1 = k
                w_lo = lo
                w_hi = hi
                if timed:  # the buckets of every path time whose window can meet this one's
                    w_lo = t0 - delta0 + (lo - t0) / (1.0 + rho)
                    w_hi = t0 + delta0 + (hi - t0) / (1.0 - rho)
                    k0 = int(np.floor(((1.0 - rho) * (w_lo - delta0) + rho * take_min) / dt)) - 1
                    k1 = int(np.floor(((1.0 + rho) * (w_hi + delta0) - rho * take_min) / dt))
                # a timed table is keyed by cell, each cell's entries by bucket: one lookup
                # per cell, then the buckets k0..k1 by bisection
                kb0, kb1 = (0, 0) if timed else (k0, k1)
                for kk in range(kb0, kb1 + 1):
                    for ix in range(ix0, ix1 + 1):
                        for iy in range(iy0, iy1 + 1):
                            for iz in range(iz0, iz1 + 1):
                                cid = (ix * ny + iy) * nz + iz
                                key = cid if timed else (((kk + 1) * nx + ix) * ny + iy) * nz + iz
                                h = _lookup(key, tkey, mask)
                                if h < 0:
                                    continue
                                e_lo = tstart[h]
                                e_end = e_lo + tcount[h]
                                last = np.int64(0)
                                if timed:
                                    first = cid * _NB + _OFF + max(k0, -_OFF)
                                    last = cid * _NB + _OFF + min(k1, _NB - _OFF - 1)
                                    b_hi = e_end
                                    while e_lo < b_hi:
                                        m = (e_lo + b_hi) // 2
                                        if ekeys[m] < first:
                                            e_lo = m + 1
                                        else:
                                            b_hi = m
                                for e in range(e_lo, e_end):
                                    r = e_idx[e]
                                    if timed:
                                        if ekeys[e] > last:
                                            break
                                        # the pieces' windows never meet (window_min_dist2
                                        # would find its polygon empty), with a slack of
                                        # a microsecond that only ever keeps a pair
                                        tr = rtake[r]
                                        if (
                                            tr - delta0 + (rt0[r] - tr) / (1.0 + rho) > w_hi + 1e-6
                                            or tr + delta0 + (rt1[r] - tr) / (1.0 - rho)
                                            < w_lo - 1e-6
                                        ):
                                            continue
                                        # the pieces' boxes too far apart for any timing
                                        if (
                                            not want_min
                                            and _box_gap2(a0, a1, rp0[r], rp1[r])
                                            >= (sep + rpad[r] + g) ** 2
                                        ):
                                            continue
                                        dist = np.sqrt(
                                            window_min_dist2(
                                                a0,
                                                a1,
                                                lo,
                                                hi,
                                                rp0[r],
                                                rp1[r],
                                                rt0[r],
                                                rt1[r],
                                                t0,
                                                delta0,
                                                rho,
                                                rtake[r],
                                                delta0,
                                                rho,
                                            )
                                        )
                                    elif box:
                                        dist = _piece_min_box(
                                            a0, a1, lo, hi, rp0[r], rp1[r], rt0[r], rt1[r], w
                                        )
                                    else:
                                        if (
                                            not want_min
                                            and _box_gap2(a0, a1, rp0[r], rp1[r])
                                            >= (sep + rpad[r] + g) ** 2
                                        ):
                                            continue  # the boxes alone keep them apart
                                        dist = np.sqrt(
                                            _piece_min_dist2(
                                                a0, a1, lo, hi, rp0[r], rp1[r], rt0[r], rt1[r]
                                            )
                                        )
                                    if dist == np.inf:
                                        continue
                                    dist -= rpad[r] + g
                                    if dist < best:
                                        best = dist
                                        if best < sep and not want_min:
                                            done = True
                                            found = s
                                            break
                                if done:
                                    break
                            if done:
                                break
                        if done:
                            break
                    if done:
                        break
            lo = hi
            k += 1
    return best, found


@population_kernel()
def _query(paths, times, args):  # pragma: no cover - numba
    """Per path (:func:`path_query` with ``args``): the smallest
    distance to a reserved piece found within the searched cells, less the piece's pad (inf
    if none), stopping at the first one below the separation unless ``want_min``; with
    ``box``, the scaled Chebyshev distance instead of the Euclidean one."""
    P = paths.shape[0]
    out = np.full(P, np.inf)
    for p in prange(P):
        out[p] = path_query(paths, times, p, args)
    return out


@njit(cache=True)
def _first_free(points, times, waits, start, stop, args, first):  # pragma: no cover - numba
    """The first ``i`` in ``start .. stop - 1`` at which the path ``points`` (n, 3), its
    ``times`` (n,) moved ``waits[i]`` later, keeps the separation from every reserved piece
    (:func:`path_query_from`), or -1; and the segment where the last conflict was found
    (``first`` if none was): each wait's search starts there, where the conflict at the wait
    before is most often found again at once."""
    n = points.shape[0]
    P = np.empty((1, n, 3))
    T = np.empty((1, n))
    for j in range(n):
        for d in range(3):
            P[0, j, d] = points[j, d]
    sep = args[4]
    hint = first
    for i in range(start, stop):
        for j in range(n):
            T[0, j] = times[j] + waits[i]
        dist, seg = path_query_from(P, T, 0, args, hint)
        if not dist < sep:
            return i, hint
        hint = seg
    return -1, hint


#: ``qgrow`` of a query whose path is held no farther than the separation
_NO_HOLD = np.zeros(0)


class ReservationTable:
    """Reserved timed trajectories and fast exact separation queries against them.

    Args:
        lower, upper: (3,) the airspace box in metres (cells outside are clamped to its edge,
            which only makes the search find more, never less).
        separation: the required distance ``S2`` between UAVs, metres; or per axis
            ``(S_x, S_y, S_z)``: the UAVs must not be closer than all three at once (an
            axis-aligned box, see the module docstring). Distances are then the scaled
            Chebyshev distance, in metres of the widest axis (:attr:`separation` is
            ``max(S_i)``, :attr:`axes` the three).
        dt: time bucket, seconds.
        cell: grid cell side, metres (default: ``max(4 separation, 40)``; any value is correct,
            it only changes speed).
        timing: ``(delta0, rho)``: every UAV's take-off and speed error (the module
            docstring); None or zeros: trajectories are flown exactly.
        lag: ``(wind, max_climb, max_descent)``: the trajectories are a fixed wing's flights
            whose heights lag their plan in that wind
            (:func:`uavplan.world.execution.lag_extents`); every reserved trajectory is
            padded segment by segment by its lag (the larger of the segment's ends'), and
            every segment of a queried path is held that much farther off (its own lag), as
            the verifier holds each pair of segments: the separation holds
            wherever both UAVs are between their planned and their lagged heights. None (or
            no wind): no lag.
    """

    def __init__(
        self,
        lower: FloatArray,
        upper: FloatArray,
        separation: float | Sequence[float],
        dt: float = 1.0,
        cell: float | None = None,
        timing: tuple[float, float] | None = None,
        lag: tuple[float, float | None, float | None] | None = None,
    ) -> None:
        axes = np.asarray(separation, dtype=np.float64).reshape(-1)
        if axes.size not in (1, 3) or not np.all(axes > 0) or not dt > 0:
            raise ValueError(
                f"separation (one number or three per axis) and dt must be positive, "
                f"got {separation}, {dt}"
            )
        #: per-axis minimum distances, or None for a sphere of radius :attr:`separation`
        self.axes: tuple[float, float, float] | None = (
            (float(axes[0]), float(axes[1]), float(axes[2])) if axes.size == 3 else None
        )
        self.separation = float(axes.max())
        # scaled Chebyshev weights S_ref / S_i (unused for a sphere)
        self._w = self.separation / np.asarray(self.axes) if self.axes is not None else np.ones(3)
        self.dt = float(dt)
        delta0, rho = (float(v) for v in (timing or (0.0, 0.0)))
        if not (delta0 >= 0 and 0 <= rho < 1):
            raise ValueError(f"timing (delta0 >= 0, 0 <= rho < 1) got {timing}")
        #: whether trajectories are compared under the execution model's windows
        self.timed = bool(delta0 or rho)
        self.delta0, self.rho = delta0, rho
        #: the lag of the flights (``(wind, max_climb, max_descent)``), None: none
        self.lag = lag if lag is not None and lag[0] > 0 else None
        if self.timed and self.axes is not None:
            raise ValueError("a per-axis separation under an execution model: use the sphere "
                             "that holds the box (ReservationTable.for_scenario does)")  # fmt: skip
        self.cell = float(cell if cell is not None else max(4.0 * self.separation, 40.0))
        lo = np.asarray(lower, dtype=np.float64)[:3]
        hi = np.asarray(upper, dtype=np.float64)[:3]
        self.origin = lo - self.cell
        self.dims = (np.ceil((hi - lo) / self.cell).astype(np.int64) + 3).astype(np.int64)
        if self.timed and float(np.prod(self.dims.astype(np.float64))) >= 2.0**41:
            raise ValueError(f"{self.dims.tolist()} cells of {self.cell} m: too many for a "
                             "timed table's keys; use larger cells")  # fmt: skip
        self.owners: list[str] = []
        self._p0 = np.zeros((0, 3))
        self._p1 = np.zeros((0, 3))
        self._t0 = np.zeros(0)
        self._t1 = np.zeros(0)
        self._pad = np.zeros(0)
        self._take = np.zeros(0)
        self._keys = np.zeros(0, dtype=np.int64)
        self._idx = np.zeros(0, dtype=np.int64)
        self._args: dict[bool, tuple[Any, ...]] = {}  # query_args, per want_min
        self._owner = np.zeros(0, dtype=np.int64)
        self._build()

    def __len__(self) -> int:
        return len(self.owners)

    @classmethod
    def for_uav(
        cls, lower: FloatArray, upper: FloatArray, uav: Any, margin: float = 0.0,
        dt: float = 1.0,
    ) -> ReservationTable:  # fmt: skip
        """The table for a scenario's UAV: its per-axis separation ``uav.s2_axes`` when it has
        one, else the sphere ``uav.s2``; ``margin`` metres wider on every axis."""
        axes = getattr(uav, "s2_axes", None)
        if axes is not None:
            return cls(lower, upper, [float(a) + margin for a in axes], dt=dt)
        return cls(lower, upper, float(uav.s2) + margin, dt=dt)

    @classmethod
    def for_scenario(
        cls, scenario: Scenario, margin: float = 0.0, dt: float = 1.0
    ) -> ReservationTable:
        """The table for a scenario's fleet: its UAV's separation (:meth:`for_uav`) under the
        scenario's execution model, when it has one: the separation widened by what tracking
        error takes away (``sqrt((2 e_h)^2 + (2 e_v)^2)``; a per-axis separation widened axis
        by axis, or, when the schedule may drift, the sphere that holds the widened box), and
        the take-off and speed errors as windows, and a fixed wing's height lag in the wind its
        heights are checked in (``lag``). Under a model whose schedule drifts the
        time bucket is at least the take-off window, ``2 delta0``: a candidate piece looks in
        every bucket its window can meet, so buckets narrower than the window only add
        lookups of the same reserved pieces (the answers are exact at any bucket)."""
        model = scenario.execution
        lo, hi, uav = scenario.bounds.lo, scenario.bounds.hi, scenario.uav
        if scenario.dim == 2:
            lo, hi = np.append(lo, 0.0), np.append(hi, 1.0)
        if model is None or model.nominal:
            return cls.for_uav(lo, hi, uav, margin, dt=dt)
        from uavplan.world.execution import slope_wind

        timing = model.timing(uav.speed)
        if model.timed:
            dt = max(dt, 2.0 * float(model.takeoff_s))
        wind = slope_wind(uav, model) if scenario.dim == 3 else 0.0
        lag = (wind, uav.max_climb_angle, uav.max_descent_angle) if wind > 0 else None
        axes = getattr(uav, "s2_axes", None)
        if axes is not None:
            grown = np.asarray(axes, dtype=np.float64) + margin
            grown += 2.0 * np.array([model.track_h, model.track_h, model.track_v])
            if not model.timed:
                return cls(lo, hi, [float(g) for g in grown], dt=dt, lag=lag)
            return cls(lo, hi, float(np.linalg.norm(grown)), dt=dt, timing=timing, lag=lag)
        sep = float(uav.s2) + margin + model.tracking_gap()
        return cls(lo, hi, sep, dt=dt, timing=timing if model.timed else None, lag=lag)

    def window(self, t0: float, tau: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The earliest and latest actual times of path times ``tau`` of a trajectory taking
        off at ``t0`` (the nominal table: ``tau`` itself)."""
        s = np.asarray(tau, dtype=np.float64) - t0
        return (t0 - self.delta0 + s / (1.0 + self.rho),
                t0 + self.delta0 + s / (1.0 - self.rho))  # fmt: skip

    @property
    def radius(self) -> float:
        """The radius of the smallest sphere that holds the separation region (``S2``, or the
        half-diagonal ``|(S_x, S_y, S_z)|`` of the box): a planner that keeps this Euclidean
        distance never conflicts."""
        return float(np.linalg.norm(self.axes)) if self.axes is not None else self.separation

    def clear_time(self) -> float:
        """The latest instant any reserved trajectory may still be flying: its landing at the
        latest its execution window allows (the landing itself in the nominal table); -inf
        when nothing is reserved."""
        if not self._t1.size:
            return -math.inf
        if not self.timed:
            return float(self._t1.max())
        latest = self._take + self.delta0 + (self._t1 - self._take) / (1.0 - self.rho)
        return float(latest.max())

    @property
    def n_pieces(self) -> int:
        return int(self._p0.shape[0])

    def add(
        self, uav_id: str, points: FloatArray, times: FloatArray, tolerance: float = 0.0
    ) -> None:
        """Reserve the timed polyline ``points`` (n, 3) at ``times`` (n,).

        ``tolerance`` > 0 (metres): a densely sampled trajectory (a smoothed flight) is
        reserved as fewer segments (:func:`simplify_timed`), each padded by its largest
        deviation from the trajectory: a query then finds every approach closer than the
        separation to the true trajectory, and may also reject one up to the pad farther
        (conservative); distances reported are lower bounds within the pad. A table with a
        :attr:`lag` pads every segment by its lag as well (the larger of its ends', in the table's
        wind: :func:`~uavplan.world.execution.lag_extents`).
        """
        pts, ts = writable(points), writable(times)
        if pts.ndim != 2 or pts.shape[1] != 3 or ts.shape != (pts.shape[0],):
            raise ValueError(f"need points (n, 3) and times (n,), got {pts.shape}, {ts.shape}")
        seg_pad = np.zeros(max(pts.shape[0] - 1, 0))
        lag = np.zeros_like(seg_pad)  # each segment held off by its lag, as the verifier holds it
        if self.lag is not None and pts.shape[0] >= 2:
            from uavplan.world.execution import lag_extents

            lag = lag_extents(pts[None], ts[None], *self.lag)[1][0]
        if tolerance > 0 and pts.shape[0] > 2:
            keep, seg_pad = _simplify(pts, ts, float(tolerance), 64)
            pts, ts = np.ascontiguousarray(pts[keep]), np.ascontiguousarray(ts[keep])
            if lag.size and keep.size > 1:  # a kept segment: the largest lag of those it spans
                lag = np.maximum.reduceat(lag, keep[:-1])
        seg_pad = seg_pad + lag
        p0, p1, t0, t1, k = _split(pts, ts, self.dt)
        # a Euclidean deviation of ``pad`` moves the scaled Chebyshev distance by at most
        # ``pad max(w)``
        pad = _piece_pads(ts, seg_pad, t0) * float(self._w.max())
        # A trajectory that takes off (lands) exactly at a bucket boundary shares that instant
        # with the bucket before (after): enter its first (last) piece there too.
        sel = np.arange(len(t0))
        kk = k.copy()
        if len(t0):
            if t0[0] == k[0] * self.dt:
                sel = np.append(sel, 0)
                kk = np.append(kk, k[0] - 1)
            if t1[-1] == (k[-1] + 1) * self.dt:
                sel = np.append(sel, len(t0) - 1)
                kk = np.append(kk, k[-1] + 1)
        if self.timed and len(kk) and not (kk.min() >= -_OFF and kk.max() < _NB - _OFF):
            raise ValueError(f"times {ts[0]}..{ts[-1]} s lie beyond the table's "
                             f"{int(_OFF)} buckets of {self.dt} s either side of 0")  # fmt: skip
        keys, idx = _cell_keys(
            p0[sel],
            p1[sel],
            kk,
            self.separation + pad[sel],
            self.origin,
            self.cell,
            self.dims,
            self.timed,
        )
        idx = sel[idx]
        base = self.n_pieces
        self.owners.append(uav_id)
        self._p0 = np.concatenate([self._p0, p0])
        self._p1 = np.concatenate([self._p1, p1])
        self._t0 = np.concatenate([self._t0, t0])
        self._t1 = np.concatenate([self._t1, t1])
        self._pad = np.concatenate([self._pad, pad])
        self._take = np.concatenate(
            [self._take, np.full(len(t0), float(ts[0]) if len(ts) else 0.0)]
        )
        self._owner = np.concatenate([self._owner, np.full(len(t0), len(self.owners) - 1)])
        # the entries stay sorted by key, equal keys in the order added (what a stable sort of
        # all of them gives): the new ones, sorted, go after the equal keys already there
        order = np.argsort(keys, kind="stable")
        keys, idx = keys[order], idx[order] + base
        at = np.searchsorted(self._keys, keys, side="right")
        self._keys = np.insert(self._keys, at, keys)
        self._idx = np.insert(self._idx, at, idx)
        self._tkey, self._tstart, self._tcount = self._hash_table()

    def _hash_table(self) -> tuple[IntArray, IntArray, IntArray]:
        # a timed table hashes cells, its entries sorted by cell then bucket
        return _build_table(self._keys // _NB if self.timed else self._keys)

    def trajectories(self) -> list[tuple[FloatArray, FloatArray]]:
        """Every reserved trajectory as ``(points (n, 3), times (n,))``, in the order added
        (the polylines as reserved: simplified ones as their kept points)."""
        out = []
        for k in range(len(self.owners)):
            sel = np.flatnonzero(self._owner == k)
            if sel.size == 0:
                continue
            pts = np.vstack([self._p0[sel], self._p1[sel[-1]][None]])
            ts = np.concatenate([self._t0[sel], [self._t1[sel[-1]]]])
            out.append((pts, ts))
        return out

    def _build(self) -> None:
        order = np.argsort(self._keys, kind="stable")
        self._keys = self._keys[order]
        self._idx = self._idx[order]
        self._tkey, self._tstart, self._tcount = self._hash_table()

    @staticmethod
    def _prepared(paths: FloatArray, times: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Paths (pop, n, 3) and times (pop, n) as the kernels take them."""
        p, t = writable(paths), writable(times)  # one kernel signature: never read-only
        if p.ndim == 2:
            p, t = p[None], t[None]
        if p.ndim != 3 or p.shape[2] != 3 or t.shape != p.shape[:2]:
            raise ValueError(f"need paths (pop, n, 3) and times (pop, n), got {p.shape}, {t.shape}")
        return p, t

    def _run(self, paths: FloatArray, times: FloatArray, want_min: bool) -> FloatArray:
        p, t = self._prepared(paths, times)
        if self.n_pieces == 0:
            return np.full(p.shape[0], np.inf)
        return np.asarray(_query(p, t, self.query_args(want_min)))

    def query_args(self, want_min: bool = False) -> tuple[Any, ...]:
        """The ``args`` of :func:`path_query`: the table as a kernel reads it (what a kernel
        that checks paths against the table passes on); made once per state of the table
        (every change of it builds a new hash table, :meth:`_hash_table`)."""
        cached = self._args.get(bool(want_min))
        if cached is not None and cached[5] is self._tkey:
            return cached
        args = (
            self.dt, self.origin, self.cell, self.dims, self.separation,
            self._tkey, self._tstart, self._tcount, self._idx,
            self._p0, self._p1, self._t0, self._t1, self._pad, bool(want_min),
            self.axes is not None, self._w, self.timed, self.delta0, self.rho, self._take,
            float(self._take.min()) if self._take.size else 0.0, self._keys, _NO_HOLD,
        )  # fmt: skip
        self._args[bool(want_min)] = args
        return args

    def held_off(self, paths: FloatArray, times: FloatArray) -> FloatArray:
        """(pop, n - 1) how much farther than the separation each segment of each timed path is
        held from the reserved trajectories: its height lag under :attr:`lag` (the larger of
        its ends', :func:`~uavplan.world.execution.lag_extents`; 0 without one), in the
        table's distance (the scaled Chebyshev one of a per-axis separation moves by at most
        that times the largest weight)."""
        p, t = self._prepared(paths, times)
        if self.lag is None:
            return np.zeros((p.shape[0], max(p.shape[1] - 1, 0)))
        from uavplan.world.execution import lag_extents

        return np.asarray(lag_extents(p, t, *self.lag)[1] * float(self._w.max()))

    def _held_args(self, extra: FloatArray) -> tuple[Any, ...]:
        """:meth:`query_args` (stopping at the first conflict) for a path whose segments are
        held ``extra`` (n - 1,) farther: subtracted from their distances, the cells searched
        around each that much wider (a reserved piece is entered in the cells within the
        separation of it)."""
        a = self.query_args(False)
        return (*a[:-1], np.ascontiguousarray(extra, dtype=np.float64))

    def conflicts(
        self, paths: FloatArray, times: FloatArray, held: bool = True
    ) -> NDArray[np.bool_]:
        """Whether each timed path (pop, n, 3) at ``times`` (pop, n) comes closer than the
        separation to a reserved trajectory at some instant (closer than the separation plus
        the pad to a padded one, and, with a :attr:`lag` and ``held``, plus the lag of the
        path's segment: :meth:`held_off`; a planned polyline, which is not what flies, is
        asked with ``held=False``), (pop,) bool."""
        out = np.asarray(self._run(paths, times, False) < self.separation)
        if self.lag is None or self.n_pieces == 0 or not held:
            return out
        extra = self.held_off(paths, times)
        p, t = self._prepared(paths, times)
        for i in np.flatnonzero((extra.max(axis=1, initial=0.0) > 0) & ~out):
            out[i] = _query(p[i : i + 1], t[i : i + 1], self._held_args(extra[i]))[0] < (
                self.separation
            )
        return out

    def first_free(
        self,
        points: FloatArray,
        times: FloatArray,
        waits: FloatArray,
        start: int,
        stop: int,
        first: int = 0,
    ) -> tuple[int, int]:
        """The first ``i`` in ``start .. stop - 1`` at which the timed path ``points`` (n, 3)
        at ``times`` (n,) taking off ``waits[i]`` seconds later does not conflict
        (:meth:`conflicts` of each such path, the same answers), or -1; and the segment of the
        path where the last conflict was found (``first`` if none was), where the search of
        each later wait starts (pass it back as ``first``). In one kernel: a UAV that waits
        for its slot asks hundreds of take-off times, most of them blocked by the traffic
        found at the wait before."""
        w = np.ascontiguousarray(waits, dtype=np.float64)
        stop = min(int(stop), w.shape[0])
        if self.n_pieces == 0:
            return (int(start) if start < stop else -1), int(first)
        p, t = self._prepared(points, times)
        extra = self.held_off(p, t)[0]  # a wait moves all times: the same lags
        args = self._held_args(extra) if extra.size and extra.max() > 0 else self.query_args(False)
        i, hint = _first_free(p[0], t[0], w, int(start), stop, args, int(first))
        return int(i), int(hint)

    def min_distance(self, paths: FloatArray, times: FloatArray) -> FloatArray:
        """Exact minimum distance from each timed path to the reserved trajectories (less the
        pads of padded ones, at least 0), (pop,) metres; ``inf`` when nothing reserved comes
        within ``separation`` of the path's cells (distances above the separation are exact
        only up to that search radius)."""
        return np.maximum(self._run(paths, times, True), 0.0)

    def min_distance_reference(self, points: FloatArray, times: FloatArray) -> float:
        """Brute force over every reserved piece, in NumPy (tests compare :meth:`min_distance`
        with it): every piece of the path against every reserved piece, exact."""
        a0, a1, t0, t1, _ = _split(writable(points), writable(times), self.dt)
        if not len(t0) or not self.n_pieces:
            return float("inf")
        b0, b1, s0, s1 = self._p0, self._p1, self._t0, self._t1
        i, j = np.nonzero((t0[:, None] <= s1[None]) & (s0[None] <= t1[:, None]))  # overlap
        if not len(i):
            return float("inf")
        lo, hi = np.maximum(t0[i], s0[j]), np.minimum(t1[i], s1[j])

        def at(p: FloatArray, q: FloatArray, u0: FloatArray, u1: FloatArray,
               t: FloatArray) -> FloatArray:  # fmt: skip
            return p + ((t - u0) / (u1 - u0))[:, None] * (q - p)

        r0 = at(a0[i], a1[i], t0[i], t1[i], lo) - at(b0[j], b1[j], s0[j], s1[j], lo)
        dr = at(a0[i], a1[i], t0[i], t1[i], hi) - at(b0[j], b1[j], s0[j], s1[j], hi) - r0
        if self.axes is not None:
            dist = _box_min_reference(r0, dr, self._w)
        else:
            dd = np.sum(dr * dr, axis=-1)
            with np.errstate(invalid="ignore", divide="ignore"):
                s = np.where(dd > 0, -np.sum(r0 * dr, axis=-1) / np.where(dd > 0, dd, 1.0), 0.0)
            s = np.clip(s, 0.0, 1.0)
            dist = np.sqrt(np.sum((r0 + s[..., None] * dr) ** 2, axis=-1))
        return float(max(np.min(dist - self._pad[j]), 0.0))


def _box_min_reference(r0: FloatArray, dr: FloatArray, w: FloatArray) -> FloatArray:
    """min over s in [0, 1] of max_i w_i |r0_i + s dr_i|, over the leading axes of ``r0``, in
    NumPy: every candidate (ends, zeros of a component, equal scaled magnitudes of two), clipped
    to [0, 1], evaluated and the smallest kept."""
    cands = [np.zeros(r0.shape[:-1]), np.ones(r0.shape[:-1])]
    with np.errstate(invalid="ignore", divide="ignore"):
        for i in range(3):
            cands.append(-r0[..., i] / dr[..., i])
            for j in range(i + 1, 3):
                for sign in (1.0, -1.0):
                    cands.append(
                        (sign * w[j] * r0[..., j] - w[i] * r0[..., i])
                        / (w[i] * dr[..., i] - sign * w[j] * dr[..., j])
                    )
    s = np.stack(cands, axis=-1)
    s = np.clip(np.where(np.isfinite(s), s, 0.0), 0.0, 1.0)
    at = np.abs(r0[..., None, :] + s[..., None] * dr[..., None, :]) * w
    return np.asarray(at.max(axis=-1).min(axis=-1))
