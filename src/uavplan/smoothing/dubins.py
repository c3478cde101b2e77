"""Dubins CSC smoothing of waypoint paths (PPSwarm, Meng et al. 2024, Drones 8:192, Sect. 4.4).

PPSwarm smooths a planned polyline with Dubins curves of turning radius ``r_δ`` (20 m in its
Sect. 5.1, ``uavplan.world.scenario.UAV.turn_radius``) and, to avoid the high-curvature CCC
words, uses only the four CSC words LSL, LSR, RSL and RSR, keeping the shortest one that
exists. This module writes them by hand (the PyPI ``dubins`` package does not build on
Python 3.11).

Frame and units: metres, x east, y north, z up; a planar pose is ``(x, y, heading)`` with the
heading in radians from +x, counter-clockwise. ``L`` is a left (counter-clockwise) arc of
radius ``rho``, ``R`` a right (clockwise) one, ``S`` a straight segment tangent to both arcs.

Construction (geometric, not the normalized closed forms): each arc lives on the circle of
radius ``rho`` to the left or right of its pose. With ``V = c1 - c0`` between the two circle
centres, the straight has length ``|V|`` and heading ``atan2(V)`` for LSL and RSR (outer
tangent), and length ``l = sqrt(|V|^2 - 4 rho^2)`` and heading ``atan2(V) ± atan2(2 rho, l)``
for LSR (+) and RSL (-) (inner tangent; it exists only if ``|V| >= 2 rho``, i.e. the circles do
not overlap). Arc angles are the headings' differences taken in ``[0, 2π)``; an angle short
of ``2π`` by no more than the round-off of the tangent heading (about ``1e-13 (1 + scale /
|V|)`` rad, at most ``1e-9``) is taken as 0, and for LSL and RSR two centres closer than
``1e-11`` times the coordinate scale are taken as one circle (a single arc, no straight), so
that round-off does not turn a straight run or a plain turn into a full loop. Either moves the
end pose by round-off only (about ``1e-13`` of the coordinate scale, ``1e-9`` rad at worst);
closer to ill-conditioned poses (centres ``1e-11`` to ``1e-4`` of the scale apart) a round-off
loop can remain: the curve still meets both poses, it is just not the shortest. LSL and RSR
always exist, so :func:`dubins_csc` with all four words never fails.

:func:`smooth_path` joins consecutive 3-D waypoints with the shortest CSC curve between their
horizontal poses (headings from :func:`waypoint_headings`) and interpolates the altitude
linearly in horizontal arc length, so each piece climbs at a constant slope and its 3-D length
is ``sqrt(L_h^2 + Δz^2)`` exactly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uavplan.world.tolerances import DUPLICATE_TOL

FloatArray = NDArray[np.float64]
Pose = tuple[float, float, float]

CSC_KINDS: tuple[str, ...] = ("LSL", "LSR", "RSL", "RSR")
"""The four CSC words PPSwarm uses, in the order ties are broken."""

TWO_PI = 2.0 * math.pi
_EPS = 1e-13  # relative round-off allowance (a few hundred ulps)
_MAX_SNAP = 1e-9  # never take an arc angle further than this below 2π as 0, rad
_SAME_CIRCLE = 1e-11  # circle centres closer than this times the coordinate scale coincide


def _mod2pi(angle: float, snap: float) -> float:
    """``angle`` in ``[0, 2π)``, with values less than ``snap`` below ``2π`` taken as 0."""
    a = math.fmod(angle, TWO_PI)
    if a < 0.0:
        a += TWO_PI
    if a >= TWO_PI - snap:
        a = 0.0
    return a


def wrap_angle(angle: ArrayLike) -> FloatArray:
    """Angles (any shape, rad) wrapped to ``[-π, π)``; same shape."""
    a = np.asarray(angle, dtype=np.float64)
    return np.asarray(np.mod(a + math.pi, TWO_PI) - math.pi, dtype=np.float64)


def _as_pose(q: Sequence[float] | ArrayLike, name: str) -> Pose:
    arr = np.asarray(q, dtype=np.float64).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a finite (x, y, heading) triple, got {q!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _turn_sign(letter: str) -> float:
    """+1 for a left (counter-clockwise) turn, -1 for a right one."""
    return 1.0 if letter == "L" else -1.0


def _centre(q: Pose, rho: float, letter: str) -> tuple[float, float]:
    """Centre of the turning circle of radius ``rho`` on the ``letter`` side of pose ``q``."""
    k = _turn_sign(letter)
    return (q[0] - k * rho * math.sin(q[2]), q[1] + k * rho * math.cos(q[2]))


def _advance(
    x: FloatArray, y: FloatArray, h: FloatArray, s: FloatArray, curvature: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Move poses ``(x, y, h)`` (each (k,)) forward by ``s`` (k,) metres at signed ``curvature``.

    ``curvature`` is ``+1/rho`` (left arc), ``-1/rho`` (right arc) or 0 (straight); returns the
    new ``(x, y, h)``, each (k,), headings not wrapped.
    """
    if curvature == 0.0:
        return x + s * np.cos(h), y + s * np.sin(h), h
    h1 = h + curvature * s
    r = 1.0 / curvature  # signed radius
    return x + r * (np.sin(h1) - np.sin(h)), y + r * (np.cos(h) - np.cos(h1)), h1


