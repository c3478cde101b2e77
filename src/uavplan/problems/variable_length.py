"""Variable-length waypoint particles (Liu et al. 2024, RGG-PSO+, Sect. 4.2.2, Algs. 1-2).

A particle holds ``N`` free waypoints; consecutive duplicates stand for a shorter path, so one
fixed-length vector encodes any path of at most ``N`` interior nodes. :func:`path_to_particle`
is Alg. 1 (a path's interior nodes -> a particle by random duplication), :func:`particle_to_path`
is Alg. 2 (drop consecutive duplicates). :class:`VariableLengthEncoding` evaluates the
*decoded* path: rows are grouped by their decoded length so each group is one batched
:meth:`PathProblem.evaluate` call. For the ``length2d`` preset this equals evaluating the particle
directly (a zero-length segment adds no length and no inside length); for presets with turning
or climb angles it does not (a zero-length segment hides the turn at a duplicated node), hence
the decoded path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import PathProblem

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]


def subsample_indices(k: int, n: int) -> IntArray:
    """``n`` distinct indices of ``0..k-1`` (``k > n``), evenly spread, in order."""
    return np.floor((np.arange(n) + 0.5) * k / n).astype(np.int64)


def path_to_particle(path: FloatArray, n: int, rng: np.random.Generator) -> FloatArray:
    """Alg. 1: ``path`` (k, d) -> particle (n, d) by random duplication.

    ``N_dup = ceil((n - k) / k)``, ``N_ran = n - k N_dup``; ``N_ran`` nodes drawn without
    replacement get ``N_dup + 1`` copies ("for i <- 0 to N_dup"), the others ``N_dup``
    ("0 to N_dup - 1"); in path order. Then ``k N_dup + N_ran = n`` and every node appears at
    least once (``N_ran = k`` when ``k`` divides ``n``). For ``k > n`` (the paper's graphs have at
    most N nodes, ours may not) ``n`` nodes are kept evenly (:func:`subsample_indices`).
    """
    p = np.asarray(path, dtype=np.float64)
    if p.ndim != 2 or len(p) == 0:
        raise ValueError(f"path must be (k >= 1, d), got shape {p.shape}")
    if n < 1:
        raise ValueError(f"particle length must be >= 1, got {n}")
    k = len(p)
    if k > n:
        return np.asarray(p[subsample_indices(k, n)].copy())
    n_dup = -(-(n - k) // k)
    n_ran = n - k * n_dup
    counts = np.full(k, n_dup, dtype=np.int64)
    counts[rng.choice(k, size=n_ran, replace=False)] += 1
    return np.asarray(np.repeat(p, counts, axis=0))


def particle_to_path(particle: FloatArray) -> FloatArray:
    """Alg. 2: drop every waypoint equal to its predecessor (consecutive duplicates)."""
    p = np.asarray(particle, dtype=np.float64)
    keep = np.ones(len(p), dtype=bool)
    keep[1:] = np.any(p[1:] != p[:-1], axis=-1)
    return np.asarray(p[keep])


def two_points(path: FloatArray) -> FloatArray:
    return path if len(path) >= 2 else np.asarray(np.vstack([path, path]))


def evaluate_paths(
    problem: PathProblem, paths: Sequence[FloatArray]
) -> tuple[FloatArray, BoolArray]:
    """Cost and feasibility of paths of any lengths, one batched call per distinct length."""
    ps = [two_points(np.asarray(p, dtype=np.float64)) for p in paths]
    lens = np.array([len(p) for p in ps], dtype=np.int64)
    cost = np.empty(len(ps))
    feas = np.zeros(len(ps), dtype=bool)
    for L in np.unique(lens):
        rows = np.flatnonzero(lens == L)
        ev = problem.evaluate(np.stack([ps[i] for i in rows]))
        cost[rows] = ev.cost
        feas[rows] = ev.feasible
    return cost, feas


#: Cost presets whose every term and feasibility rule is unchanged by repeating a waypoint
#: (a zero-length segment adds no length and no length inside an obstacle, and its point is
#: already checked as an end point): their particles can be scored as they are, in one batch,
#: with the same result as the Alg. 2-decoded paths. Presets with turn or climb angles, or
#: HR-MAGA's mean terrain height per segment, are not.
DUPLICATE_INVARIANT = frozenset({"length2d"})


def evaluate_decoded(problem: PathProblem, full: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Cost and feasibility of full paths (pop, L, d) after Alg. 2 (grouped by length)."""
    if problem.cost_name in DUPLICATE_INVARIANT:
        ev = problem.evaluate(full)
        return ev.cost, ev.feasible
    keep = np.ones(full.shape[:2], dtype=bool)
    keep[:, 1:] = np.any(full[:, 1:] != full[:, :-1], axis=-1)
    lens = keep.sum(axis=1)
    cost = np.empty(len(full))
    feas = np.zeros(len(full), dtype=bool)
    for L in np.unique(lens):
        rows = np.flatnonzero(lens == L)
        sub = full[rows][keep[rows]].reshape(len(rows), int(L), full.shape[2])
        if L < 2:
            sub = np.concatenate([sub, sub], axis=1)
        ev = problem.evaluate(sub)
        cost[rows] = ev.cost
        feas[rows] = ev.feasible
    return cost, feas


