"""RRT* (PPSwarm Alg. 1: Meng, Li, Zhang, Wang & Tian 2024, "PPSwarm: Multi-UAV path planning
based on hybrid PSO in complex scenarios", Drones 8(5), 192, Sect. 3.2 and 4.2.1), in 3-D (and
2-D), as a planner of its own (``rrt-star``) and as :func:`rrt_star`, PPSwarm's initial path.

**Alg. 1, line by line** (:meth:`RRTStarTree.iterate` is one pass of its loop):

3. ``Randsample(E)``: x, y uniform in the scenario's bounds; z uniform in the altitude band
   above the terrain (``reference="ground"``: a height drawn uniformly in the band plus
   :meth:`Scenario.ground` at (x, y)), uniform in the band intersected with the z bounds
   (``"absolute"``), or uniform in the z bounds (no band). With probability ``goal_bias`` the
   sample is the goal itself (not in the paper, see the defaults). Samples are drawn in blocks
   from the one ``numpy.random.Generator``, so a run is a function of its seed.
4. ``Nearest``: a uniform grid over the bounds (:class:`GridIndex`, Numba kernels): rings of
   cells around the query cell, outwards, until the best distance found is below the distance
   to the next ring (exact; ties go to the lower node index, as :func:`nearest_brute`). The
   cell is ``max(r(n), (box measure / n)^(1/d))`` (``r(n)`` below; the second term keeps about
   a node per cell, so that a young tree in a large world does not leave the rings empty), and
   the grid is rebuilt whenever that falls below half the current cell. Only when the rings
   would visit more cells than there are nodes are the nodes scanned instead (a tree of a few
   dozen nodes, or a query far outside it): then that is the cheaper exact answer.
5. ``Steer``: at most ``step`` metres from ``x_nearest`` towards the sample (the sample itself if
   it is closer). A sample that coincides with its nearest node is skipped.
6. ``IsCollisionFree(x_nearest, x_new)``: the segment is feasible for
   ``PathProblem(scenario, task, strict_altitude=True)`` (see *Validity*); if not, the iteration
   ends.
7. ``Near``: the nodes within ``r(n) = min(near_radius, rewire_factor * gamma*
   (log n / n)^(1/d))`` of ``x_new`` (``n`` = nodes + 1 as OMPL counts, ``d`` = 2 or 3), from the
   grid's neighbour cells (27 while ``r`` <= cell). ``gamma* = (2 (1 + 1/d) mu / zeta_d)^(1/d)``
   is the RRT* bound of Karaman & Frazzoli (2011, IJRR 30(7), Thm. 38) in OMPL's form, ``mu`` the
   measure of the sampling region and ``zeta_d`` the unit ball's. ``x_nearest`` is always a
   candidate parent.
8. ``ChooseParent``: the candidate with a free segment to ``x_new`` and the least cost-to-come
   plus segment length (ties: the lower index).
9. ``InsertNodeAndRewire``: every other candidate with a free segment whose cost-to-come through
   ``x_new`` is lower (by more than 1 nm) takes ``x_new`` as its parent; the costs of its whole
   subtree are recomputed (cost = parent cost + segment length, exactly), so the tree stays
   consistent. A rewired node is never an ancestor of ``x_new`` (its cost would be lower), so no
   cycle can form.
10. ``InGoalRegion``: ``|x_new - goal| <= goal_radius`` **and** the segment ``x_new -> goal`` is
    free: the path must end exactly at the goal, so a node in the region that cannot see the goal
    does not end the search (a small deviation: the paper only says "in the goal region").
11. ``ExtractPathToGoal``: the tree path start .. ``x_new`` plus the exact goal. With
    ``stop_at_goal=False`` the loop goes on (plain anytime RRT*) and the path is the shortest one
    through any goal-connected node.
12. ``break`` when ``stop_at_goal`` (the default of :class:`RRTStarConfig`, as Alg. 1).

In the Python loop (:meth:`RRTStarTree.iterate`, the reference) all segment checks of one
iteration (every near candidate to ``x_new``, and ``x_new`` to the goal when in the region) go to
**one** batched validator call; a segment is free in both directions, so rewiring reuses the
choose-parent checks. The Numba loop (below) checks them lazily. The paper's Sect. 3.2 text
takes the choose-parent set within the step size and the rewiring set within an unnamed
"radius"; we use one near set for both, as RRT* does.

**Validity.** A segment is free when ``PathProblem(scenario, task, cost=(),
strict_altitude=True)`` finds it feasible: in bounds, clear of cylinders, circles, polygons and
revealed uncertain areas (exact), above the terrain along the segment (exact, bilinear DEM) and
inside the altitude band along it (``strict_altitude``). No cost term is computed (``cost=()``;
feasibility does not depend on the preset, so this is the same verdict as
``cost="ppswarm"`` at about half the time). Node heights in the band are also read the way the
scenario's cost preset reads them (``nearest`` for ``spso``), so a path free for the tree is
feasible for the scenario's own problem too. Moving obstacles are checked as if each segment were
flown from the task's start time (the tree has no time); the planner re-evaluates its path
honestly.

**Defaults** (the paper gives no number for any of them; chosen for SPSO's 1045 m x 879 m
ChrismasTerrain world, 100-200 m above ground, that PPSwarm's experiments follow):

* ``step = 50`` m: about 1/18 of the 923 m start-goal distance and well under the threat
  radii (70-80 m) and the gaps between them, so the tree threads between the cylinders. On spso
  (100 seeds) the first path comes after a median 133 iterations (max 296).
* ``near_radius = 100`` m (2 ``step``), the cap of the shrinking RRT* radius; with
  ``rewire_factor = 1.1`` (OMPL's default) the rule gives r = 152 m at 100 nodes, 82 m at 1000
  and 51 m at 5000 on spso, so the cap acts only in young trees, i.e. in Alg. 1's runs that stop
  at the goal. The RRT* literature (and OMPL) caps at the step; twice the step gives a first
  path 11 % shorter on spso (median 1118 m vs 1262 m, 100 seeds) for 2.8 times the segment
  checks (400 vs 145 per run, about 35 % more time).
* ``goal_radius = 50`` m (= ``step``): a node one step from the goal may end the search.
* ``goal_bias = 0.05``: OMPL's default; the paper samples uniformly (``goal_bias=0``), which
  doubles the iterations to the first path on spso (median 264, max 1537) and lengthens it 5 %.
* ``max_iterations = 5000``: over three times the worst first-path iteration above, even
  without goal bias.
* ``shortcut = False``: greedy shortcutting
  (:func:`~uavplan.problems.validity.greedy_shortcut`) is not in the paper.
* ``informed = False``: Informed RRT* (Gammell, Srinivasa & Barfoot, "Informed RRT*", IROS
  2014), not in the paper. Once the tree has a goal path of length ``c``, only a sample ``x``
  with ``|x - start| + |x - goal| < c`` (the prolate spheroid with foci start and goal) can lie
  on a shorter path, since tree costs are Euclidean lengths; the others are rejected and drawn
  again (from the same sampler, so the samples stay uniform over the sampling region, altitude
  band included, within the spheroid; after 1,000 rejections in a row the next sample is
  kept). Goal-biased samples always pass. The near radius keeps the sampling region's
  measure (see ``docs/decisions.md``).
* ``loop = "numba"``: how iterations run, not what they compute (see below).

**The Numba loop.** Where the tree's validator has a compiled segment check
(:attr:`MotionValidator.segment_kernel`: a 3-D world of bounds, fewer than 64 cylinders,
terrain read bilinearly and the band, as ``ppswarm``, ``dense`` and the RGG scenes), whole
iterations run in Numba (:func:`uavplan.planners.sampling._rrt_star_kernels.grow`): sampling from
the drawn blocks, the grid queries, steering, the checks, choose-parent, rewiring, the goal test.
It builds the same tree as the Python loop, node for node (the tests compare them on random
worlds), but checks segments lazily (OMPL's ``delayCC``): the nearest node's segment first,
then the candidate parents in order of cost through them until one is free, then only the
candidates that the new node would make cheaper; ``edge_checks`` counts the checks made, 4-10
times fewer. Elsewhere (2-D, circles, polygons, moving obstacles, ``spso``'s nearest-node
heights, 64+ cylinders) the Python loop runs, with Numba's parallel feasibility kernels on one
thread (:func:`serial_numba`): a batch is a few dozen segments, and waking threads for it costs
more than the work. ``loop="python"`` forces the reference. Measured numbers:
``benchmarks/rrt_star_nn.py``, ``benchmarks/vs_ompl.py``.

**Planner** (:class:`RRTStarPlanner`, ``rrt-star``). One planner iteration is one RRT*
iteration, so the budget counts RRT* iterations. By default the planner is *anytime*: it keeps
growing and rewiring the tree until its budget is spent (``stop_at_goal=False``), so that it
spends the same budget as the other planners; pass ``stop_at_goal=True`` for Alg. 1's break.
Whenever the tree's shortest goal path changes, that path is evaluated under the scenario's cost
preset (one path evaluation); the result is the lowest-cost feasible path so evaluated.
``history`` is the best such cost so far per planner iteration (inf before the first path, as
``rgg``); ``evaluations`` counts segment checks (and shortcut checks), the work that dominates;
path evaluations are reported in ``config["run"]``. If no path is found, the result is the
straight start-goal segment with ``feasible=False`` and ``"no_path"`` among its violations. The
Numba loop runs up to :data:`CHUNK` iterations per call (returning early when the shortest goal
path changes) and the tracker closes them together (:meth:`Tracker.end_iterations`), so a wall-
time budget is looked at every few milliseconds; with a callback or an evaluation limit, one
iteration per call.

``tighten`` (planner option, default off; not in the paper): a new shortest tree path is
shortcut, pulled tight by an elastic band (points at most ``step / 2`` apart, each moved towards
its neighbours' midpoint by the largest of 1, 1/2, ..., 1/32 of the way whose two segments the
validator accepts; at most :data:`BAND_SWEEPS` sweeps) and shortcut again
(:mod:`uavplan.planners.sampling._tighten_kernels`; the compiled check where the Numba loop runs,
else the Python references with the validator). So are the tree paths of up to two other goal nodes
on branches of their own whose tree paths are within 1 % of the shortest
(:data:`TIGHTEN_PATHS`, :data:`TIGHTEN_SLACK`, :func:`_rrt_star_kernels.distinct_goal_nodes`):
a longer tree path may lie in a way between the obstacles that tightens shorter. The shortest
result is evaluated and offered like any tree path (kept only if its cost is lower); with
``informed``, its length bounds the spheroid (:meth:`RRTStarTree.bound_by`). It never lengthens
a path and every segment is judged by the same exact validator. A tightening costs a few
milliseconds, so it runs on the first path and then once the iterations have grown by 25 %
(:data:`TIGHTEN_GROWTH`, at least :data:`TIGHTEN_GAP`) since the last; a run with an iteration
budget stays a function of its seed. Its effect on the dense field of
``benchmarks/vs_ompl.py``: ``docs/results.md``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, fields

import numba
import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import Options, PlannerConfig, PlannerError, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.planners.sampling import _rrt_star_kernels as K
from uavplan.planners.sampling import _tighten_kernels as T
from uavplan.planners.sampling.grid_index import GridIndex, pad3
from uavplan.problems import work
from uavplan.problems.path_problem import lookup_for
from uavplan.problems.validity import MotionValidator, greedy_shortcut
from uavplan.world.scenario import Scenario, Task
from uavplan.world.tolerances import REWIRE_TOL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: Samples drawn from the generator at a time.
SAMPLE_BLOCK = 256
#: Blocks drawn at once once informed sampling is on (most samples are then rejected).
INFORMED_BLOCKS = 16
#: Most RRT* iterations the planner runs per call of the Numba loop (between two looks at the
#: wall clock).
CHUNK = 256
#: ``tighten``: the next shortest tree path is tightened once the iterations have grown by this
#: factor, and by at least this many, since the last tightening (a handful per run, each a few
#: milliseconds), with at most this many sweeps of the band.
TIGHTEN_GROWTH = 1.25
TIGHTEN_GAP = 256
BAND_SWEEPS = 200
#: ``tighten``: the tree paths tightened each time (the shortest and others on branches of
#: their own).
TIGHTEN_PATHS = 3
#: ... whose tree paths are at most this much longer than the shortest (relative).
TIGHTEN_SLACK = 0.01


# ------------------------------------------------------------------------------ configuration
@dataclass(frozen=True)
class RRTStarConfig(Options):
    """RRT* settings (metres); defaults and their reasons in the module docstring."""

    step: float = option(50.0, "steering step (Alg. 1 line 5)", low=0, low_open=True)
    max_iterations: int = option(5000, "Alg. 1's Iterations", low=1)
    goal_radius: float = option(50.0, "goal region's radius (line 10)", low=0, low_open=True)
    near_radius: float = option(100.0, "cap of the near/rewire radius (line 7)", low=0,
                                low_open=True)  # fmt: skip
    goal_bias: float = option(0.05, "probability that a sample is the goal (OMPL's; not in the "
                              "paper)", low=0, high=1, high_open=True)  # fmt: skip
    rewire_factor: float = option(1.1, "factor on the RRT* radius bound gamma* (OMPL's)", low=0,
                                  low_open=True)  # fmt: skip
    stop_at_goal: bool = option(True, "Alg. 1 line 12: stop at the first goal connection")
    shortcut: bool = option(False, "greedy shortcutting of the extracted path (not in the paper)")
    informed: bool = option(
        False, "Informed RRT*: once a goal path exists, sample only where a shorter one can pass"
    )
    loop: str = option(
        "numba", "numba: whole iterations in Numba where the world has a compiled segment check "
        "(the same tree); python: the reference loop", choices=("numba", "python"),
    )  # fmt: skip
    climb_limits: bool = option(
        False, "every edge within the UAV's climb and descent angles (ours; the paper's edges "
        "keep clear of the world only): no smoothing flies a segment steeper than the UAV climbs"
    )  # fmt: skip


@dataclass(frozen=True)
class RRTStarResult:
    """The outcome of :func:`rrt_star`.

    Attributes:
        path: (n, dim) start .. goal (the exact goal last), or None if none was found.
        n_nodes: tree size at the end; iterations: loop passes run (Alg. 1 line 2).
        found_iteration: 1-based iteration of the first goal connection, None if none.
        cost: the path's length (inf without a path).
        edge_checks: segments checked (tree and shortcut).
    """

    path: FloatArray | None
    n_nodes: int
    iterations: int
    found_iteration: int | None
    cost: float
    edge_checks: int = 0


# ------------------------------------------------------------------------------ tree kernels
def _d3(a: FloatArray, b: FloatArray) -> float:
    """``|a - b|`` of two padded 3-vectors, with the Numba loop's arithmetic."""
    return float(K.dist3(a[0], a[1], a[2], b[0], b[1], b[2]))