@dataclass(frozen=True)
class DubinsPath:
    """One CSC Dubins curve from pose ``q0`` to pose ``q1``.

    ``q0`` and ``q1`` are ``(x, y, heading)`` in metres and radians (from +x, CCW); ``rho`` is
    the turning radius in metres; ``kind`` one of ``"LSL"``, ``"LSR"``, ``"RSL"``, ``"RSR"``;
    ``lengths`` the first arc, the straight and the second arc, in metres (each ``>= 0``).
    Build it with :func:`dubins_csc`.
    """

    q0: Pose
    q1: Pose
    rho: float
    kind: str
    lengths: tuple[float, float, float]

    @property
    def length(self) -> float:
        """Total length of the curve, metres."""
        return float(sum(self.lengths))

    @property
    def curvatures(self) -> tuple[float, float, float]:
        """Signed curvature of the three pieces, 1/m (``+1/rho`` left, ``-1/rho`` right, 0)."""
        k = 1.0 / self.rho
        return (_turn_sign(self.kind[0]) * k, 0.0, _turn_sign(self.kind[2]) * k)

    @property
    def max_curvature(self) -> float:
        """Largest absolute curvature over the pieces of nonzero length, 1/m (0 if straight)."""
        a1, _, a2 = self.lengths
        return 1.0 / self.rho if (a1 > 0.0 or a2 > 0.0) else 0.0

    def poses_at(self, s: ArrayLike) -> FloatArray:
        """Poses at arc lengths ``s`` (k,) metres from ``q0``, clipped to ``[0, length]``.

        Returns (k, 3) ``x, y, heading`` with headings wrapped to ``[-π, π)``. Computed in closed
        form piece by piece (no integration), so ``poses_at([length])`` is the analytic end pose,
        equal to ``q1`` up to round-off.
        """
        s_arr = np.atleast_1d(np.asarray(s, dtype=np.float64))
        l1, l2, l3 = self.lengths
        k1, _, k3 = self.curvatures
        n = s_arr.shape[0]
        x = np.full(n, self.q0[0])
        y = np.full(n, self.q0[1])
        h = np.full(n, self.q0[2])
        x, y, h = _advance(x, y, h, np.clip(s_arr, 0.0, l1), k1)
        x, y, h = _advance(x, y, h, np.clip(s_arr - l1, 0.0, l2), 0.0)
        x, y, h = _advance(x, y, h, np.clip(s_arr - l1 - l2, 0.0, l3), k3)
        return np.stack([x, y, wrap_angle(h)], axis=1)

    def sample(self, step: float) -> FloatArray:
        """Evenly spaced poses along the curve, at most ``step`` metres apart.

        Returns (n, 3) ``x, y, heading`` (headings wrapped to ``[-π, π)``), ``n >= 2``; the first
        row is ``q0`` and the last ``q1`` exactly (positions bit for bit, headings wrapped).
        """
        if not (step > 0.0 and math.isfinite(step)):
            raise ValueError(f"step must be a positive finite length, got {step!r}")
        total = self.length
        n = max(2, math.ceil(total / step) + 1)
        out = self.poses_at(np.linspace(0.0, total, n))
        out[0] = (self.q0[0], self.q0[1], float(wrap_angle(self.q0[2])))
        out[-1] = (self.q1[0], self.q1[1], float(wrap_angle(self.q1[2])))
        return out


