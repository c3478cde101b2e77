"""RSCDWOA: reverse-search chaos differential-evolution whale optimization, vectorized.

Zhang, Zhu, Li & Wang, "A hybrid optimization algorithm for multi-agent dynamic planning with
guaranteed convergence in probability": Sect. 2.2 (WOA, Eqs. 2-10), Sect. 3 (Eqs. 11-23) and
Algorithm 1. Equation, section and reference numbers ([20], [40], [43]) below are the paper's.

One generation ``t`` (a pass of the ``while`` loop of Alg. 1), from the whale positions ``X_i``
(``i = 1..n``), their costs, and the best point found so far ``X_*``:

1. ``a = 2 - 2 t / t_max`` (Eq. 6), clamped at 0 for ``t > t_max`` (``t_max`` is
   :attr:`RSCDWOAConfig.max_iterations`; ``t = 0`` for the first move, so ``a`` starts at 2).
2. The chaotic state is advanced one step with the tent map (Eq. 14) or the logistic map
   (Eq. 13), and replaces the random numbers of WOA (Sect. 3.1): ``A = 2 a w_A - a`` (Eq. 11),
   ``C = 2 w_C`` (Eq. 12), ``l = w_l`` (Eq. 15). ``q`` is uniform in [0, 1) (the paper does not
   make it chaotic).
3. Each whale picks its move (Alg. 1 lines 10-27, Eq. 8):

   * ``q < 0.5`` and ``s < S`` and ``|A| < 1``: encircling, ``D = |C X_* - X_i|``,
     ``X_i <- X_* - A D`` (Eqs. 2-3);
   * ``q < 0.5`` and ``s < S`` and ``|A| >= 1``: search for prey around another whale
     ``X_rand`` (``rand != i``), ``D = |C X_rand - X_i|``, ``X_i <- X_rand - A D`` (Eqs. 9-10);
   * ``q >= 0.5``: spiral (bubble-net) move, ``X_i <- |X_* - X_i| e^(b l) cos(2 pi l) + X_*``
     (Eq. 15);
   * ``q < 0.5`` and ``s >= S`` (lifespan spent): differential evolution (Sect. 3.3): local
     donor over the ring k-neighbourhood ``L_i = X_i + g_1 (X_best,l - X_i) + g_2 (X_p1 - X_p2)``
     (Eq. 18) with ``g = lambda * rand`` per gene (Eq. 17); global donor
     ``G_i = X_best,g + F (X_best,g - X_i) + F (X_r1 - X_r2)`` (Eq. 19); donor
     ``V_i = omega G_i + (1 - omega) L_i`` (Eq. 20); crossover ``U_ij = V_ij`` if
     ``rand >= C_rate`` or ``j = chi_i``, else ``X_ij`` (Eq. 21); perturbation ``W_ij`` = a
     uniform random value in ``[lower_j, upper_j]`` with probability ``alpha``, else ``U_ij``
     (Eq. 22).

   Every new point is clipped to the box (Alg. 1 line 28). The WOA moves replace their whale
   unconditionally (WOA has no selection); a DE whale keeps ``W_i`` only if
   ``f(W_i) <= f(X_i)`` (Eq. 23).
4. Reverse search (Sect. 3.2) on every DE whale, after its selection: the secondary reflection
   reverse point ``x_ik(r) = x_ik + u (h_k - x_ik)``, ``u`` uniform in [0, 1) per gene,
   ``h_k = (lower_k + upper_k) / 2`` (Eq. 16), replaces ``X_i`` only if strictly better.
5. ``X_*`` is replaced on a strict improvement (Alg. 1 line 30); the lifespan counter ``s`` grows
   by one if the generation did not improve ``X_*`` (line 32); ``t`` grows by one (line 33).

**Ask/tell and what an iteration is.** Each evaluated batch is one ``ask``/``tell``, so one
base-class iteration is one batch: (i) the initial population, ``n`` points (iteration 1);
(ii) every generation's move batch, ``n`` points (WOA moves of the WOA whales and trial vectors
``W_i`` of the DE whales, in population order); (iii) only in generations with ``m > 0`` DE
whales, a reverse batch of their ``m`` reflection reverse points. A generation is therefore one
or two base iterations, ``Budget.max_iterations`` counts batches, not generations, and ``t`` in
Eq. 6 counts generations (the reverse batch is part of the same ``t``). Every point is evaluated
exactly once: after ``G`` generations the run has used ``n (G + 1) + sum_t m_t`` evaluations, which
is what the base class counts; compare algorithms by ``Budget.max_evaluations``.

**Chaotic state and its guard.** Each whale carries three independent chaotic orbits (for
``A``, ``C`` and ``l``), seeded uniformly in (0, 1) from ``self.rng`` after the initial
population is drawn, and advanced one map step per generation, whatever move the whale makes.
In floating point a chaotic map can fall onto a fixed point and stay there: the tent map with
``beta = 1/2`` shifts one mantissa bit out per step and reaches exactly 0 within about 52 steps
(``beta = 0.74`` does not, its divisions round); ``w = beta`` maps to 1 and then to the fixed
point 0; the logistic map sends ``1/2`` to 1 and then to 0; and each map has an interior fixed
point (``1 / (2 - beta)`` for the tent map, ``1 - 1/mu`` for the logistic map). After every
step, any value outside ``(eps, 1 - eps)``, within ``eps`` of an interior fixed point, or
unchanged by the step is re-seeded uniformly from ``self.rng`` (``eps = 1e-12``;
:func:`chaos_step`). With ``beta = 0.74`` and ``mu = 4`` this virtually never
fires (no orbit left (0, 1) in 10^5 steps in our tests); it is a safeguard, and keeps runs
deterministic per seed.

**Decisions where the paper is vague or inconsistent (ours, with the reason):**

* *Shape of the chaotic numbers.* The paper writes one symbol ``w(t)`` for ``A``, ``C`` and
  ``l`` (Eqs. 11, 12, 15). A single shared value would tie ``C = 1 + A / a`` (so ``A = 0`` forces
  ``C = 1``, the degenerate case of Theorem 2) and give every whale the same move, so ``w(t)``
  is read as "a chaotic number in place of each random number": one orbit per whale and per
  use. ``A``, ``C`` and ``l`` are scalars per whale, as in the WOA reference code of
  Mirjalili & Lewis [20] and Alg. 1 line 9 ("for each search agent ... update a, A, C, l and q"),
  which also makes the test ``|A| < 1`` well defined.
* *Spiral distance.* Eq. 7 reuses ``D_i`` of Eq. 2 (with ``C``), but the convergence analysis
  (Eq. 32) and WOA [20] use ``|X_* - X_i|``; we use the latter. ``l = w`` lies in (0, 1) as
  Eq. 15 writes it (not remapped to WOA's (-1, 1)).
* *Alg. 1 typos.* Line 15 cites Eq. (8) for the ``|A| >= 1`` branch: that branch is Eqs. 9-10.
  Eq. 8 uses ``q < 0.5`` and Alg. 1 ``q <= 0.5``: we use ``q < 0.5`` (equal with probability 1).
  ``X_rand`` is "another whale" (Sect. 2.2), so ``rand != i``.
* *Lifespan S.* Alg. 1 sets ``s = 0`` once (line 3) and increments it when a generation finds no
  better solution (line 32); it is never reset. We implement exactly that: ``s`` is the total
  number of non-improving generations, and once ``s >= S`` the encircling branch (``q < 0.5``)
  of every whale is replaced by DE + reverse search for the rest of the run, while the spiral
  branch (``q >= 0.5``) stays. The paper gives no value for ``S``; see :class:`RSCDWOAConfig`.
* *Order of operations.* Alg. 1 loops over the whales and updates ``X_*`` after each one. We
  move all whales at once from the positions and ``X_*`` at the start of the generation
  (synchronous, vectorized), and update ``X_*`` after each evaluated batch.
* *Reverse search: replace or compete.* The reverse point competes: it replaces ``X_i`` only if
  ``f(X_i(r)) < f(X_i)`` (Sect. 3.2, strict). It is taken after the DE selection, from the
  selected point (Alg. 1 line 23 applies Eq. 23 then Eq. 16), which costs a second batch, and
  only for the DE whales (Alg. 1 has reverse search only in that branch).
* *Reverse point distribution.* Property 3 drops the ``r_d`` and Sect. 3.2 says "a random number
  that obeys the normal distribution in the interval"; a normal law on an interval needs a
  spread the paper does not give. We use the quasi-reflected point of Ergezer, Simon & Du [40]
  (the cited source): uniform between ``x`` and the centre ``h``. The interval is the box of
  each coordinate (the paper's ``[l_i, u_i]`` indexes the individual, a typo for the gene).
* *Ring neighbourhood.* Neighbours of ``i`` are ``i-k..i+k`` modulo ``n`` in population order
  (Fig. 4, DEGL of Das et al. 2009 which Eqs. 18-20 follow); ``X_best,l`` is the lowest-cost
  whale in it, ``i`` included; ``p_1 != p_2`` are drawn from it without ``i``, and
  ``r_1 != r_2`` from the whole population without ``i`` (DEGL's rule; otherwise the
  difference vectors can vanish). ``X_best,g`` is the best whale of the current population
  (Sect. 3.3: "the best solution for the current global whale population").
* *Eq. 19 base vector.* DEGL uses ``X_i + F (X_best,g - X_i)``; Eq. 19 prints
  ``X_best,g + F (X_best,g - X_i)``. The printed form is well defined, so it is kept.
* *Eq. 17.* ``gamma = lambda * rand`` with ``lambda = 1e-4`` is kept literally, so the local
  donor is ``X_i`` plus a tiny step and ``V_i`` is close to ``(1 - omega) X_i + omega G_i``.
* *Crossover convention (Eq. 21).* Eq. 21 and the sentence after it take the donor gene when
  ``rand >= C_rate``, the opposite of the usual DE convention, while the next sentence (the
  guaranteed gene ``chi`` protects against a "too small" ``C_rate``) reasons in the usual one.
  We implement Eq. 21 as printed (donor gene with probability ``1 - C_rate``) and choose the
  default ``C_rate = 0.1``, i.e. DEGL's ``Cr = 0.9`` written in Eq. 21's convention.
* *Perturbation vector (Eq. 22).* Read literally, Eq. 22 puts back ``X_ij(t)``, which only
  undoes the crossover. The convergence proof needs a perturbation that reaches every state
  (Lemma 2, Eq. 64: ``p{m_0(Z) = Y} > 0`` for all ``Z, Y``; the analysis follows [43]), so
  each gene of ``U_i`` is replaced, with probability ``alpha`` (``phi < alpha``, so that
  ``alpha = 0`` disables it exactly), by a uniform random value in ``[lower_j, upper_j]``.
* *Population initialization* is uniform in the box (Alg. 1 line 1; the ``init`` population if
  given): the abstract's "chaotic initialization" is read as the seeding of the chaotic orbits
  (Alg. 1 lines 4-5), since Sect. 3.1 applies chaos to ``A``, ``C`` and ``l`` only.

Caveat for comparisons: the reverse point always lies between a whale and the box centre, and
WOA's moves are scaled around ``X_*``; both favour benchmarks whose optimum is at the centre of
the box (all of Table 4's are), so also test shifted functions.

Defaults and their sources: see :class:`RSCDWOAConfig`. The evaluated ``X`` handed to
:meth:`tell` is taken as the evaluated points (a caller may repair points before evaluating
them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import (
    FloatArray,
    Optimizer,
    OptimizerConfig,
    OptimizerError,
    register,
)
from uavplan.params import option

IntArray = NDArray[np.int64]
ChaosKind = Literal["tent", "logistic", "uniform"]
LRange = Literal["unit", "symmetric"]

#: Chaotic values closer than this to 0, 1 or an interior fixed point are re-seeded.
CHAOS_EPS = 1e-12


# ---------------------------------------------------------------------- chaotic maps (Sect. 3.1)
def tent_map(w: FloatArray, beta: float) -> FloatArray:
    """Tent map, Eq. 14: ``w / beta`` if ``w < beta``, else ``(1 - w) / (1 - beta)``."""
    w = np.asarray(w, dtype=np.float64)
    return np.where(w < beta, w / beta, (1.0 - w) / (1.0 - beta))


def logistic_map(w: FloatArray, mu: float) -> FloatArray:
    """Logistic map, Eq. 13: ``mu w (1 - w)``."""
    w = np.asarray(w, dtype=np.float64)
    return mu * w * (1.0 - w)


def chaos_fixed_points(kind: ChaosKind, beta: float, mu: float) -> tuple[float, ...]:
    """Interior fixed points of the map (0 is guarded separately)."""
    if kind == "uniform":
        return ()
    if kind == "tent":
        return (1.0 / (2.0 - beta),)
    return (1.0 - 1.0 / mu,) if mu > 1.0 else ()


def chaos_seed(rng: np.random.Generator, shape: int | tuple[int, ...]) -> FloatArray:
    """Uniform starting values in ``(CHAOS_EPS, 1 - CHAOS_EPS)``."""
    w = rng.random(shape)
    while True:  # a draw this close to 0 or 1 has probability ~2e-12
        bad = (w <= CHAOS_EPS) | (w >= 1.0 - CHAOS_EPS)
        if not np.any(bad):
            return w
        w[bad] = rng.random(int(bad.sum()))


def chaos_step(
    w: FloatArray,
    kind: ChaosKind,
    beta: float,
    mu: float,
    rng: np.random.Generator,
) -> FloatArray:
    """One step of the chosen map, guarded: values that left ``(eps, 1 - eps)``, landed within
    ``eps`` of an interior fixed point, or did not move, are re-seeded from ``rng``."""
    w = np.asarray(w, dtype=np.float64)
    if kind == "uniform":  # the control: WOA's own uniform draws in place of the chaos
        return chaos_seed(rng, w.shape)
    w_next = tent_map(w, beta) if kind == "tent" else logistic_map(w, mu)
    bad = ~((w_next > CHAOS_EPS) & (w_next < 1.0 - CHAOS_EPS)) | (w_next == w)
    for p in chaos_fixed_points(kind, beta, mu):
        bad |= np.abs(w_next - p) < CHAOS_EPS
    if np.any(bad):
        w_next[bad] = chaos_seed(rng, int(bad.sum()))
    return w_next


# ---------------------------------------------------------------------- operators
def randint(rng: np.random.Generator, high: int, size: int) -> IntArray:
    """``size`` integers uniform in ``[0, high)``."""
    return np.asarray(rng.integers(0, high, size=size), dtype=np.int64)


def coefficient_a(t: int, t_max: int) -> float:
    """Eq. 6, ``a = 2 - 2 t / t_max``, clamped at 0 for ``t > t_max``."""
    return max(0.0, 2.0 - 2.0 * t / t_max)


def ring_neighbourhood(n: int, k: int) -> IntArray:
    """Indices ``i-k, ..., i+k`` (mod ``n``) of every whale's ring neighbourhood, (n, 2k+1)
    (Fig. 4); column ``k`` is ``i`` itself."""
    if not 1 <= k <= (n - 1) // 2:
        raise OptimizerError(f"ring radius k must be in [1, (n-1)/2] = [1, {(n - 1) // 2}]")
    offsets = np.arange(-k, k + 1, dtype=np.int64)
    return np.asarray((np.arange(n, dtype=np.int64)[:, None] + offsets) % n, dtype=np.int64)


def ring_pairs(
    rng: np.random.Generator, rows: IntArray, n: int, k: int
) -> tuple[IntArray, IntArray]:
    """For each whale ``i`` in ``rows``, two distinct ring neighbours ``p_1 != p_2`` drawn
    uniformly from ``i-k..i+k`` without ``i`` (Eq. 18)."""
    m = rows.shape[0]
    o1 = randint(rng, 2 * k, m)
    o2 = randint(rng, 2 * k - 1, m)
    o2 = o2 + (o2 >= o1)  # distinct offset slots

    def slot_to_offset(o: IntArray) -> IntArray:  # slots 0..2k-1 -> -k..-1, 1..k
        return o - k + (o >= k)

    p1 = (rows + slot_to_offset(o1)) % n
    p2 = (rows + slot_to_offset(o2)) % n
    return p1.astype(np.int64), p2.astype(np.int64)


def two_others(rng: np.random.Generator, rows: IntArray, n: int) -> tuple[IntArray, IntArray]:
    """For each ``i`` in ``rows``, ``r_1 != r_2``, both ``!= i``, uniform in ``[0, n)`` (Eq. 19);
    draw from the indices left and step over the taken ones in increasing order."""
    m = rows.shape[0]
    r1 = randint(rng, n - 1, m)
    r1 = r1 + (r1 >= rows)
    r2 = randint(rng, n - 2, m)
    lo, hi = np.minimum(rows, r1), np.maximum(rows, r1)
    r2 = r2 + (r2 >= lo)
    r2 = r2 + (r2 >= hi)
    return r1.astype(np.int64), r2.astype(np.int64)


def reflection_reverse_point(
    X: FloatArray, lower: FloatArray, upper: FloatArray, u: FloatArray
) -> FloatArray:
    """Secondary reflection reverse point (Property 3, Eq. 16): ``x + u (h - x)`` with the box
    centre ``h = (lower + upper) / 2`` and ``u`` in [0, 1) per gene (uniform in the optimizer):
    a point between ``x`` and ``h``."""
    h = 0.5 * (np.asarray(lower) + np.asarray(upper))
    return np.asarray(X + u * (h - X), dtype=np.float64)


# ---------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class RSCDWOAConfig(OptimizerConfig):
    """RSCDWOA hyperparameters. The paper's values where it gives them, else cited choices.

    * ``pop_size = 30``: not given by the paper; the 30 search agents of WOA
      (Mirjalili & Lewis 2016 [20]).
    * ``max_iterations = 100``: ``t_max`` of Eq. 6, in generations; Table 4 runs every benchmark
      for 100 iterations.
    * ``chaos = "tent"``, ``beta = 0.74``: Sect. 5.2 selects the tent map with beta = 0.74
      (Table 2, smallest mean p-value; Theorem 2 case (2): the tent map never gives A = 0 with
      C = 1). ``mu = 4`` for the logistic map: Sect. 5.2 / Fig. 8 ("when mu = 4 the logistic map
      has a better distribution").
    * ``l_range = "unit"``: l = w(t) in (0, 1) as Eq. 15 writes it; ``"symmetric"`` maps it to
      WOA's (-1, 1) of Sect. 2.2 (the two sections disagree; the variant is tested in the
      ``functions-variants`` experiment).
    * ``b = 1``: spiral shape constant, Sect. 2.2.
    * ``S = 10``: lifespan; Alg. 1 line 2 initializes it without giving a value. Our choice:
      10 % of the paper's 100 iterations (see the module docstring for its meaning).
    * ``k = None``: ring radius, "a nonzero integer in [1, (n-1)/2]" (Sect. 3.3) with no value;
      ``None`` means 10 % of the population (DEGL, Das et al. 2009), at least 1 and at most
      ``(n-1)/2``: 3 for 30 whales.
    * ``lam = 1e-4``: lambda of Eq. 17, "set to 0.0001 in this paper" (Sect. 3.3).
    * ``F = 0.8``: scale factor of Eq. 19, not given; DEGL's value (also this package's DE,
      PPSwarm Table 2).
    * ``omega = 0.5``: weight of Eq. 20, "omega in (0, 1)" with no value; our choice, equal
      weight for the global and local donors.
    * ``C_rate = 0.1``: crossover rate of Eq. 21, not given; with Eq. 21's ``rand >= C_rate``
      convention this takes the donor gene with probability 0.9, DEGL's ``Cr = 0.9``.
    * ``alpha = 0.01``: perturbation probability of Eq. 22 per gene, "usually set to a smaller
      number between 0 and 1" (Remark 1) with no value; our choice: small enough that most
      trials are unperturbed (W = U for about 74 % of 30-gene trials, as Remark 1 wants), and
      positive so that the convergence argument (Lemma 2) holds.
    """

    pop_size: int = option(30, "n, the whales (DE's p_1, p_2, i and r_1, r_2, i distinct)",
                           low=3)  # fmt: skip
    max_iterations: int = option(100, "t_max of Eq. 6, in generations (a = 0 beyond it)", low=1)
    chaos: ChaosKind = option(
        "tent", "the chaotic map replacing A's, C's and l's random numbers (Sect. 5.2); "
        "uniform: plain uniform draws (a control, not the paper's)",
        choices=("tent", "logistic", "uniform"),
    )  # fmt: skip
    l_range: LRange = option(
        "unit", "l of the spiral: unit = w in (0, 1) as Eq. 15 writes it; symmetric = 2 w - 1 "
        "in (-1, 1) as Sect. 2.2 (WOA) has it", choices=("unit", "symmetric"),
    )  # fmt: skip
    beta: float = option(0.74, "tent map parameter (Eq. 14, Sect. 5.2)", low=0, high=1,
                         low_open=True, high_open=True)  # fmt: skip
    mu: float = option(4.0, "logistic map parameter (Eq. 13)", low=0, high=4, low_open=True)
    b: float = option(1.0, "spiral shape constant (Eqs. 7, 15)")
    S: int = option(10, "lifespan: DE and reverse search after S non-improving generations",
                    low=0)  # fmt: skip
    k: int | None = option(
        None, "ring neighbourhood radius (None: 10 % of pop_size), in [1, (n-1)/2]", low=1
    )
    lam: float = option(1e-4, "lambda of Eq. 17 (gamma_1, gamma_2 = lambda x rand)", low=0)
    F: float = option(0.8, "scale factor of the global donor (Eq. 19)", low=0, low_open=True)
    omega: float = option(0.5, "weight of the global donor in V (Eq. 20)", low=0, high=1)
    C_rate: float = option(0.1, "crossover rate: the donor gene when rand >= C_rate (Eq. 21)",
                           low=0, high=1)  # fmt: skip
    alpha: float = option(0.01, "per-gene probability of a uniform perturbation (Eq. 22)",
                          low=0, high=1)  # fmt: skip

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.k is not None and not self.k <= (self.pop_size - 1) // 2:
            raise OptimizerError(
                f"k must be in [1, (pop_size-1)/2] = [1, {(self.pop_size - 1) // 2}], got {self.k}"
            )

    def ring_radius(self) -> int:
        """``k``, or 10 % of the population in ``[1, (n-1)/2]`` when ``k`` is None."""
        if self.k is not None:
            return self.k
        return int(min(max(1, round(0.1 * self.pop_size)), (self.pop_size - 1) // 2))


# ---------------------------------------------------------------------- optimizer
@register
class RSCDWOA(Optimizer):
    """Whale optimization with chaotic coefficients, lifespan-triggered DE and reverse search.

    State after each ``tell``: ``x`` / ``fx`` (population and costs), ``x_star`` / ``f_star``
    (best so far, ``X_*``), ``w`` (3, n) chaotic orbits for ``A``, ``C`` and ``l``, ``t``
    (generations completed), ``s`` (lifespan counter), ``phase`` (``"move"`` or ``"reverse"``:
    what the next ``ask`` returns) and, for the generation under way, ``de_rows`` (whales on the
    DE branch).

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random points
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "rscdwoa"
    Config: ClassVar[type[OptimizerConfig]] = RSCDWOAConfig
    config: RSCDWOAConfig

    def _setup(self) -> None:
        n, d = self.config.pop_size, self.dim
        self.k = self.config.ring_radius()
        self.ring = ring_neighbourhood(n, self.k)
        self.x: FloatArray = np.empty((n, d))
        self.fx: FloatArray = np.full(n, np.inf)
        self.x_star: FloatArray = np.empty(d)
        self.f_star = np.inf
        self.w: FloatArray = np.empty((3, n))  # chaotic orbits for A, C, l (seeded at init)
        self.t = 0  # generations completed
        self.s = 0  # lifespan counter: non-improving generations so far
        self.phase = "init"
        self.de_rows: IntArray = np.zeros(0, dtype=np.int64)
        self.woa_mask = np.ones(n, dtype=bool)
        self.f_star_start = np.inf  # f_star when the generation under way began
        # coefficients of the last generation (for inspection)
        self.a = 2.0
        self.A: FloatArray = np.zeros(n)
        self.C: FloatArray = np.zeros(n)
        self.l: FloatArray = np.zeros(n)
        self.q: FloatArray = np.zeros(n)

    # ------------------------------------------------------------------ hooks
    def _initialize(self) -> FloatArray:
        X = self.initial_population()
        self.w = chaos_seed(self.rng, (3, self.config.pop_size))
        return X

    def _ask(self) -> FloatArray:
        if self.phase == "reverse":
            u = self.rng.random((self.de_rows.shape[0], self.dim))
            return self.clip(
                reflection_reverse_point(self.x[self.de_rows], self.lower, self.upper, u)
            )
        return self._move()

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self.phase == "init":
            self.x, self.fx = X.copy(), f.copy()
            i = int(np.argmin(f))
            self.x_star, self.f_star = X[i].copy(), float(f[i])
            self.phase = "move"
            return
        if self.phase == "move":
            woa = self.woa_mask
            self.x[woa] = X[woa]  # WOA moves replace their whale unconditionally
            self.fx[woa] = f[woa]
            de = self.de_rows
            won = de[f[de] <= self.fx[de]]  # Eq. 23: W_i if f(W_i) <= f(X_i)
            self.x[won] = X[won]
            self.fx[won] = f[won]
            self._update_star(X, f)
            if de.shape[0] > 0:
                self.phase = "reverse"
                return
        else:  # reverse batch: the reflection points of the DE whales, in de_rows order
            de = self.de_rows
            better = f < self.fx[de]  # Sect. 3.2: replace only if strictly better
            self.x[de[better]] = X[better]
            self.fx[de[better]] = f[better]
            self._update_star(X, f)
        self._end_generation()

    # ------------------------------------------------------------------ one generation
    def _move(self) -> FloatArray:
        cfg = self.config
        rng = self.rng
        x, x_star = self.x, self.x_star
        n = x.shape[0]
        self.f_star_start = self.f_star

        a = self.a = coefficient_a(self.t, cfg.max_iterations)  # Eq. 6
        self.w = chaos_step(self.w, cfg.chaos, cfg.beta, cfg.mu, rng)  # Eq. 13 / 14
        w_A, w_C, w_l = self.w
        A = self.A = 2.0 * a * w_A - a  # Eq. 11
        C = self.C = 2.0 * w_C  # Eq. 12
        # Eq. 15: l replaced by w(t); or WOA's range (-1, 1) of Sect. 2.2
        l = self.l = w_l.copy() if cfg.l_range == "unit" else 2.0 * w_l - 1.0
        q = self.q = np.asarray(rng.random(n), dtype=np.float64)

        encircle = q < 0.5  # Eq. 8
        use_de = encircle & (self.s >= cfg.S)  # Alg. 1 lines 11, 13, 16
        exploit = encircle & ~use_de & (np.abs(A) < 1.0)
        explore = encircle & ~use_de & (np.abs(A) >= 1.0)
        spiral = ~encircle

        new = np.empty_like(x)
        e = np.flatnonzero(exploit)  # Eqs. 2-3
        D = np.abs(C[e, None] * x_star - x[e])
        new[e] = x_star - A[e, None] * D

        e = np.flatnonzero(explore)  # Eqs. 9-10, X_rand another whale
        rand = randint(rng, n - 1, e.shape[0])
        rand = rand + (rand >= e)
        x_rand = x[rand]
        D = np.abs(C[e, None] * x_rand - x[e])
        new[e] = x_rand - A[e, None] * D

        e = np.flatnonzero(spiral)  # Eq. 15 with D' = |X_* - X_i| (Eq. 32)
        D = np.abs(x_star - x[e])
        new[e] = D * (np.exp(cfg.b * l[e]) * np.cos(2.0 * np.pi * l[e]))[:, None] + x_star

        self.de_rows = np.flatnonzero(use_de).astype(np.int64)
        self.woa_mask = ~use_de
        if self.de_rows.shape[0] > 0:
            new[self.de_rows] = self._de_trials(self.de_rows)
        return self.clip(new)  # Alg. 1 line 28

    def _de_trials(self, rows: IntArray) -> FloatArray:
        """Trial vectors ``W_i`` of the whales ``rows`` (Eqs. 17-22)."""
        cfg = self.config
        rng = self.rng
        x, fx = self.x, self.fx
        n, d = x.shape
        m = rows.shape[0]
        xi = x[rows]

        nb = self.ring[rows]  # (m, 2k+1) ring neighbourhood, i included
        x_lbest = x[nb[np.arange(m), np.argmin(fx[nb], axis=1)]]  # X_i,best,l
        p1, p2 = ring_pairs(rng, rows, n, self.k)
        gamma1 = cfg.lam * rng.random((m, d))  # Eq. 17
        gamma2 = cfg.lam * rng.random((m, d))
        L = xi + gamma1 * (x_lbest - xi) + gamma2 * (x[p1] - x[p2])  # Eq. 18

        x_gbest = x[int(np.argmin(fx))]  # X_best,g of the current population
        r1, r2 = two_others(rng, rows, n)
        G = x_gbest + cfg.F * (x_gbest - xi) + cfg.F * (x[r1] - x[r2])  # Eq. 19

        V = cfg.omega * G + (1.0 - cfg.omega) * L  # Eq. 20

        chi = randint(rng, d, m)  # Eq. 21
        take = rng.random((m, d)) >= cfg.C_rate
        take[np.arange(m), chi] = True
        U = np.where(take, V, xi)

        phi = rng.random((m, d))  # Eq. 22, uniform random perturbation
        noise = self.lower + rng.random((m, d)) * (self.upper - self.lower)
        return np.asarray(np.where(phi < cfg.alpha, noise, U), dtype=np.float64)

    def _update_star(self, X: FloatArray, f: FloatArray) -> None:
        i = int(np.argmin(f))
        if f[i] < self.f_star:  # Alg. 1 line 30
            self.x_star, self.f_star = X[i].copy(), float(f[i])

    def _end_generation(self) -> None:
        if not self.f_star < self.f_star_start:  # Alg. 1 line 32
            self.s += 1
        self.t += 1  # line 33
        self.phase = "move"
