"""Random geometric graph (RGG) path candidates (Liu et al. 2024, RGG-PSO+, Sect. 4.2.1), and
the ``rgg`` planner: the graph's shortest path alone, a baseline.

Sect. 4.2.1 samples collision-free nodes, joins them with the start and the goal into an RGG
(an edge between every two nodes closer than a connection radius ``r``) and takes Dijkstra's
shortest path as a path candidate for the swarm. Here:

* **Sampling.** ``n`` points uniform in the sampling region, rejected (in batches) where a point
  is not feasible for :class:`~uavplan.problems.path_problem.PathProblem` (obstacles, bounds,
  terrain, altitude band). 2-D: the scene's box. 3-D: x, y in the box; z uniform in the
  altitude band above the terrain (``reference="ground"``), in the band intersected with the box
  (``"absolute"``), or in the box's z range (no band; points under the terrain are rejected).
  The paper samples exactly N (the particle length, 20) nodes; that leaves typical scenes
  disconnected, so we sample ``n_samples`` (default 100) and, if the start and the goal are
  still not connected, densify the same graph by doubling the samples (``max_doublings``
  times).
* **Connection radius** ``r = gamma (log n / n)^(1/d) mu^(1/d)``, ``n`` the number of samples,
  ``d`` the dimension and ``mu`` the measure (area / volume) of the sampling region. The PRM*
  connectivity / asymptotic-optimality bound (Karaman & Frazzoli 2011) is
  ``gamma > 2 (1 + 1/d)^(1/d) zeta_d^(-1/d)`` with ``zeta_d`` the unit ball's volume
  (using ``mu(X_free) <= mu``): 1.38 for d = 2 and 1.37 for d = 3. The default
  ``gamma = 1.5`` (:data:`DEFAULT_GAMMA`) sits just above it and connects the built-in and test
  scenes with 100 samples.
* **Edges.** Neighbour pairs within ``r`` from :meth:`scipy.spatial.cKDTree.query_pairs`; every
  candidate edge is checked at once as a batch of ``(E, 2, d)`` one-segment paths with a
  feasibility-only :class:`PathProblem` (no cost terms), i.e. with exactly the planners' exact
  kernels (circles, polygons, cylinders, bilinear terrain, bounds, altitude band at the nodes);
  no Python loop per edge. The straight start-goal edge is always a candidate, whatever ``r``.
  Moving obstacles are checked as if each edge were flown from the task's start time (the graph
  has no time); planners re-evaluate the final path honestly.
* **Shortest path**: :func:`scipy.sparse.csgraph.dijkstra` on Euclidean edge lengths (the
  paper's cost; for weighted presets the graph still minimizes length).
* **Several distinct candidates** (:func:`rgg_candidates`): after each shortest path, the
  lengths of its edges are multiplied by ``1 + penalty`` (default: doubled) and Dijkstra runs
  again (the penalty method for alternative routes); distinct node sequences are kept, sorted by
  true length, until ``n_candidates`` are found or ``3 n_candidates`` searches were made. One
  graph, many routes: alternatives differ in whole stretches (other homotopy classes when
  there are any), not just by a node.

Edge checks are feasibility tests of segments, not cost evaluations; :class:`RGG` counts them
(``edge_checks``) and the planners report them in ``PlanResult.info``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, PlannerError, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.problems.path_problem import lookup_for
from uavplan.problems.validity import MotionValidator
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Default RGG connectivity constant gamma (just above the PRM* bound, 1.38 in 2-D, 1.37 in 3-D).
DEFAULT_GAMMA = 1.5
#: Default number of samples of one graph.
DEFAULT_SAMPLES = 100


def prm_star_gamma(dim: int) -> float:
    """The PRM* lower bound ``2 (1 + 1/d)^(1/d) / zeta_d^(1/d)`` in units of ``mu^(1/d)``."""
    zeta = math.pi ** (dim / 2) / math.gamma(dim / 2 + 1)
    return float(2.0 * (1.0 + 1.0 / dim) ** (1.0 / dim) / zeta ** (1.0 / dim))


def connection_radius(n: int, dim: int, measure: float, gamma: float = DEFAULT_GAMMA) -> float:
    """``gamma (log n / n)^(1/d) measure^(1/d)`` for ``n >= 2`` samples (``n < 2``: the
    region's diameter-like scale ``measure^(1/d) gamma``)."""
    scale = measure ** (1.0 / dim)
    if n < 2:
        return float(gamma * scale)
    return float(gamma * (math.log(n) / n) ** (1.0 / dim) * scale)


def feasibility_problem(
    scenario: Scenario,
    task: Task | str | int | None = None,
    strict_altitude: bool = False,
    lookup: str | None = None,
) -> MotionValidator:
    """The validator of the graph's nodes and edges.

    ``lookup``: how terrain heights are read for the altitude band at the nodes (default: as
    the scenario's cost preset reads them, e.g. ``nearest`` for ``spso``), so that a node the
    graph accepts is feasible for the planner's problem too.
    """
    return MotionValidator(
        scenario,
        task,
        strict_altitude=strict_altitude,
        lookup=lookup if lookup is not None else lookup_for(scenario.cost),
    )


@dataclass(frozen=True)
class SamplingRegion:
    """Where RGG nodes are drawn: x, y (and z) in ``lo..hi``; ``z_mode`` ``"box"`` or
    ``"ground"`` (z = terrain + U(lo[2], hi[2])); ``measure`` = its area or volume."""

    lo: FloatArray
    hi: FloatArray
    z_mode: str
    measure: float

    @classmethod
    def of(cls, scenario: Scenario) -> SamplingRegion:
        lo = scenario.bounds.lo.astype(np.float64).copy()
        hi = scenario.bounds.hi.astype(np.float64).copy()
        z_mode = "box"
        band = scenario.altitude
        if scenario.dim == 3 and band is not None:
            if band.reference == "ground" and scenario.terrain is not None:
                lo[2], hi[2] = band.min, band.max
                z_mode = "ground"
            else:
                lo[2], hi[2] = max(lo[2], band.min), min(hi[2], band.max)
                if hi[2] <= lo[2]:
                    raise PlannerError("the altitude band does not meet the bounds")
        return cls(lo, hi, z_mode, float(np.prod(hi - lo)))

    def draw(
        self, scenario: Scenario, n: int, rng: np.random.Generator, lookup: str = "bilinear"
    ) -> FloatArray:
        p = self.lo + rng.random((n, len(self.lo))) * (self.hi - self.lo)
        if self.z_mode == "ground" and scenario.terrain is not None:
            p[:, 2] += scenario.terrain.lookup(p[:, 0], p[:, 1], lookup)
        return np.asarray(p)


def sample_free(
    feas: MotionValidator,
    n: int,
    rng: np.random.Generator,
    region: SamplingRegion | None = None,
    max_rounds: int = 64,
) -> FloatArray:
    """``n`` feasible points uniform in the sampling region (batched rejection sampling).

    Returns fewer than ``n`` points (possibly none) only when ``max_rounds`` batches could not
    find enough, i.e. when (almost) nothing of the region is free.
    """
    region = region or SamplingRegion.of(feas.scenario)
    found: list[FloatArray] = []
    have = 0
    rate = 1.0
    for _ in range(max_rounds):
        if have >= n:
            break
        m = max(32, math.ceil(1.2 * (n - have) / max(rate, 0.02)))
        p = region.draw(feas.scenario, m, rng, feas.lookup)
        ok = feas.is_valid(p)
        rate = max(float(ok.mean()), 1e-3)
        found.append(p[ok])
        have += int(ok.sum())
    pts = np.concatenate(found, axis=0) if found else np.zeros((0, len(region.lo)))
    return np.asarray(pts[:n])


class RGG:
    """A random geometric graph over the free space of one task, grown in batches.

    Node 0 is the start and node 1 the goal; nodes ``2..`` are samples. Edges ``(i, j)``, i < j,
    are collision-free segments; once accepted, an edge is kept when the graph densifies (so a
    densified graph's shortest path never gets longer).

    Args:
        scenario, task: the world and the task whose start and goal are joined.
        gamma: connectivity constant of :func:`connection_radius`.
        strict_altitude: as :class:`PathProblem`'s; lookup: see :func:`feasibility_problem`.
    """

    def __init__(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        gamma: float = DEFAULT_GAMMA,
        strict_altitude: bool = False,
        lookup: str | None = None,
    ) -> None:
        if not gamma > 0:
            raise PlannerError(f"gamma must be > 0, got {gamma}")
        self.feas = feasibility_problem(scenario, task, strict_altitude, lookup)
        self.scenario = scenario
        self.task = self.feas.task
        start = np.asarray(self.task.start, dtype=np.float64)
        goal = np.asarray(self.task.goal, dtype=np.float64)
        self.gamma = float(gamma)
        self.region = SamplingRegion.of(scenario)
        self.dim = scenario.dim
        self.nodes: FloatArray = np.stack([start, goal])
        self.edges: IntArray = np.zeros((0, 2), dtype=np.int64)
        self.lengths: FloatArray = np.zeros(0)
        self.radius = 0.0
        self.edge_checks = 1
        self._csr_cache: tuple[tuple[int, int], Any, IntArray] | None = None
        if bool(self.feas.segments_valid(self.nodes[:1], self.nodes[1:])[0]):
            self._add_edges(np.array([[0, 1]], dtype=np.int64))

    @property
    def n_samples(self) -> int:
        return len(self.nodes) - 2

    def _add_edges(self, pairs: IntArray) -> None:
        d = np.linalg.norm(self.nodes[pairs[:, 1]] - self.nodes[pairs[:, 0]], axis=1)
        self.edges = np.concatenate([self.edges, pairs], axis=0)
        self.lengths = np.concatenate([self.lengths, d])

    def add_samples(self, m: int, rng: np.random.Generator) -> int:
        """Draw ``m`` new free samples, shrink ``r`` to the new sample count, and check every
        new candidate edge (a pair within ``r`` with at least one new node) in one batch.
        Returns the number of samples added."""
        new = sample_free(self.feas, m, rng, self.region)
        n_old = len(self.nodes)
        self.nodes = np.concatenate([self.nodes, new], axis=0)
        self.radius = connection_radius(self.n_samples, self.dim, self.region.measure, self.gamma)
        if len(new) == 0:
            return 0
        from scipy.spatial import cKDTree  # lazy: SciPy's import is 0.3 s of a CLI start

        pairs = cKDTree(self.nodes).query_pairs(self.radius, output_type="ndarray")
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        pairs = np.sort(pairs, axis=1)
        pairs = pairs[(pairs[:, 1] >= n_old) & ~((pairs[:, 0] == 0) & (pairs[:, 1] == 1))]
        if len(pairs):
            ok = self.feas.segments_valid(self.nodes[pairs[:, 0]], self.nodes[pairs[:, 1]])
            self.edge_checks += len(pairs)
            self._add_edges(pairs[ok])
        return len(new)

    def shortest_path(self, weights: FloatArray | None = None) -> IntArray | None:
        """Node indices of Dijkstra's shortest start-goal path (``weights`` default: lengths),
        or None when the start and the goal are not connected."""
        w = self.lengths if weights is None else weights
        if len(self.edges) == 0:
            return None
        from scipy.sparse.csgraph import dijkstra

        g, entry_edge = self._csr()
        g.data = np.maximum(w, 1e-12)[entry_edge]  # an explicit zero would be no edge
        dist, pred = dijkstra(g, directed=False, indices=0, return_predecessors=True)
        if not np.isfinite(dist[1]):
            return None
        out = [1]
        while out[-1] != 0:
            out.append(int(pred[out[-1]]))
        return np.asarray(out[::-1], dtype=np.int64)

    def _csr(self) -> tuple[Any, IntArray]:
        """The graph as a sparse matrix for :func:`scipy.sparse.csgraph.dijkstra`, built once
        per set of nodes and edges (the edge-penalty searches change only the weights), and
        the edge of each stored entry: the matrix ``csr_matrix((w, (i, j)))`` would be, with
        its entries set to ``w[entry_edge]``."""
        key = (len(self.nodes), len(self.edges))
        if self._csr_cache is None or self._csr_cache[0] != key:
            from scipy.sparse import csr_matrix

            n = len(self.nodes)
            tag = np.arange(1.0, len(self.edges) + 1.0)  # entry k holds edge tag[k] - 1
            g = csr_matrix((tag, (self.edges[:, 0], self.edges[:, 1])), shape=(n, n))
            assert g.nnz == len(self.edges), "an edge is listed twice"
            self._csr_cache = (key, g, np.asarray(g.data, dtype=np.int64) - 1)
        return self._csr_cache[1], self._csr_cache[2]

    def path(self, idx: IntArray) -> FloatArray:
        """Waypoints (k, d) of a node-index path."""
        return np.asarray(self.nodes[idx].copy())

    def candidates(self, n_candidates: int, penalty: float = 1.0) -> list[IntArray]:
        """Up to ``n_candidates`` distinct start-goal node paths by the edge-penalty method
        (see the module docstring), shortest first."""
        key = self.edges[:, 0] * len(self.nodes) + self.edges[:, 1]
        order = np.argsort(key)
        w = self.lengths.copy()
        found: dict[tuple[int, ...], float] = {}
        for _ in range(3 * n_candidates):
            idx = self.shortest_path(w)
            if idx is None:
                break
            t = tuple(int(i) for i in idx)
            if t not in found:
                found[t] = float(np.sum(np.linalg.norm(np.diff(self.nodes[idx], axis=0), axis=1)))
                if len(found) >= n_candidates:
                    break
            a, b = np.minimum(idx[:-1], idx[1:]), np.maximum(idx[:-1], idx[1:])
            used = order[np.searchsorted(key, a * len(self.nodes) + b, sorter=order)]
            w[used] *= 1.0 + penalty
        ranked = sorted(found.items(), key=lambda kv: kv[1])
        return [np.asarray(k, dtype=np.int64) for k, _ in ranked]


def build_rgg(
    scenario: Scenario,
    rng: np.random.Generator,
    task: Task | str | int | None = None,
    n_samples: int = DEFAULT_SAMPLES,
    gamma: float = DEFAULT_GAMMA,
    max_doublings: int = 3,
    strict_altitude: bool = False,
    lookup: str | None = None,
) -> RGG:
    """An RGG of ``n_samples`` samples, densified by doubling (at most ``max_doublings`` times)
    until the start and the goal are connected."""
    if n_samples < 1:
        raise PlannerError(f"n_samples must be >= 1, got {n_samples}")
    g = RGG(scenario, task, gamma, strict_altitude, lookup)
    g.add_samples(n_samples, rng)
    for _ in range(max_doublings):
        if g.shortest_path() is not None:
            break
        g.add_samples(max(g.n_samples, n_samples), rng)
    return g


@dataclass(frozen=True)
class Candidates:
    """Distinct RGG paths (each (k, d), start and goal included), shortest first, and the work
    spent: ``edge_checks`` segment feasibility tests and the graph's final ``n_samples``."""

    paths: list[FloatArray]
    edge_checks: int
    n_samples: int
    radius: float


def rgg_candidates(
    scenario: Scenario,
    rng: np.random.Generator,
    task: Task | str | int | None = None,
    n_candidates: int = 10,
    n_samples: int = DEFAULT_SAMPLES,
    gamma: float = DEFAULT_GAMMA,
    penalty: float = 1.0,
    max_doublings: int = 3,
    strict_altitude: bool = False,
    lookup: str | None = None,
) -> Candidates:
    """Several distinct path candidates for the swarm (Sect. 4.2.1): one RGG (see
    :func:`build_rgg`), alternatives by the edge-penalty method. Empty when disconnected."""
    if n_candidates < 1:
        raise PlannerError(f"n_candidates must be >= 1, got {n_candidates}")
    if penalty < 0:
        raise PlannerError(f"penalty must be >= 0, got {penalty}")
    g = build_rgg(scenario, rng, task, n_samples, gamma, max_doublings, strict_altitude, lookup)
    paths = [g.path(idx) for idx in g.candidates(n_candidates, penalty)]
    return Candidates(paths, g.edge_checks, g.n_samples, g.radius)


def rgg_shortest_path(
    scenario: Scenario,
    rng: np.random.Generator,
    task: Task | str | int | None = None,
    n_samples: int = DEFAULT_SAMPLES,
    gamma: float = DEFAULT_GAMMA,
    max_doublings: int = 3,
    strict_altitude: bool = False,
    lookup: str | None = None,
) -> FloatArray | None:
    """The RGG's shortest start-goal path (k, d), or None if the graph stays disconnected."""
    g = build_rgg(scenario, rng, task, n_samples, gamma, max_doublings, strict_altitude, lookup)
    idx = g.shortest_path()
    return None if idx is None else g.path(idx)


# ---------------------------------------------------------------------------------- the planner
@dataclass(frozen=True)
class RGGConfig(PlannerConfig):
    """Options of the ``rgg`` planner (ours: the paper uses the RGG only to seed PSO)."""

    samples: int = option(DEFAULT_SAMPLES, "free samples added to the graph per iteration", low=1)
    gamma: float = option(
        DEFAULT_GAMMA, "connectivity constant of the radius (PRM* bound: 1.38 in 2-D)", low=0,
        low_open=True,
    )  # fmt: skip


@register_planner
class RGGPlanner(Planner):
    """The RGG's shortest path alone (a baseline), anytime by batch densification.

    Iteration t adds ``samples`` samples to one graph, shrinks ``r`` to the new sample count,
    checks the new edges and runs Dijkstra; the path is evaluated (one evaluation) when it
    changed. ``history`` is the best cost so far (inf until the start and goal connect). If they
    never connect, the result is the straight start-goal segment, ``feasible=False``, with
    ``"disconnected"`` among its violations.

    Budget: its iterations (default 20; an evaluation-only budget is capped there too, since an
    unchanged path is not re-evaluated), stopped earlier by its evaluations or time.
    """

    # its graph has no time: moving obstacles are refused
    specs = PlannerSpecs(handles_moving=False, default_iterations=20)

    name = "rgg"
    Config = RGGConfig
    config: RGGConfig

    def iteration_limit(self, budget: Budget) -> int | None:
        return budget.max_iterations or self.specs.default_iterations

    def _plan(self, run: Run) -> Outcome:
        cfg = self.config
        problem = run.problem
        rng = np.random.default_rng(np.random.SeedSequence(run.seed))
        g = RGG(run.scenario, run.task, cfg.gamma, lookup=problem.lookup)
        tr = run.tracker
        last: IntArray | None = None
        while True:
            g.add_samples(cfg.samples, rng)
            idx = g.shortest_path()
            if idx is not None and (last is None or not np.array_equal(idx, last)):
                last = idx
                path = g.path(idx)
                ev = problem.evaluate(path[None])
                tr.evaluations += 1
                tr.offer(path, float(ev.cost[0]), bool(ev.feasible[0]))
            if tr.end_iteration():
                break
        disconnected = tr.path is None
        return Outcome(
            reasons=("disconnected",) if disconnected else (),
            info={
                "edge_checks": g.edge_checks,
                "n_samples": g.n_samples,
                "radius": g.radius,
                "edges": len(g.edges),
                "reason": "start and goal not connected in the RGG" if disconnected else "",
            },
        )