def sample_pieces(pieces: Sequence[DubinsPath], step: float) -> list[FloatArray]:
    """``[p.sample(step) for p in pieces]`` bit for bit, in one vectorized pass over every
    sample of every piece (the same operations on each sample: NumPy's ``linspace`` formula,
    the three pieces advanced in closed form, the exact ends); what :func:`smooth_path` uses,
    :meth:`DubinsPath.sample` being its reference."""
    if not (step > 0.0 and math.isfinite(step)):
        raise ValueError(f"step must be a positive finite length, got {step!r}")
    if not pieces:
        return []
    totals = [p.length for p in pieces]
    counts = np.array([max(2, math.ceil(t / step) + 1) for t in totals], dtype=np.intp)
    ends = np.cumsum(counts)
    starts = ends - counts
    piece = np.repeat(np.arange(len(pieces)), counts)

    def per(values: Sequence[float]) -> FloatArray:
        return np.asarray(values, dtype=np.float64)[piece]

    j = np.arange(int(ends[-1]), dtype=np.float64) - per([float(a) for a in starts])
    tot = per(totals)
    div = per([float(c - 1) for c in counts])
    inc = tot / div
    # np.linspace(0.0, total, n): j * (total / (n - 1)) + 0.0, or (j / (n - 1)) * total where
    # that step is 0; the last one exactly total
    s = np.where(inc == 0, (j / div) * tot, j * inc) + 0.0
    s[ends - 1] = tot[ends - 1]
    l1, l2, l3 = (per([p.lengths[i] for p in pieces]) for i in range(3))
    k1 = per([p.curvatures[0] for p in pieces])
    k3 = per([p.curvatures[2] for p in pieces])
    x = per([p.q0[0] for p in pieces])
    y = per([p.q0[1] for p in pieces])
    h = per([p.q0[2] for p in pieces])
    x, y, h = _advance_each(x, y, h, np.clip(s, 0.0, l1), k1)
    d = np.clip(s - l1, 0.0, l2)
    x, y = x + d * np.cos(h), y + d * np.sin(h)
    x, y, h = _advance_each(x, y, h, np.clip(s - l1 - l2, 0.0, l3), k3)
    out = np.stack([x, y, wrap_angle(h)], axis=1)
    for i, p in enumerate(pieces):  # the exact end poses (positions bit for bit)
        out[starts[i]] = (p.q0[0], p.q0[1], float(wrap_angle(p.q0[2])))
        out[ends[i] - 1] = (p.q1[0], p.q1[1], float(wrap_angle(p.q1[2])))
    return np.split(out, ends[:-1])


