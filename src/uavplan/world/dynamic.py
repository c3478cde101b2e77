"""Moving obstacles: a sphere (or, in 2-D, a disc) following a timed piecewise-linear trajectory.

RSCDWOA (Zhang et al., Sect. on moving obstacles) moves obstacles along known trajectories; we
store the trajectory as knots ``(times, positions)``, hold the first and last positions outside
them, and compute distances to a timed path exactly (both motions are linear between knots).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from uavplan.world.kernel_arrays import writable
from uavplan.world.reservations import window_min_dist2

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class MovingObstacle:
    """A moving obstacle of ``radius`` metres.

    Attributes:
        radius: metres (> 0).
        times: (K,) strictly increasing seconds.
        positions: (K, 3) metres (2-D input gets z = 0).
    """

    radius: float
    times: FloatArray
    positions: FloatArray

    def __post_init__(self) -> None:
        t = np.atleast_1d(np.asarray(self.times, dtype=np.float64))
        p = np.atleast_2d(np.asarray(self.positions, dtype=np.float64))
        if p.shape[-1] == 2:
            p = np.concatenate([p, np.zeros((p.shape[0], 1))], axis=1)
        if t.ndim != 1 or p.shape != (t.shape[0], 3) or t.shape[0] < 1:
            raise ValueError(
                f"moving obstacle needs K times and K positions, got {t.shape} and {p.shape}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise ValueError("moving obstacle times and positions must be finite")
        if np.any(np.diff(t) <= 0):
            raise ValueError("moving obstacle times must be strictly increasing")
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"moving obstacle radius must be positive, got {self.radius}")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "positions", p)

    def position_at(self, t: ArrayLike) -> FloatArray:
        """Positions at any array of times, (..., 3)."""
        tt = np.asarray(t, dtype=np.float64)
        return np.stack([np.interp(tt, self.times, self.positions[:, k]) for k in range(3)], -1)

    def min_distance(self, paths: ArrayLike, times: ArrayLike) -> FloatArray:
        """Exact min distance, over continuous time, from each segment of timed paths.

        Args:
            paths: (pop, n, 3) metres; times: (pop, n) seconds.
        Returns:
            (pop, n - 1) metres.
        """
        return min_distances((self,), paths, times)[..., 0]


def _timed(paths: ArrayLike, times: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Paths (2-D ones at z = 0) and their times as the kernels take them: contiguous and
    writable (a read-only array would be a second kernel signature to compile)."""
    from uavplan.world.geometry import as_3d

    p = as_3d(np.asarray(paths, dtype=np.float64))
    return p, writable(np.broadcast_to(times, p.shape[:-1]))


def min_distances(
    obstacles: Sequence[MovingObstacle], paths: ArrayLike, times: ArrayLike
) -> FloatArray:
    """:meth:`MovingObstacle.min_distance` to each of ``obstacles``, (pop, n - 1, K), the paths
    (2-D ones at z = 0) and times prepared once for all of them."""
    from uavplan.world.geometry import timed_path_min_distance

    p, tt = _timed(paths, times)
    out = [timed_path_min_distance(p, tt, o.times, o.positions) for o in obstacles]
    return np.stack(out, axis=-1) if out else np.zeros((*p.shape[:-2], p.shape[-2] - 1, 0))


def robust_min_distances(
    obstacles: Sequence[MovingObstacle],
    paths: ArrayLike,
    times: ArrayLike,
    delta0: float,
    rho: float,
) -> FloatArray:
    """:func:`min_distances` when the UAV's schedule may drift (take-off error ``delta0`` s,
    speed error ``rho``; :mod:`uavplan.world.execution`) and the obstacles keep theirs: per
    path segment and obstacle, the least distance over the pairs of the segment's path time and
    the obstacle's time that can coincide, (pop, n - 1, K). Exact
    (:func:`uavplan.world.reservations.window_min_dist2` per pair of pieces)."""
    p, tt = _timed(paths, times)
    out = []
    for o in obstacles:
        # the held first and last positions as pieces reaching far before and after
        ot = np.concatenate([[min(o.times[0], 0.0) - FAR], o.times, [o.times[-1] + FAR]])
        op = np.concatenate([o.positions[:1], o.positions, o.positions[-1:]])
        out.append(_robust_obstacle(p, tt, ot, np.ascontiguousarray(op), delta0, rho))
    return np.stack(out, axis=-1) if out else np.zeros((*p.shape[:-2], p.shape[-2] - 1, 0))


#: How far before its first and after its last knot a moving obstacle is taken to hold still
#: (beyond every time a scenario may give, 1e7 s).
FAR = 2e7


@njit(cache=True)
def _robust_obstacle(P, T, ot, op, delta0, rho):  # pragma: no cover - numba
    pop, n = T.shape
    K = ot.shape[0]
    out = np.full((pop, n - 1), np.inf)
    for q in range(pop):
        t0 = T[q, 0]
        for s in range(n - 1):
            ta, tb = T[q, s], T[q, s + 1]
            if not tb >= ta:
                continue
            lo = t0 - delta0 + (ta - t0) / (1.0 + rho)
            hi = t0 + delta0 + (tb - t0) / (1.0 - rho)
            j = max(np.searchsorted(ot, lo) - 1, 0)
            best = np.inf
            while j < K - 1 and ot[j] <= hi:
                d2 = window_min_dist2(P[q, s], P[q, s + 1], ta, tb, op[j], op[j + 1], ot[j],
                                      ot[j + 1], t0, delta0, rho, ot[0], 0.0, 0.0)  # fmt: skip
                best = min(best, d2)
                j += 1
            out[q, s] = np.sqrt(best)
    return out
