"""Numba kernels of a simulated flight's errors against its plan
(:func:`uavplan.sim.runs.errors_against` and :func:`uavplan.sim.runs.conformance`; their NumPy
references are ``errors_against_reference`` and ``conformance_reference`` there, which the
tests compare them with).

Both answer the same questions as the references with less work, not other questions:

* :func:`errors_kernel` looks, for each sample, only at the plan's segments within the time
  window (a contiguous run of a plan whose times never decrease, found by bisection) instead
  of masking all of them; where none is in the window, at all, as the reference does.
* :func:`conformance_kernel` finds the least schedule shift in tolerance by walking outwards
  from no shift (negative shifts first at equal size, the reference's first index), then the
  best-aligned shift within its run of admissible shifts; only a sample that no shift brings
  within tolerance (a flight outside the model there, and every sample under a nominal
  model, whose tolerance is 0) looks for the nearest shift among all: by blocks of
  :data:`BLOCK` shifts, each block's middle shift first, a block skipped where its middle's
  distance less the most the plan can move over the block's half-width (the plan's largest
  horizontal and vertical speeds, scaled as the distance is: the distance is Lipschitz in
  the shift) exceeds the best middle's; where the plan jumps (a zero-time segment) every
  shift. After twice :data:`BLOCK` shifts either side of none, the walk outwards looks only in
  the blocks that those bounds let hold a shift in tolerance. The reference evaluates all
  2,401 shifts of every sample: a 500-UAV execution spent about half its time there.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _interp(x, xp, fp, j):  # pragma: no cover - numba
    """``np.interp(x, xp, fp)`` for ``xp[0] <= x <= xp[-1]``, with its segment found from
    ``j`` (a guess, walked in either direction); returns (value, segment)."""
    n = len(xp)
    if x >= xp[n - 1]:
        return fp[n - 1], n - 2
    if j < 0:
        j = 0
    if j > n - 2:
        j = n - 2
    while j > 0 and xp[j] > x:
        j -= 1
    while j < n - 2 and xp[j + 1] <= x:
        j += 1
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + fp[j], j


@njit(cache=True)
def _shift_distance(t, q, taus, k, tp, px, py, pz, pg, sh, sv, j):  # pragma: no cover - numba
    """The scaled distance of sample ``q`` at ``t`` from the plan at ``t - taus[k]``, its
    height difference less the plan's slack there (``pg``, interpolated as the points are)."""
    x = t - taus[k]
    if x < tp[0]:
        x = tp[0]
    if x > tp[len(tp) - 1]:
        x = tp[len(tp) - 1]
    zp, j = _interp(x, tp, pz, j)
    xq, j = _interp(x, tp, px, j)
    yq, j = _interp(x, tp, py, j)
    g, j = _interp(x, tp, pg, j)
    dz = max(abs(zp - q[2]) - g, 0.0)
    dx = xq - q[0]
    dy = yq - q[1]
    return max(math.hypot(dx, dy) / sh, dz / sv), j


#: Shifts per block of the search for the nearest shift where none is admissible.
BLOCK = 16


@njit(cache=True)
def _plan_speed_bound(tp, pp, pg, sh, sv):  # pragma: no cover - numba
    """How fast the scaled distance of a sample from the plan at ``t - tau`` can change with
    ``tau``: the larger of the plan's horizontal speed over ``sh`` and its vertical speed plus
    the rate of its slack ``pg`` over ``sv`` (inf where a segment moves in no time)."""
    L = 0.0
    for k in range(len(tp) - 1):
        dt = tp[k + 1] - tp[k]
        dh = math.hypot(pp[k + 1, 0] - pp[k, 0], pp[k + 1, 1] - pp[k, 1])
        dz = abs(pp[k + 1, 2] - pp[k, 2]) + abs(pg[k + 1] - pg[k])
        if dt > 0.0:
            L = max(L, max(dh / dt / sh, dz / dt / sv))
        elif dh > 0.0 or dz > 0.0:
            return np.inf
    return L


@njit(cache=True)
def _block_middles(ti, q, taus, tp, px, py, pz, pg, sh, sv, j, L, mids):  # pragma: no cover
    """Each block's middle shift's distance into ``mids``; returns (the least distance any
    shift can have by the blocks' bounds, the best middle's ``distance + 1e-9 |tau|``, j)."""
    K = len(taus)
    nb = (K + BLOCK - 1) // BLOCK
    top = np.inf
    floor = np.inf
    for b in range(nb):
        _, _, c, half = _block(b, taus)
        dk, j = _shift_distance(ti, q, taus, c, tp, px, py, pz, pg, sh, sv, j)
        mids[b] = dk
        top = min(top, dk + 1e-9 * abs(taus[c]))
        floor = min(floor, dk - L * half)
    return floor, top, j