@njit(cache=True)
def _insert_rewire(pts, parent, cost, first_child, next_sib, stack, new, cand, ok):
    """Alg. 1 lines 8-9 for node ``new`` (its point already in ``pts``): choose the parent among
    the candidates with ``ok`` segments, then rewire the others through ``new`` and recompute the
    costs of their subtrees. Returns the number of rewired nodes (-1 if no candidate is ok)."""
    best = -1
    bc = np.inf
    for t in range(cand.shape[0]):
        if ok[t]:
            c = cost[cand[t]] + K.dist3(
                pts[cand[t], 0], pts[cand[t], 1], pts[cand[t], 2], pts[new, 0], pts[new, 1],
                pts[new, 2],
            )  # fmt: skip
            if c < bc:
                bc = c
                best = cand[t]
    if best < 0:
        return -1
    K.link(parent, cost, first_child, next_sib, new, best, bc)
    rewired = 0
    for t in range(cand.shape[0]):
        j = cand[t]
        if not ok[t] or j == best:
            continue
        c = bc + K.dist3(pts[j, 0], pts[j, 1], pts[j, 2], pts[new, 0], pts[new, 1], pts[new, 2])
        if c + REWIRE_TOL < cost[j]:
            K.reparent(pts, parent, cost, first_child, next_sib, stack, j, new, c)
            rewired += 1
    return rewired


