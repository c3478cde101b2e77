"""Encodings: turn an optimizer's flat vectors into paths for a :class:`PathProblem`.

:class:`CartesianEncoding` is the direct waypoint encoding (HR-MAGA Eq. 3; the PSO/GA/DE baselines):
``n_waypoints`` free waypoints between the fixed start and goal, each ``(x, y[, z])``. In 3-D, when
the scenario has an altitude band above ground, the z gene is the height above the terrain inside
the band (as SPSO encodes it), turned into absolute altitude at decoding; with an absolute band it
is the absolute altitude inside the band; otherwise z spans the bounds.

Both decode a population in one Numba pass (:func:`decode_kernel`: steps, clipping, terrain
heights, the task's start and goal); :meth:`SphericalEncoding.to_cartesian_genes` and
:meth:`CartesianEncoding.decode_reference` are the NumPy forms it is tested against.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.problems.path_problem import Evaluation, PathProblem
from uavplan.world._terrain_kernels import ground_one
from uavplan.world.kernel_arrays import read_only

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
        self._decode_args = decode_args(problem, self.z_mode, np.zeros(d), lo, hi)

    @property
    def dim(self) -> int:
        return int(self.lower.shape[0])

    def decode(self, X: FloatArray) -> FloatArray:
        """(pop, dim) genes -> (pop, n_waypoints + 2, scenario dim) absolute paths."""
        return decode(self, X, spherical=False)

    def decode_reference(self, X: FloatArray) -> FloatArray:
        """:meth:`decode` in NumPy (the reference :func:`decode_kernel` is tested against)."""
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

        With ``track_feasibility`` the best feasible cost so far is appended to
        :attr:`feasible_history` (inf until one is found): the feasibility of a path is decided
        only where it could lower that figure (:func:`best_feasible`).
        """
        self.evaluations += len(X)
        return self.evaluate_paths(self.decode(X))

    def evaluate_paths(self, paths: FloatArray) -> FloatArray:
        """:meth:`evaluate` of decoded paths (the evaluation is not counted here)."""
        f = self.problem.cost(paths)
        if self.track_feasibility:
            self._record(paths, f)
        return f

    def _record(self, paths: FloatArray, f: FloatArray) -> float:
        prev = self.feasible_history[-1] if self.feasible_history else np.inf
        self.feasible_history.append(min(prev, best_feasible(self.problem, paths, f, prev)))
        return self.feasible_history[-1]

    def track(self, X: FloatArray, f: FloatArray) -> float:
        """Append to :attr:`feasible_history` the best cost so far among feasible gene vectors,
        after ``X`` (pop, dim) with costs ``f`` (pop,) (any constraint rule's number: a feasible
        point's is its cost), and return it; only the points that could lower it are decoded and
        checked. For a caller that tracks what an optimizer kept rather than every evaluation."""
        prev = self.feasible_history[-1] if self.feasible_history else np.inf
        rows = np.flatnonzero(np.asarray(f) < prev)
        return self._record(self.decode(np.asarray(X)[rows]), np.asarray(f)[rows])

    def evaluate_cv(self, X: FloatArray, exact: bool = True) -> tuple[FloatArray, FloatArray]:
        """Cost and constraint violation apart (see :meth:`PathProblem.evaluate_cv`); with
        ``track_feasibility`` the best cost among the paths with no violation joins
        :attr:`feasible_history`, as :meth:`evaluate` does."""
        self.evaluations += len(X)
        return self.evaluate_cv_paths(self.decode(X), exact)

    def evaluate_cv_paths(
        self, paths: FloatArray, exact: bool = True
    ) -> tuple[FloatArray, FloatArray]:
        """:meth:`evaluate_cv` of decoded paths (the evaluation is not counted here)."""
        f, cv = self.problem.evaluate_cv(paths, exact)
        if self.track_feasibility:
            ok = (cv == 0) & np.isfinite(f)
            best = float(np.min(f[ok], initial=np.inf))
            prev = self.feasible_history[-1] if self.feasible_history else np.inf
            self.feasible_history.append(min(prev, best))
        return f, cv

    def evaluate_full(self, X: FloatArray) -> Evaluation:
        return self.problem.evaluate(self.decode(X))


#: :func:`best_feasible`: the candidates checked in the first call, before all the others
FIRST_CHECKS = 8


def best_feasible(problem: PathProblem, paths: FloatArray, f: FloatArray, below: float) -> float:
    """The least cost ``f`` among the feasible ``paths`` whose cost is below ``below``, else
    inf: the candidates are checked in order of cost, the :data:`FIRST_CHECKS` cheapest first,
    then the rest only if none of those passes (the same figure as checking every path)."""
    cand = np.flatnonzero(f < below)
    if not cand.size:
        return float("inf")
    cand = cand[np.argsort(f[cand], kind="stable")]
    for part in (cand[:FIRST_CHECKS], cand[FIRST_CHECKS:]):
        if part.size:
            ok = problem.feasible(paths[part])
            if ok.any():
                return float(f[part[np.argmax(ok)]])
    return float("inf")


