"""Post-processing of a 3-D polyline in Numba, judged by the compiled segment check of the
motion validator (:attr:`uavplan.problems.validity.MotionValidator.segment_kernel`): the
greedy line-of-sight shortcut and an elastic-band tightening (RRT*'s ``tighten`` option,
:mod:`uavplan.planners.sampling.rrt_star`). References in Python: :func:`shortcut_reference` is
:func:`uavplan.problems.validity.greedy_shortcut`'s rule, :func:`band_reference` the band's;
the tests compare them.

**Shortcut.** From each kept vertex, jump to the farthest later vertex whose straight segment
is valid (checked farthest first, so the first valid one ends the search), the next vertex
when none is: never longer, start and goal kept.

**Band.** Subdivide every segment into equal pieces of at most ``spacing`` metres, then sweep
the interior points in order: move each towards the midpoint of its two neighbours by the
first share of :data:`SHARES` whose two segments are valid (a point of a valid path that does
not move keeps its valid segments, so the path stays valid). Moving a point towards that
midpoint never lengthens the path (``|a - p| + |p - b|`` is convex in ``p`` with its least
value at the midpoint). Sweeps stop when one shortens the path by less than ``tol`` metres, or
after ``rounds``. Start and goal are kept.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.planners.sampling._rrt_star_kernels import _check, dist3

FloatArray = NDArray[np.float64]

#: The shares of the move towards the neighbours' midpoint that the band tries, in order.
SHARES = (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125)
#: The band stops after a sweep that shortens the path by less than this, metres.
TOL = 1e-3


@njit(cache=True)
def shortcut(path, kargs):  # pragma: no cover - numba
    """Greedy line-of-sight shortcut of ``path`` (n, 3); returns (kept vertices, checks)."""
    n = path.shape[0]
    keep = np.empty(n, dtype=np.int64)
    keep[0] = 0
    m = 1
    a = 0
    checks = 0
    edge = np.empty((1, 2, 3))
    while a < n - 1:
        nxt = a + 1
        for j in range(n - 1, a, -1):
            checks += 1
            if _check(edge, path[a], path[j], kargs):
                nxt = j
                break
        a = nxt
        keep[m] = a
        m += 1
    return path[keep[:m]].copy(), checks


@njit(cache=True)
def subdivide(path, spacing):  # pragma: no cover - numba
    """Every segment cut into equal pieces of at most ``spacing`` (ends kept exactly)."""
    n = path.shape[0]
    counts = np.empty(n - 1, dtype=np.int64)
    total = 1
    for s in range(n - 1):
        a, b = path[s], path[s + 1]
        k = max(1, int(np.ceil(dist3(a[0], a[1], a[2], b[0], b[1], b[2]) / spacing)))
        counts[s] = k
        total += k
    out = np.empty((total, 3))
    out[0] = path[0]
    m = 1
    for s in range(n - 1):
        k = counts[s]
        for i in range(1, k):
            for d in range(3):
                out[m, d] = path[s, d] + (path[s + 1, d] - path[s, d]) * (i / k)
            m += 1
        out[m] = path[s + 1]
        m += 1
    return out


@njit(cache=True)
def length(path):  # pragma: no cover - numba
    total = 0.0
    for s in range(path.shape[0] - 1):
        a, b = path[s], path[s + 1]
        total += dist3(a[0], a[1], a[2], b[0], b[1], b[2])
    return total


@njit(cache=True)
def band(path, spacing, rounds, tol, shares, kargs):  # pragma: no cover - numba
    """The elastic band of the module docstring; returns (points, sweeps, checks)."""
    P = subdivide(path, spacing)
    n = P.shape[0]
    e1 = np.empty((1, 2, 3))
    e2 = np.empty((1, 2, 3))
    q = np.empty(3)
    checks = 0
    sweeps = 0
    for _ in range(rounds):
        sweeps += 1
        before = length(P)
        for i in range(1, n - 1):
            for s in shares:
                for d in range(3):
                    q[d] = P[i, d] + s * (0.5 * (P[i - 1, d] + P[i + 1, d]) - P[i, d])
                checks += 1
                if not _check(e1, P[i - 1], q, kargs):
                    continue
                checks += 1
                if _check(e2, q, P[i + 1], kargs):
                    for d in range(3):
                        P[i, d] = q[d]
                    break
        if before - length(P) < tol:
            break
    return P, sweeps, checks


def tighten(
    path: FloatArray, kargs: tuple[object, ...], spacing: float, rounds: int, tol: float = TOL
) -> tuple[FloatArray, int]:
    """Shortcut, band, shortcut: a valid path (n, 3) made shorter; returns it and the segment
    checks spent."""
    p = np.ascontiguousarray(path, dtype=np.float64)
    s1, c1 = shortcut(p, kargs)
    b, _, c2 = band(s1, float(spacing), int(rounds), float(tol), np.asarray(SHARES), kargs)
    s2, c3 = shortcut(b, kargs)
    return s2, int(c1 + c2 + c3)


# ------------------------------------------------------------------------------ references
def shortcut_reference(ok: object, path: FloatArray) -> FloatArray:
    """:func:`shortcut` in Python, ``ok(a, b)`` deciding a segment (every later vertex checked,
    the farthest valid one taken, as :func:`uavplan.problems.validity.greedy_shortcut`)."""
    wp = np.asarray(path, dtype=np.float64)
    n, keep, a = len(wp), [0], 0
    while a < n - 1:
        good = [j for j in range(a + 1, n) if ok(wp[a], wp[j])]  # type: ignore[operator]
        a = max(good) if good else a + 1
        keep.append(a)
    return wp[keep]


def band_reference(
    ok: object, path: FloatArray, spacing: float, rounds: int, tol: float
) -> FloatArray:
    """:func:`band` in Python (:func:`subdivide` shared), ``ok(a, b)`` deciding a segment."""
    P = subdivide(np.ascontiguousarray(path, dtype=np.float64), float(spacing))
    for _ in range(rounds):
        before = float(length(P))
        for i in range(1, len(P) - 1):
            for s in SHARES:
                q = P[i] + s * (0.5 * (P[i - 1] + P[i + 1]) - P[i])
                if ok(P[i - 1], q) and ok(q, P[i + 1]):  # type: ignore[operator]
                    P[i] = q
                    break
        if before - float(length(P)) < tol:
            break
    return P