# ------------------------------------------------------------------------------ problem helpers
@contextmanager
def serial_numba() -> Iterator[None]:
    """Run Numba's parallel kernels on one thread inside the block (this thread only; the
    previous count is restored): RRT*'s segment batches are a few dozen segments, for which
    waking and joining threads costs more than the work."""
    prev = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(prev)


def validity_problem(
    scenario: Scenario, task: Task | str | int | None = None, climb: bool = False
) -> MotionValidator:
    """The segment checker of the tree: strict-altitude validity, node heights read as the
    scenario's cost preset reads them (see the module docstring); with ``climb``, each edge
    also within the UAV's climb and descent angles."""
    return MotionValidator(scenario, task, strict_altitude=True,
                           lookup=lookup_for(scenario.cost), climb=climb)  # fmt: skip


# ------------------------------------------------------------------------------ the tree
def _unit_ball_volume(d: int) -> float:
    return float(math.pi ** (d / 2) / math.gamma(d / 2 + 1))


def _counter(i: int, doc: str) -> property:
    """A read-only view of the loop's counter ``i`` as an int."""
    return property(lambda self: int(self._ctr[i]), doc=doc)


class RRTStarTree:
    """One RRT* run (PPSwarm Alg. 1), one loop pass per :meth:`iterate`.

    Node 0 is the start. Arrays (first ``n_nodes`` rows valid): ``points`` (n, dim),
    ``parent`` (-1 for the root), ``cost`` (cost-to-come, metres). ``goal_nodes`` are the nodes
    whose segment to the exact goal is free and within ``goal_radius``.

    :meth:`iterate` is one pass in Python (the reference: every segment of the pass checked in
    one batch by the validator). :meth:`run` and :meth:`advance` run many passes in Numba
    (:func:`uavplan.planners.sampling._rrt_star_kernels.grow`) where the validator has a compiled
    segment check (:attr:`MotionValidator.segment_kernel`; ``fast=False`` turns it off): the
    same tree, node for node, with the segments checked lazily (fewer ``edge_checks``).

    Args:
        scenario, task: the world and the task (start = root, goal).
        config: :class:`RRTStarConfig`.
        rng: the only source of randomness.
        validator: the segment checker (default :func:`validity_problem`).
        fast: use the Numba loop where it applies (default: ``config.loop == "numba"``).
    """

    def __init__(
        self,
        scenario: Scenario,
        task: Task | str | int | None,
        config: RRTStarConfig,
        rng: np.random.Generator,
        validator: MotionValidator | None = None,
        fast: bool | None = None,
    ) -> None:
        self.scenario = scenario
        self.task = task if isinstance(task, Task) else scenario.task(task)
        self.config = config
        self.rng = rng
        self.validator = validator or validity_problem(scenario, self.task, config.climb_limits)
        self.dim = scenario.dim
        self.start = np.asarray(self.task.start, dtype=np.float64)
        self.goal = np.asarray(self.task.goal, dtype=np.float64)
        self._start3, self._goal3 = pad3(self.start), pad3(self.goal)
        # sampling region
        lo = scenario.bounds.lo.astype(np.float64).copy()
        hi = scenario.bounds.hi.astype(np.float64).copy()
        self._ground_z = False
        band = scenario.altitude
        if self.dim == 3 and band is not None:
            if band.reference == "ground":
                lo[2], hi[2] = band.min, band.max
                self._ground_z = True
            else:
                lo[2], hi[2] = max(lo[2], band.min), min(hi[2], band.max)
                if hi[2] <= lo[2]:
                    raise PlannerError("rrt-star: the altitude band does not meet the bounds")
        self._lo, self._hi = lo, hi
        self.measure = float(np.prod(hi - lo))
        d = self.dim
        self.gamma = config.rewire_factor * float(
            (2.0 * (1.0 + 1.0 / d) * self.measure / _unit_ball_volume(d)) ** (1.0 / d)
        )
        # the grid covers the bounds, the start and the goal
        blo = np.minimum.reduce([scenario.bounds.lo, self.start, self.goal])
        bhi = np.maximum.reduce([scenario.bounds.hi, self.start, self.goal])
        side = float(np.prod((bhi - blo)[: self.dim])) ** (1.0 / self.dim)
        self.grid = GridIndex(blo, bhi, max(config.near_radius, side))
        cap = len(self.grid.buffer)
        self._parent = np.full(cap, -1, dtype=np.int64)
        self._cost = np.zeros(cap)
        self._first_child = np.full(cap, -1, dtype=np.int64)
        self._next_sib = np.full(cap, -1, dtype=np.int64)
        self._stack = np.zeros(cap, dtype=np.int64)
        self._goal_nodes = np.zeros(cap, dtype=np.int64)
        self.grid.add(self.start)
        #: the loop's counters (:mod:`uavplan.planners.sampling._rrt_star_kernels`'s ``ctr``
        #: entries)
        self._ctr = np.zeros(K.N_CTR, dtype=np.int64)
        self._ctr[K.N] = 1
        self._ctr[K.BEST] = -1
        self._fl = np.array([math.inf, 0.0, math.inf])
        self._samples = np.zeros((0, 3))
        self._goal_draw = np.zeros(0, dtype=bool)
        if fast is None:
            fast = config.loop == "numba"
        kernel = self.validator.segment_kernel if fast and self.dim == 3 else None
        self._kargs = None if kernel is None else kernel[1]
        self._cfg = np.zeros(K.N_CFG)
        self._cfg[[K.STEP, K.GOAL_RADIUS, K.NEAR_RADIUS, K.GAMMA, K.DIM]] = (
            config.step, config.goal_radius, config.near_radius, self.gamma, d
        )  # fmt: skip
        self._cfg[K.MEASURE] = self.grid.measure
        self._cfg[K.INFORMED] = float(config.informed)

    # ---------------------------------------------------------------- views
    @property
    def fast(self) -> bool:
        """Whether :meth:`run` and :meth:`advance` run the Numba loop."""
        return self._kargs is not None

    @property
    def n_nodes(self) -> int:
        return self.grid.n

    @property
    def points(self) -> FloatArray:
        return self.grid.points

    @property
    def parent(self) -> IntArray:
        return self._parent[: self.n_nodes]

    @property
    def cost(self) -> FloatArray:
        return self._cost[: self.n_nodes]

    @property
    def goal_nodes(self) -> list[int]:
        return self._goal_nodes[: self._ctr[K.N_GOAL]].tolist()

    iterations = _counter(K.ITER, "Loop passes run (Alg. 1 line 2).")
    edge_checks = _counter(K.CHECKS, "Segments checked.")
    rewires = _counter(K.REWIRES, "Nodes given a new parent (line 9).")
    rejected = _counter(K.REJECTED, "Informed samples drawn again.")

    @property
    def found_iteration(self) -> int | None:
        return int(self._ctr[K.FOUND]) or None

    def radius(self) -> float:
        """The near radius for the current tree (Alg. 1 line 7)."""
        card = self.n_nodes + 1
        r = self.gamma * (math.log(card) / card) ** (1.0 / self.dim)
        return float(min(self.config.near_radius, r))

    # ---------------------------------------------------------------- Alg. 1
    def _refill(self) -> None:
        """The next sample blocks: each ``SAMPLE_BLOCK`` goal draws, then as many samples, from
        the generator; one block at a time, :data:`INFORMED_BLOCKS` once informed sampling
        rejects most samples (the same stream: only how much is drawn ahead differs)."""
        b = SAMPLE_BLOCK
        k = INFORMED_BLOCKS if self.config.informed and self._ctr[K.N_GOAL] else 1
        # block by block: b goal draws, then b samples; one draw of k such blocks is the same
        # stream (the generator fills an array value after value)
        u = self.rng.random((k, b * (1 + self.dim)))
        self._goal_draw = (u[:, :b] < self.config.goal_bias).ravel()
        out = np.zeros((k * b, 3))
        # lo + u (hi - lo), written in place (the same values, no temporaries)
        np.multiply(u[:, b:].reshape(k, b, self.dim), self._hi - self._lo,
                    out=out.reshape(k, b, 3)[:, :, : self.dim])  # fmt: skip
        p = out[:, : self.dim]
        p += self._lo
        if self._ground_z:
            p[:, 2] += self.scenario.ground(p[:, 0], p[:, 1])
        self._samples = out
        self._ctr[K.POS] = 0

    def _draw(self) -> FloatArray:
        if self._ctr[K.POS] >= len(self._samples):
            self._refill()
        i = int(self._ctr[K.POS])
        self._ctr[K.POS] += 1
        return self._goal3.copy() if self._goal_draw[i] else self._samples[i].copy()

    def informed_bound(self) -> float:
        """Informed RRT*'s ``c_best``: the length of the shortest goal path in the tree, or of
        the path given to :meth:`bound_by` if shorter (inf if neither)."""
        return min(float(self._best()[1]), float(self._fl[K.BOUND]))

    def bound_by(self, length: float) -> None:
        """A start-goal path of this ``length`` is known (e.g. the tree's, tightened): with
        ``informed``, sample only where a shorter one can pass."""
        self._fl[K.BOUND] = min(float(self._fl[K.BOUND]), float(length))

    def _best(self) -> tuple[int, float]:
        return K.best_goal(
            self.grid.buffer, self._cost, self._goal_nodes, self._ctr[K.N_GOAL], self._goal3
        )

    def sample(self) -> FloatArray:
        """Alg. 1 line 3 (padded to 3 coordinates); with ``informed``, within the spheroid of
        the shortest goal path so far."""
        q = self._draw()
        if not self.config.informed or not self._ctr[K.N_GOAL]:
            return q
        c = self.informed_bound()
        for _ in range(K.MAX_REJECTIONS):
            if _d3(q, self._start3) + _d3(q, self._goal3) < c:
                break
            self._ctr[K.REJECTED] += 1
            q = self._draw()
        return q

    def _grow(self) -> None:
        self.grid.reserve()
        cap = len(self.grid.buffer)
        for name, fill in (("_parent", -1), ("_cost", 0), ("_first_child", -1), ("_next_sib", -1),
                           ("_goal_nodes", 0)):  # fmt: skip
            old = getattr(self, name)
            if len(old) < cap:
                new = np.full(cap, fill, dtype=old.dtype)
                new[: len(old)] = old
                setattr(self, name, new)
        if len(self._stack) < cap:
            self._stack = np.zeros(cap, dtype=np.int64)

    def iterate(self) -> bool:
        """One pass of Alg. 1's loop (lines 3-10), in Python (the reference of the Numba loop).
        True if ``x_new`` joined the goal."""
        self._ctr[K.ITER] += 1
        cfg = self.config
        q = self.sample()
        r = self.radius()
        self.grid.balance(r)
        i_near, d_near = self.grid.nearest(q)
        if d_near <= 0.0:
            return False
        x_near = self.grid.buffer[i_near]
        x_new = q.copy() if d_near <= cfg.step else x_near + (q - x_near) * (cfg.step / d_near)
        cand = self.grid.near(x_new, r)
        pos = int(np.searchsorted(cand, i_near))
        if pos == len(cand) or cand[pos] != i_near:
            cand = np.insert(cand, pos, i_near)
        d = self.dim
        want_goal = _d3(x_new, self._goal3) <= cfg.goal_radius
        k = len(cand)
        edges = np.empty((k + int(want_goal), 2, d))
        edges[:k, 0] = self.grid.buffer[cand, :d]
        edges[:k, 1] = x_new[:d]
        if want_goal:
            edges[k, 0] = x_new[:d]
            edges[k, 1] = self.goal
        ok = self.validator.paths_valid(edges)
        self._ctr[K.CHECKS] += len(edges)
        if not ok[pos]:
            return False
        self._grow()
        new = self.grid.add(x_new)
        self._ctr[K.N] = self.grid.n
        self._ctr[K.REWIRES] += int(
            _insert_rewire(
                self.grid.buffer,
                self._parent,
                self._cost,
                self._first_child,
                self._next_sib,
                self._stack,
                new,
                cand,
                ok[:k],
            )
        )
        if want_goal and ok[k]:
            self._goal_nodes[self._ctr[K.N_GOAL]] = new
            self._ctr[K.N_GOAL] += 1
            if not self._ctr[K.FOUND]:
                self._ctr[K.FOUND] = self._ctr[K.ITER]
            return True
        return False

    def advance(self, max_iterations: int, stop_at_goal: bool, stop_on_improve: bool) -> int:
        """Run the Numba loop until ``max_iterations`` passes in all (``K.DONE``), a node joins
        the goal with ``stop_at_goal`` (``K.GOAL``) or, with ``stop_on_improve``, the shortest
        goal path gets shorter (``K.IMPROVED``); returns that status. Only where :attr:`fast`."""
        if self._kargs is None:
            raise RuntimeError("this tree's validator has no compiled segment check")
        g = self.grid
        cfg = self._cfg
        self._grow()
        cfg[K.SCAN_LIMIT] = g.scan_limit
        while True:
            before = int(self._ctr[K.CHECKS])
            status = K.grow(
                g.buffer, g._nxt, g._head, g._lo, g.cell, g._dims, self._parent, self._cost,
                self._first_child, self._next_sib, self._stack, self._goal_nodes,
                self._samples, self._goal_draw, self._start3, self._goal3, self._ctr, self._fl,
                cfg, int(max_iterations), bool(stop_at_goal), bool(stop_on_improve),
                self._kargs,
            )  # fmt: skip
            g.n = int(self._ctr[K.N])
            k = int(self._ctr[K.CHECKS]) - before  # segments the compiled loop checked
            work.add(checked_paths=k, checked_segments=k)
            if status == K.GROW:
                self._grow()
            elif status == K.NEED_SAMPLES:
                self._refill()
            elif status == K.REBUILD:
                target = float(self._fl[K.TARGET])
                g.set_cell(target)
                if g.cell >= 2 * target:  # the grid cannot get finer (MAX_CELLS)
                    cfg[K.MIN_CELL] = g.cell
            else:
                return int(status)

    def run(self, max_iterations: int, stop_at_goal: bool) -> None:
        """Iterate until ``max_iterations`` passes in all, or the goal when ``stop_at_goal``
        (in :func:`serial_numba`; the Numba loop where :attr:`fast`)."""
        if self.fast:
            self.advance(max_iterations, stop_at_goal, False)
            return
        with serial_numba():
            while self.iterations < max_iterations:
                if self.iterate() and stop_at_goal:
                    break

    # ---------------------------------------------------------------- Alg. 1 line 11
    def best_goal_node(self) -> int | None:
        """The goal-connected node with the shortest start-goal path, None if none yet."""
        node = int(self._best()[0])
        return None if node < 0 else node

    def path_indices(self, node: int) -> IntArray:
        """Node indices start .. ``node`` along the tree."""
        out = [node]
        while self._parent[out[-1]] >= 0:
            out.append(int(self._parent[out[-1]]))
            if len(out) > self.n_nodes:
                raise RuntimeError("cycle in the RRT* tree")
        return np.asarray(out[::-1], dtype=np.int64)

    def path_of(self, idx: IntArray) -> FloatArray:
        """Waypoints of the nodes ``idx`` plus the exact goal (not repeated if the last node is
        the goal)."""
        p = self.grid.buffer[idx, : self.dim]
        if np.array_equal(p[-1], self.goal):
            return np.asarray(p.copy())
        return np.asarray(np.vstack([p, self.goal[None]]))

    def path(self) -> FloatArray | None:
        """The shortest start-goal path found so far (None if none)."""
        node = self.best_goal_node()
        return None if node is None else self.path_of(self.path_indices(node))