def decode_args(
    problem: PathProblem, z_mode: str, start: FloatArray, lo: FloatArray, hi: FloatArray
) -> tuple[object, ...]:
    """:func:`decode_kernel`'s arguments after ``spherical``, for an encoding of ``problem``."""
    terrain = problem.scenario.terrain
    ground = z_mode == "ground" and terrain is not None
    if terrain is not None:
        H, x0, y0, dx, dy = terrain.heights, terrain.x0, terrain.y0, terrain.dx, terrain.dy
    else:
        H, x0, y0, dx, dy = read_only(np.zeros((2, 2))), 0.0, 0.0, 1.0, 1.0  # as heights
    if problem.lookup not in ("nearest", "bilinear"):
        raise ValueError(f"unknown terrain lookup method {problem.lookup!r}")
    f64 = [np.ascontiguousarray(a, dtype=np.float64) for a in (start, lo, hi)]
    return (*f64, ground, problem.lookup == "nearest", H, float(x0), float(y0), float(dx),
            float(dy), problem.start, problem.goal)  # fmt: skip


def decode(
    enc: CartesianEncoding | SphericalEncoding, X: FloatArray, spherical: bool
) -> FloatArray:
    """:func:`decode_kernel` of an encoding's genes ``X`` (pop, dim)."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] != enc.dim:
        raise ValueError(f"genes must be (pop, {enc.dim}), got shape {X.shape}")
    return np.asarray(decode_kernel(X, spherical, *enc._decode_args))


@njit(cache=True)
def decode_kernel(
    X, spherical, start, lo, hi, ground, nearest, H, x0, y0, dx, dy, first, last
):  # pragma: no cover - numba
    """Genes (pop, n d) -> paths (pop, n + 2, d), ``first`` and ``last`` (the task's start and
    goal) around the free waypoints. Cartesian genes are the waypoints; spherical ones
    ``(r, psi, phi)`` (``(r, phi)`` in 2-D) are steps from the previous node (from ``start``
    for the first), each coordinate clipped to ``[lo, hi]`` after every step
    (:func:`clipped_cumsum`). With ``ground``, z is above the terrain ``H`` (nearest node or
    bilinear) and made absolute. The arithmetic, in the same order, of
    :meth:`SphericalEncoding.to_cartesian_genes` and :meth:`CartesianEncoding.decode_reference`.
    """
    pop = X.shape[0]
    d = first.shape[0]
    n = X.shape[1] // d
    out = np.empty((pop, n + 2, d))
    for p in range(pop):
        for c in range(d):
            out[p, 0, c] = first[c]
            out[p, n + 1, c] = last[c]
        x = start[0]
        y = start[1]
        z = start[d - 1]
        for i in range(n):
            k = i * d
            if spherical:
                r = X[p, k]
                if d == 3:
                    psi = X[p, k + 1]
                    phi = X[p, k + 2]
                    rc = r * np.cos(psi)
                    x = min(max(x + rc * np.cos(phi), lo[0]), hi[0])
                    y = min(max(y + rc * np.sin(phi), lo[1]), hi[1])
                    z = min(max(z + r * np.sin(psi), lo[2]), hi[2])
                else:
                    phi = X[p, k + 1]
                    x = min(max(x + r * np.cos(phi), lo[0]), hi[0])
                    y = min(max(y + r * np.sin(phi), lo[1]), hi[1])
            else:
                x = X[p, k]
                y = X[p, k + 1]
                z = X[p, k + d - 1]
            out[p, i + 1, 0] = x
            out[p, i + 1, 1] = y
            if d == 3:
                out[p, i + 1, 2] = z
    if d == 3 and ground:  # apart, so that the terrain's cache misses overlap
        for p in range(pop):
            for i in range(1, n + 1):
                x = out[p, i, 0]
                y = out[p, i, 1]
                out[p, i, 2] += ground_one(H, True, nearest, x0, y0, dx, dy, x, y)
    return out


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
        c = self.cart
        self._decode_args = decode_args(problem, c.z_mode, start, c.point_lower, c.point_upper)

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
        return decode(self, X, spherical=True)

    def decode_reference(self, X: FloatArray) -> FloatArray:
        """:meth:`decode` in NumPy (the reference :func:`decode_kernel` is tested against)."""
        return self.cart.decode_reference(self.to_cartesian_genes(X))

    def evaluate(self, X: FloatArray) -> FloatArray:
        self.evaluations += len(X)
        self.cart.evaluations += len(X)
        return self.cart.evaluate_paths(self.decode(X))

    def evaluate_cv(self, X: FloatArray, exact: bool = True) -> tuple[FloatArray, FloatArray]:
        self.evaluations += len(X)
        self.cart.evaluations += len(X)
        return self.cart.evaluate_cv_paths(self.decode(X), exact)

    def track(self, X: FloatArray, f: FloatArray) -> float:
        """:meth:`CartesianEncoding.track` of spherical genes."""
        return CartesianEncoding.track(self, X, f)  # type: ignore[arg-type]

    def _record(self, paths: FloatArray, f: FloatArray) -> float:
        return self.cart._record(paths, f)

    def evaluate_full(self, X: FloatArray) -> Evaluation:
        return self.problem.evaluate(self.decode(X))


Encoding = CartesianEncoding | SphericalEncoding

ENCODINGS: dict[str, type[CartesianEncoding] | type[SphericalEncoding]] = {
    "cartesian": CartesianEncoding,
    "spherical": SphericalEncoding,
}