@njit(cache=True, inline="always")
def _block(b, taus):  # pragma: no cover - numba
    """Block ``b`` of the shifts: its first and last index, its middle, and the farthest any
    of its shifts lies from the middle (s)."""
    K = len(taus)
    lo = b * BLOCK
    hi = min(lo + BLOCK, K) - 1
    c = min(lo + BLOCK // 2, K - 1)
    return lo, hi, c, max(taus[c] - taus[lo], taus[hi] - taus[c])


@njit(cache=True, inline="always")
def _may_hold(k, taus, mids, L):  # pragma: no cover - numba
    """Whether shift ``k``'s block can hold a shift in tolerance (distance <= 1) by its
    middle's distance ``mids`` and the bound ``L`` (:func:`_block_middles`)."""
    b = k // BLOCK
    return mids[b] - L * _block(b, taus)[3] <= 1.0 + 1e-12


@njit(cache=True)
def _nearest_shift(ti, q, taus, tp, px, py, pz, pg, sh, sv, j, L, mids, top):  # pragma: no cover
    """The index of the shift of least ``distance + 1e-9 |tau|`` (the first of a tie, as
    an argmin over all), by blocks whose middle's distance (``mids``, the best middle's
    score ``top``: :func:`_block_middles`) bounds theirs (module docstring); every shift
    where the plan jumps (``L`` inf)."""
    K = len(taus)
    best = 0
    score = np.inf
    for b in range((K + BLOCK - 1) // BLOCK):
        lo, hi, _, half = _block(b, taus)
        if math.isfinite(L) and mids[b] - L * half > top * (1.0 + 1e-12) + 1e-12:
            continue
        for k in range(lo, hi + 1):
            dk, j = _shift_distance(ti, q, taus, k, tp, px, py, pz, pg, sh, sv, j)
            s = dk + 1e-9 * abs(taus[k])
            if s < score:
                score = s
                best = k
    return best, j


@njit(cache=True)
def conformance_kernel(t, Q, taus, tp, pp, pg, sh, sv, lag, need):  # pragma: no cover - numba
    """Per sample ``(t[i], Q[i])``: ``need[i]`` the least ``|tau|`` (of ``taus``, ascending and
    symmetric about 0) that puts it within tolerance of the plan ``(tp, pp)`` at
    ``t - tau`` (inf: none; its height is in tolerance within ``sv`` of the plan's vertical
    slack ``pg``), ``lag[i]`` the best-aligned shift of that shift's run of admissible
    shifts, or the nearest shift where none is admissible."""
    K = len(taus)
    mid = K // 2
    px = np.ascontiguousarray(pp[:, 0])
    py = np.ascontiguousarray(pp[:, 1])
    pz = np.ascontiguousarray(pp[:, 2])
    L = _plan_speed_bound(tp, pp, pg, sh, sv)
    mids = np.empty((K + BLOCK - 1) // BLOCK)
    j = 0
    for i in range(len(t)):
        q = Q[i]
        least = -1
        d_least = d_hi = 0.0
        top = np.inf  # the blocks' middles, once looked at (mids)
        bounded = False  # the blocks' middles looked at: shifts in blocks that cannot hold
        for m in range(mid + 1):  # outwards from tau = 0: the smaller |tau|, then the lower index
            if m == 2 * BLOCK and math.isfinite(L):
                # none near: which blocks can hold a shift in tolerance, by their bounds?
                floor, top, j = _block_middles(
                    t[i], q, taus, tp, px, py, pz, pg, sh, sv, j, L, mids
                )
                if floor > 1.0 + 1e-12:
                    break
                bounded = True
            lo_k, hi_k = mid - m, mid + m
            ok_lo = ok_hi = False
            d_lo = d_hi = 0.0
            if not bounded or _may_hold(lo_k, taus, mids, L):
                d_lo, j = _shift_distance(t[i], q, taus, lo_k, tp, px, py, pz, pg, sh, sv, j)
                ok_lo = d_lo <= 1.0
            if m > 0 and hi_k < K and (not bounded or _may_hold(hi_k, taus, mids, L)):
                d_hi, j = _shift_distance(t[i], q, taus, hi_k, tp, px, py, pz, pg, sh, sv, j)
                ok_hi = d_hi <= 1.0
            if ok_lo and ok_hi:
                least, d_least = (hi_k, d_hi) if abs(taus[hi_k]) < abs(taus[lo_k]) else (lo_k, d_lo)
            elif ok_lo:
                least, d_least = lo_k, d_lo
            elif ok_hi:
                least, d_least = hi_k, d_hi
            if least >= 0:
                break
        if least >= 0:
            need[i] = abs(taus[least])
            best = least
            score = d_least + 1e-9 * abs(taus[least])
            k = least - 1  # the run of admissible shifts around it, leftwards ...
            while k >= 0:
                dk, j = _shift_distance(t[i], q, taus, k, tp, px, py, pz, pg, sh, sv, j)
                if not dk <= 1.0:
                    break
                s = dk + 1e-9 * abs(taus[k])
                if s <= score:  # the first index of a tie, as argmin
                    score = s
                    best = k
                k -= 1
            k = least + 1  # ... and rightwards
            while k < K:
                dk, j = _shift_distance(t[i], q, taus, k, tp, px, py, pz, pg, sh, sv, j)
                if not dk <= 1.0:
                    break
                s = dk + 1e-9 * abs(taus[k])
                if s < score:
                    score = s
                    best = k
                k += 1
            lag[i] = taus[best]
        else:
            need[i] = np.inf
            if math.isfinite(L) and not math.isfinite(top):
                _, top, j = _block_middles(t[i], q, taus, tp, px, py, pz, pg, sh, sv, j, L, mids)
            best, j = _nearest_shift(t[i], q, taus, tp, px, py, pz, pg, sh, sv, j, L, mids, top)
            lag[i] = taus[best]


@njit(cache=True)
def errors_kernel(Q, tq, A, B, tA, tB, gA, gB, window, h, v, te):  # pragma: no cover - numba
    """Per sample ``(Q[i], tq[i])``: the plan's segment (``A -> B``, times ``tA -> tB``,
    vertical slack ``gA -> gB``) nearest in 3-D (its point horizontally nearest; heights
    within the slack count as on it) among those within ``window`` seconds, or among all
    when none is; ``h``, ``v``, ``te`` the horizontal distance, the height difference beyond
    the slack and the time error there."""
    n = len(A)
    ordered = True
    for k in range(n - 1):
        if tA[k + 1] < tA[k] or tB[k + 1] < tB[k]:
            ordered = False
            break
    for i in range(len(Q)):
        qx, qy, qz = Q[i, 0], Q[i, 1], Q[i, 2]
        # the segments within the window: a contiguous run where the plan's times never
        # decrease, else each tested; all of them where none is within it
        lo, hi, each = 0, n, False
        if ordered:
            lo = np.searchsorted(tB, tq[i] - window, side="left")
            hi = np.searchsorted(tA, tq[i] + window, side="right")
            if lo >= hi:
                lo, hi = 0, n
        else:
            for k in range(n):
                if tB[k] >= tq[i] - window and tA[k] <= tq[i] + window:
                    each = True
                    break
        best = -1
        score = np.inf
        bs = 0.0
        bd2 = 0.0
        bdz = 0.0
        for k in range(lo, hi):
            if each and not (tB[k] >= tq[i] - window and tA[k] <= tq[i] + window):
                continue
            Dx = B[k, 0] - A[k, 0]
            Dy = B[k, 1] - A[k, 1]
            dd = max(Dx * Dx + Dy * Dy, 1e-12)
            s = ((qx - A[k, 0]) * Dx + (qy - A[k, 1]) * Dy) / dd
            s = min(max(s, 0.0), 1.0)
            fx = qx - (A[k, 0] + s * Dx)
            fy = qy - (A[k, 1] + s * Dy)
            d2 = fx * fx + fy * fy
            dz = qz - (A[k, 2] + s * (B[k, 2] - A[k, 2]))
            dz = math.copysign(max(abs(dz) - (gA[k] + s * (gB[k] - gA[k])), 0.0), dz)
            sc = d2 + dz * dz
            if best < 0 or sc < score:
                best = k
                score = sc
                bs = s
                bd2 = d2
                bdz = dz
        h[i] = math.sqrt(bd2)
        v[i] = bdz
        te[i] = tq[i] - (tA[best] + bs * (tB[best] - tA[best]))
