"""The Dubins smoothing of :mod:`uavplan.smoothing.dubins` in one Numba pass per path.

A fleet planner smooths thousands of candidate polylines (two smoothings each, with and without
line-of-sight shortcuts), and in Python each costs about a millisecond of per-piece work: the
four CSC words, a sampling pass, the altitude and the chaining. :func:`smooth_kernel` does the
same arithmetic in the same order (:func:`uavplan.smoothing.dubins.smooth_path_reference` is
the reference the tests compare it with): the words as :func:`~uavplan.smoothing.dubins.
_shortest_csc` builds them, the samples as :func:`~uavplan.smoothing.dubins.sample_pieces`
takes them (NumPy's ``linspace`` formula, the pieces advanced in closed form, the exact ends),
the altitude linear in each piece's samples. The trigonometric functions are the C library's
here and NumPy's own in the reference, which on some CPUs differ by an ulp: the two agree to
round-off, not always bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TWO_PI = 2.0 * math.pi
_EPS = 1e-13
_MAX_SNAP = 1e-9
_SAME_CIRCLE = 1e-11
#: the CSC words in the order ties are broken (``CSC_KINDS``): (first turn, last turn), +1 left
_FIRST = (1.0, 1.0, -1.0, -1.0)
_LAST = (1.0, -1.0, 1.0, -1.0)


@njit(cache=True, inline="always")
def _mod2pi(angle, snap):  # pragma: no cover - numba
    a = np.fmod(angle, TWO_PI)
    if a < 0.0:
        a += TWO_PI
    if a >= TWO_PI - snap:
        a = 0.0
    return a


@njit(cache=True, inline="always")
def _wrap(a):  # pragma: no cover - numba
    """``np.mod(a + pi, 2 pi) - pi`` (NumPy's floored remainder, written out)."""
    x = a + math.pi
    m = np.fmod(x, TWO_PI)
    if m != 0.0:
        if m < 0.0:
            m += TWO_PI
    else:
        m = math.copysign(0.0, TWO_PI)
    return m - math.pi


@njit(cache=True)
def _shortest(x0, y0, h0, x1, y1, h1, rho, allowed):  # pragma: no cover - numba
    """The shortest allowed CSC word from pose 0 to pose 1: ``(word, arc, straight, arc)``,
    word -1 when none exists."""
    scale = rho + max(max(abs(x0), abs(y0)), max(abs(x1), abs(y1)))
    best = -1
    b1 = 0.0
    b2 = 0.0
    b3 = 0.0
    s0, c0, s1, c1 = math.sin(h0), math.cos(h0), math.sin(h1), math.cos(h1)  # once, 4 words
    for w in range(4):
        if not allowed[w]:
            continue
        k0 = _FIRST[w]
        k1 = _LAST[w]
        cx0 = x0 - k0 * rho * s0
        cy0 = y0 + k0 * rho * c0
        cx1 = x1 - k1 * rho * s1
        cy1 = y1 + k1 * rho * c1
        vx = cx1 - cx0
        vy = cy1 - cy0
        dist = math.hypot(vx, vy)
        if k0 == k1:
            if dist <= _SAME_CIRCLE * scale:
                straight = 0.0
                psi = h0
            else:
                straight = dist
                psi = math.atan2(vy, vx)
        else:
            sq = dist * dist - 4.0 * rho * rho
            if sq < -_EPS * rho * scale:
                continue
            straight = math.sqrt(max(sq, 0.0))
            offset = math.atan2(2.0 * rho, straight)
            psi = math.atan2(vy, vx) + (offset if k0 > 0.0 else -offset)
        snap = min(_MAX_SNAP, _EPS * (1.0 + abs(h0) + abs(h1) + scale / max(dist, 1e-300)))
        l1 = rho * _mod2pi(k0 * (psi - h0), snap)
        l3 = rho * _mod2pi(k1 * (h1 - psi), snap)
        if best < 0 or (l1 + straight) + l3 < (b1 + b2) + b3:
            best = w
            b1 = l1
            b2 = straight
            b3 = l3
    return best, b1, b2, b3


@njit(cache=True)
def smooth_kernel(wp, hd, rho, step, allowed):  # pragma: no cover - numba
    """The smoothing of distinct waypoints ``wp`` (k, 3) at headings ``hd`` (k,), turning
    radius ``rho``, samples at most ``step`` apart, the words ``allowed`` (4,) bool:
    ``(points (m, 3), headings (m,), waypoint index (k,), words (k - 1,), lengths (k - 1, 3),
    failed)``, ``failed`` the first pair of poses no allowed word joins (-1: none)."""
    k = wp.shape[0]
    npc = max(k - 1, 0)
    words = np.empty(npc, dtype=np.int64)
    lengths = np.empty((npc, 3))
    counts = np.empty(npc, dtype=np.int64)
    m = 1
    for i in range(npc):
        w, l1, l2, l3 = _shortest(wp[i, 0], wp[i, 1], hd[i], wp[i + 1, 0], wp[i + 1, 1],
                                  hd[i + 1], rho, allowed)  # fmt: skip
        if w < 0:
            return (np.empty((0, 3)), np.empty(0), np.empty(0, dtype=np.int64), words, lengths,
                    i)  # fmt: skip
        words[i] = w
        lengths[i, 0] = l1
        lengths[i, 1] = l2
        lengths[i, 2] = l3
        total = (l1 + l2) + l3
        counts[i] = max(2, math.ceil(total / step) + 1)
        m += counts[i] - 1
    pts = np.empty((m, 3))
    heads = np.empty(m)
    index = np.empty(k, dtype=np.int64)
    pts[0, 0] = wp[0, 0]
    pts[0, 1] = wp[0, 1]
    pts[0, 2] = wp[0, 2]
    heads[0] = _wrap(hd[0])
    index[0] = 0
    r = 1
    inv = 1.0 / rho
    for i in range(npc):
        l1 = lengths[i, 0]
        l2 = lengths[i, 1]
        l3 = lengths[i, 2]
        tot = (l1 + l2) + l3
        n = counts[i]
        div = float(n - 1)
        inc = tot / div
        c1 = _FIRST[words[i]] * inv
        c3 = _LAST[words[i]] * inv
        za = wp[i, 2]
        zb = wp[i + 1, 2]
        fstep = 1.0 / div
        for j in range(1, n):
            if j == n - 1:  # the pose and the waypoint exactly
                pts[r, 0] = wp[i + 1, 0]
                pts[r, 1] = wp[i + 1, 1]
                pts[r, 2] = zb
                heads[r] = _wrap(hd[i + 1])
                r += 1
                continue
            fj = float(j)
            s = ((fj / div) * tot if inc == 0.0 else fj * inc) + 0.0
            x = wp[i, 0]
            y = wp[i, 1]
            h = hd[i]
            # the first arc, the straight, the last arc (sample_pieces' closed forms)
            a = min(max(s, 0.0), l1)
            h1 = h + c1 * a
            rr = 1.0 / c1
            x = x + rr * (math.sin(h1) - math.sin(h))
            y = y + rr * (math.cos(h) - math.cos(h1))
            h = h1
            d = min(max(s - l1, 0.0), l2)
            x = x + d * math.cos(h)
            y = y + d * math.sin(h)
            a = min(max(s - l1 - l2, 0.0), l3)
            h1 = h + c3 * a
            rr = 1.0 / c3
            x = x + rr * (math.sin(h1) - math.sin(h))
            y = y + rr * (math.cos(h) - math.cos(h1))
            frac = fj * fstep + 0.0
            pts[r, 0] = x
            pts[r, 1] = y
            pts[r, 2] = za + (zb - za) * frac
            heads[r] = _wrap(h1)
            r += 1
        index[i + 1] = r - 1
    return pts, heads, index, words, lengths, -1


@njit(cache=True)
def headings_kernel(p):  # pragma: no cover - numba
    """:func:`uavplan.smoothing.dubins.waypoint_headings` of ``p`` (n, 2|3), the same steps:
    each segment's unit direction (zero-length ones take the previous one's, leading ones the
    first), the bisector at interior waypoints (an exact reversal: the incoming direction
    turned 90 degrees left), wrapped to ``[-pi, pi)``."""
    n = p.shape[0]
    out = np.zeros(n)
    if n < 2:
        return out
    ux = np.zeros(n - 1)
    uy = np.zeros(n - 1)
    ok = np.zeros(n - 1, dtype=np.bool_)
    first = -1
    for i in range(n - 1):
        dx = p[i + 1, 0] - p[i, 0]
        dy = p[i + 1, 1] - p[i, 1]
        nm = math.hypot(dx, dy)
        if nm > 0.0:
            ux[i] = dx / nm
            uy[i] = dy / nm
            ok[i] = True
            if first < 0:
                first = i
    if first < 0:
        return out
    src = first
    for i in range(n - 1):  # forward from the previous valid one, leading ones the first
        if ok[i]:
            src = i
        ux[i] = ux[src]
        uy[i] = uy[src]
    out[0] = _wrap(math.atan2(uy[0], ux[0]))
    for i in range(1, n - 1):
        sx = ux[i - 1] + ux[i]
        sy = uy[i - 1] + uy[i]
        if math.hypot(sx, sy) < 1e-12:
            sx = -uy[i - 1]
            sy = ux[i - 1]
        out[i] = _wrap(math.atan2(sy, sx))
    out[n - 1] = _wrap(math.atan2(uy[n - 2], ux[n - 2]))
    return out
