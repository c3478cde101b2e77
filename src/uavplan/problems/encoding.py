"""Encodings: turn an optimizer's flat vectors into paths for a :class:`PathProblem`.

:class:`CartesianEncoding` is the direct waypoint encoding (HR-MAGA Eq. 3; the PSO/GA/DE baselines):
``n_waypoints`` free waypoints between the fixed start and goal, each ``(x, y[, z])``. In 3-D, when
the scenario has an altitude band above ground, the z gene is the height above the terrain inside
the band (as SPSO encodes it), turned into absolute altitude at decoding; with an absolute band it
is the absolute altitude inside the band; otherwise z spans the bounds.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.problems.path_problem import Evaluation, PathProblem

FloatArray = NDArray[np.float64]


class CartesianEncoding:
    """An optimizer-facing problem (``dim``, ``lower``, ``upper``, ``block``, ``evaluate``)."""

    def __init__(
        self, problem: PathProblem, n_waypoints: int | None = None, track_feasibility: bool = False
    ) -> None:
        self.problem = problem
        self.track_feasibility = track_feasibility
        #: with ``track_feasibility``: best cost among feasible paths so far, after each call
        self.feasible_history: list[float] = []
        sc = problem.scenario
        self.n_waypoints = int(n_waypoints if n_waypoints is not None else sc.n_waypoints)
        if self.n_waypoints < 1:
            raise ValueError(f"n_waypoints must be >= 1, got {self.n_waypoints}")
        d = sc.dim
        lo = sc.bounds.lo.copy()
        hi = sc.bounds.hi.copy()
        self.z_mode = "absolute"
        if d == 3 and sc.altitude is not None:
            lo[2], hi[2] = sc.altitude.min, sc.altitude.max
            if sc.altitude.reference == "ground" and sc.terrain is not None:
                self.z_mode = "ground"
            else:
                lo[2], hi[2] = max(lo[2], sc.altitude.min), min(hi[2], sc.altitude.max)
        self.point_lower = lo
        self.point_upper = hi
        self.block = d
        self.lower = np.tile(lo, self.n_waypoints)
        self.upper = np.tile(hi, self.n_waypoints)
        self.evaluations = 0

    @property
    def dim(self) -> int:
        return int(self.lower.shape[0])

    def decode(self, X: FloatArray) -> FloatArray:
        """(pop, dim) genes -> (pop, n_waypoints + 2, scenario dim) absolute paths."""
        X = np.asarray(X, dtype=np.float64)
        d = self.problem.dim
        free = X.reshape(X.shape[0], self.n_waypoints, d).copy()
        if self.z_mode == "ground":
            terrain = self.problem.scenario.terrain
            assert terrain is not None
            free[..., 2] += terrain.lookup(free[..., 0], free[..., 1], self.problem.lookup)
        return self.problem.with_endpoints(free)

    def encode(self, paths: FloatArray) -> FloatArray:
        """Inverse of :meth:`decode` for paths with ``n_waypoints`` free waypoints."""
        p = np.asarray(paths, dtype=np.float64)[:, 1:-1].copy()
        if p.shape[1] != self.n_waypoints:
            raise ValueError(f"paths have {p.shape[1]} free waypoints, need {self.n_waypoints}")
        if self.z_mode == "ground":
            terrain = self.problem.scenario.terrain
            assert terrain is not None
            p[..., 2] -= terrain.lookup(p[..., 0], p[..., 1], self.problem.lookup)
        return p.reshape(p.shape[0], -1)

    def evaluate(self, X: FloatArray) -> FloatArray:
        """Total cost of each gene vector, (pop,).

        With ``track_feasibility`` the feasibility of every path is decided too, and the best
        feasible cost so far is appended to :attr:`feasible_history` (inf until one is found).
        """
        self.evaluations += len(X)
        if not self.track_feasibility:
            return self.problem.cost(self.decode(X))
        ev = self.problem.evaluate(self.decode(X))
        best = float(np.min(ev.cost[ev.feasible], initial=np.inf))
        prev = self.feasible_history[-1] if self.feasible_history else np.inf
        self.feasible_history.append(min(prev, best))
        return ev.cost

    def evaluate_cv(self, X: FloatArray, exact: bool = True) -> tuple[FloatArray, FloatArray]:
        """Cost and constraint violation apart (see :meth:`PathProblem.evaluate_cv`); with
        ``track_feasibility`` the best cost among the paths with no violation joins
        :attr:`feasible_history`, as :meth:`evaluate` does."""
        self.evaluations += len(X)
        f, cv = self.problem.evaluate_cv(self.decode(X), exact)
        if self.track_feasibility:
            ok = (cv == 0) & np.isfinite(f)
            best = float(np.min(f[ok], initial=np.inf))
            prev = self.feasible_history[-1] if self.feasible_history else np.inf
            self.feasible_history.append(min(prev, best))
        return f, cv

    def evaluate_full(self, X: FloatArray) -> Evaluation:
        return self.problem.evaluate(self.decode(X))


@njit(cache=True)
def clipped_cumsum(steps, start, lo, hi):  # pragma: no cover - numba
    """Waypoints from steps (pop, n, d): ``x_i = clip(x_{i-1} + step_i, lo, hi)``, ``x_0`` the
    start (d,); clipped after every step, so a cumulative sum will not do."""
    pop, n, d = steps.shape
    out = np.empty((pop, n, d))
    for p in range(pop):
        for c in range(d):
            x = start[c]
            for i in range(n):
                x = min(max(x + steps[p, i, c], lo[c]), hi[c])
                out[p, i, c] = x
    return out


def clipped_cumsum_reference(
    steps: FloatArray, start: FloatArray, lo: FloatArray, hi: FloatArray
) -> FloatArray:
    """NumPy reference of :func:`clipped_cumsum` (tests compare the two)."""
    pop, n, d = steps.shape
    out = np.empty((pop, n, d))
    prev = np.broadcast_to(start, (pop, d)).copy()
    for i in range(n):
        prev = np.clip(prev + steps[:, i], lo, hi)
        out[:, i] = prev
    return out


class SphericalEncoding:
    """SPSO's spherical-vector encoding (Phung & Ha 2021); a polar form in 2-D.

    Each free waypoint is reached from the previous node by a segment of length ``r``, elevation
    ``psi`` and azimuth ``phi`` (3-D genes ``(r, psi, phi)``; 2-D genes ``(r, phi)``):
    ``x_i = x_{i-1} + r cos(psi) cos(phi)``, ``y_i = y_{i-1} + r cos(psi) sin(phi)``,
    ``z_i = z_{i-1} + r sin(psi)``, each coordinate clipped to its range after every step as
    the reference code does. Ranges, as in SPSO's ``main.m``: ``r`` in
    ``[0, 2 |goal - start| / n]``, ``psi`` in ``[-pi/4, pi/4]``, ``phi`` within ``pi/4`` of the
    start-goal heading. As in :class:`CartesianEncoding`, with an altitude band above ground z is
    accumulated and clipped as height above the terrain (SPSO's relative z) and made absolute at
    the end.
    """

    angle_range = np.pi / 4

    def __init__(
        self, problem: PathProblem, n_waypoints: int | None = None, track_feasibility: bool = False
    ) -> None:
        self.cart = CartesianEncoding(problem, n_waypoints, track_feasibility)
        self.problem = problem
        self.n_waypoints = self.cart.n_waypoints
        self.track_feasibility = track_feasibility
        self.feasible_history = self.cart.feasible_history
        d = problem.dim
        self.block = d
        start = self._zspace(problem.start[None, None])[0, 0]
        goal = self._zspace(problem.goal[None, None])[0, 0]
        self._start = start
        heading = goal - start
        phi0 = float(np.arctan2(heading[1], heading[0]))
        r_max = 2.0 * float(np.linalg.norm(heading)) / self.n_waypoints
        if r_max <= 0:
            raise ValueError("spherical encoding needs distinct start and goal")
        a = self.angle_range
        if d == 3:
            lo = np.array([0.0, -a, phi0 - a])
            hi = np.array([r_max, a, phi0 + a])
        else:
            lo = np.array([0.0, phi0 - a])
            hi = np.array([r_max, phi0 + a])
        self.lower = np.tile(lo, self.n_waypoints)
        self.upper = np.tile(hi, self.n_waypoints)
        self.evaluations = 0

    @property
    def dim(self) -> int:
        return int(self.lower.shape[0])

    def _zspace(self, paths: FloatArray) -> FloatArray:
        """Absolute paths -> the space the genes live in (z above ground if the band says so)."""
        p = np.array(paths, dtype=np.float64)
        if self.cart.z_mode == "ground":
            terrain = self.problem.scenario.terrain
            assert terrain is not None
            p[..., 2] -= terrain.lookup(p[..., 0], p[..., 1], self.problem.lookup)
        return p

    def to_cartesian_genes(self, X: FloatArray) -> FloatArray:
        """(pop, dim) spherical genes -> (pop, dim) Cartesian genes of :class:`CartesianEncoding`
        (waypoints in the gene space, clipped step by step)."""
        X = np.asarray(X, dtype=np.float64)
        d = self.problem.dim
        n = self.n_waypoints
        g = X.reshape(X.shape[0], n, d)
        lo, hi = self.cart.point_lower, self.cart.point_upper
        r = g[:, :, 0]
        if d == 3:
            psi, phi = g[:, :, 1], g[:, :, 2]
            rc = r * np.cos(psi)
            steps = np.stack([rc * np.cos(phi), rc * np.sin(phi), r * np.sin(psi)], axis=2)
        else:
            phi = g[:, :, 1]
            steps = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=2)
        pts = clipped_cumsum(np.ascontiguousarray(steps), self._start, lo, hi)
        return pts.reshape(X.shape[0], -1)

    def decode(self, X: FloatArray) -> FloatArray:
        """(pop, dim) genes -> (pop, n_waypoints + 2, scenario dim) absolute paths."""
        return self.cart.decode(self.to_cartesian_genes(X))

    def evaluate(self, X: FloatArray) -> FloatArray:
        self.evaluations += len(X)
        return self.cart.evaluate(self.to_cartesian_genes(X))

    def evaluate_cv(self, X: FloatArray, exact: bool = True) -> tuple[FloatArray, FloatArray]:
        self.evaluations += len(X)
        return self.cart.evaluate_cv(self.to_cartesian_genes(X), exact)

    def evaluate_full(self, X: FloatArray) -> Evaluation:
        return self.problem.evaluate(self.decode(X))


ENCODINGS: dict[str, type[CartesianEncoding] | type[SphericalEncoding]] = {
    "cartesian": CartesianEncoding,
    "spherical": SphericalEncoding,
}
