"""Multi-agent genetic algorithm as used by HR-MAGA ("P-MAGA"), vectorized over the lattice.

Yang, Liu & Li, "Path planning of UAVs under dynamic environment based on a hierarchical recursive
multiagent genetic algorithm", IEEE CEC 2020, Sect. III-A..C and Alg. 1 (P-MAGA); the hierarchical
recursion of Alg. 2 is a planner built on top of this optimizer, not part of it. The lattice model
comes from MAGA, Zhong, Liu, Xue & Jiao, IEEE Trans. SMC-B 34(2), 1128-1141, 2004 (HR-MAGA's
ref. [26]).

Agents and lattice (Sect. III-A)
--------------------------------
An agent is one gene vector (for paths: the free waypoints, HR-MAGA Eq. 3). The ``pop_size``
agents sit on a ``rows x cols`` lattice with wrap-around; agent ``L_ij`` sees the four agents of
Eq. (10)::

    Neighbor_ij = {L_i'j, L_ij', L_i''j, L_ij''},  i' = i - 1, i'' = i + 1 (mod rows),
                                                   j' = j - 1, j'' = j + 1 (mod cols)

(:func:`torus_neighbours`; flat index ``i * cols + j``, 0-based).

One generation (Alg. 1, lines 4-15)
-----------------------------------
1. **Competition** (Eq. 11): ``L_ij`` is a *winner* if ``F(L_ij) < F(Min_ij)``, ``Min_ij`` its
   lowest-cost neighbour, else a *loser* (:func:`competition`). Eq. (11) has no parameter (Table I
   lists none for it either; MAGA's occupying probability ``P_o`` is replaced in HR-MAGA by the
   genetic operators below).
2. **Loser -> New_ij** (Sect. III-B, Fig. 3; Alg. 1 lines 7-8) from parent1 ``L_ij`` and parent2
   ``Min_ij``:

   a. *single-point crossover* with probability ``P_c``: a cut ``c`` uniform in
      ``{1, ..., n_w - 1}`` between waypoints (``n_w`` = number of gene blocks); the child is
      parent1's waypoints before the cut followed by parent2's after it
      (:func:`single_point_crossover`);
   b. *mutation* with probability ``P_m``: one waypoint (a block of ``block`` genes; one gene for
      plain functions) chosen uniformly is moved to an "adjacent coordinate point"
      (:func:`mutate_adjacent`);
   c. *smoothing* of turn-backs (Eq. 5 / constraint Eq. 6, :func:`smooth`), for paths only.

   ``New_ij`` occupies the loser's lattice point whatever its cost (no greedy selection: the loser
   lost its place).
3. **Self-learning** (Sect. III-B, Alg. 1 lines 10-11): each winner, with probability
   ``self_learning_rate = 0.5``, builds an ``sL_size x sL_size`` lattice ``L_new`` holding itself
   and ``sL_size^2 - 1 = 8`` mutants of itself (mutation operator b), then runs ``sGen``
   generations of competition + crossover + mutation + smoothing on ``L_new`` (same ``P_c``,
   ``P_m``) with elite retention, and is replaced by the best agent of ``L_new``. Every selected
   agent's ``L_new`` runs at once, as one ``(targets, sL_size^2, dim)`` stack.
4. **Elite retention** on the main lattice (see the decisions below).

Decisions where the paper is vague (and why)
--------------------------------------------
* **Lattice shape.** Table I: ``L_size = 7``, so ``pop_size = 49`` (= 7 x 7) by default; Table I's
  ``Pop = 256`` is the GA baseline's population. ``pop_size`` stays the one size parameter (every
  optimizer and planner sets it, e.g. ``pop_size=40``): the lattice is ``rows x cols`` with
  ``rows`` the largest divisor of ``pop_size`` not above its square root, i.e. ``L_size x L_size``
  whenever ``pop_size`` is a square (49 -> 7 x 7), else the most square rectangle (40 -> 5 x 8); a
  prime ``pop_size`` gives a ``1 x pop_size`` ring whose up/down neighbours (the agent itself) are
  dropped. :attr:`MAGAConfig.lattice_shape` and :attr:`MAGAConfig.L_size` report it.
* **Synchronous update.** Alg. 1 visits agents one by one but evaluates the lattice only at line
  15, so every competition of generation ``k`` uses the costs of generation ``k - 1``; we apply
  all competitions and offspring at once (vectorized), which is exactly that. Ties in Eq. (11)
  count as losses (the inequality is strict); ``Min_ij`` ties go to the first neighbour in
  Eq. (10)'s order.
* **No crossover.** With probability ``1 - P_c`` the child starts as a copy of parent2
  ``Min_ij`` (MAGA's occupying strategies build ``New_ij`` from ``Min_ij``: the loser's place goes
  to the winner's line), then mutation and smoothing apply. With one waypoint there is no cut.
* **"Adjacent coordinate point".** HR-MAGA works on a gridded map and moves one coordinate pair to
  a neighbouring grid point; our genes are continuous, so each gene ``j`` of the chosen waypoint
  moves by ``U(-h_j, h_j)`` with ``h_j = mutation_step * (upper_j - lower_j)`` (a continuous
  neighbourhood of one grid step) and is clipped to the box. ``mutation_step = 0.05`` (a grid of
  20 steps per axis) is our choice, the paper gives no step: in our trials at 2e4 evaluations
  (5 seeds) 0.01 stalled on Rastrigin-10 (median 29 vs 24 at 0.05, 0.002 at 0.1) and 0.1 was
  slowest on sphere-30 (0.35 vs 0.17 at 0.05, 0.10 at 0.025); on the jacksboro and simple2d
  scenarios (1e4 evaluations) 0.05 and 0.1 were alike and better than 0.025, on spso the three
  differed by less than the spread over seeds.
* **Smoothing** (Fig. 3(c), no formula in the paper). Only when genes are waypoints
  (``block >= 2`` and ``dim`` a multiple of ``block``); skipped for plain functions. The turn
  cosine ``theta_k`` of Eq. (5) is computed at every *interior* free waypoint; the optimizer does
  not know the start and goal (they are not genes), so the turns at the first and last free
  waypoint are not checked (the cost's length term penalises those). A waypoint with
  ``theta_k <= 0`` (the path turns back) is moved to the midpoint of its two neighbours, which
  makes that turn straight; odd- then even-indexed waypoints are visited (red-black
  Gauss-Seidel, vectorized) and the pass repeated, at most ``smooth_passes = 30`` times, until
  no turn-back is left (random 5-waypoint paths need <= 10 passes, 27-waypoint ones <= 30). A
  zero-length segment has no direction and counts as no turn-back. Angles are measured in gene
  space (for a height-above-ground z gene, that is the encoded path). Midpoints of in-box points
  stay in the box. Without smoothing, P-MAGA found no feasible path on the spso scenario in our
  trials (0 of 5 runs at 1e4 evaluations, 4 of 5 with it; GA and PSO: 2 of 5).
* **Which agents self-learn.** Sect. III-B/III-C and Alg. 1 line 10: every winner, with
  probability 0.5 (``self_learning="winners"``, the default). ``self_learning="best"`` restricts it
  to the lattice's best agent, as in the original MAGA [26] (set ``self_learning_rate=1`` for
  MAGA's every-generation self-learning). The 8 initial mutants are mutated (operator b, forced)
  but not smoothed: the paper says they are "generated by mutating".
* **Self-learning generations** ``sGen``: not in the paper (Table I lists none); 10, the value of
  MAGA [26] (our reading of that paper, which is not in the project's paper set).
* **Elite retention.** In ``L_new`` (stated by the paper) and on the main lattice (our choice,
  as MAGA [26] keeps its best agent): after a generation, if the lattice's best is worse than the
  best before it, the worst agent is replaced by the old best. With a strict Eq. (11) the best
  agent only loses on a tie (e.g. with its own copy), so this rarely acts, but without it a tie
  could drop the best agent from the lattice. ``elitism=False`` switches the main-lattice one off.
* **Known costs are not re-evaluated.** Alg. 1 line 15 evaluates the whole lattice each
  generation; a winner's cost is known (costs are assumed deterministic), so only new agents are
  evaluated. Likewise a child (or initial mutant) identical to a parent (e.g. no
  crossover, no mutation, nothing to smooth; or a mutation clipped back onto the wall) gets its
  parent's known cost and is not asked for. If every row of a batch is such a copy, the batch
  is evaluated anyway, so an ask is never empty.

Ask/tell: what an "iteration" is
--------------------------------
One :meth:`ask` / :meth:`tell` = one evaluated batch. The first is the initial lattice (Alg. 1
lines 1-2). A generation is then:

* one batch: the new agents of the losers + the ``8 x targets`` initial self-learning mutants;
* ``sGen`` batches, one per self-learning generation, each holding the new agents of the losers
  of every ``L_new`` at once (none if no agent self-learns this generation).

So one generation of Alg. 1 is ``1 + sGen`` iterations (1 when nobody self-learns), and batches
vary in size; :attr:`MAGA.generation` counts finished generations. Budgets in evaluations compare
fairly with other optimizers. Each evaluation is asked, and therefore counted by the base class,
exactly once; agents whose cost is known are never re-asked. The evaluated ``X`` handed to
:meth:`tell` is taken as the new agents (a caller may repair points before evaluating them).

Implementations
---------------
:class:`ReferenceMAGA` is the algorithm in NumPy, one lattice per object (the first
implementation). :class:`MAGABatch` advances many independent lattices (HR-MAGA's sub-problems of
a level) with one Numba call per ask and one per tell (:mod:`uavplan.optimizers._maga_kernels`):
the operators run agent by agent in the reference's order, and each lattice draws from its own
generator's PCG64 stream as NumPy would (the kernels advance a copy of its state), so a lattice
of a batch gives the numbers of a :class:`ReferenceMAGA` with the same generator, bit for bit
(``tests/optimizers/test_maga_batch.py``: the stream draw for draw, each operator, whole runs).
The registered :class:`MAGA` (``maga``, P-MAGA's planner) is a batch of one lattice behind the
ask/tell interface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers import _maga_kernels as _mk
from uavplan.optimizers.base import (
    FloatArray,
    Optimizer,
    OptimizerConfig,
    OptimizerError,
    register,
)
from uavplan.params import option

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


# ---------------------------------------------------------------------- lattice (Sect. III-A)
def lattice_shape(n: int) -> tuple[int, int]:
    """``(rows, cols)`` with ``rows * cols = n`` and ``rows`` the largest divisor ``<= sqrt(n)``
    (``L_size x L_size`` when ``n = L_size^2``)."""
    if n < 1:
        raise OptimizerError(f"lattice needs n >= 1, got {n}")
    rows = math.isqrt(n)
    while n % rows:
        rows -= 1
    return rows, n // rows


def torus_neighbours(rows: int, cols: int) -> IntArray:
    """Eq. (10): flat indices of the neighbours ``(L_i'j, L_ij', L_i''j, L_ij'')`` (up, left, down,
    right, wrapping around) of every lattice point, ``(rows * cols, 4)`` int64; point ``(i, j)`` is
    row ``i * cols + j``. On a one-row lattice the up/down "neighbours" would be the agent itself;
    they are replaced by its left neighbour (a duplicate, harmless for the minimum)."""
    i, j = np.divmod(np.arange(rows * cols, dtype=np.int64), cols)
    nb = np.stack(
        [
            ((i - 1) % rows) * cols + j,  # L_i'j
            i * cols + (j - 1) % cols,  # L_ij'
            ((i + 1) % rows) * cols + j,  # L_i''j
            i * cols + (j + 1) % cols,  # L_ij''
        ],
        axis=1,
    )
    me = (i * cols + j)[:, None]
    return np.where(nb == me, nb[:, 1:2], nb)


def competition(F: FloatArray, neighbours: IntArray) -> tuple[IntArray, BoolArray]:
    """Eq. (11) on one lattice or a stack of them.

    Args:
        F: costs ``(..., N)`` of the agents on lattices of ``N`` points.
        neighbours: ``(N, 4)`` from :func:`torus_neighbours`.

    Returns:
        ``Min`` ``(..., N)``: flat index of each agent's lowest-cost neighbour (first in Eq. (10)'s
        order on ties), and ``winner`` ``(..., N)``: ``F(L_ij) < F(Min_ij)``.
    """
    Fn = F[..., neighbours]  # (..., N, 4)
    k = np.argmin(Fn, axis=-1)
    Min = neighbours[np.arange(neighbours.shape[0]), k]
    F_min = np.take_along_axis(Fn, k[..., None], axis=-1)[..., 0]
    return Min, F_min > F


# ---------------------------------------------------------------------- genetic behaviours (Fig. 3)
def single_point_crossover(
    P1: FloatArray,
    P2: FloatArray,
    P_c: float,
    block: int,
    rng: np.random.Generator,
) -> FloatArray:
    """Fig. 3(a): with probability ``P_c`` per row, ``P1``'s waypoints before a cut ``c`` uniform in
    ``{1, ..., n_w - 1}`` followed by ``P2``'s from ``c`` on (``n_w`` waypoints of ``block``
    genes); otherwise, and when ``n_w = 1``, a copy of ``P2``. Shapes ``(n, dim)``."""
    n, D = P1.shape
    gene_block = np.arange(D) // max(block, 1)
    n_w = int(gene_block[-1]) + 1 if D else 0
    cross = rng.random(n) < P_c
    c = rng.integers(1, n_w, size=n) if n_w >= 2 else np.zeros(n, dtype=np.int64)
    c = np.where(cross, c, 0)  # c = 0: every gene from P2
    return np.where(gene_block[None, :] < c[:, None], P1, P2)


def mutate_adjacent(
    X: FloatArray,
    P_m: float,
    h: FloatArray,
    block: int,
    lower: FloatArray,
    upper: FloatArray,
    rng: np.random.Generator,
) -> FloatArray:
    """Fig. 3(b): with probability ``P_m`` per row, one waypoint (``block`` genes) chosen uniformly
    moves to an adjacent point: each of its genes ``j`` by ``U(-h_j, h_j)``; clipped to the box.
    ``P_m = 1`` mutates every row (the self-learning mutants). ``X`` ``(n, dim)``, ``h`` ``(dim,)``.
    """
    n, D = X.shape
    gene_block = np.arange(D) // max(block, 1)
    n_w = int(gene_block[-1]) + 1 if D else 0
    mutate = np.asarray(rng.random(n) < P_m)
    w = np.asarray(rng.integers(n_w, size=n))
    step = rng.uniform(-1.0, 1.0, size=(n, D)) * h
    moved = mutate[:, None] & (gene_block[None, :] == w[:, None])
    return np.clip(np.where(moved, X + step, X), lower, upper)


def turn_cosines(P: FloatArray) -> FloatArray:
    """Eq. (5): ``theta_k = lambda_{k+1} . lambda_k / (|lambda_{k+1}| |lambda_k|)`` with
    ``lambda_k = P_{k+1} - P_k``, at the interior points of polylines ``P`` ``(n, n_p, d)``;
    returns ``(n, n_p - 2)``, ``theta[:, k]`` the turn at ``P[:, k + 1]``. A zero-length segment
    has no direction: its turns are reported as ``1`` (straight)."""
    lam = np.diff(P, axis=1)
    dot = np.sum(lam[:, 1:] * lam[:, :-1], axis=-1)
    norm = np.linalg.norm(lam[:, 1:], axis=-1) * np.linalg.norm(lam[:, :-1], axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        theta = dot / norm
    return np.where(norm > 0, theta, 1.0)


def smooth(X: FloatArray, block: int, passes: int) -> FloatArray:
    """Fig. 3(c): remove turn-backs (``theta_k <= 0``, Eq. 5; Eq. 6 asks ``theta_k > 0``).

    The same operation as :func:`smooth_reference` (bit-identical, tested), one row at a time in
    Numba: rows are independent, so the red-black passes of a row do not wait for the others.
    It was a third of P-MAGA's run time in NumPy (many small batches in self-learning)."""
    n, D = X.shape
    if block < 2 or D % block or D // block < 3 or passes < 1 or n == 0:
        return X.copy()
    P = np.ascontiguousarray(X, dtype=np.float64).reshape(n, D // block, block).copy()
    _mk.smooth_rows(P, passes)
    return P.reshape(n, D)


def smooth_reference(X: FloatArray, block: int, passes: int) -> FloatArray:
    """The NumPy reference of :func:`smooth`. Fig. 3(c): remove turn-backs (``theta_k <= 0``,
    Eq. 5; Eq. 6 asks ``theta_k > 0``).

    ``X`` ``(n, n_w * block)`` is read as ``n_w`` waypoints of ``block`` coordinates. An interior
    waypoint that turns back is moved to the midpoint of its two neighbours (its turn becomes
    straight). One pass visits the odd-indexed interior waypoints, then the even-indexed ones
    (red-black Gauss-Seidel: waypoints of one parity only read the other, so each half-pass is one
    vectorized step); passes repeat on the rows still turning back, at most ``passes`` times. The
    first and last waypoint never move. Returns a new array."""
    n, D = X.shape
    if block < 2 or D % block or D // block < 3 or passes < 1 or n == 0:
        return X.copy()
    P = X.reshape(n, D // block, block).copy()
    rows = np.flatnonzero(np.any(turn_cosines(P) <= 0, axis=1))
    interior = np.arange(1, P.shape[1] - 1)
    for _ in range(passes):
        if rows.size == 0:
            break
        Q = P[rows]
        for k in (interior[0::2], interior[1::2]):
            lam_in, lam_out = Q[:, k] - Q[:, k - 1], Q[:, k + 1] - Q[:, k]
            dot = np.sum(lam_in * lam_out, axis=-1)
            defined = np.any(lam_in != 0, axis=-1) & np.any(lam_out != 0, axis=-1)
            back = (dot <= 0) & defined  # theta_k <= 0 (same sign as the dot product)
            Q[:, k] = np.where(back[..., None], 0.5 * (Q[:, k - 1] + Q[:, k + 1]), Q[:, k])
        P[rows] = Q
        rows = rows[np.any(turn_cosines(Q) <= 0, axis=1)]
    return P.reshape(n, D)


# ---------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class MAGAConfig(OptimizerConfig):
    """P-MAGA hyperparameters; defaults from HR-MAGA Table I and Sect. III-B where it gives them.

    ``pop_size`` is the number of agents (lattice points): 49 = ``L_size^2`` with Table I's
    ``L_size = 7``; see the module docstring for non-square sizes.
    """

    pop_size: int = option(49, "agents on the lattice, L_size x L_size = 7 x 7 (Table I)", low=2)
    P_c: float = option(0.5, "crossover rate (Table I)", low=0, high=1)
    P_m: float = option(0.3, "mutation rate, per new agent (Table I)", low=0, high=1)
    mutation_step: float = option(
        0.05, "adjacent-coordinate mutation: +-step x box width per gene (ours)", low=0,
        low_open=True,
    )  # fmt: skip
    self_learning: Literal["winners", "best"] = option(
        "winners", "who may self-learn (Alg. 1 line 10)", choices=("winners", "best")
    )
    self_learning_rate: float = option(
        0.5, "probability of self-learning, U(0, 1) < 0.5 (Alg. 1 line 10, Sect. III-B)", low=0,
        high=1,
    )  # fmt: skip
    sL_size: int = option(3, "self-learning lattice sL_size x sL_size: 8 mutants + the agent",
                          low=2)  # fmt: skip
    sGen: int = option(10, "self-learning generations (not in the paper; MAGA [26])", low=0)
    smooth: bool = option(True, "smoothing behaviour (Fig. 3(c); with blocks of >= 2 genes)")
    smooth_passes: int = option(30, "passes of the smoothing at most (ours)", low=0)
    elitism: bool = option(True, "main-lattice elite retention (ours, as MAGA [26])")

    @property
    def lattice_shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the agent lattice."""
        return lattice_shape(self.pop_size)

    @property
    def L_size(self) -> int | None:
        """Side of the square lattice (Table I's ``L_size``), None if ``pop_size`` is no square."""
        rows, cols = self.lattice_shape
        return rows if rows == cols else None


# ---------------------------------------------------------------------- optimizer
class ReferenceMAGA(Optimizer):
    """P-MAGA (HR-MAGA Alg. 1) in NumPy, one lattice: agent lattice, neighbourhood competition,
    crossover, adjacent mutation, smoothing, self-learning with elite retention. See the module
    docstring. The reference of :class:`MAGA` and :class:`MAGABatch` (same numbers; not
    registered).

    State: ``L`` ``(pop_size, dim)`` agents on the lattice (flat index ``i * cols + j``) and their
    costs ``F``; :attr:`generation` finished generations of Alg. 1.

    Args:
        init: optional first lattice (pop_size, dim) used instead of uniform random agents
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "maga-reference"
    Config: ClassVar[type[OptimizerConfig]] = MAGAConfig
    config: MAGAConfig

    def _setup(self) -> None:
        cfg = self.config
        N, D = cfg.pop_size, self.dim
        self.neighbours = torus_neighbours(*cfg.lattice_shape)
        self.s_neighbours = torus_neighbours(cfg.sL_size, cfg.sL_size)
        self.h = cfg.mutation_step * (self.upper - self.lower)
        self.L: FloatArray = np.empty((N, D))
        self.F: FloatArray = np.full(N, np.inf)
        self.generation = 0
        self.phase: Literal["lattice", "self_learning"] = "lattice"
        self.s_generation = 0  # self-learning generations done in the current generation
        # self-learning lattices L_new of the current generation: (T, sL^2, D), (T, sL^2)
        self.targets: IntArray = np.zeros(0, dtype=np.int64)
        self.sL: FloatArray = np.empty((0, cfg.sL_size**2, D))
        self.sF: FloatArray = np.empty((0, cfg.sL_size**2))
        self.s_best_x: FloatArray = np.empty((0, D))
        self.s_best_f: FloatArray = np.empty(0)
        self._elite: tuple[FloatArray, float] = (np.empty(D), np.inf)
        self._plan: dict[str, Any] = {}

    # ------------------------------------------------------------------ operators
    def new_agents(self, P1: FloatArray, P2: FloatArray) -> FloatArray:
        """``New`` from parents ``P1 = L_ij`` (loser) and ``P2 = Min_ij``: crossover (``P_c``),
        mutation (``P_m``), smoothing (paths only). Shapes ``(n, dim)``."""
        cfg, rng = self.config, self.rng
        X = single_point_crossover(P1, P2, cfg.P_c, self.block, rng)
        X = mutate_adjacent(X, cfg.P_m, self.h, self.block, self.lower, self.upper, rng)
        if cfg.smooth:
            X = self.clip(smooth(X, self.block, cfg.smooth_passes))
        return X

    def mutants(self, X: FloatArray, m: int) -> FloatArray:
        """``m`` mutants of each row of ``X`` ``(T, dim)`` -> ``(T, m, dim)`` (self-learning)."""
        T = X.shape[0]
        rep = np.repeat(X, m, axis=0)
        M = mutate_adjacent(rep, 1.0, self.h, self.block, self.lower, self.upper, self.rng)
        return M.reshape(T, m, self.dim)

    @staticmethod
    def _known_costs(
        X: FloatArray, P1: FloatArray, F1: FloatArray, P2: FloatArray, F2: FloatArray
    ) -> FloatArray:
        """Cost of each row of ``X`` equal to its parent ``P2`` or ``P1``, NaN where unknown."""
        known = np.full(X.shape[0], np.nan)
        known = np.where(np.all(X == P1, axis=1), F1, known)
        return np.where(np.all(X == P2, axis=1), F2, known)

    def _batch(self, parts: list[tuple[FloatArray, FloatArray]]) -> FloatArray:
        """Rows to evaluate from ``(X, known)`` parts (unknown = NaN); all rows when every one is
        known (an ask is never empty). Records which rows were asked in ``self._plan``."""
        asks = [np.isnan(k) for _, k in parts]
        if not any(a.any() for a in asks):
            asks = [np.ones(len(k), dtype=bool) for _, k in parts]
        self._plan["asked"] = asks
        return np.concatenate([X[a] for (X, _), a in zip(parts, asks, strict=True)])

    def _fill(self, X: FloatArray, f: FloatArray) -> list[tuple[FloatArray, FloatArray]]:
        """Put the evaluated rows back into the parts of the last :meth:`_batch`."""
        out = []
        start = 0
        for (Xp, known), a in zip(self._plan["parts"], self._plan["asked"], strict=True):
            Xp, Fp = Xp.copy(), known.copy()
            n = int(a.sum())
            Xp[a], Fp[a] = X[start : start + n], f[start : start + n]
            start += n
            out.append((Xp, Fp))
        return out

    # ------------------------------------------------------------------ ask/tell hooks
    def _initialize(self) -> FloatArray:
        return self.initial_population()  # Alg. 1 line 1; evaluated as line 2

    def _ask(self) -> FloatArray:
        if self.phase == "lattice":
            return self._ask_lattice()
        return self._ask_self_learning()

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self.iterations == 0:
            self.L, self.F = X.copy(), f.copy()
        elif self.phase == "lattice":
            self._tell_lattice(X, f)
        else:
            self._tell_self_learning(X, f)

    # ------------------------------------------------------------------ main lattice
    def _ask_lattice(self) -> FloatArray:
        cfg, rng = self.config, self.rng
        L, F = self.L, self.F
        b = int(np.argmin(F))
        self._elite = (L[b].copy(), float(F[b]))

        Min, winner = competition(F, self.neighbours)  # Eq. (11)
        losers = np.flatnonzero(~winner)
        P1, P2 = L[losers], L[Min[losers]]
        New = self.new_agents(P1, P2)
        known = self._known_costs(New, P1, F[losers], P2, F[Min[losers]])

        # self-learning targets (Alg. 1 line 10)
        u = rng.random(cfg.pop_size)
        if cfg.self_learning == "winners":
            targets = np.flatnonzero(winner & (u < cfg.self_learning_rate))
        else:
            targets = np.array([b] if u[b] < cfg.self_learning_rate else [], dtype=np.int64)
        m = cfg.sL_size**2 - 1
        M = self.mutants(L[targets], m).reshape(-1, self.dim)
        parent = np.repeat(targets, m)
        known_M = self._known_costs(M, L[parent], F[parent], L[parent], F[parent])

        self.targets = targets
        self._plan = {"losers": losers, "parts": [(New, known), (M, known_M)]}
        return self._batch(self._plan["parts"])

    def _tell_lattice(self, X: FloatArray, f: FloatArray) -> None:
        (New, F_new), (M, F_M) = self._fill(X, f)
        losers = self._plan["losers"]
        self.L[losers], self.F[losers] = New, F_new  # New_ij occupies the loser's place
        T, m = len(self.targets), self.config.sL_size**2 - 1
        if T == 0:
            self._end_generation()
            return
        self.sL = np.concatenate([self.L[self.targets][:, None], M.reshape(T, m, self.dim)], 1)
        self.sF = np.concatenate([self.F[self.targets][:, None], F_M.reshape(T, m)], 1)
        k = np.argmin(self.sF, axis=1)
        self.s_best_x = self.sL[np.arange(T), k].copy()
        self.s_best_f = self.sF[np.arange(T), k].copy()
        self.s_generation = 0
        self.phase = "self_learning"
        if self.config.sGen == 0:
            self._end_self_learning()

    # ------------------------------------------------------------------ self-learning lattices
    def _ask_self_learning(self) -> FloatArray:
        sL, sF = self.sL, self.sF
        T = sL.shape[0]
        Min, winner = competition(sF, self.s_neighbours)  # Eq. (11) on every L_new
        t, p = np.nonzero(~winner)
        q = Min[t, p]
        P1, P2 = sL[t, p], sL[t, q]
        New = self.new_agents(P1, P2)
        known = self._known_costs(New, P1, sF[t, p], P2, sF[t, q])
        self._plan = {"losers": (t, p), "parts": [(New, known)]}
        assert T > 0
        return self._batch(self._plan["parts"])

    def _tell_self_learning(self, X: FloatArray, f: FloatArray) -> None:
        ((New, F_new),) = self._fill(X, f)
        t, p = self._plan["losers"]
        self.sL[t, p], self.sF[t, p] = New, F_new
        # elite retention in L_new: the best so far replaces the worst agent if it was lost
        T = self.sL.shape[0]
        rows = np.arange(T)
        k = np.argmin(self.sF, axis=1)
        best_now = self.sF[rows, k]
        lost = best_now > self.s_best_f
        worst = np.argmax(self.sF, axis=1)
        self.sL[rows[lost], worst[lost]] = self.s_best_x[lost]
        self.sF[rows[lost], worst[lost]] = self.s_best_f[lost]
        better = best_now < self.s_best_f
        self.s_best_x[better] = self.sL[rows[better], k[better]]
        self.s_best_f[better] = best_now[better]
        self.s_generation += 1
        if self.s_generation >= self.config.sGen:
            self._end_self_learning()

    def _end_self_learning(self) -> None:
        """The best agent of each ``L_new`` replaces its agent (never worse: elite retention)."""
        self.L[self.targets] = self.s_best_x
        self.F[self.targets] = self.s_best_f
        self._end_generation()

    def _end_generation(self) -> None:
        if self.config.elitism:
            x_e, f_e = self._elite
            if np.min(self.F) > f_e:
                w = int(np.argmax(self.F))
                self.L[w], self.F[w] = x_e, f_e
        self.generation += 1
        self.phase = "lattice"


@register
class MAGA(ReferenceMAGA):
    """P-MAGA (HR-MAGA Alg. 1), registered as ``maga``: :class:`ReferenceMAGA`'s optimizer
    stepped by the Numba kernels of :class:`MAGABatch` (one lattice), the same numbers. The
    generator's state goes into the kernels before each ask and comes back after it, so
    ``self.rng`` stays the one stream. A generator that is not PCG64 (NumPy's default) runs
    the reference code. ``L``, ``F``, ``phase``, ``targets``, ``sL``, ``sF`` and ``s_best_*``
    read as :class:`ReferenceMAGA`'s (the lattice ones are views of the batch's arrays)."""

    name: ClassVar[str] = "maga"

    def _setup(self) -> None:
        super()._setup()
        self._engine: MAGABatch | None = None
        if isinstance(self.rng.bit_generator, np.random.PCG64):
            init = None if self.init is None else self.init[None]
            b = MAGABatch(self.lower, self.upper, self.block, self.config, [self.rng], init)
            self._engine = b
            self._sync()

    def _sync(self) -> None:
        """The reference's attributes from the batch's state."""
        b = self._engine
        assert b is not None
        ints = b.ints[0]
        T = int(ints[_mk.NTAR])
        self.L, self.F = b.L[0], b.F[0]
        self.generation = int(ints[_mk.GEN])
        self.s_generation = int(ints[_mk.SGEN])
        self.phase = "lattice" if ints[_mk.PHASE] == 0 else "self_learning"
        self.targets = b.targets[0, :T].copy()
        self.sL, self.sF = b.sL[0, :T], b.sF[0, :T]
        self.s_best_x, self.s_best_f = b.s_best_x[0, :T], b.s_best_f[0, :T]
        self._elite = (b.elite_x[0].copy(), float(b.elite_f[0]))

    def _engine_ask(self) -> FloatArray:
        b = self._engine
        assert b is not None
        bg = self.rng.bit_generator
        assert isinstance(bg, np.random.PCG64)
        b.states[0] = _mk.pcg64_row(bg)
        X, _ = b.ask()
        _mk.set_pcg64_row(bg, b.states[0])
        self._sync()
        return X

    def _initialize(self) -> FloatArray:
        return super()._initialize() if self._engine is None else self._engine_ask()

    def _ask(self) -> FloatArray:
        return super()._ask() if self._engine is None else self._engine_ask()

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self._engine is None:
            super()._tell(X, f)
            return
        self._engine.tell(f, X)
        self._sync()


# ---------------------------------------------------------------------- many lattices at once
class MAGABatch:
    """``S`` independent P-MAGA optimizers (Alg. 1) of the same gene count and configuration,
    advanced together: one :meth:`ask` (or :meth:`tell`) is one ask (or tell) of every live
    lattice, computed by one Numba call (:mod:`uavplan.optimizers._maga_kernels`) instead of a
    Python pass over each lattice's operators.

    Lattice ``s`` gives the same numbers as a :class:`MAGA` on the box ``lower[s]..upper[s]``
    with the generator ``seeds[s]`` (the same random draws in the same order, the same
    operators, the same bookkeeping: ``tests/optimizers/test_maga_batch.py``). What differs is
    the interface: there is no problem object (the caller evaluates); :meth:`ask` returns the
    asked rows of every live lattice in one array, lattice by lattice, with the lattice of each
    row; :meth:`tell` takes their costs in that order. The asked rows are the new agents (the
    caller does not repair them).

    Args:
        lower, upper: ``(S, D)`` gene boxes.
        block: genes per waypoint (smoothing and the mutation's waypoint).
        config: the lattices' configuration.
        seeds: ``S`` generators (PCG64, NumPy's default), seed sequences or ints; a generator's
            state is copied, not advanced.
        init: optional first lattices ``(S, pop_size, D)`` (clipped to the boxes).
    """

    def __init__(
        self,
        lower: FloatArray,
        upper: FloatArray,
        block: int,
        config: MAGAConfig,
        seeds: list[Any],
        init: FloatArray | None = None,
    ) -> None:
        lo = np.ascontiguousarray(np.atleast_2d(lower), dtype=np.float64)
        hi = np.ascontiguousarray(np.atleast_2d(upper), dtype=np.float64)
        S, D = lo.shape
        if hi.shape != (S, D) or len(seeds) != S or S == 0 or D == 0:
            raise OptimizerError(
                f"MAGABatch: lower and upper must be (S, D) alike with S seeds; got {lo.shape}, "
                f"{hi.shape}, {len(seeds)}"
            )
        cfg = config
        N, K = cfg.pop_size, cfg.sL_size**2
        self.config, self.block, self.lower, self.upper = cfg, int(block), lo, hi
        self.h = cfg.mutation_step * (hi - lo)
        self.neighbours = torus_neighbours(*cfg.lattice_shape)
        self.s_neighbours = torus_neighbours(cfg.sL_size, cfg.sL_size)
        self.states = np.stack([_mk.pcg64_row(_bit_generator(g)) for g in seeds])
        self.init = (
            np.empty((0, N, D))
            if init is None
            else np.ascontiguousarray(np.clip(init, lo[:, None], hi[:, None]), dtype=np.float64)
        )
        if init is not None and self.init.shape != (S, N, D):
            raise OptimizerError(f"MAGABatch: init must be {(S, N, D)}, got {self.init.shape}")
        self.ints = np.zeros((S, _mk.INT_COLUMNS), dtype=np.int64)
        self.L = np.zeros((S, N, D))
        self.F = np.full((S, N), np.inf)
        self.targets = np.zeros((S, N), dtype=np.int64)
        self.sL = np.zeros((S, N, K, D))
        self.sF = np.zeros((S, N, K))
        self.s_best_x = np.zeros((S, N, D))
        self.s_best_f = np.zeros((S, N))
        self.elite_x = np.zeros((S, D))
        self.elite_f = np.zeros(S)
        self.cand = np.zeros((S, N * K, D))
        self.known = np.zeros((S, N * K))
        self.loser = np.zeros((S, N * K), dtype=np.int64)
        self.asked = np.zeros((S, N * K), dtype=np.bool_)
        self.best_x = np.zeros((S, D))
        self.best_f = np.full(S, np.inf)
        self.has_best = np.zeros(S, dtype=np.bool_)
        self.evaluations = np.zeros(S, dtype=np.int64)
        self._live: NDArray[np.bool_] | None = None
        self._rows = 0

    @property
    def generation(self) -> IntArray:
        """Finished generations of Alg. 1 per lattice."""
        return self.ints[:, _mk.GEN]

    @property
    def iterations(self) -> IntArray:
        """Asks told per lattice."""
        return self.ints[:, _mk.ITER]

    def ask(self, live: NDArray[np.bool_] | None = None) -> tuple[FloatArray, IntArray]:
        """The rows to evaluate of every ``live`` lattice (default all), ``(R, D)``, and the
        lattice of each row ``(R,)``."""
        if self._live is not None:
            raise OptimizerError("MAGABatch: ask() called twice without tell()")
        cfg = self.config
        lv = np.ones(len(self.F), dtype=np.bool_) if live is None else np.asarray(live, bool)
        X, owner = _mk.ask_all(
            lv, self.states, self.ints, self.L, self.F, self.lower, self.upper, self.h,
            self.init, self.neighbours, self.s_neighbours, self.targets, self.sL, self.sF,
            self.elite_x, self.elite_f, self.cand, self.known, self.loser, self.asked,
            cfg.P_c, cfg.P_m, cfg.self_learning_rate, cfg.self_learning == "best",
            self.block, cfg.smooth, cfg.smooth_passes,
        )  # fmt: skip
        self._live, self._rows = lv, len(X)
        return X, owner

    def tell(self, f: FloatArray, X: FloatArray | None = None) -> None:
        """The costs of the rows of the last :meth:`ask`, in its order (no NaN). ``X``: the
        rows as evaluated, if the caller changed them (they become the new agents, as
        :meth:`MAGA.tell` takes them)."""
        if self._live is None:
            raise OptimizerError("MAGABatch: tell() called without a pending ask()")
        f = np.ascontiguousarray(f, dtype=np.float64)
        if f.shape != (self._rows,) or np.isnan(f).any():
            raise OptimizerError(f"MAGABatch: tell() needs one cost per asked row, got {f.shape}")
        X = np.empty((0, self.L.shape[2])) if X is None else np.ascontiguousarray(X, np.float64)
        if X.shape[0] and X.shape != (self._rows, self.L.shape[2]):
            raise OptimizerError(f"MAGABatch: tell() got X of shape {X.shape}")
        _mk.tell_all(
            self._live, f, X, self.ints, self.L, self.F, self.targets, self.sL, self.sF,
            self.s_best_x, self.s_best_f, self.elite_x, self.elite_f, self.cand, self.known,
            self.loser, self.asked, self.best_x, self.best_f, self.has_best, self.evaluations,
            self.config.sGen, self.config.elitism,
        )  # fmt: skip
        self._live = None


def _bit_generator(seed: Any) -> np.random.PCG64:
    """The PCG64 of a generator (refused if it has another bit generator), or a new one."""
    if isinstance(seed, np.random.Generator):
        bg = seed.bit_generator
        if not isinstance(bg, np.random.PCG64):
            raise OptimizerError(f"MAGABatch draws as PCG64 does; got {type(bg).__name__}")
        return bg
    return np.random.PCG64(seed)