def _advance_each(
    x: FloatArray, y: FloatArray, h: FloatArray, s: FloatArray, curvature: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`_advance` with a curvature per pose (arcs only: none is 0)."""
    h1 = h + curvature * s
    r = 1.0 / curvature
    return x + r * (np.sin(h1) - np.sin(h)), y + r * (np.cos(h) - np.cos(h1)), h1


def _csc_between(
    q0: Pose,
    q1: Pose,
    rho: float,
    kind: str,
    c0: tuple[float, float],
    c1: tuple[float, float],
    scale: float,
) -> tuple[float, float, float] | None:
    """Arc, straight, arc lengths (m) of the CSC word ``kind`` from ``q0`` to ``q1``, given the
    turning circles' centres ``c0`` (of ``q0`` on the side of ``kind[0]``) and ``c1`` (of
    ``q1``, ``kind[2]``) and the coordinate ``scale`` (``rho`` plus the largest coordinate);
    ``None`` when the word does not exist (LSR or RSL with overlapping circles)."""
    first, last = kind[0], kind[2]
    cx0, cy0 = c0
    cx1, cy1 = c1
    vx, vy = cx1 - cx0, cy1 - cy0
    dist = math.hypot(vx, vy)
    if first == last:  # outer tangent: parallel to the line of centres
        if dist <= _SAME_CIRCLE * scale:
            # One circle (the centres apart by round-off only, whose direction is noise): turn
            # on it from q0 to q1 without a straight.
            straight, psi = 0.0, q0[2]
        else:
            straight, psi = dist, math.atan2(vy, vx)
    else:  # inner tangent: crosses the line of centres
        sq = dist * dist - 4.0 * rho * rho
        if sq < -_EPS * rho * scale:
            return None
        straight = math.sqrt(max(sq, 0.0))
        offset = math.atan2(2.0 * rho, straight)
        psi = math.atan2(vy, vx) + (offset if first == "L" else -offset)
    # Round-off in psi is about ulp(scale) / dist; an arc that short of 2π is a zero arc.
    snap = min(_MAX_SNAP, _EPS * (1.0 + abs(q0[2]) + abs(q1[2]) + scale / max(dist, 1e-300)))
    k0, k1 = _turn_sign(first), _turn_sign(last)
    arc0 = _mod2pi(k0 * (psi - q0[2]), snap)
    arc1 = _mod2pi(k1 * (q1[2] - psi), snap)
    return (rho * arc0, straight, rho * arc1)


def dubins_csc(
    q0: Sequence[float] | ArrayLike,
    q1: Sequence[float] | ArrayLike,
    rho: float,
    kinds: Sequence[str] = CSC_KINDS,
) -> DubinsPath:
    """Shortest CSC Dubins curve among ``kinds`` from pose ``q0`` to pose ``q1``.

    ``q0``, ``q1``: ``(x, y, heading)``, metres and radians from +x, CCW. ``rho``: turning
    radius, metres. ``kinds``: subset of ``("LSL", "LSR", "RSL", "RSR")``; ties go to the first
    listed. Raises ``ValueError`` if ``rho`` is not positive and finite, a pose is not finite, a
    kind is unknown, or none of ``kinds`` exists (LSR and RSL need the start circle and the end
    circle not to overlap; LSL and RSR always exist). Coincident poses give length 0.
    """
    p0 = _as_pose(q0, "q0")
    p1 = _as_pose(q1, "q1")
    rho = float(rho)
    if not (rho > 0.0 and math.isfinite(rho)):
        raise ValueError(f"rho must be a positive finite radius, got {rho!r}")
    return _shortest_csc(p0, p1, rho, _checked_kinds(kinds))


def _checked_kinds(kinds: Sequence[str]) -> tuple[str, ...]:
    kinds = tuple(kinds)
    if not kinds:
        raise ValueError("kinds must not be empty")
    for kind in kinds:
        if kind not in CSC_KINDS:
            raise ValueError(f"unknown Dubins CSC kind {kind!r}; expected one of {CSC_KINDS}")
    return kinds


def _shortest_csc(p0: Pose, p1: Pose, rho: float, kinds: tuple[str, ...]) -> DubinsPath:
    """:func:`dubins_csc` of checked poses (Python floats), radius and kinds: each turning
    circle's centre computed once for the words that share it."""
    best: DubinsPath | None = None
    scale = rho + max(abs(p0[0]), abs(p0[1]), abs(p1[0]), abs(p1[1]))
    centres: dict[tuple[int, str], tuple[float, float]] = {}
    for kind in kinds:
        first, last = kind[0], kind[2]
        c0 = centres.get((0, first))
        if c0 is None:
            c0 = centres[(0, first)] = _centre(p0, rho, first)
        c1 = centres.get((1, last))
        if c1 is None:
            c1 = centres[(1, last)] = _centre(p1, rho, last)
        lengths = _csc_between(p0, p1, rho, kind, c0, c1, scale)
        if lengths is None:
            continue
        if best is None or sum(lengths) < best.length:
            best = DubinsPath(q0=p0, q1=p1, rho=rho, kind=kind, lengths=lengths)
    if best is None:
        raise ValueError(
            f"no CSC Dubins curve of kinds {kinds} from {p0} to {p1} with rho={rho} "
            "(the turning circles overlap)"
        )
    return best


