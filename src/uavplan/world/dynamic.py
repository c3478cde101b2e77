"""Moving obstacles: a sphere (or, in 2-D, a disc) following a timed piecewise-linear trajectory.

RSCDWOA (Zhang et al., Sect. on moving obstacles) moves obstacles along known trajectories; we
store the trajectory as knots ``(times, positions)``, hold the first and last positions outside
them, and compute distances to a timed path exactly (both motions are linear between knots).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


def min_distances(
    obstacles: Sequence[MovingObstacle], paths: ArrayLike, times: ArrayLike
) -> FloatArray:
    """:meth:`MovingObstacle.min_distance` to each of ``obstacles``, (pop, n - 1, K), the paths
    (2-D ones at z = 0) and times prepared once for all of them."""
    from uavplan.world.geometry import timed_path_min_distance

    p = np.ascontiguousarray(paths, dtype=np.float64)
    if p.shape[-1] == 2:
        p = np.concatenate([p, np.zeros((*p.shape[:-1], 1))], axis=-1)
    # writable like ``p`` (a read-only array would be a second kernel signature to compile)
    tt = np.require(np.broadcast_to(times, p.shape[:-1]), np.float64, ["C", "W"])
    out = [timed_path_min_distance(p, tt, o.times, o.positions) for o in obstacles]
    return np.stack(out, axis=-1) if out else np.zeros((*p.shape[:-2], p.shape[-2] - 1, 0))
