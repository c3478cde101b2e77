"""The plan checked under its execution model, and the margins it has: how much take-off error,
speed error and tracking error it tolerates before a check fails.

The model (:mod:`uavplan.world.execution`, read here as data): each UAV takes off within
``delta0`` s of its time, flies its path at a ground speed within ``rho`` of the planned one,
and stays within ``e_h`` / ``e_v`` of its path. The verifier does its own geometry:

* **Separation.** UAV ``A`` can be at its path time ``tau_A`` at any actual time in
  ``T_A(tau_A) = [t0 - delta0 + (tau_A - t0) / (1 + rho), t0 + delta0 + (tau_A - t0) / (1 - rho)]``.
  Two UAVs can be at ``tau_A`` and ``tau_B`` at once when their intervals meet. For a pair of
  segments, the pairs ``(tau_A, tau_B)`` form the segments' time rectangle clipped by those two
  conditions, a convex polygon (Sutherland-Hodgman clipping here), on which the squared
  distance between the two points is a convex quadratic: minimised exactly (inside, or along
  the polygon's edges). Only segment pairs that can come within the separation at all (their
  untimed distance) at a time both can be there with errors up to the margins' search limits
  (:data:`TAKEOFF_CAP`, :data:`SPEED_CAP`; found with a uniform grid over all the fleet's
  segments in space and time) are examined. A
  pair fails when its least distance is below ``S2 + sqrt((2 e_h)^2 + (2 e_v)^2)``: each UAV
  may be ``e_h`` and ``e_v`` off its point. A per-axis separation (a box) is taken as the
  sphere that holds it (conservative).
* **Moving obstacles**: the same with the obstacle on its own schedule (no error), against
  ``radius + sqrt(e_h^2 + e_v^2)``.
* **Static clearances**: the horizontal ones (cylinders, circles, polygons, bounds) must be at
  least ``e_h``, the vertical ones (terrain, the altitude band, bounds) at least ``e_v``.

**Margins** (per pair and per UAV): the largest take-off error (s) with the model's speed and
tracking errors, the largest speed error with the model's take-off and tracking errors (both
by bisection on the pair's close segments: failing is monotone in each), and the largest
tracking error (m, the same horizontally and vertically, both UAVs) with the model's timing:
``(d - S2) / (2 sqrt 2)`` from the least distance ``d``. A UAV's margins are the least over
its pairs and obstacles; its horizontal and vertical static clearances are its tracking
margins there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.verify.report import TOL, Violation, fmt_num, fmt_points

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: The largest take-off error (s) and speed error a margin is searched to: beyond them a pair
#: is reported as not limited (``inf``). They are also the horizon of the pair search: two
#: segments are examined only when they can come close in space and, with errors up to these,
#: in time (a 1,000-UAV fleet over open ground crosses itself everywhere in space, and
#: searching every crossing made 10^9 pairs).
TAKEOFF_CAP = 60.0
SPEED_CAP = 0.2
#: Bisection steps (take-off to 60 / 2^14 s = 0.004 s; speed to 0.2 / 2^14)
BISECT = 14
#: A pair whose segments need different distances (height lags that vary along the flights)
#: is checked in at most this many groups, each against its largest need.
LEVELS = 8


# ================================================================================ window QP
@njit(cache=True)
def _pair_terms(P, i, j):  # pragma: no cover - numba
    """Segments ``i`` (``A0 + u e``) and ``j`` (``B0 + w g``) of ``P``: ``r = A0 - B0``, ``e``,
    ``g`` and the dot products ``e.e``, ``g.g``, ``e.g``, ``r.e``, ``r.g``."""
    rx, ry, rz = P[i, 0] - P[j, 0], P[i, 1] - P[j, 1], P[i, 2] - P[j, 2]
    ex, ey, ez = P[i + 1, 0] - P[i, 0], P[i + 1, 1] - P[i, 1], P[i + 1, 2] - P[i, 2]
    gx, gy, gz = P[j + 1, 0] - P[j, 0], P[j + 1, 1] - P[j, 1], P[j + 1, 2] - P[j, 2]
    return (rx, ry, rz, ex, ey, ez, gx, gy, gz,
            ex * ex + ey * ey + ez * ez, gx * gx + gy * gy + gz * gz, ex * gx + ey * gy + ez * gz,
            rx * ex + ry * ey + rz * ez, rx * gx + ry * gy + rz * gz)  # fmt: skip


@njit(cache=True)
def _clip(px, py, n, a, b, c, tol):  # pragma: no cover - numba
    """Sutherland-Hodgman: the convex polygon ``(px, py)[:n]`` cut to ``a + b u + c w >= 0``;
    returns the new vertex arrays and count."""
    qx = np.empty(8)
    qy = np.empty(8)
    m = 0
    for k in range(n):
        x0, y0 = px[k], py[k]
        x1, y1 = px[(k + 1) % n], py[(k + 1) % n]
        f0 = a + b * x0 + c * y0
        f1 = a + b * x1 + c * y1
        if f0 >= -tol:
            qx[m] = x0
            qy[m] = y0
            m += 1
        if (f0 >= -tol) != (f1 >= -tol):
            s = f0 / (f0 - f1)
            qx[m] = x0 + s * (x1 - x0)
            qy[m] = y0 + s * (y1 - y0)
            m += 1
    return qx, qy, m


@njit(cache=True, inline="always")
def _corners_max(a, b, c):  # pragma: no cover - numba
    """The largest of ``a + b u + c w`` over the unit square's corners, each summed as
    :func:`_clip` sums it."""
    return max(a + b * 0.0 + c * 0.0, a + b * 1.0 + c * 0.0, a + b * 1.0 + c * 1.0,
               a + b * 0.0 + c * 1.0)  # fmt: skip


@njit(cache=True)
def _win_min(P, i, j, T, t0a, da, ra, t0b, db, rb):  # pragma: no cover - numba
    """``(d2, u, w)``: the least squared distance between segment ``i`` (of UAV ``A``) and
    segment ``j`` (of ``B``) of ``P``/``T`` over the pairs of their parameters whose windows
    meet, and where; ``d2`` inf when none do."""
    ta0, ta1, tb0, tb1 = T[i], T[i + 1], T[j], T[j + 1]
    LA, LB = ta1 - ta0, tb1 - tb0
    tol = 1e-12 * (1.0 + abs(ta1) + abs(tb1))
    # A's earliest time no later than B's latest, and B's earliest no later than A's latest
    a1 = -((t0a - da + (ta0 - t0a) / (1.0 + ra)) - (t0b + db + (tb0 - t0b) / (1.0 - rb)))
    b1, c1 = -LA / (1.0 + ra), LB / (1.0 - rb)
    a2 = -((t0b - db + (tb0 - t0b) / (1.0 + rb)) - (t0a + da + (ta0 - t0a) / (1.0 - ra)))
    b2, c2 = LA / (1.0 - ra), -LB / (1.0 + rb)
    # most pairs of a fleet's crossings pass at times too far apart for any window to meet:
    # settled on the square's corners before the polygon is built. The first cut keeps
    # nothing exactly when no corner passes it (the same sums _clip makes); the second cut's
    # polygon lies in the square, so no corner within a margin far above round-off (the
    # cut points of the first are a few ulps off the square's edges) means none of it passes
    if _corners_max(a1, b1, c1) < -tol:
        return np.inf, 0.0, 0.0
    if _corners_max(a2, b2, c2) < -tol - 1e-9 * (1.0 + abs(a2) + abs(b2) + abs(c2)):
        return np.inf, 0.0, 0.0
    px = np.empty(8)
    py = np.empty(8)
    px[0], py[0], px[1], py[1], px[2], py[2], px[3], py[3] = 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0
    px, py, n = _clip(px, py, 4, a1, b1, c1, tol)
    if n == 0:
        return np.inf, 0.0, 0.0
    px, py, n = _clip(px, py, n, a2, b2, c2, tol)
    if n == 0:
        return np.inf, 0.0, 0.0
    # squared distance |(A0 + u eA) - (B0 + w eB)|^2
    rx, ry, rz, ex, ey, ez, gx, gy, gz, aa, bb, ab, ra_, rb_ = _pair_terms(P, i, j)
    best = np.inf
    bu = 0.0
    bw = 0.0
    det = aa * bb - ab * ab
    if det > 1e-12 * (1.0 + aa * bb) and n >= 3:
        u = (ab * rb_ - bb * ra_) / det
        w = (aa * rb_ - ab * ra_) / det
        inside = True
        area = 0.0
        for k in range(n):
            area += px[k] * py[(k + 1) % n] - px[(k + 1) % n] * py[k]
        sgn = 1.0 if area >= 0.0 else -1.0
        if abs(area) <= 1e-15:  # a point or a sliver: its edges hold every point of it
            inside = False
        for k in range(n):
            if not inside:
                break
            cx = px[(k + 1) % n] - px[k]
            cy = py[(k + 1) % n] - py[k]
            if sgn * (cx * (w - py[k]) - cy * (u - px[k])) < -1e-12:
                inside = False
                break
        if inside:
            dx = rx + u * ex - w * gx
            dy = ry + u * ey - w * gy
            dz = rz + u * ez - w * gz
            return dx * dx + dy * dy + dz * dz, u, w
    for k in range(n):
        u0, w0 = px[k], py[k]
        du, dw = px[(k + 1) % n] - u0, py[(k + 1) % n] - w0
        # r(t) = (r + u0 e - w0 g) + t (du e - dw g)
        sx = rx + u0 * ex - w0 * gx
        sy = ry + u0 * ey - w0 * gy
        sz = rz + u0 * ez - w0 * gz
        vx = du * ex - dw * gx
        vy = du * ey - dw * gy
        vz = du * ez - dw * gz
        vv = vx * vx + vy * vy + vz * vz
        t = 0.0
        if vv > 0.0:
            t = min(max(-(sx * vx + sy * vy + sz * vz) / vv, 0.0), 1.0)
        qx, qy, qz = sx + t * vx, sy + t * vy, sz + t * vz
        d2 = qx * qx + qy * qy + qz * qz
        if d2 < best:
            best = d2
            bu = u0 + t * du
            bw = w0 + t * dw
    return best, bu, bw


# ================================================================================ close pairs
@njit(cache=True)
def _seg_dist2(P, i, j):  # pragma: no cover - numba
    """Squared distance between segments ``i`` and ``j`` of ``P`` (as point sets)."""
    rx, ry, rz, ex, ey, ez, gx, gy, gz, aa, bb, ab, ra, rb = _pair_terms(P, i, j)
    best = np.inf
    # the ends against the other segment, and the interior critical point
    cands = np.empty((6, 2))
    m = 0
    det = aa * bb - ab * ab
    if det > 1e-12 * (1.0 + aa * bb):
        u = (ab * rb - bb * ra) / det
        w = (aa * rb - ab * ra) / det
        if 0.0 <= u <= 1.0 and 0.0 <= w <= 1.0:
            cands[m, 0], cands[m, 1] = u, w
            m += 1
    for e in range(2):
        w = float(e)
        u = 0.0 if aa == 0.0 else min(max((w * ab - ra) / aa, 0.0), 1.0)
        cands[m, 0], cands[m, 1] = u, w
        m += 1
        u = float(e)
        w = 0.0 if bb == 0.0 else min(max((u * ab + rb) / bb, 0.0), 1.0)
        cands[m, 0], cands[m, 1] = u, w
        m += 1
    for k in range(m):
        u, w = cands[k, 0], cands[k, 1]
        dx = rx + u * ex - w * gx
        dy = ry + u * ey - w * gy
        dz = rz + u * ez - w * gz
        best = min(best, dx * dx + dy * dy + dz * dz)
    return best


#: :func:`_close_pairs`: consecutive segments of one trajectory per entry of its grid
CHUNK_SEGMENTS = 8


@njit(cache=True)
def _close_pairs(
    P, owner, valid, gap, cell, T, take, dcap, rcap, chunk=CHUNK_SEGMENTS
):  # pragma: no cover
    """Every pair of segments ``(i, j)`` of different owners (``owner[i] < owner[j]``; segment
    ``i`` runs from row ``i`` to ``i + 1``, ``valid[i]`` it is one) whose untimed distance is
    below ``gap`` and whose flown time windows with a take-off error up to ``dcap`` and a
    speed error up to ``rcap`` meet (``T``: the rows' planned times, ``take``: each row's
    owner's take-off). The grid's entries are runs of up to ``chunk`` consecutive segments of
    one trajectory (a densely sampled flight has hundreds of short segments in a cell: pairs of
    runs are ``chunk``^2 fewer), each with the box of its points and the union of its
    segments' windows: a uniform grid of side ``cell`` in space and of the runs' longest window
    in time holds each run in the cells its box grown by ``gap`` towards +x, +y, +z and its
    window touch (two segments closer than ``gap`` lie in runs whose boxes, so grown, overlap
    on every axis, at the larger of their closest coordinates, and two meeting windows in runs
    with a time cell in common, so the runs share a cell). A pair of runs is taken in one of
    its common cells only, the first, when its windows meet and its boxes are within ``gap``
    on every axis; then each pair of their segments as the brute force takes it: windows
    compared exactly, then the distance."""
    n = P.shape[0] - 1
    wlo = np.empty(n)
    whi = np.empty(n)
    for i in range(n):
        if valid[i]:
            t0 = take[i]
            wlo[i] = t0 - dcap + (T[i] - t0) / (1.0 + rcap)
            whi[i] = t0 + dcap + (T[i + 1] - t0) / (1.0 - rcap)
    # the runs: consecutive valid segments of one owner, at most ``chunk`` of them
    first = np.empty(n, dtype=np.int64)
    stop = np.empty(n, dtype=np.int64)
    m = 0
    i = 0
    while i < n:
        if not valid[i]:
            i += 1
            continue
        j = i + 1
        while j < n and j - i < chunk and valid[j] and owner[j] == owner[i]:
            j += 1
        first[m] = i
        stop[m] = j
        m += 1
        i = j
    if m == 0:
        return np.empty((0, 2), dtype=np.int64)
    clo = np.empty((m, 4))  # x, y, z, window: the run's least ...
    chi = np.empty((m, 4))  # ... and greatest
    t_lo = np.inf
    t_hi = -np.inf
    span = 0.0
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for c in range(m):
        for d in range(3):
            clo[c, d] = np.inf
            chi[c, d] = -np.inf
        clo[c, 3] = np.inf
        chi[c, 3] = -np.inf
        for i in range(first[c], stop[c]):
            for d in range(3):
                clo[c, d] = min(clo[c, d], P[i, d], P[i + 1, d])
                chi[c, d] = max(chi[c, d], P[i, d], P[i + 1, d])
            clo[c, 3] = min(clo[c, 3], wlo[i])
            chi[c, 3] = max(chi[c, 3], whi[i])
        for d in range(3):
            lo[d] = min(lo[d], clo[c, d])
            hi[d] = max(hi[d], chi[c, d])
        t_lo = min(t_lo, clo[c, 3])
        t_hi = max(t_hi, chi[c, 3])
        span = max(span, chi[c, 3] - clo[c, 3])
    tcell = max(span, 1e-9)
    dims = np.empty(4, dtype=np.int64)
    for d in range(3):
        dims[d] = int((hi[d] - lo[d] + gap) / cell) + 2
    dims[3] = int((t_hi - t_lo) / tcell) + 2
    # each run's cells: x in [lo0, hi0], y [lo1, hi1], z [lo2, hi2], time [lo3, hi3]
    box = np.empty((m, 8), dtype=np.int64)
    count = 0
    for c in range(m):
        k = 1
        for d in range(3):
            box[c, d] = int((clo[c, d] - lo[d]) / cell)
            box[c, 4 + d] = int((chi[c, d] + gap - lo[d]) / cell)
            k *= box[c, 4 + d] - box[c, d] + 1
        box[c, 3] = int((clo[c, 3] - t_lo) / tcell)
        box[c, 7] = int((chi[c, 3] - t_lo) / tcell)
        count += k * (box[c, 7] - box[c, 3] + 1)
    keys = np.empty(count, dtype=np.int64)
    runs = np.empty(count, dtype=np.int64)
    e = 0
    for c in range(m):
        for x in range(box[c, 0], box[c, 4] + 1):
            for y in range(box[c, 1], box[c, 5] + 1):
                for z in range(box[c, 2], box[c, 6] + 1):
                    for w in range(box[c, 3], box[c, 7] + 1):
                        keys[e] = ((x * dims[1] + y) * dims[2] + z) * dims[3] + w
                        runs[e] = c
                        e += 1
    order = np.argsort(keys, kind="mergesort")
    keys = keys[order]
    runs = runs[order]
    found = np.empty(1024, dtype=np.int64)  # pair codes i (n + 1) + j, grown by doubling
    nf = 0
    g2 = gap * gap
    here = np.empty(4, dtype=np.int64)
    s = 0
    while s < e:
        t = s
        while t < e and keys[t] == keys[s]:
            t += 1
        k = keys[s]
        for d in range(3, -1, -1):
            here[d] = k % dims[d]
            k //= dims[d]
        for p in range(s, t):
            for q in range(p + 1, t):
                a, b = runs[p], runs[q]
                if owner[first[a]] == owner[first[b]]:
                    continue
                # a pair of runs is taken once, in the first cell the two share (where the
                # larger of their lower cells lies on every axis), and only when its windows
                # meet and its boxes come within the gap
                once = True
                for d in range(4):
                    if max(box[a, d], box[b, d]) != here[d]:
                        once = False
                        break
                if not once or clo[a, 3] > chi[b, 3] or clo[b, 3] > chi[a, 3]:
                    continue
                near = True
                for d in range(3):
                    if clo[b, d] - chi[a, d] > gap or clo[a, d] - chi[b, d] > gap:
                        near = False
                        break
                if not near:
                    continue
                for i0 in range(first[a], stop[a]):
                    for j0 in range(first[b], stop[b]):
                        if wlo[i0] > whi[j0] or wlo[j0] > whi[i0]:
                            continue
                        i, j = (i0, j0) if owner[i0] < owner[j0] else (j0, i0)
                        if _seg_dist2(P, i, j) < g2:
                            if nf == found.shape[0]:
                                grown = np.empty(2 * nf, dtype=np.int64)
                                grown[:nf] = found
                                found = grown
                            found[nf] = i * (n + 1) + j
                            nf += 1
        s = t
    out = np.empty((nf, 2), dtype=np.int64)
    if nf:
        arr = np.sort(found[:nf])  # each pair found once (runs partition the segments)
        out = np.empty((arr.shape[0], 2), dtype=np.int64)
        for k in range(arr.shape[0]):
            out[k, 0] = arr[k] // (n + 1)
            out[k, 1] = arr[k] % (n + 1)
    return out


@njit(cache=True)
def _group_min(P, T, pairs, take, da, ra, db, rb, start, stop, stop_below):  # pragma: no cover
    """The least window distance over ``pairs[start:stop]`` (segment rows of one pair of
    owners; ``take[i]``: the take-off time of the owner of row ``i``), and the row and ``(u,
    w)`` where it is; stops at the first below ``stop_below``."""
    best = np.inf
    at = -1
    bu = 0.0
    bw = 0.0
    for k in range(start, stop):
        i, j = pairs[k, 0], pairs[k, 1]
        d2, u, w = _win_min(P, i, j, T, take[i], da, ra, take[j], db, rb)
        if d2 < best:
            best = d2
            at = k
            bu, bw = u, w
            if math.sqrt(best) < stop_below:
                break
    return math.sqrt(best), at, bu, bw


@njit(cache=True)
def _fails_at(P, T, pairs, take, start, stop, delta, rho, moving, below):  # pragma: no cover
    """Whether segment pairs ``pairs[start:stop]`` come closer than ``below`` with take-off
    error ``delta`` and speed error ``rho`` (the second side without error when ``moving``)."""
    if start >= stop:
        return False
    db, rb = (0.0, 0.0) if moving else (delta, rho)
    return _group_min(P, T, pairs, take, delta, rho, db, rb, start, stop, below)[0] < below


@njit(cache=True)
def _largest_tolerated(
    P, T, pairs, take, start, stop, d0, r0, moving, below, known, cap, on_speed
):  # fmt: skip  # pragma: no cover - numba
    """:func:`_largest` of the take-off error (with the speed error ``r0``) or, with
    ``on_speed``, of the speed error (with the take-off error ``d0``), ``known`` not failing:
    the same bisection, in one call."""
    if known <= 0.0 and _fails_at(P, T, pairs, take, start, stop, d0 if on_speed else 0.0,
                                  0.0 if on_speed else r0, moving, below):  # fmt: skip
        return 0.0
    if not _fails_at(P, T, pairs, take, start, stop, d0 if on_speed else cap,
                     cap if on_speed else r0, moving, below):  # fmt: skip
        return np.inf
    lo, hi = known, cap
    for _ in range(BISECT):
        mid = 0.5 * (lo + hi)
        if _fails_at(P, T, pairs, take, start, stop, d0 if on_speed else mid,
                     mid if on_speed else r0, moving, below):  # fmt: skip
            hi = mid
        else:
            lo = mid
    return lo


@njit(cache=True)
def _pair_dists(P, pairs):  # pragma: no cover - numba
    """The untimed distance of each segment pair (a lower bound of its distance under any
    timing)."""
    out = np.empty(pairs.shape[0])
    for k in range(pairs.shape[0]):
        out[k] = math.sqrt(_seg_dist2(P, pairs[k, 0], pairs[k, 1]))
    return out


# ================================================================================ records
@dataclass(frozen=True)
class PairMargin:
    """How much execution error a pair (two UAVs, or a UAV and a moving obstacle) tolerates.

    Attributes:
        uav, other: the UAV ids (``other`` may be ``"moving obstacle k"``).
        time: an actual time when the closest approach under the model can happen, s.
        where: the two points, metres.
        distance: the least distance under the model's take-off and speed errors, metres.
        required: the separation (or the obstacle's radius) plus what the model's tracking
            error takes away, metres.
        takeoff_s, speed: the largest take-off error (s) and speed error (fraction)
            tolerated, each with the model's other errors; ``inf``: not limited (beyond
            :data:`TAKEOFF_CAP` / :data:`SPEED_CAP`).
        track_h, track_v: the largest horizontal and vertical tracking errors tolerated with
            the model's timing, in the model's proportions (the same both ways when the model
            has none), metres.
    """

    uav: str
    other: str
    time: float
    where: tuple[tuple[float, ...], ...]
    distance: float
    required: float
    takeoff_s: float
    speed: float
    track_h: float
    track_v: float

    @property
    def ok(self) -> bool:
        return self.distance >= self.required - TOL

    def to_dict(self) -> dict[str, Any]:
        return {"uav": self.uav, "other": self.other, "time": _num(self.time),
                "distance": _num(self.distance), "required": self.required,
                "takeoff_s": _num(self.takeoff_s), "speed": _num(self.speed),
                "track_h": _num(self.track_h), "track_v": _num(self.track_v),
                "ok": self.ok}  # fmt: skip


@dataclass
class UAVMargin:
    """A UAV's margins: the least over its pairs and obstacles (``inf``: unlimited), and what
    limits each."""

    uav: str
    takeoff_s: float = math.inf
    speed: float = math.inf
    track_h: float = math.inf
    track_v: float = math.inf
    limited_by: dict[str, str] = field(default_factory=dict)

    def take(self, what: str, value: float, by: str) -> None:
        if value < getattr(self, what):
            setattr(self, what, value)
            self.limited_by[what] = by

    def to_dict(self) -> dict[str, Any]:
        return {"uav": self.uav, "takeoff_s": _num(self.takeoff_s), "speed": _num(self.speed),
                "track_h": _num(self.track_h), "track_v": _num(self.track_v),
                "limited_by": dict(self.limited_by)}  # fmt: skip


def _num(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


# ================================================================================ the checks
@dataclass(frozen=True)
class Timing:
    """The model's numbers as the checks use them."""

    delta0: float
    rho: float
    track_h: float
    track_v: float

    @property
    def gap(self) -> float:
        return math.hypot(2.0 * self.track_h, 2.0 * self.track_v)

    @property
    def norm(self) -> float:
        return math.hypot(self.track_h, self.track_v)


def timing_of(model: Any, cruise: float) -> Timing:
    """The model (an :class:`~uavplan.world.execution.ExecutionModel` or its record) for a
    UAV cruising at ``cruise`` m/s: the wind's share added to the speed error."""
    rec = model.record() if hasattr(model, "record") else dict(model)
    rho = float(rec.get("speed", 0.0)) + (float(rec.get("wind", 0.0)) / cruise if cruise else 0)
    return Timing(float(rec.get("takeoff_s", 0.0)), rho, float(rec.get("track_h", 0.0)),
                  float(rec.get("track_v", 0.0)))  # fmt: skip


def _pack(trajs: Sequence[Trajectory]) -> tuple[FloatArray, FloatArray, IntArray, NDArray[Any]]:
    n = sum(len(t.times) for t in trajs)
    P = np.zeros((n, 3))
    T = np.zeros(n)
    owner = np.full(n, -1, dtype=np.int64)
    valid = np.zeros(n, dtype=np.bool_)
    r = 0
    for k, t in enumerate(trajs):
        m = len(t.times)
        P[r : r + m, : t.dim] = t.points
        T[r : r + m] = t.times
        owner[r : r + m] = k
        valid[r : r + m - 1] = True  # the last row of each starts no segment
        r += m
    return P, T, owner, valid


def _row_lags(trajs: Sequence[Trajectory], lags: Sequence[Any] | None, n: int) -> FloatArray:
    """Each packed row's height lag (:func:`_pack`'s rows; a row is the segment it starts): a
    trajectory's ``lags`` entry is one number for its whole flight or one per segment."""
    out = np.zeros(n)
    if lags is None:
        return out
    r = 0
    for t, lg in zip(trajs, lags, strict=True):
        m = len(t.times)
        out[r : r + max(m - 1, 0)] = np.asarray(lg, dtype=np.float64) if m > 1 else 0.0
        r += m
    return out


def _levels(need: FloatArray) -> list[NDArray[np.intp]]:
    """Indices into ``need`` in groups checked against one requirement each (the group's
    largest need, so every segment pair is held at least to its own): one group where all
    needs are equal, else at most :data:`LEVELS` groups of equal size in order of need."""
    if not len(need) or float(need.max() - need.min()) <= 1e-9:
        return [np.arange(len(need))]
    order = np.argsort(need, kind="stable")
    return [g for g in np.array_split(order, min(LEVELS, len(need))) if len(g)]


def _levelled_margin(
    P: FloatArray, T: FloatArray, rows: IntArray, take: FloatArray, need: FloatArray,
    timing: Timing, a: str, b: str, moving: bool,
) -> tuple[PairMargin, NDArray[np.intp]]:  # fmt: skip
    """One pair's margin when its segment pairs ``rows`` need different distances ``need``
    (their UAVs' height lags differ along the flights): each group of :func:`_levels` checked
    against its largest need; the margins the least over the groups, the distance and the
    requirement those of the group with the least slack (returned with its rows' indices)."""
    best: tuple[float, PairMargin, NDArray[np.intp]] | None = None
    lo = [math.inf] * 4
    for g in _levels(need):
        gp = np.ascontiguousarray(rows[g])
        m = _pair_margin(P, T, gp, take, 0, len(gp), float(need[g].max()), timing, a, b, moving)
        lo = [min(x, y) for x, y in zip(lo, (m.takeoff_s, m.speed, m.track_h, m.track_v),
                                        strict=True)]  # fmt: skip
        slack = m.distance - m.required
        if best is None or slack < best[0]:
            best = (slack, m, g)
    assert best is not None
    m = best[1]
    return replace(m, takeoff_s=lo[0], speed=lo[1], track_h=lo[2], track_v=lo[3]), best[2]


def separation_under(
    trajs: Sequence[Trajectory], s2: float, timing: Timing, lags: Sequence[Any] | None = None
) -> tuple[list[Violation], list[PairMargin]]:
    """Every pair of UAVs under the model: a violation for each pair that can come closer
    than ``s2`` plus the tracking gap (plus both UAVs' ``lags``: how far each one's heights
    can lag its plan, m, per trajectory one number or one per segment: each pair of segments
    held apart by its own two), and the margins of every pair that can come within
    ``s2 + 2 gap + 10`` m (and the two largest lags) at all (the others tolerate any
    timing)."""
    if len(trajs) < 2:
        return [], []
    P, T, owner, valid = _pack(trajs)
    take = np.array([float(trajs[k].times[0]) for k in range(len(trajs))])[np.maximum(owner, 0)]
    rowlag = _row_lags(trajs, lags, len(P))
    base = s2 + timing.gap
    tops = np.zeros(len(trajs))
    np.maximum.at(tops, np.maximum(owner, 0), rowlag)
    top2 = np.sort(tops)[-2:].sum()
    search = s2 + 2.0 * timing.gap + 10.0 + float(top2)
    # the chunk passed, not omitted: the tests pass it, and an omitted argument is another
    # signature to compile
    pairs = _close_pairs(P, owner, valid, float(search), float(max(search, 20.0)), T, take,
                         TAKEOFF_CAP, SPEED_CAP, int(CHUNK_SEGMENTS))  # fmt: skip
    if not len(pairs):
        return [], []
    key = owner[pairs[:, 0]] * len(trajs) + owner[pairs[:, 1]]
    order = np.argsort(key, kind="stable")
    pairs, key = np.ascontiguousarray(pairs[order]), key[order]
    cuts = np.flatnonzero(np.diff(key)) + 1
    starts = np.concatenate([[0], cuts])
    stops = np.concatenate([cuts, [len(key)]])
    # whether a pair fails is decided by its segment pairs that are closer than they need
    # without any timing (a timed distance is never less): the bisections read those alone
    need = base + rowlag[pairs[:, 0]] + rowlag[pairs[:, 1]]
    near = _pair_dists(P, pairs) < need - TOL + 1e-6
    close = np.ascontiguousarray(pairs[near])
    close_need = need[near]
    at = np.concatenate([[0], np.cumsum(near)])
    out: list[Violation] = []
    margins: list[PairMargin] = []
    for s, e in zip(starts, stops, strict=True):
        ia, ib = int(owner[pairs[s, 0]]), int(owner[pairs[s, 1]])
        a, b = trajs[ia], trajs[ib]
        cs, ce = int(at[s]), int(at[e])
        cn = close_need[cs:ce]
        held = close[cs:ce]
        if len(_levels(cn)) == 1:
            required = float(cn.max()) if len(cn) else float(need[s:e].max())
            m = _pair_margin(P, T, pairs, take, int(s), int(e), required, timing, a.id, b.id,
                             False, (close, cs, ce))  # fmt: skip
        else:
            m, g = _levelled_margin(P, T, held, take, cn, timing, a.id, b.id, False)
            held = held[g]
        margins.append(m)
        if not m.ok:
            la = float(rowlag[held[:, 0]].max()) if len(held) else 0.0
            lb = float(rowlag[held[:, 1]].max()) if len(held) else 0.0
            lagged = ", ".join(f"{t.id}'s heights lagging up to {fmt_num(lg)} m"
                               for t, lg in ((a, la), (b, lb)) if lg > 0)  # fmt: skip
            out.append(Violation(
                "separation", (a.id, b.id), m.time, m.where, m.distance, m.required,
                f"{a.id} and {b.id} can come {fmt_num(m.distance)} m apart under the execution "
                f"model (take-off ±{timing.delta0:g} s, speed ±{100 * timing.rho:.3g} %), "
                f"about t={m.time:.1f} s, where {fmt_num(m.required)} m is needed (S2 {s2:g} m "
                f"+ {fmt_num(timing.gap)} m of tracking{' + ' + lagged if lagged else ''}): "
                f"{a.id} near "
                f"{fmt_points(m.where[0])}, {b.id} near {fmt_points(m.where[1])}; it tolerates "
                f"take-off ±{_show(m.takeoff_s)} s, speed ±{_show(100 * m.speed)} %, tracking "
                f"{_show(m.track_h)} m horizontal and {_show(m.track_v)} m vertical",
            ))  # fmt: skip
    return out, margins


def _show(v: float) -> str:
    return "any" if not math.isfinite(v) else f"{v:.3g}"


def _pair_margin(
    P: FloatArray, T: FloatArray, pairs: IntArray, take: FloatArray, s: int, e: int,
    required: float, timing: Timing, a: str, b: str, moving: bool,
    close: tuple[IntArray, int, int] | None = None,
) -> PairMargin:  # fmt: skip
    """One pair's least distance under the model and its margins (module docstring);
    ``moving``: the second side is a moving obstacle on its own schedule (no error);
    ``close``: the segment pairs (rows ``[start, stop)``) that alone can fail, if known."""
    d0, r0 = timing.delta0, timing.rho
    fp, fs, fe = (pairs, s, e) if close is None else close

    def dist(delta: float, rho: float, stop: float = -1.0) -> tuple[float, int, float, float]:
        db, rb = (0.0, 0.0) if moving else (delta, rho)
        return _group_min(P, T, pairs, take, delta, rho, db, rb, s, e, stop)

    # each search from the model's own errors when the pair passes with them (a known lower
    # end), else from 0: :func:`_largest`, compiled with the pair's fails (one call each)
    below = required - TOL
    passes = not _fails_at(P, T, fp, take, fs, fe, d0, r0, moving, below)
    takeoff = float(_largest_tolerated(P, T, fp, take, fs, fe, d0, r0, moving, below,
                                       d0 if passes else 0.0, TAKEOFF_CAP, False))  # fmt: skip
    speed = float(_largest_tolerated(P, T, fp, take, fs, fe, d0, r0, moving, below,
                                     r0 if passes else 0.0, SPEED_CAP, True))  # fmt: skip
    d, k, u, w = dist(d0, r0)
    if k < 0:  # no two points can coincide under the model
        return PairMargin(a, b, math.nan, (), math.inf, float(required), takeoff, speed,
                          math.inf, math.inf)  # fmt: skip
    i, j = int(pairs[k, 0]), int(pairs[k, 1])
    pa = P[i] + u * (P[i + 1] - P[i])
    pb = P[j] + w * (P[j + 1] - P[j])
    tau_a = T[i] + u * (T[i + 1] - T[i])
    tau_b = T[j] + w * (T[j + 1] - T[j])
    lo_a = take[i] - d0 + (tau_a - take[i]) / (1 + r0)
    hi_a = take[i] + d0 + (tau_a - take[i]) / (1 - r0)
    lo_b, hi_b = tau_b, tau_b
    if not moving:
        lo_b = take[j] - d0 + (tau_b - take[j]) / (1 + r0)
        hi_b = take[j] + d0 + (tau_b - take[j]) / (1 - r0)
    t = 0.5 * (max(lo_a, lo_b) + min(hi_a, hi_b))
    # the tracking errors the least distance leaves room for, in the model's proportions
    eh, ev = (timing.track_h, timing.track_v) if timing.gap > 0 else (1.0, 1.0)
    per = math.hypot(eh, ev) * (1.0 if moving else 2.0)  # what (eh, ev) takes away
    base = required - (timing.norm if moving else timing.gap)  # the separation or radius
    k_ = max(0.0, (d - base) / per)
    return PairMargin(a, b, float(t), (tuple(pa.tolist()), tuple(pb.tolist())), float(d),
                      float(required), takeoff, speed, float(k_ * eh), float(k_ * ev))  # fmt: skip


def _largest(fails: Any, cap: float, known: float = 0.0) -> float:
    """The largest ``x`` in [0, cap] with ``fails(x)`` False (failing monotone in x), ``known``
    a value known not to fail: 0 when it fails at 0, inf when not at ``cap``. The reference of
    :func:`_largest_tolerated`, which does the same for a pair's margins in one compiled call
    (a test holds the two equal)."""
    if known <= 0.0 and fails(0.0):
        return 0.0
    if not fails(cap):
        return math.inf
    lo, hi = known, cap
    for _ in range(BISECT):
        mid = 0.5 * (lo + hi)
        if fails(mid):
            hi = mid
        else:
            lo = mid
    return lo


def moving_under(
    traj: Trajectory, obstacles: Sequence[Any], timing: Timing, lag: Any = 0.0
) -> tuple[list[Violation], list[PairMargin]]:
    """The UAV against each moving obstacle (on its own schedule) under the model, its
    heights lagging its plan by up to ``lag`` m (one number, or one per segment: each segment
    held off by its own)."""
    out: list[Violation] = []
    margins: list[PairMargin] = []
    seg_lag = np.zeros(max(len(traj.times) - 1, 0))
    seg_lag[:] = np.asarray(lag, dtype=np.float64) if len(seg_lag) else 0.0
    for oi, obs in enumerate(obstacles):
        ot = np.asarray(obs.times, dtype=np.float64)
        op = np.asarray(obs.positions, dtype=np.float64)[:, :3]
        far = 2e7
        times = np.concatenate([[min(0.0, ot[0]) - far], ot, [ot[-1] + far]])
        pts = np.concatenate([op[:1], op, op[-1:]])
        other = Trajectory(f"moving obstacle {oi}", pts, times)
        P, T, owner, valid = _pack([traj, other])
        take = np.where(owner == 0, float(traj.times[0]), float(times[0]))
        ia = np.flatnonzero(valid & (owner == 0))
        ib = np.flatnonzero(valid & (owner == 1))
        pairs = np.stack(np.meshgrid(ia, ib, indexing="ij"), axis=-1).reshape(-1, 2)
        pairs = np.ascontiguousarray(pairs, dtype=np.int64)
        need = float(obs.radius) + timing.norm + seg_lag[pairs[:, 0]]
        if len(_levels(need)) == 1:
            m = _pair_margin(P, T, pairs, take, 0, len(pairs), float(need.max()), timing,
                             traj.id, other.id, True)  # fmt: skip
            lg = float(seg_lag.max()) if len(seg_lag) else 0.0
        else:
            m, g = _levelled_margin(P, T, pairs, take, need, timing, traj.id, other.id, True)
            lg = float(seg_lag[pairs[g, 0]].max())
        margins.append(m)
        if not m.ok:
            out.append(Violation(
                "moving", (traj.id,), m.time, (m.where[0],), m.distance, m.required,
                f"{traj.id} can come {fmt_num(m.distance)} m from the centre of moving obstacle "
                f"{oi} under the execution model, about t={m.time:.1f} s, where "
                f"{fmt_num(m.required)} m is needed (radius {obs.radius:g} m + "
                f"{fmt_num(timing.norm)} m of tracking"
                f"{f' + {fmt_num(lg)} m of height lag' if lg else ''}); "
                f"it tolerates take-off "
                f"±{_show(m.takeoff_s)} s, speed ±{_show(100 * m.speed)} %",
            ))  # fmt: skip
    return out, margins


def horizontal_clearance(
    traj: Trajectory,
    scenario: Any,
    checks: Any,
    known: float = 0.0,
    ground: Any = None,
    ground_fails: Any = None,
) -> tuple[float, str]:
    """The largest horizontal tracking error the UAV's static checks tolerate (cylinders,
    circles, polygons widened by it, as a robust plan is planned; and, with ``ground``, the
    checks against the ground, which a horizontal error moves under the UAV: ``ground(e)``
    says which fails with a horizontal error ``e`` and the model's vertical one, or ""),
    found by bisection from ``known``, the model's, when the checks pass with it; and what
    limits it. ``checks``: ``(check_cylinders, check_circles, check_polygons)``.
    ``ground_fails(e)``: whether ``ground(e)`` fails, when that is cheaper to tell than why
    (the bisection's steps ask only whether; what limits the margin is ``ground``'s)."""
    cyl, circ, poly = checks
    cylinders = tuple(scenario.cylinders) if traj.dim == 3 else ()
    circles = tuple(scenario.circles)
    polygons = tuple(scenario.no_fly_polygons)
    if not (cylinders or circles or polygons or ground is not None):
        return math.inf, ""

    def fails(e: float, why_: bool = False) -> str:
        """What fails with a horizontal error ``e`` ("" if nothing); with ``why_`` the
        ground's own reason, else "ground" where ``ground_fails`` says it fails."""
        if ground is not None:
            if ground_fails is None or why_:
                why = ground(e)
                if why:
                    return str(why)
            elif ground_fails(e):
                return "ground"
        if cylinders and cyl(traj, [replace(c, margin=c.margin + e) for c in cylinders]):
            return "cylinders"
        if circles and circ(traj, [replace(c, margin=c.margin + e) for c in circles]):
            return "circles"
        if polygons and poly(traj, [replace(p, margin=p.margin + e) for p in polygons]):
            return "polygons"
        return ""

    lo = known if known > 0.0 and not fails(known) else 0.0
    if lo == 0.0 and fails(0.0):
        return 0.0, fails(0.0, True)
    cap = 1000.0
    if not fails(cap):
        return math.inf, ""
    hi = cap
    for _ in range(BISECT + 6):
        mid = 0.5 * (lo + hi)
        if fails(mid):
            hi = mid
        else:
            lo = mid
    return lo, fails(hi, True) or "obstacles"


def vertical_clearance(
    traj: Trajectory, scenario: Any, source: Any, extrema: Any, reach: float = 0.0,
    within: Any = None, scratch: dict[str, Any] | None = None,
) -> tuple[float, str]:  # fmt: skip
    """The largest vertical tracking error the UAV's flight tolerates (exact for ``reach``
    0): the least of its height above the ground (the raster's own, ``source``, else the
    scenario's grid), its distances to the altitude band's ends along every segment, and to
    the bounds' floor and ceiling; and what limits it. With a horizontal tracking error
    ``reach``, the ground anywhere within it of the flight (a bound: the grid's nodes moved to
    the highest and lowest within reach, ``within``, :func:`~uavplan.verify.terrain.
    within_reach`). ``extrema``: the verifier's grid clearance function
    (``terrain_clearance_extrema``); ``source``: ``source(traj, reach)``, the clearances over
    the raster (:func:`~uavplan.verify.source_terrain.source_clearance`), or None.
    ``scratch``: a dict kept by the caller for one flight over many reaches (a margin's
    bisection): the grid nodes the clearances read and the grids they are written into."""
    if traj.dim != 3:
        return math.inf, ""
    z = traj.points[:, 2]
    lo, hi = scenario.bounds.lower[2], scenario.bounds.upper[2]
    best = (float(min(np.min(z - lo), np.min(hi - z))), "bounds")
    band = scenario.altitude
    low_c, high_c = math.inf, -math.inf
    terrain = scenario.terrain
    if source is not None:
        low_c, high_c = source(traj, reach)
    elif terrain is not None:
        side = _GroundSides(traj, terrain, reach, extrema, within, scratch)
        low_c, high_c = -math.inf, math.inf
        for how in side.hows:
            low_c = max(low_c, side(True, how))
            high_c = min(high_c, side(False, how))
    elif band is not None and band.reference == "ground":  # flat ground at 0
        low_c, high_c = float(z.min()), float(z.max())
    if math.isfinite(low_c):
        best = min(best, (low_c, "terrain"))
    if band is not None:
        if band.reference == "ground":
            best = min(best, (low_c - band.min, "altitude band's floor"),
                       (band.max - high_c, "altitude band's ceiling"))  # fmt: skip
        else:
            best = min(best, (float(np.min(z - band.min)), "altitude band's floor"),
                       (float(np.min(band.max - z)), "altitude band's ceiling"))  # fmt: skip
    return max(best[0], 0.0), best[1]


def vertical_fails(
    traj: Trajectory, scenario: Any, extrema: Any, reach: float, need: float, within: Any,
    scratch: dict[str, Any] | None = None,
) -> bool:  # fmt: skip
    """Whether :func:`vertical_clearance` (without a raster ``source``) is below ``need`` (> 0),
    the same answer with less work: the floor's clearance is the larger of the two bounds of
    the ground within reach ("height", "slope") and the ceiling's the smaller, and each check
    can only fail more as its clearance shrinks, so a side that passes on one bound passes,
    and a side that fails decides alone (a margin's bisection asks this at every step)."""
    if traj.dim != 3 or not need > 0.0:
        return False
    z = traj.points[:, 2]
    lo, hi = scenario.bounds.lower[2], scenario.bounds.upper[2]
    if float(min(np.min(z - lo), np.min(hi - z))) < need:
        return True
    band = scenario.altitude
    ground_band = band is not None and band.reference == "ground"
    if (band is not None and not ground_band
            and min(float(np.min(z - band.min)), float(np.min(band.max - z))) < need):  # fmt: skip
        return True

    def floor_fails(c: float) -> bool:
        return (math.isfinite(c) and c < need) or (ground_band and c - band.min < need)

    terrain = scenario.terrain
    if terrain is None:  # flat ground at 0 under a band above it
        return ground_band and (floor_fails(float(z.min())) or band.max - float(z.max()) < need)
    side = _GroundSides(traj, terrain, reach, extrema, within, scratch)
    low_c = -math.inf
    for how in side.hows:  # the floor: low_c = max over the bounds
        low_c = max(low_c, side(True, how))
        if math.isfinite(low_c) and not floor_fails(low_c):
            break
    else:
        if floor_fails(low_c):
            return True
    if not ground_band:
        return False
    high_c = math.inf
    for how in side.hows:  # the ceiling: high_c = min over the bounds
        high_c = min(high_c, side(False, how))
        if not band.max - high_c < need:
            return False
    return True


class _GroundSides:
    """A flight's clearances to the ground moved within ``reach``: called ``(True, how)``, the
    least height above the floor along the flight; ``(False, how)``, the greatest above the
    top; for each bound ``how`` of :attr:`hows` (:func:`~uavplan.verify.terrain.
    within_reach`'s "height" and "slope", or "" for the ground as it is)."""

    def __init__(self, traj: Trajectory, terrain: Any, reach: float, extrema: Any, within: Any,
                 scratch: dict[str, Any] | None) -> None:  # fmt: skip
        self.a, self.b = traj.points[:-1], traj.points[1:]
        self.floor0 = terrain.heights
        self.top0 = terrain.heights if terrain.lower is None else terrain.lower
        # the clearances read only the nodes at the cells under the flight: the grids moved
        # within reach are computed there alone (one table query per node, not a filter of
        # the whole raster per UAV and step) into grids cut to those cells (and one node
        # around); the values read are the same
        view = None if scratch is None else scratch.get("view")
        if view is None:
            view = _GroundView(traj, terrain, self.a, self.b)
            if scratch is not None:
                scratch["view"] = view
        self.view, self.reach, self.extrema, self.within = view, reach, extrema, within
        self.hows = ("height", "slope") if reach > 0 and within is not None else ("",)

    def __call__(self, floor: bool, how: str) -> float:
        grid = self.view.moved(self.floor0 if floor else self.top0, self.reach, floor, how,
                               self.within)  # fmt: skip
        e = self.extrema(self.a, self.b, grid)
        return float(np.min(e[:, 0])) if floor else float(np.max(e[:, 2]))


class _Grid:
    """A cut of a terrain grid (``heights``: the nodes ``cut`` of ``terrain``), as the clearance
    kernels read a grid."""

    def __init__(self, heights: FloatArray, terrain: Any, cut: tuple[slice, slice]) -> None:
        self.heights = heights
        self.dx, self.dy = float(terrain.dx), float(terrain.dy)
        self.x0 = float(terrain.x0) + cut[1].start * self.dx
        self.y0 = float(terrain.y0) + cut[0].start * self.dy


class _GroundView:
    """One flight's view of a terrain grid: the cut of the grid under it (:func:`_cells_under`),
    the nodes there that the clearance kernel reads (``nodes``, the whole grid's rows and
    columns; ``local``, the cut's), and two grids of the cut's shape that hold the ground moved
    within reach at those nodes (NaN elsewhere: never read)."""

    def __init__(self, traj: Trajectory, terrain: Any, a: FloatArray, b: FloatArray) -> None:
        from uavplan.verify.terrain import nodes_read

        self.terrain = terrain
        self.cut = _cells_under(traj.points, terrain)
        self.nodes = nodes_read(a, b, terrain, self.cut)
        self.local = (self.nodes[0] - self.cut[0].start, self.nodes[1] - self.cut[1].start)
        shape = (self.cut[0].stop - self.cut[0].start, self.cut[1].stop - self.cut[1].start)
        self.floor = np.full(shape, np.nan)
        self.top = np.full(shape, np.nan)

    def moved(self, H: FloatArray, reach: float, highest: bool, how: str, within: Any) -> _Grid:
        """The grid ``H`` (the terrain's floor or top) moved within ``reach`` as ``how`` says
        (``within(..., nodes=)``), at the nodes read; ``how`` "": ``H`` as it is."""
        if not how:
            return _Grid(H[self.cut], self.terrain, self.cut)
        buf = self.floor if highest else self.top
        t = self.terrain
        buf[self.local] = within(H, t.dx, t.dy, reach, highest, how, nodes=self.nodes)
        return _Grid(buf, t, self.cut)


def _cells_under(points: FloatArray, terrain: Any) -> tuple[slice, slice]:
    """The rows and columns of the nodes of every cell the flight's points lie in (and so its
    segments, each inside its ends' box), one node more on each side; a point outside the grid
    counts where the clearance kernels clamp it, at the edge."""
    ny, nx = np.shape(terrain.heights)
    i = np.clip(np.floor((points[:, 0] - float(terrain.x0)) / float(terrain.dx)), 0, nx - 2)
    j = np.clip(np.floor((points[:, 1] - float(terrain.y0)) / float(terrain.dy)), 0, ny - 2)
    c0, c1 = max(0, int(i.min()) - 1), min(nx, int(i.max()) + 3)
    r0, r1 = max(0, int(j.min()) - 1), min(ny, int(j.max()) + 3)
    return slice(r0, r1), slice(c0, c1)


def horizontal_bounds(traj: Trajectory, scenario: Any) -> float:
    """The least horizontal distance from the flight's points to the bounds' sides."""
    p = traj.points[:, :2]
    lo, hi = np.asarray(scenario.bounds.lower[:2]), np.asarray(scenario.bounds.upper[:2])
    return max(float(min(np.min(p - lo), np.min(hi - p))), 0.0)