def waypoint_headings(waypoints: ArrayLike) -> FloatArray:
    """Horizontal heading at each waypoint for Dubins smoothing.

    ``waypoints``: (n, 2) or (n, 3) metres (only x and y are used). Returns (n,) headings in
    ``[-π, π)``, radians from +x, CCW:

    * first waypoint: direction of the first segment; last: direction of the last segment;
    * interior waypoint: the bisector of the incoming and outgoing directions, i.e. the
      direction of the sum of the two unit vectors, so the curve meets the waypoint half-way
      through the turn; for an exact reversal (the two directions opposite) the incoming
      direction turned 90° left.

    Segments of zero horizontal length take the direction of the previous segment of nonzero
    length (the next one for leading zero segments); if all are zero, every heading is 0.
    """
    p = np.asarray(waypoints, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"waypoints must be (n, 2) or (n, 3), got shape {p.shape}")
    n = p.shape[0]
    if n < 2:
        return np.zeros(n)
    d = np.diff(p[:, :2], axis=0)  # (n-1, 2)
    norm = np.hypot(d[:, 0], d[:, 1])
    ok = norm > 0.0
    if not np.any(ok):
        return np.zeros(n)
    u = np.zeros_like(d)
    u[ok] = d[ok] / norm[ok, None]
    # Fill zero-length segments: forward from the previous valid one, leading ones backward.
    idx = np.where(ok, np.arange(n - 1), -1)
    idx = np.maximum.accumulate(idx)
    idx[idx < 0] = int(np.argmax(ok))
    u = u[idx]
    s = u[:-1] + u[1:]  # (n-2, 2) bisector directions of interior waypoints
    s_norm = np.hypot(s[:, 0], s[:, 1])
    rev = s_norm < 1e-12
    s[rev] = np.stack([-u[:-1][rev, 1], u[:-1][rev, 0]], axis=1)  # incoming turned 90° left
    dirs = np.concatenate([u[:1], s, u[-1:]], axis=0)
    return wrap_angle(np.arctan2(dirs[:, 1], dirs[:, 0]))


def discrete_curvature(points_xy: ArrayLike) -> FloatArray:
    """Menger curvature of consecutive sample triples of a planar polyline.

    ``points_xy``: (m, 2) or (m, 3) metres (only x and y are used). Returns (max(m - 2, 0),) in
    1/m: ``2 |(b - a) x (c - b)| / (|b - a| |c - b| |c - a|)``, the inverse radius of the circle
    through ``a, b, c``. A triple with a zero-length side ``a-b`` or ``b-c`` (duplicate samples)
    gives 0; a reversal (``c - b`` opposite to ``b - a``, or ``c == a``) gives ``inf``.
    """
    p = np.asarray(points_xy, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] < 2:
        raise ValueError(f"points must be (m, 2) or (m, 3), got shape {p.shape}")
    if p.shape[0] < 3:
        return np.zeros(0)
    p = p[:, :2] - p[0, :2]  # relative coordinates: less cancellation
    ab = p[1:-1] - p[:-2]
    bc = p[2:] - p[1:-1]
    ac = p[2:] - p[:-2]
    lab = np.hypot(ab[:, 0], ab[:, 1])
    lbc = np.hypot(bc[:, 0], bc[:, 1])
    lac = np.hypot(ac[:, 0], ac[:, 1])
    cross = np.abs(ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0])
    dot = ab[:, 0] * bc[:, 0] + ab[:, 1] * bc[:, 1]
    den = lab * lbc * lac
    out = np.zeros(p.shape[0] - 2)
    good = den > 0.0
    out[good] = 2.0 * cross[good] / den[good]
    nondegenerate = (lab > 0.0) & (lbc > 0.0)
    reversal = nondegenerate & ((lac == 0.0) | ((dot < 0.0) & (cross <= 1e-12 * lab * lbc)))
    out[reversal] = np.inf
    return out


