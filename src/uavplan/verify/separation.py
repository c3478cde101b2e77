"""Separation between UAVs over continuous time: every pair, exact closest approach per common
interval, pruned by sort-and-sweep on whole-flight boxes.

Two kinds of separation: a sphere (the UAVs at least ``S2`` apart, Euclidean) or per axis
``(S_x, S_y, S_z)`` (the RSCDWOA paper's ``[50, 50, 20]`` m: the UAVs are too close when closer
than all three at once, an axis-aligned box). For the box the measure is ``S_ref q`` with
``q = max_i |r_i| / S_i`` and ``S_ref = max_i S_i``, so "distance below ``S_ref``" means "inside
the box" and the rest of the code is shared. On a common interval the offset ``r(s)`` is
linear; the verifier finds the smallest ``q`` by bisection on the level ``lam``: the set of
``s`` in [0, 1] with ``|r_i(s)| <= lam S_i`` on every axis is an intersection of three
intervals, non-empty exactly when ``lam >= q_min`` (the planner's reservation table enumerates
the kinks of ``q(s)`` instead: two methods, so that one cannot hide the other's bug)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

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
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ================================================================================ separation
@njit(cache=True)
def _box_level(r0x, r0y, r0z, drx, dry, drz, S, lam):  # pragma: no cover - numba
    """The interval ``[lo, hi]`` of ``s`` in [0, 1] on which ``|r_i(s)| <= lam S_i`` on every
    axis (``lo > hi``: empty)."""
    lo = 0.0
    hi = 1.0
    for c in range(3):
        r = r0x if c == 0 else (r0y if c == 1 else r0z)
        d = drx if c == 0 else (dry if c == 1 else drz)
        half = lam * S[c]
        if d == 0.0:
            if abs(r) > half:
                return 1.0, 0.0
            continue
        s1 = (-half - r) / d
        s2 = (half - r) / d
        lo = max(lo, min(s1, s2))
        hi = min(hi, max(s1, s2))
    return lo, hi


@njit(cache=True)
def _box_min(r0x, r0y, r0z, drx, dry, drz, S):  # pragma: no cover - numba
    """(q_min, s at the minimum) of ``q(s) = max_i |r0_i + s dr_i| / S_i`` over [0, 1], by
    bisection on the level (80 halvings: to the last bits of a double)."""
    q0 = max(abs(r0x) / S[0], max(abs(r0y) / S[1], abs(r0z) / S[2]))
    q1 = max(abs(r0x + drx) / S[0], max(abs(r0y + dry) / S[1], abs(r0z + drz) / S[2]))
    hi = min(q0, q1)
    s_hi = 0.0 if q0 <= q1 else 1.0
    lo = 0.0
    a, b = _box_level(r0x, r0y, r0z, drx, dry, drz, S, 0.0)
    if a <= b:
        return 0.0, 0.5 * (a + b)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if not (lo < mid < hi):
            break
        a, b = _box_level(r0x, r0y, r0z, drx, dry, drz, S, mid)
        if a <= b:
            hi = mid
            s_hi = 0.5 * (a + b)
        else:
            lo = mid
    return hi, s_hi


@njit(cache=True, inline="always")
def _box_bound(r0x, r0y, r0z, drx, dry, drz, S):  # pragma: no cover - numba
    """A lower bound of :func:`_box_min`'s level: the largest over the axes of the least
    ``|r0_i + s dr_i| / S_i`` on [0, 1] (0 where the axis's interval holds 0)."""
    q = 0.0
    for r0, dr, si in ((r0x, drx, S[0]), (r0y, dry, S[1]), (r0z, drz, S[2])):
        r1 = r0 + dr
        if (r0 > 0.0 and r1 > 0.0) or (r0 < 0.0 and r1 < 0.0):
            q = max(q, min(abs(r0), abs(r1)) / si)
    return q


@njit(cache=True)
def _walk(P, T, a0, a1, b0, b1, rec, record, box, S):  # pragma: no cover - numba
    """Exact minimum distance between two timed polylines over their common flight time.

    Rows ``a0:a1`` of ``P`` (N, 3) / ``T`` (N,) are UAV a, rows ``b0:b1`` UAV b (>= 2 rows each,
    times non-decreasing). Walks the union of both breakpoint lists; on each common interval the
    relative motion is linear, so the minimum is that of a quadratic. A zero-length segment (a
    jump) is swept as a straight motion at its instant. If ``record``, writes one row per interval
    into ``rec`` (t_start, t_end, d_min, t_min, pa xyz and pb xyz at the minimum, b - a at
    t_start and at t_end).

    ``box``: the per-axis separation ``S`` (3,): the measure is ``max(S) q`` (module docstring)
    instead of the Euclidean distance.

    Returns (d_min, t_min, pa_x, pa_y, pa_z, pb_x, pb_y, pb_z, n_rows); d_min is inf when the
    flights do not overlap in time.
    """
    s_ref = max(S[0], max(S[1], S[2]))
    best = np.inf
    res = np.full(8, np.nan)
    res[0] = np.inf
    n = 0
    T0 = max(T[a0], T[b0])
    T1 = min(T[a1 - 1], T[b1 - 1])
    if T0 > T1:
        return res, 0
    i = a0
    while i < a1 - 2 and T[i + 1] < T0:
        i += 1
    j = b0
    while j < b1 - 2 and T[j + 1] < T0:
        j += 1
    t = T0
    pa = np.empty(3)
    qa = np.empty(3)
    pb = np.empty(3)
    qb = np.empty(3)
    while True:
        # once one UAV has landed (at t = T1), the other's jumps at that instant still count
        a_done = i >= a1 - 1
        b_done = j >= b1 - 1
        if (a_done and b_done) or (a_done and T[j + 1] > t) or (b_done and T[i + 1] > t):
            break
        ea = np.inf if a_done else T[i + 1]
        eb = np.inf if b_done else T[j + 1]
        e = min(ea, eb)
        for c in range(3):
            if a_done:
                pa[c] = P[a1 - 1, c]
                qa[c] = P[a1 - 1, c]
            elif ea > T[i]:
                va = (P[i + 1, c] - P[i, c]) / (ea - T[i])
                pa[c] = P[i, c] + va * (t - T[i])
                qa[c] = P[i, c] + va * (e - T[i])
            else:
                pa[c] = P[i, c]
                qa[c] = P[i + 1, c]
            if b_done:
                pb[c] = P[b1 - 1, c]
                qb[c] = P[b1 - 1, c]
            elif eb > T[j]:
                vb = (P[j + 1, c] - P[j, c]) / (eb - T[j])
                pb[c] = P[j, c] + vb * (t - T[j])
                qb[c] = P[j, c] + vb * (e - T[j])
            else:
                pb[c] = P[j, c]
                qb[c] = P[j + 1, c]
        r0x = pb[0] - pa[0]
        r0y = pb[1] - pa[1]
        r0z = pb[2] - pa[2]
        drx = (qb[0] - qa[0]) - r0x
        dry = (qb[1] - qa[1]) - r0y
        drz = (qb[2] - qa[2]) - r0z
        if box:
            # the level's bisection costs 80 steps: skipped (not recording) where no axis can
            # come nearer than the best so far (per axis, the nearer end unless it crosses 0)
            if not record and s_ref * _box_bound(r0x, r0y, r0z, drx, dry, drz, S) >= best:
                n += 1
                if ea == e:
                    i += 1
                if eb == e:
                    j += 1
                t = e
                continue
            q, w = _box_min(r0x, r0y, r0z, drx, dry, drz, S)
            d = s_ref * q
        else:
            dd = drx * drx + dry * dry + drz * drz
            w = 0.0
            if dd > 0.0:
                w = -(r0x * drx + r0y * dry + r0z * drz) / dd
                w = min(max(w, 0.0), 1.0)
            x = r0x + w * drx
            y = r0y + w * dry
            z = r0z + w * drz
            d = math.sqrt(x * x + y * y + z * z)
        tm = t + w * (e - t)
        if record:
            rec[n, 0] = t
            rec[n, 1] = e
            rec[n, 2] = d
            rec[n, 3] = tm
            for c in range(3):
                rec[n, 4 + c] = pa[c] + w * (qa[c] - pa[c])
                rec[n, 7 + c] = pb[c] + w * (qb[c] - pb[c])
                rec[n, 10 + c] = pb[c] - pa[c]
                rec[n, 13 + c] = qb[c] - qa[c]
        n += 1
        if d < best:
            best = d
            res[0] = d
            res[1] = tm
            for c in range(3):
                res[2 + c] = pa[c] + w * (qa[c] - pa[c])
                res[5 + c] = pb[c] + w * (qb[c] - pb[c])
        if ea == e:
            i += 1
        if eb == e:
            j += 1
        t = e
    return res, n


@njit(cache=True)
def _pairs_min(P, T, off, pairs, box, S):  # pragma: no cover - numba
    """(m, 2) minimum distance and its time for each pair of trajectories (rows of ``off``)."""
    m = pairs.shape[0]
    out = np.empty((m, 2))
    dummy = np.empty((1, 16))
    for q in range(m):
        a = pairs[q, 0]
        b = pairs[q, 1]
        res, _ = _walk(P, T, off[a], off[a + 1], off[b], off[b + 1], dummy, False, box, S)
        out[q, 0] = res[0]
        out[q, 1] = res[1]
    return out


@njit(cache=True)
def _sweep(lo, hi, t0, t1, gap, out, fill):  # pragma: no cover - numba
    """Sort-and-sweep along x: pairs (a < b) whose boxes ``lo..hi`` (n, 3), grown by ``gap``,
    overlap on every axis and whose time windows ``[t0, t1]`` overlap. Returns their number;
    if ``fill``, writes them into ``out`` (m, 2) int64."""
    n = lo.shape[0]
    order = np.argsort(lo[:, 0], kind="mergesort")
    m = 0
    for p in range(n):
        a = order[p]
        for r in range(p + 1, n):
            b = order[r]
            if lo[b, 0] - hi[a, 0] > gap:
                break
            if t0[a] > t1[b] or t0[b] > t1[a]:
                continue
            ok = True
            for c in range(1, 3):
                if lo[b, c] - hi[a, c] > gap or lo[a, c] - hi[b, c] > gap:
                    ok = False
                    break
            if not ok:
                continue
            if fill:
                out[m, 0] = min(a, b)
                out[m, 1] = max(a, b)
            m += 1
    return m


def _pack(trajs: Sequence[Trajectory]) -> tuple[FloatArray, FloatArray, IntArray]:
    """Stack trajectories into P (N, 3) (z = 0 for 2-D), T (N,), offsets (n + 1,)."""
    counts = [len(t.times) for t in trajs]
    off = np.zeros(len(trajs) + 1, dtype=np.int64)
    off[1:] = np.cumsum(counts)
    P = np.zeros((int(off[-1]), 3))
    T = np.zeros(int(off[-1]))
    for k, tr in enumerate(trajs):
        P[off[k] : off[k + 1], : tr.dim] = tr.points
        T[off[k] : off[k + 1]] = tr.times
    return P, T, off


def candidate_pairs(trajs: Sequence[Trajectory], gap: float) -> IntArray:
    """Pairs ``(a, b)``, a < b, that could come closer than ``gap``: their flight time windows
    overlap and their whole-flight boxes, grown by ``gap``, overlap (sort-and-sweep). Every
    pair left out stays farther than ``gap`` apart at every instant. Returns (m, 2) int64."""
    if len(trajs) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    lo = np.zeros((len(trajs), 3))
    hi = np.zeros((len(trajs), 3))
    for k, tr in enumerate(trajs):
        lo[k, : tr.dim] = tr.points.min(axis=0)
        hi[k, : tr.dim] = tr.points.max(axis=0)
    t0 = np.array([tr.times.min() for tr in trajs])
    t1 = np.array([tr.times.max() for tr in trajs])
    m = int(_sweep(lo, hi, t0, t1, float(gap), np.zeros((1, 2), dtype=np.int64), False))
    pairs = np.zeros((m, 2), dtype=np.int64)
    _sweep(lo, hi, t0, t1, float(gap), pairs, True)
    if len(pairs):
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    return pairs


Axes = tuple[float, float, float] | None


def _metric(axes: Axes) -> tuple[bool, FloatArray]:
    return axes is not None, np.asarray(axes if axes is not None else (1.0, 1.0, 1.0), float)


def box_measure(offset: FloatArray, axes: Axes) -> float:
    """The separation measure of one offset: its length, or for per-axis ``axes`` the scaled
    Chebyshev ``max(S) max_i |r_i| / S_i`` (below ``max(S)`` exactly inside the box)."""
    if axes is None:
        return float(np.linalg.norm(offset))
    S = np.asarray(axes, dtype=np.float64)
    return float(S.max() * np.max(np.abs(np.asarray(offset)[:3]) / S))


def pair_min_distance(a: Trajectory, b: Trajectory, axes: Axes = None) -> tuple[float, float]:
    """Exact minimum distance between two UAVs over continuous time while both fly, and the
    time it happens: ``(metres, seconds)``, ``(inf, nan)`` if their flights do not overlap.
    With per-axis ``axes``: the box measure (:func:`box_measure`)."""
    P, T, off = _pack([a, b])
    box, S = _metric(axes)
    res, _ = _walk(P, T, off[0], off[1], off[1], off[2], np.empty((1, 16)), False, box, S)
    return float(res[0]), float(res[1])


def pair_encounters(a: Trajectory, b: Trajectory, s2: float, axes: Axes = None) -> list[Violation]:
    """Every close encounter of two UAVs (a run of consecutive common intervals on which they
    come closer than ``s2 - TOL``), reported at its closest point. With per-axis ``axes``,
    ``s2`` is ``max(axes)`` and "closer" is the box measure (:func:`box_measure`)."""
    P, T, off = _pack([a, b])
    box, S = _metric(axes)
    rec = np.empty((len(a.times) + len(b.times) + 2, 16))
    _, n = _walk(P, T, off[0], off[1], off[1], off[2], rec, True, box, S)
    rows = rec[:n]
    out = []
    k = 0
    while k < n:
        if rows[k, 2] >= s2 - TOL:
            k += 1
            continue
        e = k
        # the run goes on while the distance stays below s2 across the shared breakpoint
        while (
            e + 1 < n
            and rows[e + 1, 2] < s2 - TOL
            and box_measure(rows[e, 13:16], axes) < s2 - TOL
            and box_measure(rows[e + 1, 10:13], axes) < s2 - TOL
        ):
            e += 1
        run = rows[k : e + 1]
        w = int(np.argmin(run[:, 2]))
        d, t = float(run[w, 2]), float(run[w, 3])
        pa = fmt_point(run[w, 4 : 4 + a.dim])
        pb = fmt_point(run[w, 7 : 7 + b.dim])
        t_in = _crossing(run[0], s2, first=True, axes=axes)
        t_out = _crossing(run[-1], s2, first=False, axes=axes)
        what = (
            f"S2 {s2:g} m"
            if axes is None
            else "within the box "
            + "/".join(f"{x:g}" for x in axes)
            + " m, offset "
            + fmt_points(run[w, 7:10] - run[w, 4:7])
        )
        out.append(
            Violation(
                "separation",
                (a.id, b.id),
                t,
                (pa, pb),
                d,
                s2,
                f"{a.id} and {b.id} {fmt_num(d)} m apart at t={t:.3f} s ({what}; "
                f"closer from t={t_in:.3f} to {t_out:.3f} s): "
                f"{a.id} at {fmt_points(pa)}, {b.id} at {fmt_points(pb)}",
            )
        )
        k = e + 1
    return out


def _crossing(row: FloatArray, s2: float, first: bool, axes: Axes = None) -> float:
    """The time at which the distance of a recorded interval crosses ``s2``: the first time it
    drops below (``first``) or the last time it is below; the interval's end if it never
    crosses inside it. (With ``axes``: when the offset enters or leaves the box.)"""
    t0, t1 = float(row[0]), float(row[1])
    r0 = row[10:13]
    dr = row[13:16] - r0
    if axes is not None:
        S = np.asarray(axes, dtype=np.float64)
        lo, hi = _box_level(r0[0], r0[1], r0[2], dr[0], dr[1], dr[2], S, s2 / float(S.max()))
        if lo > hi:
            return t0 if first else t1
        return t0 + (lo if first else hi) * (t1 - t0)
    qa, qb, qc = float(dr @ dr), 2.0 * float(r0 @ dr), float(r0 @ r0) - s2 * s2
    disc = qb * qb - 4 * qa * qc
    if qa <= 0 or disc < 0:
        return t0 if first else t1
    w = (-qb - math.sqrt(disc)) / (2 * qa) if first else (-qb + math.sqrt(disc)) / (2 * qa)
    w = min(max(w, 0.0), 1.0)
    return t0 + w * (t1 - t0)


@dataclass(frozen=True)
class SeparationResult:
    """What :func:`check_separation` found: the violations, the number of pairs checked exactly,
    and the overall minimum distance among them with its pair and time."""

    violations: list[Violation]
    pairs_checked: int
    min_distance: float
    min_pair: tuple[str, str] | None
    min_time: float | None


def check_separation(
    trajs: Sequence[Trajectory], s2: float, prune: bool = True, exact_min: bool = True,
    axes: Axes = None,
) -> SeparationResult:  # fmt: skip
    """Every pair of UAVs at least ``s2`` apart over continuous time (exact).

    Args:
        trajs: the UAVs (times non-decreasing).
        s2: the required separation, metres (with ``axes``: ignored, ``max(axes)``).
        axes: per-axis separation ``(S_x, S_y, S_z)`` (a box; module docstring), or None.
        prune: skip pairs that cannot come within ``s2`` (see :func:`candidate_pairs`); False
            checks every pair exactly (for tests and benchmarks).
        exact_min: when no checked pair comes within ``s2``, widen the pruning until the fleet's
            overall minimum separation is found exactly (pairs pruned at a gap ``g`` are farther
            than ``g`` apart, so once some pair is found at ``<= g`` it is the minimum); False
            reports the minimum over the pairs checked for ``s2`` only (inf if none).

    Returns:
        The violations (one per close encounter), the number of pairs checked exactly for
        ``s2``, and the minimum separation with its pair and time.
    """
    n = len(trajs)
    if axes is not None:
        s2 = float(max(axes))
    if n < 2:
        return SeparationResult([], 0, math.inf, None, None)
    P, T, off = _pack(trajs)
    box, S = _metric(axes)

    def exact(pairs: IntArray) -> FloatArray:
        if len(pairs) == 0:
            return np.zeros((0, 2))
        return np.asarray(_pairs_min(P, T, off, np.ascontiguousarray(pairs), box, S))

    if prune:
        pairs = candidate_pairs(trajs, s2)
    else:
        ia, ib = np.triu_indices(n, 1)
        pairs = np.stack([ia, ib], axis=1).astype(np.int64)
    res = exact(pairs)
    out: list[Violation] = []
    for bad in np.flatnonzero(res[:, 0] < s2 - TOL):
        a, b = trajs[int(pairs[bad, 0])], trajs[int(pairs[bad, 1])]
        out.extend(pair_encounters(a, b, s2, axes))
    checked = len(pairs)
    best = float(res[:, 0].min()) if len(res) else math.inf
    if prune and exact_min and not best <= s2:
        lo = np.min([t.points.min(axis=0) for t in trajs], axis=0)
        hi = np.max([t.points.max(axis=0) for t in trajs], axis=0)
        diameter = float(np.linalg.norm(hi - lo))
        gap = best if math.isfinite(best) else 2.0 * max(s2, 1.0)
        while True:
            pairs = candidate_pairs(trajs, gap)
            res = exact(pairs)
            best = float(res[:, 0].min()) if len(res) else math.inf
            if best <= gap or gap > diameter:
                break
            gap = best if math.isfinite(best) else 2.0 * gap
    if not len(res) or not math.isfinite(best):
        return SeparationResult(out, checked, math.inf, None, None)
    q = int(np.argmin(res[:, 0]))
    pair = (trajs[int(pairs[q, 0])].id, trajs[int(pairs[q, 1])].id)
    return SeparationResult(out, checked, float(res[q, 0]), pair, float(res[q, 1]))


def check_moving(traj: Trajectory, obstacles: Sequence[Any]) -> list[Violation]:
    """The UAV stays at least ``radius`` from every moving obstacle's centre over continuous
    time (the obstacle holds its first and last positions outside its knots)."""
    out = []
    for oi, obs in enumerate(obstacles):
        ot = np.asarray(obs.times, dtype=np.float64)
        op = np.asarray(obs.positions, dtype=np.float64)[:, : traj.dim]
        t_lo, t_hi = float(traj.times[0]), float(traj.times[-1])
        times = np.concatenate([[min(t_lo, ot[0])], ot, [max(t_hi, ot[-1])]])
        pts = np.concatenate([op[:1], op, op[-1:]])
        other = Trajectory(f"moving obstacle {oi}", pts, times)
        for v in pair_encounters(traj, other, float(obs.radius)):
            d, t = v.value, v.time
            out.append(
                Violation(
                    "moving",
                    (traj.id,),
                    t,
                    v.where,
                    d,
                    float(obs.radius),
                    f"{traj.id}: {fmt_num(d)} m from the centre of moving obstacle {oi} (radius "
                    f"{obs.radius:g} m) at t={t:.3f} s, UAV at {fmt_points(v.where[0])}, "
                    f"obstacle at {fmt_points(v.where[1])}",
                )
            )
    return out