def same_answers(a: PathProblem, b: PathProblem) -> bool:
    """Whether the two problems give any path the same cost and feasibility, so that their
    batches can be evaluated in one call (:func:`evaluate_many`): one world, one cost model
    that depends on the path alone (:data:`DUPLICATE_INVARIANT`), no timed checks (moving
    obstacles, other UAVs' reservations), the same validator settings. Only their tasks (start,
    goal, start time) may differ, and none of these checks reads them."""
    va, vb = a.validator, b.validator
    return (
        a.scenario is b.scenario
        and a.cost_name == b.cost_name
        and a.cost_name in DUPLICATE_INVARIANT
        and a.terms == b.terms
        and not a.scenario.moving_obstacles
        and va.reservations is None
        and vb.reservations is None
        and not va.kinematics
        and not vb.kinematics
        and va.strict_altitude == vb.strict_altitude
        and va.lookup == vb.lookup
    )


class VariableLengthEncoding(CartesianEncoding):
    """Cartesian genes of ``N`` waypoints, evaluated on the Alg. 2-decoded path.

    Tracks the best evaluated point overall (``best_x``, ``best_f``) and the best feasible one
    (``best_feasible_x``, ``best_feasible_f``), and :attr:`feasible_history` per call.
    """

    def __init__(
        self, problem: PathProblem, n_waypoints: int | None = None, counter: Any | None = None
    ) -> None:
        super().__init__(problem, n_waypoints, track_feasibility=True)
        #: an object whose ``evaluations`` attribute also counts this encoding's evaluations
        #: (RGG-PSO+ counts every sub-swarm's in one place)
        self.counter = counter
        self.best_x: FloatArray | None = None
        self.best_f = np.inf
        self.best_feasible_x: FloatArray | None = None
        self.best_feasible_f = np.inf
        self._best: tuple[FloatArray, float, bool] | None = None

    def path(self, x: FloatArray) -> FloatArray:
        """The decoded (Alg. 2) path of one gene vector, start and goal included."""
        return particle_to_path(self.decode(np.asarray(x)[None])[0])

    def evaluate(self, X: FloatArray) -> FloatArray:
        X = np.asarray(X, dtype=np.float64)
        cost, feas = evaluate_decoded(self.problem, self.decode(X))
        self.record(X, cost, feas)
        return cost

    def record(self, X: FloatArray, cost: FloatArray, feas: BoolArray) -> None:
        """Count an evaluated batch and keep its bests (what :meth:`evaluate` does after
        evaluating; :func:`evaluate_many` evaluates several encodings' batches at once)."""
        self.evaluations += len(X)
        if self.counter is not None:
            self.counter.evaluations += len(X)
        i = int(np.argmin(cost))
        if self.best_x is None or cost[i] < self.best_f:
            self.best_x, self.best_f = X[i].copy(), float(cost[i])
            self._best = None
        if feas.any():
            fc = np.where(feas, cost, np.inf)
            j = int(np.argmin(fc))
            if self.best_feasible_x is None or fc[j] < self.best_feasible_f:
                self.best_feasible_x, self.best_feasible_f = X[j].copy(), float(fc[j])
                self._best = None
        prev = self.feasible_history[-1] if self.feasible_history else np.inf
        self.feasible_history.append(min(prev, self.best_feasible_f))

    def best(self) -> tuple[FloatArray, float, bool]:
        """(decoded path, cost, feasible) of the best feasible point, else of the best point
        (decoded once per new best: RGG-PSO+ asks for it at every iteration)."""
        if self._best is None:
            if self.best_feasible_x is not None:
                self._best = (self.path(self.best_feasible_x), self.best_feasible_f, True)
            elif self.best_x is None:
                raise RuntimeError("nothing evaluated yet")
            else:
                self._best = (self.path(self.best_x), self.best_f, False)
        return self._best


def evaluate_many(
    encs: Sequence[VariableLengthEncoding], Xs: Sequence[FloatArray]
) -> list[FloatArray]:
    """``[e.evaluate(X) for e, X in zip(encs, Xs)]``, with the batches of encodings whose
    problems give the same answers (:func:`same_answers`) and whose particles have one length
    evaluated in one call (one kernel pass instead of several: RGG-PSO+'s halves step in
    lockstep). Each path's cost and feasibility are the same either way."""
    Xs = [np.asarray(X, dtype=np.float64) for X in Xs]
    out: list[FloatArray] = [np.zeros(0)] * len(encs)
    groups: list[list[int]] = []
    for i, e in enumerate(encs):
        for g in groups:
            f = encs[g[0]]
            if f.n_waypoints == e.n_waypoints and same_answers(f.problem, e.problem):
                g.append(i)
                break
        else:
            groups.append([i])
    for g in groups:
        full = [encs[i].decode(Xs[i]) for i in g]
        cost, feas = evaluate_decoded(encs[g[0]].problem, np.concatenate(full))
        at = 0
        for i in g:
            n = len(Xs[i])
            encs[i].record(Xs[i], cost[at : at + n], feas[at : at + n])
            out[i] = cost[at : at + n].copy()
            at += n
    return out