def max_discrete_curvature(points_xy: ArrayLike) -> float:
    """Largest :func:`discrete_curvature` of a planar polyline (m, 2|3), 1/m; 0 if ``m < 3``."""
    k = discrete_curvature(points_xy)
    return float(np.max(k)) if k.size else 0.0


@dataclass(frozen=True, eq=False)
class SmoothedPath:
    """A waypoint path smoothed with Dubins CSC curves (see :func:`smooth_path`).

    * ``points``: (m, 3) dense polyline x, y, z in metres; every waypoint appears exactly.
    * ``headings``: (m,) horizontal heading at each point, rad in ``[-π, π)``.
    * ``waypoints``: (k, 3) the waypoints after dropping consecutive duplicates.
    * ``waypoint_index``: (k,) int, ``points[waypoint_index] == waypoints``.
    * ``pieces``: the k - 1 horizontal Dubins curves, one per consecutive waypoint pair.
    * ``turn_radius``: metres.
    """

    points: FloatArray
    headings: FloatArray
    waypoints: FloatArray
    waypoint_index: NDArray[np.intp]
    pieces: tuple[DubinsPath, ...]
    turn_radius: float

    @property
    def kinds(self) -> tuple[str, ...]:
        """CSC word of each piece, (k - 1) strings."""
        return tuple(p.kind for p in self.pieces)

    @property
    def horizontal_lengths(self) -> FloatArray:
        """Horizontal (Dubins) length of each piece, (k - 1,) metres."""
        return np.array([p.length for p in self.pieces], dtype=np.float64)

    @property
    def piece_lengths(self) -> FloatArray:
        """3-D length of each piece, (k - 1,) metres: ``sqrt(L_h^2 + Δz^2)`` (constant slope)."""
        dz = np.diff(self.waypoints[:, 2])
        return np.asarray(np.hypot(self.horizontal_lengths, dz), dtype=np.float64)

    @property
    def length(self) -> float:
        """Total 3-D length of the smoothed path, metres (analytic, not the polyline's)."""
        return float(np.sum(self.piece_lengths))

    def curvature(self) -> FloatArray:
        """Discrete horizontal curvature at the interior samples, (m - 2,) 1/m.

        Menger curvature of consecutive ``points`` triples (:func:`discrete_curvature`); never
        above ``1 / turn_radius`` up to round-off for samples of the true curves.
        """
        return discrete_curvature(self.points)


def drop_consecutive_duplicates(p: FloatArray, atol: float) -> NDArray[np.intp]:
    """Indices of the rows of ``p`` (n, d) kept after dropping rows within ``atol`` m of the
    last kept row; returns (k,) int, first row always kept."""
    if p.shape[0] > 1 and bool(np.all(np.linalg.norm(np.diff(p, axis=0), axis=1) > atol)):
        return np.arange(p.shape[0], dtype=np.intp)  # no duplicates: each row's predecessor kept
    keep = [0]
    for i in range(1, p.shape[0]):
        if float(np.linalg.norm(p[i] - p[keep[-1]])) > atol:
            keep.append(i)
    return np.asarray(keep, dtype=np.intp)


