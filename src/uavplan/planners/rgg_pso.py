"""RGG-PSO and RGG-PSO+ (Liu et al. 2024, J. Intell. Robot. Syst.): PSO over variable-length
waypoint particles seeded by random geometric graphs, and its divide-and-conquer version.

**Particles (Sect. 4.2.2).** A particle holds ``N`` free waypoints (default: the scenario's
``n_waypoints``; 20 in the paper and in ``simple2d``); the task's start and goal stay fixed
outside it (the paper adds them "to either end of the vector"; its footnote counts 22 nodes for
N = 20). :func:`path_to_particle` is Alg. 1 applied to a path's interior nodes, and
:func:`particle_to_path` is Alg. 2. The genes are those of
:class:`~uavplan.problems.encoding.CartesianEncoding` (x, y[, z]; z above ground in a ground
band), so PSO moves exactly the paper's Eq. (1) particles.

**Evaluation.** :class:`VariableLengthEncoding` evaluates the *decoded* path: start + particle +
goal with consecutive duplicates dropped (Alg. 2), rows grouped by their decoded length so each
group is one batched :meth:`PathProblem.evaluate` call. For the ``length2d`` preset this equals
evaluating the particle directly (a zero-length segment adds no length and no inside length; a
test checks it); for presets with turning or climb angles it does not (a zero-length segment
hides the turn at a duplicated node), hence the decoded path.

**RGG-PSO (``rgg-pso``).** RGG candidates (:func:`uavplan.planners.rgg.rgg_candidates`, one
graph of ``N`` free samples per swarm, Sect. 4.2.1, not densified by default) give the
initial swarm: particle ``i`` is Alg. 1 of candidate ``i mod n_candidates`` with its own random
duplication. A candidate with more than ``N`` interior nodes is first shortened by an exact
dynamic program to the shortest feasible sub-sequence of its nodes with at most ``N`` interior
nodes (shortcuts only, so still feasible and never longer); if no such sub-sequence exists,
``N`` of its nodes are kept evenly (:func:`subsample_indices`; may be infeasible, PSO repairs
it). A candidate with no interior node (the straight segment is free) contributes its midpoint.
If the RGG cannot connect the task, the swarm starts uniform in the box (plain PSO).
The result is the lowest-cost *feasible* path evaluated (else the lowest-cost one), decoded by
Alg. 2. Defaults: Sect. 5.2.2 (100 particles, 200 iterations, w = 1 damped by 0.98,
c1 = c2 = 1.5).

**RGG-PSO+ (``rgg-pso+``), Alg. 3 and Alg. 4.** With ``T`` iterations:

1. RGG-PSO on the whole task for ``T_w = round(whole_fraction T)`` iterations (at least 1;
   ``whole_fraction = 0.5``: 100 of 200, the paper's "100 iterations per sub-path within 200").
2. Divide (Alg. 3): split the current best path (``L`` nodes, start and goal included) at node
   ``idx = floor(L / 2)`` (the paper's ``ceil(len / 2)`` with ``len`` counting segments; with
   ``len`` = nodes and 0-based indices, L = 3 would give an empty second half), into
   ``path[:idx + 1]`` and ``path[idx:]``; each half becomes its own task (start and goal = its
   end nodes; the second leaves at the first's arrival time) and is optimized by RGG-PSO
   seeded with the half itself (Alg. 3 line 3: "PSO(path_1)") plus RGG candidates of the
   sub-task. Both halves run in lockstep for the remaining ``T - T_w`` iterations (one overall
   iteration = one swarm step of every active sub-swarm), so every sub-path gets ``T - T_w``
   iterations and the run has ``T`` in all. With ``depth > 1`` a half divides again the same way
   within its own budget.
3. Conquer (Alg. 4, :func:`conquer`): over every node pair ``(i, j)`` build
   ``path_1[:i + 1] + path_2[j:]`` (the paper's ``path_1[0:node_1]`` read inclusively, so the
   tested junction is ``node_1 -> node_2``); every merge is evaluated in full (cost and
   feasibility; equivalent to the paper's junction test when both halves are feasible, and safe
   when they are not) and the lowest-cost feasible one is kept. The plain concatenation is the
   merge ``(len(path_1) - 1, 0)``. If no merge is feasible, the pre-divide best is kept if
   feasible. The result is the cheaper of the best merge and the pre-divide best (feasible ones
   first), so RGG-PSO+ never returns a path worse than its own pre-divide best.

**Bookkeeping.** ``history`` is the best whole-task cost so far per overall iteration: the
swarm's best in the whole phase, then the whole-task cost of the concatenation of the halves'
current bests (each half's best feasible path if it has one), evaluated on the whole task's
problem when it changed; the last iteration includes the conquer result. ``evaluations`` counts
every cost evaluation: swarm evaluations of every (sub-)swarm, those monitoring evaluations and
every Alg. 4 merge; the final re-evaluation of the returned path is not counted (as in every
planner). RGG edge checks are feasibility tests, reported in ``config["run"]["edge_checks"]``.
Budgets: ``T`` is the budget's iterations (200 if none); an evaluation-only budget plans the
``T`` whose expected swarm evaluations fit it; evaluation, time and callback limits stop the run
early, and the halves are then conquered as they are. All randomness comes from
``numpy.random.SeedSequence(seed)``, spawned per (sub-)swarm.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan import optimizers
from uavplan.optimizers.base import Budget, OptimizerError, config_dict
from uavplan.optimizers.pso import PSO, PSOConfig
from uavplan.planners.base import (
    _REGISTRY,
    Planner,
    PlannerError,
    PlanResult,
    ProgressCallback,
    register_planner,
)
from uavplan.planners.rgg import (
    DEFAULT_GAMMA,
    RGGPlanner,
    feasibility_problem,
    rgg_candidates,
)
from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import PathProblem
from uavplan.problems.validity import MotionValidator
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]

#: Iterations when no budget is given (Sect. 5.2.2).
DEFAULT_ITERATIONS = 200


# ------------------------------------------------------------------------------ Alg. 1 and 2
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


def _two_points(path: FloatArray) -> FloatArray:
    return path if len(path) >= 2 else np.asarray(np.vstack([path, path]))


def evaluate_paths(
    problem: PathProblem, paths: Sequence[FloatArray]
) -> tuple[FloatArray, BoolArray]:
    """Cost and feasibility of paths of any lengths, one batched call per distinct length."""
    ps = [_two_points(np.asarray(p, dtype=np.float64)) for p in paths]
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


@dataclass
class _Stats:
    """Work counters shared by every (sub-)swarm of one run."""

    evaluations: int = 0
    edge_checks: int = 0
    uniform_seeded: list[str] = field(default_factory=list)
    rgg_samples: list[int] = field(default_factory=list)


class VariableLengthEncoding(CartesianEncoding):
    """Cartesian genes of ``N`` waypoints, evaluated on the Alg. 2-decoded path.

    Tracks the best evaluated point overall (``best_x``, ``best_f``) and the best feasible one
    (``best_feasible_x``, ``best_feasible_f``), and :attr:`feasible_history` per call.
    """

    def __init__(
        self, problem: PathProblem, n_waypoints: int | None = None, stats: _Stats | None = None
    ) -> None:
        super().__init__(problem, n_waypoints, track_feasibility=True)
        self.stats = stats
        self.best_x: FloatArray | None = None
        self.best_f = np.inf
        self.best_feasible_x: FloatArray | None = None
        self.best_feasible_f = np.inf

    def path(self, x: FloatArray) -> FloatArray:
        """The decoded (Alg. 2) path of one gene vector, start and goal included."""
        return particle_to_path(self.decode(np.asarray(x)[None])[0])

    def evaluate(self, X: FloatArray) -> FloatArray:
        X = np.asarray(X, dtype=np.float64)
        self.evaluations += len(X)
        if self.stats is not None:
            self.stats.evaluations += len(X)
        cost, feas = evaluate_decoded(self.problem, self.decode(X))
        i = int(np.argmin(cost))
        if self.best_x is None or cost[i] < self.best_f:
            self.best_x, self.best_f = X[i].copy(), float(cost[i])
        if feas.any():
            fc = np.where(feas, cost, np.inf)
            j = int(np.argmin(fc))
            if self.best_feasible_x is None or fc[j] < self.best_feasible_f:
                self.best_feasible_x, self.best_feasible_f = X[j].copy(), float(fc[j])
        prev = self.feasible_history[-1] if self.feasible_history else np.inf
        self.feasible_history.append(min(prev, self.best_feasible_f))
        return cost

    def best(self) -> tuple[FloatArray, float, bool]:
        """(decoded path, cost, feasible) of the best feasible point, else of the best point."""
        if self.best_feasible_x is not None:
            return self.path(self.best_feasible_x), self.best_feasible_f, True
        if self.best_x is None:
            raise RuntimeError("nothing evaluated yet")
        return self.path(self.best_x), self.best_f, False


# ------------------------------------------------------------------------------ candidates
def shortcut(
    path: FloatArray, max_interior: int, feas: MotionValidator
) -> tuple[FloatArray | None, int]:
    """The shortest sub-sequence of ``path``'s nodes (first and last kept) whose segments are
    all feasible and which has at most ``max_interior`` interior nodes (exact DP over the
    visibility DAG of the nodes), or None; and the number of segments checked."""
    p = np.asarray(path, dtype=np.float64)
    K = len(p)
    i, j = np.triu_indices(K, k=1)
    ok = feas.segments_valid(p[i], p[j])
    W = np.full((K, K), np.inf)
    W[i[ok], j[ok]] = np.linalg.norm(p[j[ok]] - p[i[ok]], axis=1)
    # f[c, v]: shortest chain 0 -> v visiting c nodes after 0 (v included)
    f = np.full(K, np.inf)
    f[0] = 0.0
    preds: list[IntArray] = []
    best_c, best_len = -1, np.inf
    for c in range(1, max_interior + 2):
        tot = f[:, None] + W
        arg = np.argmin(tot, axis=0)
        f = tot[arg, np.arange(K)]
        preds.append(arg)
        if f[K - 1] < best_len:
            best_c, best_len = c, float(f[K - 1])
    if best_c < 0:
        return None, len(i)
    out = [K - 1]
    for c in range(best_c - 1, -1, -1):
        out.append(int(preds[c][out[-1]]))
    return np.asarray(p[out[::-1]]), len(i)


def fit_interior(path: FloatArray, n: int, feas: MotionValidator) -> tuple[FloatArray, int]:
    """The interior nodes (k <= n, d) that Alg. 1 turns into a particle for candidate ``path``
    (start and goal included); see the module docstring. Returns them and the segment checks."""
    p = np.asarray(path, dtype=np.float64)
    inner = p[1:-1]
    if len(inner) == 0:
        return np.asarray(0.5 * (p[:1] + p[-1:])), 0
    if len(inner) <= n:
        return np.asarray(inner), 0
    short, checks = shortcut(p, n, feas)
    if short is not None:
        inner = short[1:-1]
        if len(inner) == 0:
            return np.asarray(0.5 * (p[:1] + p[-1:])), checks
        return np.asarray(inner), checks
    return np.asarray(inner[subsample_indices(len(inner), n)]), checks


def initial_swarm(
    enc: CartesianEncoding,
    interiors: Sequence[FloatArray],
    pop_size: int,
    rng: np.random.Generator,
) -> FloatArray:
    """Genes (pop_size, dim): particle ``i`` is Alg. 1 of ``interiors[i mod len]``."""
    X = np.empty((pop_size, enc.dim))
    n = enc.n_waypoints
    for i in range(pop_size):
        particle = path_to_particle(interiors[i % len(interiors)], n, rng)
        X[i] = enc.encode(enc.problem.with_endpoints(particle[None]))[0]
    return X


# ------------------------------------------------------------------------------ Alg. 4
@dataclass(frozen=True)
class Merge:
    """One Alg. 4 merge ``path_1[:i + 1] + path_2[j:]``: its path, cost and feasibility."""

    path: FloatArray
    cost: float
    feasible: bool
    i: int
    j: int


@dataclass(frozen=True)
class Conquest:
    """Alg. 4's outcome: ``best`` is the lowest-cost feasible merge (None if none is
    feasible), ``concatenation`` the plain ``path_1 + path_2[1:]``; ``evaluations`` made."""

    best: Merge | None
    concatenation: Merge
    evaluations: int


def conquer(problem: PathProblem, path1: FloatArray, path2: FloatArray) -> Conquest:
    """Alg. 4: merge two consecutive paths (``path1[-1]`` is ``path2[0]``) at the best feasible
    shortcut; every merge is evaluated in full, so ``best`` is never infeasible."""
    p1 = particle_to_path(path1)
    p2 = particle_to_path(path2)
    merges: list[FloatArray] = []
    ij: list[tuple[int, int]] = []
    for i in range(len(p1)):
        for j in range(len(p2)):
            merges.append(particle_to_path(np.concatenate([p1[: i + 1], p2[j:]])))
            ij.append((i, j))
    cost, feas = evaluate_paths(problem, merges)
    k_cat = ij.index((len(p1) - 1, 0))
    cat = Merge(_two_points(merges[k_cat]), float(cost[k_cat]), bool(feas[k_cat]), *ij[k_cat])
    best = None
    if feas.any():
        k = int(np.argmin(np.where(feas, cost, np.inf)))
        best = Merge(_two_points(merges[k]), float(cost[k]), True, *ij[k])
    return Conquest(best, cat, len(merges))


# ------------------------------------------------------------------------------ planners
_PSO_FIELDS = tuple(f.name for f in fields(PSOConfig))


class RGGPSOPlanner(Planner):
    """RGG-PSO (``rgg-pso``); see the module docstring.

    Args:
        n_waypoints: particle length N (default: the scenario's ``n_waypoints``).
        cost, weights: cost preset and weight overrides (the scenario's by default).
        n_samples: RGG samples per graph; default (None) the particle length N, as the paper
            says ("Sample N random nodes ... N denotes the PSO particle vector's length").
        max_doublings: densify a graph that does not connect the task by doubling its samples,
            at most this many times (0, the paper's behaviour: a swarm whose graph does not
            connect starts uniform, like PSO).
        gamma: RGG connectivity constant (:data:`uavplan.planners.rgg.DEFAULT_GAMMA`).
        n_candidates: distinct RGG paths seeding the swarm (at most ``pop_size``).
        penalty: edge-penalty factor for alternative candidates (lengths times ``1 + penalty``).
        track_feasibility: accepted for the common planner interface; always tracked.
        **pso: :class:`PSOConfig` fields (``pop_size``, ``w``, ``w_damp``, ``c1``, ``c2``,
            ``velocity_fraction``).
    """

    name = "rgg-pso"
    _own: tuple[str, ...] = (
        "n_waypoints",
        "cost",
        "weights",
        "n_samples",
        "max_doublings",
        "gamma",
        "n_candidates",
        "penalty",
        "track_feasibility",
    )

    def __init__(
        self,
        n_waypoints: int | None = None,
        cost: str | None = None,
        weights: dict[str, float] | None = None,
        n_samples: int | None = None,
        gamma: float = DEFAULT_GAMMA,
        n_candidates: int = 10,
        penalty: float = 1.0,
        track_feasibility: bool = True,
        max_doublings: int = 0,
        **pso: Any,
    ) -> None:
        unknown = set(pso) - set(_PSO_FIELDS)
        if unknown:
            known = sorted({*_PSO_FIELDS, *self._known()})
            raise PlannerError(
                f"{self.name}: unknown parameter(s) {sorted(unknown)}; known: {known}"
            )
        try:
            self.pso = PSOConfig(**pso)
        except OptimizerError as e:
            raise PlannerError(f"{self.name}: {e}") from None
        if n_waypoints is not None and int(n_waypoints) < 1:
            raise PlannerError(f"n_waypoints must be >= 1, got {n_waypoints}")
        if (n_samples is not None and int(n_samples) < 1) or int(n_candidates) < 1:
            raise PlannerError("n_samples and n_candidates must be >= 1")
        if int(max_doublings) < 0:
            raise PlannerError(f"max_doublings must be >= 0, got {max_doublings}")
        if not gamma > 0 or penalty < 0:
            raise PlannerError(f"need gamma > 0 and penalty >= 0, got {gamma}, {penalty}")
        self.n_waypoints = None if n_waypoints is None else int(n_waypoints)
        self.cost = cost
        self.weights = weights
        self.n_samples = None if n_samples is None else int(n_samples)
        self.max_doublings = int(max_doublings)
        self.gamma = float(gamma)
        self.n_candidates = int(n_candidates)
        self.penalty = float(penalty)

    def _known(self) -> tuple[str, ...]:
        return self._own

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "n_waypoints": self.n_waypoints,
            "cost": self.cost,
            "weights": self.weights,
            "n_samples": self.n_samples,
            "max_doublings": self.max_doublings,
            "gamma": self.gamma,
            "n_candidates": self.n_candidates,
            "penalty": self.penalty,
            **config_dict(self.pso),
        }

    def _swarm(
        self,
        problem: PathProblem,
        ss: np.random.SeedSequence,
        stats: _Stats,
        seed_path: FloatArray | None = None,
    ) -> tuple[VariableLengthEncoding, PSO]:
        """The encoding and the RGG-seeded PSO of one (sub-)task."""
        rgg_ss, init_ss, pso_ss = ss.spawn(3)
        enc = VariableLengthEncoding(problem, self.n_waypoints, stats)
        pop = self.pso.pop_size
        cands = rgg_candidates(
            problem.scenario,
            np.random.default_rng(rgg_ss),
            problem.task,
            n_candidates=min(self.n_candidates, pop),
            n_samples=self.n_samples if self.n_samples is not None else enc.n_waypoints,
            max_doublings=self.max_doublings,
            gamma=self.gamma,
            penalty=self.penalty,
            strict_altitude=problem.strict_altitude,
            lookup=problem.lookup,
        )
        stats.edge_checks += cands.edge_checks
        stats.rgg_samples.append(cands.n_samples)
        paths = ([seed_path] if seed_path is not None else []) + cands.paths
        paths = paths[:pop]
        init = None
        if paths:
            feas = feasibility_problem(
                problem.scenario, problem.task, problem.strict_altitude, problem.lookup
            )
            interiors = []
            for p in paths:
                inner, checks = fit_interior(p, enc.n_waypoints, feas)
                stats.edge_checks += checks
                interiors.append(inner)
            init = initial_swarm(enc, interiors, pop, np.random.default_rng(init_ss))
        else:
            stats.uniform_seeded.append(problem.task.id)
        return enc, PSO(enc, self.pso, seed=np.random.default_rng(pso_ss), init=init)

    def _problem(self, scenario: Scenario, task: Task) -> PathProblem:
        try:
            return PathProblem(scenario, task, cost=self.cost, weights=self.weights)
        except ValueError as e:
            raise PlannerError(f"{self.name}: {e}") from None

    def _plan(
        self,
        scenario: Scenario,
        task: Task,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> PlanResult:
        t0 = time.perf_counter()
        problem = self._problem(scenario, task)
        stats = _Stats()
        enc, opt = self._swarm(problem, np.random.SeedSequence(seed), stats)

        def cb(o: optimizers.Optimizer) -> bool:
            return bool(callback(o.iterations, o.best_f)) if callback else False

        res = optimizers.run(opt, budget if budget is not None else DEFAULT_ITERATIONS, seed, cb)
        path, _, _ = enc.best()
        return _result(
            self,
            problem,
            path,
            seed,
            history=res.history,
            feasible_history=np.asarray(enc.feasible_history),
            evaluations=res.evaluations,
            evaluations_history=res.evaluations_history,
            wall_time=time.perf_counter() - t0,
            run=_run_info(stats),
        )


def _run_info(stats: _Stats) -> dict[str, Any]:
    return {
        "edge_checks": stats.edge_checks,
        "rgg_samples": list(stats.rgg_samples),
        "uniform_seeded": list(stats.uniform_seeded),
    }


def _result(
    planner: RGGPSOPlanner,
    problem: PathProblem,
    path: FloatArray,
    seed: int | None,
    history: FloatArray,
    feasible_history: FloatArray,
    evaluations: int,
    evaluations_history: NDArray[np.int64],
    wall_time: float,
    run: dict[str, Any],
) -> PlanResult:
    ev = problem.evaluate(path[None])
    fh = np.asarray(feasible_history, dtype=np.float64)
    finite = np.flatnonzero(np.isfinite(fh))
    config = planner.describe()
    config["run"] = run
    return PlanResult(
        uav_id=problem.task.id,
        waypoints=path,
        times=problem.times(path[None])[0],
        cost=float(ev.cost[0]),
        terms={k: float(v[0]) for k, v in ev.terms.items()},
        feasible=bool(ev.feasible[0]),
        evaluations=int(evaluations),
        iterations=len(history),
        wall_time=wall_time,
        history=np.asarray(history, dtype=np.float64),
        algorithm=planner.name,
        config=config,
        seed=seed,
        cost_model=problem.cost_name,
        violations=tuple(k for k, v in ev.violations.items() if v[0]),
        feasible_history=fh,
        first_feasible_iteration=int(finite[0]) + 1 if len(finite) else None,
        evaluations_history=np.asarray(evaluations_history, dtype=np.int64),
    )


class _Solver:
    """One (sub-)task of RGG-PSO+: whole-path swarm, then (maybe) two halves in lockstep."""

    def __init__(
        self,
        planner: RGGPSOPlusPlanner,
        scenario: Scenario,
        task: Task,
        iterations: int,
        depth: int,
        ss: np.random.SeedSequence,
        stats: _Stats,
        seed_path: FloatArray | None = None,
    ) -> None:
        self.planner = planner
        self.scenario = scenario
        self.problem = planner._problem(scenario, task)
        swarm_ss, self._kids_ss = ss.spawn(2)
        self.enc, self.opt = planner._swarm(self.problem, swarm_ss, stats, seed_path)
        self.stats = stats
        self.T = int(iterations)
        self.depth = int(depth)
        whole = round(planner.whole_fraction * self.T)
        self.T_w = self.T if self.depth <= 0 else min(self.T, max(1, whole))
        self.t = 0
        self.children: list[_Solver] | None = None
        #: (path, cost, feasible) on this solver's problem
        self.pre: tuple[FloatArray, float, bool] | None = None
        self.final: tuple[FloatArray, float, bool] | None = None
        self.split: int | None = None
        self.merge = ""

    def step(self) -> None:
        if self.children is None and self.t >= self.T_w and not self._divide():
            self.T_w = self.T
        if self.children is None:
            X = self.opt.ask()
            self.opt.tell(X, self.enc.evaluate(X))
        else:
            for c in self.children:
                c.step()
        self.t += 1
        if self.t >= self.T:
            self.finish()

    def _divide(self) -> bool:
        """Alg. 3: split the current best path at its middle node into two sub-tasks."""
        if self.depth <= 0:
            return False
        path, cost, feasible = self.enc.best()
        L = len(path)
        if L < 3:
            return False
        idx = L // 2
        p1, p2 = path[: idx + 1], path[idx:]
        if np.array_equal(p1[0], p1[-1]) or np.array_equal(p2[0], p2[-1]):
            return False
        task = self.problem.task
        t_split = task.start_time + float(
            np.sum(np.linalg.norm(np.diff(p1, axis=0), axis=1)) / self.scenario.uav.speed
        )
        t1 = Task(f"{task.id}/1", tuple(p1[0]), tuple(p1[-1]), task.start_time)
        t2 = Task(f"{task.id}/2", tuple(p2[0]), tuple(p2[-1]), t_split)
        s1, s2 = self._kids_ss.spawn(2)
        rest = self.T - self.t
        d = self.depth - 1
        self.children = [
            _Solver(self.planner, self.scenario, t1, rest, d, s1, self.stats, p1),
            _Solver(self.planner, self.scenario, t2, rest, d, s2, self.stats, p2),
        ]
        self.pre = (path, cost, feasible)
        self.split = idx
        return True

    def current(self) -> FloatArray:
        """The current best path of this (sub-)task."""
        if self.final is not None:
            return self.final[0]
        if self.children is None:
            return self.enc.best()[0]
        a, b = (c.current() for c in self.children)
        return particle_to_path(np.concatenate([a, b[1:]]))

    def finish(self) -> None:
        """Stop: a whole-path solver keeps its best; a divided one conquers (Alg. 4)."""
        if self.final is not None:
            return
        if self.children is None:
            self.final = self.enc.best()
            return
        for c in self.children:
            c.finish()
        a, b = (c.current() for c in self.children)
        res = conquer(self.problem, a, b)
        self.stats.evaluations += res.evaluations
        assert self.pre is not None
        pre_path, pre_cost, pre_feasible = self.pre
        options: list[tuple[float, FloatArray, str]] = []
        if res.best is not None:
            m = res.best
            kind = "concatenation" if (m.i, m.j) == (res.concatenation.i, 0) else "shortcut"
            options.append((m.cost, m.path, kind))
        if pre_feasible:
            options.append((pre_cost, pre_path, "pre-divide"))
        if options:
            cost, path, kind = min(options, key=lambda o: o[0])
            self.final = (path, cost, True)
        else:  # nothing feasible at all: the cheaper of the concatenation and the pre-divide best
            cat = res.concatenation
            if cat.cost <= pre_cost:
                self.final, kind = (cat.path, cat.cost, False), "concatenation (infeasible)"
            else:
                self.final, kind = (pre_path, pre_cost, False), "pre-divide (infeasible)"
        self.merge = kind


class RGGPSOPlusPlanner(RGGPSOPlanner):
    """RGG-PSO+ (``rgg-pso+``): RGG-PSO with divide and conquer (Alg. 3, 4); see the module
    docstring.

    Args:
        depth: recursion depth of the divide (1: the paper's one split into two halves).
        whole_fraction: share of the iterations spent on the whole path before dividing (0.5:
            100 of 200, then 100 per sub-path in lockstep).
        others: as :class:`RGGPSOPlanner`.
    """

    name = "rgg-pso+"

    def __init__(self, depth: int = 1, whole_fraction: float = 0.5, **kwargs: Any) -> None:
        if int(depth) < 0:
            raise PlannerError(f"depth must be >= 0, got {depth}")
        if not 0.0 < float(whole_fraction) < 1.0:
            raise PlannerError(f"whole_fraction must be in (0, 1), got {whole_fraction}")
        self.depth = int(depth)
        self.whole_fraction = float(whole_fraction)
        super().__init__(**kwargs)

    def _known(self) -> tuple[str, ...]:
        return (*self._own, "depth", "whole_fraction")

    def _iterations(self, b: Budget) -> int:
        """The overall iteration count T the divide is planned on: the budget's iterations; for
        an evaluation-only budget the T whose planned swarm evaluations fit it (the swarm count
        doubles at each divide level: ``pop (f + 2 f (1 - f) + ... + 2^depth (1 - f)^depth)``
        per iteration on average, ``f = whole_fraction``); else :data:`DEFAULT_ITERATIONS`.
        Any limit still stops the run early (the halves are then conquered as they are)."""
        if b.max_iterations is not None:
            return b.max_iterations
        if b.max_evaluations is None:
            return DEFAULT_ITERATIONS
        f, d = self.whole_fraction, self.depth
        swarms = sum(2**level * f * (1 - f) ** level for level in range(d)) + (2 * (1 - f)) ** d
        return max(1, int(b.max_evaluations / (self.pso.pop_size * swarms)))

    def describe(self) -> dict[str, Any]:
        return {**super().describe(), "depth": self.depth, "whole_fraction": self.whole_fraction}

    def _plan(
        self,
        scenario: Scenario,
        task: Task,
        budget: Budget | int | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> PlanResult:
        t0 = time.perf_counter()
        b = Budget.of(budget if budget is not None else DEFAULT_ITERATIONS)
        T = self._iterations(b)
        stats = _Stats()
        root = _Solver(self, scenario, task, T, self.depth, np.random.SeedSequence(seed), stats)
        hist: list[float] = []
        fhist: list[float] = []
        ehist: list[int] = []
        seen: tuple[FloatArray, float, bool] | None = None

        def record() -> None:
            nonlocal seen
            if root.children is None:
                h, fh = root.opt.best_f, root.enc.feasible_history[-1]
            elif root.final is not None:
                _, h, feas = root.final
                fh = h if feas else np.inf
            else:
                path = root.current()
                if seen is None or not np.array_equal(seen[0], path):
                    c, f = evaluate_paths(root.problem, [path])
                    stats.evaluations += 1
                    seen = (path, float(c[0]), bool(f[0]))
                h, fh = seen[1], seen[1] if seen[2] else np.inf
            hist.append(min(hist[-1], h) if hist else h)
            fhist.append(min(fhist[-1], fh) if fhist else fh)
            ehist.append(stats.evaluations)

        while root.final is None:
            root.step()
            record()
            stop = callback is not None and bool(callback(len(hist), hist[-1]))
            stop = stop or (
                b.max_evaluations is not None and stats.evaluations >= b.max_evaluations
            )
            stop = stop or (b.max_time is not None and time.perf_counter() - t0 >= b.max_time)
            if stop and root.final is None:
                root.finish()  # conquer what the halves have so far
                assert root.final is not None
                _, h, feas = root.final
                hist[-1] = min(hist[-1], h)
                fhist[-1] = min(fhist[-1], h if feas else np.inf)
                ehist[-1] = stats.evaluations
        assert root.final is not None
        run = _run_info(stats)
        run.update(
            pre_divide_cost=root.pre[1] if root.pre is not None else None,
            pre_divide_feasible=root.pre[2] if root.pre is not None else None,
            split_index=root.split,
            divided_at=root.T_w if root.pre is not None else None,
            merge=root.merge,
        )
        return _result(
            self,
            root.problem,
            root.final[0],
            seed,
            history=np.asarray(hist),
            feasible_history=np.asarray(fhist),
            evaluations=stats.evaluations,
            evaluations_history=np.asarray(ehist, dtype=np.int64),
            wall_time=time.perf_counter() - t0,
            run=run,
        )


def register_all() -> None:
    """Register ``rgg``, ``rgg-pso`` and ``rgg-pso+`` (idempotent)."""
    for name, factory in (
        ("rgg", RGGPlanner),
        ("rgg-pso", RGGPSOPlanner),
        ("rgg-pso+", RGGPSOPlusPlanner),
    ):
        if name not in _REGISTRY:
            register_planner(name, factory)
