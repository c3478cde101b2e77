"""RGG-PSO (Liu et al. 2024, J. Intell. Robot. Syst.): PSO over variable-length waypoint
particles seeded by random geometric graphs; its divide-and-conquer version RGG-PSO+ is in
:mod:`uavplan.planners.sampling.rgg_pso_plus`, the particles in
:mod:`uavplan.problems.variable_length`.

**Particles (Sect. 4.2.2).** A particle holds ``N`` free waypoints (default: the scenario's
``n_waypoints``; 20 in the paper and in ``simple2d``); the task's start and goal stay fixed
outside it (the paper adds them "to either end of the vector"; its footnote counts 22 nodes for
N = 20). Algs. 1-2 and the encoding that evaluates the decoded paths are in
:mod:`uavplan.problems.variable_length`; the genes are those of
:class:`~uavplan.problems.encoding.CartesianEncoding` (x, y[, z]; z above ground in a ground
band), so PSO moves exactly the paper's Eq. (1) particles.

**RGG-PSO (``rgg-pso``).** RGG candidates (:func:`uavplan.planners.sampling.rgg.rgg_candidates`, one
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

**Bookkeeping.** ``history`` is PSO's best cost so far per iteration, ``feasible_history`` the
best feasible one; ``evaluations`` counts swarm evaluations; RGG edge checks are feasibility
tests, reported in ``PlanResult.info["edge_checks"]``. All randomness comes from
``numpy.random.SeedSequence(seed)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.pso import PSO, PSOConfig
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.planners.sampling.rgg import DEFAULT_GAMMA, feasibility_problem, rgg_candidates
from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import PathProblem
from uavplan.problems.validity import MotionValidator, shortest_subsequence
from uavplan.problems.variable_length import (
    VariableLengthEncoding,
    evaluate_paths,
    particle_to_path,
    path_to_particle,
    subsample_indices,
    two_points,
)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]


@dataclass
class Stats:
    """Work counters shared by every (sub-)swarm of one run."""

    evaluations: int = 0
    edge_checks: int = 0
    uniform_seeded: list[str] = field(default_factory=list)
    rgg_samples: list[int] = field(default_factory=list)

    def info(self) -> dict[str, Any]:
        return {
            "edge_checks": self.edge_checks,
            "rgg_samples": list(self.rgg_samples),
            "uniform_seeded": list(self.uniform_seeded),
        }


# ------------------------------------------------------------------------------ candidates
def fit_interior(path: FloatArray, n: int, feas: MotionValidator) -> tuple[FloatArray, int]:
    """The interior nodes (k <= n, d) that Alg. 1 turns into a particle for candidate ``path``
    (start and goal included); see the module docstring. Returns them and the segment checks."""
    p = np.asarray(path, dtype=np.float64)
    inner = p[1:-1]
    if len(inner) == 0:
        return np.asarray(0.5 * (p[:1] + p[-1:])), 0
    if len(inner) <= n:
        return np.asarray(inner), 0
    short, checks = shortest_subsequence(feas, p, n)
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
    n = enc.n_waypoints
    particles = [path_to_particle(interiors[i % len(interiors)], n, rng) for i in range(pop_size)]
    return enc.encode(enc.problem.with_endpoints(np.stack(particles)))


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
    cat = Merge(two_points(merges[k_cat]), float(cost[k_cat]), bool(feas[k_cat]), *ij[k_cat])
    best = None
    if feas.any():
        k = int(np.argmin(np.where(feas, cost, np.inf)))
        best = Merge(two_points(merges[k]), float(cost[k]), True, *ij[k])
    return Conquest(best, cat, len(merges))


# ------------------------------------------------------------------------------ the planner
@dataclass(frozen=True)
class RGGPSOConfig(PlannerConfig):
    """RGG-PSO's options; PSO's (``pop_size``, ``w``, ``w_damp``, ``c1``, ``c2``,
    ``velocity_fraction``; Sect. 5.2.2: 100 particles, w = 1 damped by 0.98, c1 = c2 = 1.5) are
    routed into ``optimizer_options``."""

    optimizer_options: dict[str, Any] = option(
        default_factory=dict, doc="PSO's options (pop_size, w, w_damp, c1, c2, ...), given plainly"
    )
    n_waypoints: int | None = option(None, "particle length N (default: the scenario's)", low=1)
    n_samples: int | None = option(
        None, "RGG samples per graph (default N, as Sect. 4.2.1 says)", low=1
    )
    max_doublings: int = option(
        0, "densify a graph that does not connect the task by doubling its samples, at most this "
        "often (0: the paper's behaviour, such a swarm starts uniform)", low=0
    )  # fmt: skip
    gamma: float = option(DEFAULT_GAMMA, "RGG connectivity constant", low=0, low_open=True)
    n_candidates: int = option(10, "distinct RGG paths seeding the swarm (at most pop_size)", low=1)
    penalty: float = option(
        1.0, "edge-penalty factor for alternative candidates (lengths x (1 + penalty))", low=0
    )


@register_planner
class RGGPSOPlanner(Planner):
    """RGG-PSO: PSO over variable-length particles seeded by RGG paths (see the module)."""

    name = "rgg-pso"
    specs = PlannerSpecs(supports_reservations=True, inner_optimizer="pso", default_iterations=200)
    Config = RGGPSOConfig
    config: RGGPSOConfig

    def swarm(
        self,
        problem: PathProblem,
        ss: np.random.SeedSequence,
        stats: Stats,
        seed_path: FloatArray | None = None,
    ) -> tuple[VariableLengthEncoding, PSO]:
        """The encoding and the RGG-seeded PSO of one (sub-)task."""
        cfg = self.config
        pso = self.optimizer_config
        assert isinstance(pso, PSOConfig)
        rgg_ss, init_ss, pso_ss = ss.spawn(3)
        enc = VariableLengthEncoding(problem, cfg.n_waypoints, stats)
        pop = pso.pop_size
        cands = rgg_candidates(
            problem.scenario,
            np.random.default_rng(rgg_ss),
            problem.task,
            n_candidates=min(cfg.n_candidates, pop),
            n_samples=cfg.n_samples if cfg.n_samples is not None else enc.n_waypoints,
            max_doublings=cfg.max_doublings,
            gamma=cfg.gamma,
            penalty=cfg.penalty,
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
        return enc, PSO(enc, pso, seed=np.random.default_rng(pso_ss), init=init)

    def _plan(self, run: Run) -> Outcome:
        stats = Stats()
        enc, opt = self.swarm(run.problem, np.random.SeedSequence(run.seed), stats)
        tr = run.tracker
        while True:
            X = opt.ask()
            opt.tell(X, enc.evaluate(X))
            tr.evaluations += len(X)
            if tr.end_iteration(best=opt.best_f, feasible_best=enc.feasible_history[-1]):
                break
        path, _, _ = enc.best()
        return Outcome(path, info=stats.info())