def smooth_path(
    waypoints: ArrayLike,
    turn_radius: float,
    step: float = 5.0,
    headings: ArrayLike | None = None,
    *,
    kinds: Sequence[str] = CSC_KINDS,
    duplicate_tol: float = DUPLICATE_TOL,
) -> SmoothedPath:
    """Smooth a 3-D waypoint path with Dubins CSC curves (PPSwarm Sect. 4.4).

    ``waypoints``: (n, 3) x, y, z in metres, start and goal included. Consecutive waypoints
    closer than ``duplicate_tol`` m (3-D) are dropped first (with their headings). Each pair of
    consecutive waypoints is joined, in the horizontal plane, by the shortest curve of ``kinds``
    (:func:`dubins_csc`, radius ``turn_radius`` m) between their poses; the headings are
    ``headings`` ((n,) rad, one per input waypoint) or else :func:`waypoint_headings`. The
    altitude moves linearly in horizontal arc length from one waypoint's z to the next's (so z
    is monotone between waypoints); a piece with no horizontal extent (a purely vertical
    segment with equal headings) keeps just its two end points.

    Each piece is sampled at most ``step`` m apart (horizontally); the pieces are chained
    without repeating shared end points. Raises ``ValueError`` on bad shapes, non-finite input,
    a non-positive ``turn_radius`` or ``step``, or (only with a restricted ``kinds``) a pair
    of poses that no allowed word joins.

    Computed in one Numba pass (:func:`uavplan.smoothing._dubins_kernels.smooth_kernel`);
    :func:`smooth_path_reference` is the same in Python, to round-off.
    """
    from uavplan.smoothing._dubins_kernels import smooth_kernel

    wp, hd, rho, kinds = _smoothing_input(waypoints, turn_radius, step, headings, kinds,
                                          duplicate_tol, compiled=True)  # fmt: skip
    allowed = np.array([k in kinds for k in CSC_KINDS])
    pts, heads, index, words, lengths, failed = smooth_kernel(
        np.ascontiguousarray(wp), np.ascontiguousarray(hd, dtype=np.float64), rho, float(step),
        allowed,
    )  # fmt: skip
    poses = [(float(x), float(y), float(h)) for x, y, h in zip(wp[:, 0], wp[:, 1], hd, strict=True)]
    if failed >= 0:
        _shortest_csc(poses[failed], poses[failed + 1], rho, kinds)  # raises, saying which
    pieces = tuple(
        DubinsPath(poses[i], poses[i + 1], rho, CSC_KINDS[w], (float(a), float(b), float(c)))
        for i, (w, (a, b, c)) in enumerate(zip(words.tolist(), lengths.tolist(), strict=True))
    )
    return SmoothedPath(pts, heads, wp, np.asarray(index, dtype=np.intp), pieces, rho)