def _length(path: FloatArray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def rrt_star(
    scenario: Scenario,
    task: Task | str | int | None,
    config: RRTStarConfig,
    rng: np.random.Generator,
    max_iterations: int | None = None,
) -> RRTStarResult:
    """PPSwarm Alg. 1: RRT* from the task's start until a node joins the goal (or, with
    ``config.stop_at_goal=False``, for all iterations), then the tree path plus the exact goal,
    shortcut if ``config.shortcut``. ``max_iterations`` overrides the config's."""
    tree = RRTStarTree(scenario, task, config, rng)
    n_it = int(max_iterations if max_iterations is not None else config.max_iterations)
    tree.run(n_it, config.stop_at_goal)
    path = tree.path()
    checks = tree.edge_checks
    if path is not None and config.shortcut:
        with serial_numba():
            path, _, k = greedy_shortcut(tree.validator, path)
        checks += k
    return RRTStarResult(
        path=path,
        n_nodes=tree.n_nodes,
        iterations=tree.iterations,
        found_iteration=tree.found_iteration,
        cost=_length(path) if path is not None else float("inf"),
        edge_checks=checks,
    )


def tightened(tree: RRTStarTree, path: FloatArray) -> tuple[FloatArray, int]:
    """``path`` (valid) shortcut, tightened by an elastic band with points at most half a step
    apart, and shortcut again (:mod:`uavplan.planners.sampling._tighten_kernels`), every segment
    judged
    by the tree's validator (its compiled check where it has one, else the Python references);
    returns it (never longer) and the segment checks spent."""
    d = tree.dim
    p3 = np.zeros((len(path), 3))
    p3[:, :d] = path
    spacing = 0.5 * tree.config.step
    if tree._kargs is not None:
        out, checks = T.tighten(p3, tree._kargs, spacing, BAND_SWEEPS)
        work.add(checked_paths=checks, checked_segments=checks)
        return np.asarray(out[:, :d]), checks
    count = [0]

    def ok(a: FloatArray, b: FloatArray) -> bool:
        count[0] += 1
        return bool(tree.validator.paths_valid(np.stack([a[:d], b[:d]])[None])[0])

    out = T.shortcut_reference(ok, p3)
    out = T.band_reference(ok, out, spacing, BAND_SWEEPS, T.TOL)
    out = T.shortcut_reference(ok, out)
    return np.asarray(out[:, :d]), count[0]


def tightest(tree: RRTStarTree, path: FloatArray) -> tuple[FloatArray, int]:
    """The shortest of ``path`` (the tree's shortest) and the tree paths of up to
    :data:`TIGHTEN_PATHS` - 1 other goal nodes on branches of their own
    (:func:`_rrt_star_kernels.distinct_goal_nodes`), each :func:`tightened`: a longer tree path
    may lie in a way between the obstacles that tightens shorter. Returns it and the checks."""
    best, checks = tightened(tree, path)
    nodes = K.distinct_goal_nodes(
        tree.grid.buffer, tree._parent, tree._cost, tree._goal_nodes, tree._ctr[K.N_GOAL],
        tree._goal3, TIGHTEN_PATHS, TIGHTEN_SLACK,
    )  # fmt: skip
    for node in nodes[1:]:
        p, k = tightened(tree, tree.path_of(tree.path_indices(int(node))))
        checks += k
        if _length(p) < _length(best):
            best = p
    return best, checks


# ------------------------------------------------------------------------------ the planner
@dataclass(frozen=True)
class RRTStarPlannerConfig(RRTStarConfig, PlannerConfig):
    """The ``rrt-star`` planner's options: :class:`RRTStarConfig`'s, anytime by default."""

    stop_at_goal: bool = option(
        False, "stop at the first goal connection (Alg. 1); the planner is anytime by default"
    )
    tighten: bool = option(
        False, "shortcut and tighten new shortest tree paths (an elastic band judged by the "
        "exact segment check; not in the paper); informed sampling then uses their length",
    )  # fmt: skip


class RRTStarPlanner(Planner):
    """RRT* as a planner (``rrt-star``); see the module docstring.

    One planner iteration is one RRT* iteration. Budget: iterations (default the config's
    ``max_iterations``), stopped earlier by its evaluations (segment checks), its time or the
    callback, or at the first goal connection with ``stop_at_goal``.
    """

    # its graph has no time: moving obstacles are refused
    specs = PlannerSpecs(handles_moving=False)

    name = "rrt-star"
    Config = RRTStarPlannerConfig
    config: RRTStarPlannerConfig

    def budget(self, budget: Budget | int | None) -> Budget:
        return super().budget(budget if budget is not None else self.config.max_iterations)

    def iteration_limit(self, budget: Budget) -> int | None:
        if budget.max_iterations is None and budget.max_evaluations is None:
            return None if budget.max_time is not None else self.config.max_iterations
        return budget.max_iterations or self.config.max_iterations

    def rrt_config(self) -> RRTStarConfig:
        cfg = self.config
        return RRTStarConfig(**{f.name: getattr(cfg, f.name) for f in fields(RRTStarConfig)})

    def _plan(self, run: Run) -> Outcome:
        cfg = self.config
        problem = run.problem
        rng = np.random.default_rng(np.random.SeedSequence(run.seed))
        tree = RRTStarTree(run.scenario, run.task, self.rrt_config(), rng)
        tr = run.tracker
        best_length = np.inf
        path_evaluations = shortcut_checks = tightenings = 0
        tighten_from = 0  # the iteration from which a new shortest tree path is tightened
        last: IntArray | None = None
        term = run.termination
        # the Numba loop closes up to CHUNK iterations per call; one where a callback or an
        # evaluation limit must see every iteration
        chunk = 1 if term.callback is not None or term.max_evaluations is not None else CHUNK
        limit = run.max_iterations
        with serial_numba():
            while True:
                if tree.fast:
                    before = tree.iterations
                    end = before + chunk if limit is None else min(before + chunk, limit)
                    status = tree.advance(max(end, before + 1), cfg.stop_at_goal, True)
                    changed = status in (K.IMPROVED, K.GOAL)
                    n_done = tree.iterations - before
                else:
                    tree.iterate()
                    changed, n_done = True, 1
                stop = tr.end_iterations(n_done - 1)  # passes that left the best path as it was
                node = tree.best_goal_node() if changed else None
                if node is not None:
                    idx = tree.path_indices(node)
                    if last is None or not np.array_equal(idx, last):
                        last = idx
                        path = tree.path_of(idx)
                        if cfg.tighten and tree.iterations >= tighten_from:
                            path, k = tightest(tree, path)
                            shortcut_checks += k
                            tightenings += 1
                            tree.bound_by(_length(path))
                            tighten_from = max(tree.iterations + TIGHTEN_GAP,
                                               int(TIGHTEN_GROWTH * tree.iterations))  # fmt: skip
                        elif cfg.shortcut:
                            path, _, k = greedy_shortcut(tree.validator, path)
                            shortcut_checks += k
                        ev = problem.evaluate(path[None])
                        path_evaluations += 1
                        if tr.offer(path, float(ev.cost[0]), bool(ev.feasible[0])):
                            best_length = _length(path)
                tr.evaluations = tree.edge_checks + shortcut_checks
                if stop:
                    tr.amend(tr.cost, tr.cost if tr.feasible else math.inf)
                    break
                stop = tr.end_iteration()
                if stop or (cfg.stop_at_goal and tree.found_iteration is not None):
                    break
        found = tr.path is not None
        return Outcome(
            reasons=() if found else ("no_path",),
            info={
                "rrt_iterations": tree.iterations,
                "found_iteration": tree.found_iteration,
                "n_nodes": tree.n_nodes,
                "edge_checks": tree.edge_checks,
                "shortcut_checks": shortcut_checks,
                "tightenings": tightenings,
                "path_evaluations": path_evaluations,
                "rewires": tree.rewires,
                "informed_rejections": tree.rejected,
                "radius": tree.radius(),
                "length": best_length if found else None,
                "reason": "" if found else "no start-goal path found within the budget",
            },
        )


register_planner(RRTStarPlanner)


#: RRT*'s steering step as a share of the map's horizontal diagonal when it rescues another
#: planner's path (its default, 50 m, is the PPSwarm paper's for a 1 km map; a 30 km map
#: needs longer steps).
RESCUE_STEP_SHARE = 0.02


def map_scaled_lengths(scenario: Scenario) -> dict[str, float]:
    """RRT*'s lengths for ``scenario``'s map: the step :data:`RESCUE_STEP_SHARE` of the
    horizontal diagonal, at least its default 50 m (the default on a map of up to 2.5 km
    across, such as the PPSwarm and SPSO maps), the goal radius one step and the near radius
    two, in the defaults' proportions. A 50 m step reaches no goal 90 km away within 5,000
    iterations."""
    lo, hi = scenario.bounds.lo, scenario.bounds.hi
    d = RRTStarConfig()
    step = max(d.step, RESCUE_STEP_SHARE * float(np.hypot(hi[0] - lo[0], hi[1] - lo[1])))
    k = step / d.step
    return {"step": step, "goal_radius": d.goal_radius * k, "near_radius": d.near_radius * k}


def map_scaled_options(scenario: Scenario) -> dict[str, object]:
    """RRT* as a rescue (the single UAV's fallback, a fleet's repair): every edge checked as
    flown; its lengths scaled to the map (:func:`map_scaled_lengths`); informed, anytime
    within its iteration budget, its shortest tree paths tightened, every edge within the
    UAV's climb and descent angles (a rescue's path must fly: RRT*'s edges otherwise join
    vertices metres apart at any angle)."""
    return {
        **map_scaled_lengths(scenario),
        "informed": True,
        "stop_at_goal": False,
        "tighten": True,
        "climb_limits": True,
    }