def _smoothing_input(
    waypoints: ArrayLike,
    turn_radius: float,
    step: float,
    headings: ArrayLike | None,
    kinds: Sequence[str],
    duplicate_tol: float,
    compiled: bool = False,
) -> tuple[FloatArray, FloatArray, float, tuple[str, ...]]:
    """:func:`smooth_path`'s arguments checked: the distinct waypoints (k, 3), their headings
    (k,; given, else :func:`waypoint_headings`, in Numba if ``compiled``), the radius and the
    kinds."""
    p = np.asarray(waypoints, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 1:
        raise ValueError(f"waypoints must be (n, 3) with n >= 1, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("waypoints must be finite")
    rho = float(turn_radius)
    if not (rho > 0.0 and math.isfinite(rho)):
        raise ValueError(f"turn_radius must be positive and finite, got {turn_radius!r}")
    if not (step > 0.0 and math.isfinite(step)):
        raise ValueError(f"step must be positive and finite, got {step!r}")
    keep = drop_consecutive_duplicates(p, duplicate_tol)
    wp = p[keep].copy()
    if headings is None and compiled:
        from uavplan.smoothing._dubins_kernels import headings_kernel

        hd = headings_kernel(wp)  # waypoint_headings, to round-off
    elif headings is None:
        hd = waypoint_headings(wp)
    else:
        h_in = np.asarray(headings, dtype=np.float64).reshape(-1)
        if h_in.shape != (p.shape[0],) or not np.all(np.isfinite(h_in)):
            raise ValueError(f"headings must be ({p.shape[0]},) finite, got {h_in.shape}")
        hd = h_in[keep]
    return wp, np.asarray(hd, dtype=np.float64), rho, _checked_kinds(kinds)


def smooth_path_reference(
    waypoints: ArrayLike,
    turn_radius: float,
    step: float = 5.0,
    headings: ArrayLike | None = None,
    *,
    kinds: Sequence[str] = CSC_KINDS,
    duplicate_tol: float = DUPLICATE_TOL,
) -> SmoothedPath:
    """:func:`smooth_path` in Python: the words by :func:`_shortest_csc`, the samples by
    :func:`sample_pieces` (what the kernel is tested against)."""
    wp, hd, rho, kinds = _smoothing_input(waypoints, turn_radius, step, headings, kinds,
                                          duplicate_tol)  # fmt: skip
    xs, ys, hs = wp[:, 0].tolist(), wp[:, 1].tolist(), hd.tolist()
    pieces = [
        _shortest_csc((xs[i], ys[i], hs[i]), (xs[i + 1], ys[i + 1], hs[i + 1]), rho, kinds)
        for i in range(wp.shape[0] - 1)
    ]
    chunks_xyz: list[FloatArray] = [wp[:1]]
    chunks_h: list[FloatArray] = [wrap_angle(hd[:1])]
    index = [0]
    sampled = sample_pieces(pieces, step)  # (n_i, 3) x, y, heading each; exact ends
    for i, (piece, samples) in enumerate(zip(pieces, sampled, strict=True)):
        a, b = wp[i], wp[i + 1]
        total = piece.length
        if total > 0.0:
            frac = np.linspace(0.0, 1.0, samples.shape[0])
        else:
            frac = np.array([0.0, 1.0])
            samples = samples[[0, -1]]
        z = a[2] + (b[2] - a[2]) * frac
        z[-1] = b[2]
        xyz = np.column_stack([samples[:, :2], z])
        xyz[-1] = b  # the waypoint exactly
        chunks_xyz.append(xyz[1:])
        chunks_h.append(samples[1:, 2])
        index.append(index[-1] + xyz.shape[0] - 1)

    return SmoothedPath(
        points=np.concatenate(chunks_xyz, axis=0),
        headings=np.concatenate(chunks_h),
        waypoints=wp,
        waypoint_index=np.asarray(index, dtype=np.intp),
        pieces=tuple(pieces),
        turn_radius=rho,
    )


def midpoint_poses(waypoints: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Poses for corner-cutting smoothing: the start, the midpoint of every segment and the
    goal, each heading along its segment (the start and goal along the first and last ones).

    Dubins curves between these poses turn *at* each interior waypoint's corner instead of
    passing *through* it (:func:`waypoint_headings`), so a sharp corner is cut by a short arc
    rather than looped around. Returns points (n + 1, 3) and headings (n + 1,) for an (n, 3)
    path of n >= 2 distinct waypoints; consecutive duplicates are dropped first.
    """
    p = np.asarray(waypoints, dtype=np.float64)
    p = p[drop_consecutive_duplicates(p, DUPLICATE_TOL)]
    if p.shape[0] < 2:
        return p.copy(), waypoint_headings(p)
    seg = np.diff(p, axis=0)
    h = waypoint_headings(p)  # handles vertical and degenerate segments
    seg_h = np.where(
        np.hypot(seg[:, 0], seg[:, 1]) > 1e-12, np.arctan2(seg[:, 1], seg[:, 0]), h[:-1]
    )
    mids = 0.5 * (p[:-1] + p[1:])
    pts = np.concatenate([p[:1], mids, p[-1:]])
    heads = np.concatenate([seg_h[:1], seg_h, seg_h[-1:]])
    return pts, wrap_angle(heads)


def schedule(smoothed: SmoothedPath, pose_times: ArrayLike) -> FloatArray:
    """Times of ``smoothed.points`` for a UAV that reaches every pose at its time in
    ``pose_times`` ((k,) s, one per ``smoothed.waypoints``, non-decreasing) and flies each piece
    at a constant speed: within a piece the time grows linearly in 3-D arc length of the
    samples. Returns (m,) seconds; ``times[waypoint_index] == pose_times`` exactly."""
    tp = np.asarray(pose_times, dtype=np.float64).reshape(-1)
    idx = smoothed.waypoint_index
    if tp.shape != idx.shape or not np.all(np.isfinite(tp)):
        raise ValueError(f"pose_times must be ({idx.shape[0]},) finite, got shape {tp.shape}")
    if np.any(np.diff(tp) < 0):
        raise ValueError("pose_times must be non-decreasing")
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(smoothed.points, axis=0), axis=1))])
    out = np.interp(s, s[idx], tp)  # poses are distinct, so s[idx] increases strictly
    out[idx] = tp
    return out
