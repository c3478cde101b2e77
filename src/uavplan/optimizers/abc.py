"""Artificial Bee Colony (ABC), vectorized over the food sources.

Karaboga, "An idea based on honey bee swarm for numerical optimization", Technical Report TR06,
Erciyes University, 2005; Karaboga & Basturk, "A powerful and efficient algorithm for numerical
function optimization: artificial bee colony (ABC) algorithm", J. Global Optimization 39,
459-471, 2007. The colony of ``pop_size`` bees is half employed, half onlookers; there are
``SN = pop_size // 2`` food sources ``x_i`` (one per employed bee). One cycle:

* employed phase: every employed bee tries ``v_ij = x_ij + phi_ij (x_ij - x_kj)`` on one random
  dimension ``j``, with a random neighbour ``k != i`` and ``phi_ij`` uniform in [-1, 1] (2007,
  Eq. 2); greedy selection keeps the better of ``x_i`` and ``v_i`` and counts a failed trial in
  ``trial_i`` (reset to 0 on improvement);
* onlooker phase: ``SN`` onlookers each pick a source by roulette wheel with
  ``p_i = fit_i / sum_n fit_n`` (2007, Eq. 1), ``fit = 1 / (1 + f)`` for ``f >= 0`` and
  ``1 + |f|`` otherwise, and try the same move from it, with the same greedy selection;
* scout phase: a source not improved in ``limit`` trials is abandoned and replaced by a uniform
  random point; as in Karaboga's reference code ("In Basic ABC, only one scout is allowed to
  occur in each cycle"), only the source with the most trials, if ``trial >= limit`` (the
  reference C code's test; its MATLAB port uses ``>``).

Hyperparameters (:class:`ABCConfig`): ``pop_size = 300`` (``SN = FoodNumber = 150``) as in PPSwarm
Table 2 (Meng, Chen & Qu, Drones 2024); ``limit = SN * D`` by default (Karaboga & Basturk 2007).
A move that leaves the box is clipped to it (as the reference code does).

**Ask/tell and iterations.** The onlookers choose their sources from the costs the employed bees
have just found, so the two phases cannot share one batch. Each :meth:`ask` therefore returns one
phase, ``SN`` candidates, and one iteration of the base class is **one phase** (``SN``
evaluations): iteration 1 evaluates the ``SN`` initial sources, then even iterations are employed
phases and odd ones onlooker phases. One ABC cycle (Karaboga's "cycle", as counted by MCN and by
PPSwarm's ``N_iter``) is two iterations and ``2 SN = pop_size`` evaluations (for an even
``pop_size``; an odd one leaves a bee idle), the cost of one iteration of a population of
``pop_size`` in PSO, DE, GWO or WOA. To run ``N`` cycles, give a
budget of ``2 N + 1`` iterations or ``pop_size * N + SN`` evaluations (PPSwarm's 100 cycles:
``Budget(max_iterations=201)``); comparisons across algorithms are fairest in evaluations.

Batch evaluation makes the phases synchronous: all candidates of a phase are made from the food
sources as they stood when the phase began (Karaboga's sequential code lets a bee see sources
its predecessors improved in the same phase). When several onlookers pick the same source, its
best candidate (the first on ties) replaces it if strictly better, which resets its trial count
to 0; otherwise each of those onlookers counts one failed trial. Selection compares costs ``f``
rather than ``fit`` (equivalent, but ``1 / (1 + f)`` rounds to 1 for tiny ``f`` and would stall).

A scout's new random source is evaluated in the next employed batch, in place of that source's
employed move, and is accepted whatever its cost (the source was abandoned): every batch holds
exactly ``SN`` points, and a scout costs no evaluation beyond the ``2 SN`` per cycle.

Initial population: ``SN`` uniform points; a user ``init`` population has ``pop_size`` rows (the
common contract of :class:`~uavplan.optimizers.base.Optimizer`): all of them are evaluated in
iteration 1 and the ``SN`` best become the food sources. The evaluated ``X`` handed to
:meth:`tell` is taken as the candidates (a caller may repair points before evaluating them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import (
    FloatArray,
    Optimizer,
    OptimizerConfig,
    register,
)
from uavplan.params import option

IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class ABCConfig(OptimizerConfig):
    """ABC hyperparameters; colony size from PPSwarm Table 2, ``limit`` from Karaboga & Basturk
    2007."""

    pop_size: int = option(
        300, "colony size, employed + onlookers (SN = pop_size // 2 food sources; PPSwarm "
        "Table 2)", low=4,
    )  # fmt: skip
    limit: int | None = option(
        None, "trials before a food source is abandoned (None: SN x D, Karaboga & Basturk)", low=1
    )


def abc_fitness(f: FloatArray) -> FloatArray:
    """Karaboga's fitness of costs ``f``: ``1 / (1 + f)`` if ``f >= 0``, else ``1 + |f|`` (an
    infinite cost has fitness 0)."""
    f = np.asarray(f, dtype=np.float64)
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(f >= 0, 1.0 / (1.0 + np.maximum(f, 0.0)), 1.0 + np.abs(f))


def _neighbours(rng: np.random.Generator, i: IntArray, SN: int) -> IntArray:
    """For each entry of ``i``, a uniform random ``k`` in ``[0, SN)`` with ``k != i``."""
    k = np.asarray(rng.integers(0, SN - 1, size=i.shape[0]), dtype=np.int64)
    return k + (k >= i)


@register
class ABC(Optimizer):
    """Artificial Bee Colony with one phase per ask (see the module docstring).

    State: food sources ``x`` (SN, D), their costs ``fx``, trial counters ``trial``; ``phase``
    is the phase of the last batch (``"init"``, ``"employed"`` or ``"onlooker"``), ``cycles`` the
    number of completed cycles, ``scout`` the source to be replaced in the next employed batch.

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random points
            (e.g. paths seeded by RRT* or RGG); clipped to the box; its SN best rows become the
            food sources.
    """

    name: ClassVar[str] = "abc"
    Config: ClassVar[type[OptimizerConfig]] = ABCConfig
    config: ABCConfig

    def _setup(self) -> None:
        SN, D = self.config.pop_size // 2, self.dim
        self.SN = SN
        self.limit = int(self.config.limit) if self.config.limit is not None else SN * D
        self.x: FloatArray = np.empty((SN, D))  # food sources
        self.fx: FloatArray = np.full(SN, np.inf)  # their costs
        self.trial: IntArray = np.zeros(SN, dtype=np.int64)  # failed trials per source
        self.phase = "init"
        self.cycles = 0
        self.scout: int | None = None  # source abandoned at the end of the last cycle
        self.scout_x: FloatArray = np.empty(D)  # its replacement, evaluated next
        self.source: IntArray = np.arange(SN, dtype=np.int64)  # source of each candidate
        self.k: IntArray = np.zeros(SN, dtype=np.int64)  # neighbour of each candidate
        self.j: IntArray = np.zeros(SN, dtype=np.int64)  # dimension each candidate changes

    # ------------------------------------------------------------------ moves
    def _move(self, source: IntArray) -> FloatArray:
        """``v = x_source`` with ``v_j = x_j + phi (x_j - x_kj)`` on one random ``j`` per row."""
        x, rng = self.x, self.rng
        n = source.shape[0]
        k = _neighbours(rng, source, self.SN)
        j = np.asarray(rng.integers(0, self.dim, size=n), dtype=np.int64)
        phi = rng.uniform(-1.0, 1.0, size=n)
        v = x[source].copy()
        rows = np.arange(n)
        v[rows, j] = x[source, j] + phi * (x[source, j] - x[k, j])
        self.source, self.k, self.j = source, k, j
        return self.clip(v)

    def probabilities(self) -> FloatArray:
        """Onlooker selection probabilities ``p_i = fit_i / sum fit`` (uniform if every source
        has fitness 0, i.e. infinite cost)."""
        fit = abc_fitness(self.fx)
        if np.any(np.isinf(fit)):  # cost -inf: only those sources
            fit = np.isinf(fit).astype(np.float64)
        total = float(fit.sum())
        if total <= 0.0:
            return np.full(self.SN, 1.0 / self.SN)
        return np.asarray(fit / total)

    def _roulette(self, p: FloatArray, n: int) -> IntArray:
        c = np.cumsum(p)
        u = self.rng.random(n) * c[-1]
        idx = np.searchsorted(c, u, side="right")
        return np.asarray(np.minimum(idx, self.SN - 1), dtype=np.int64)

    # ------------------------------------------------------------------ hooks
    def _initialize(self) -> FloatArray:
        self.phase = "init"
        return self.initial_population(self.SN)

    def _ask(self) -> FloatArray:
        if self.phase == "employed":
            self.phase = "onlooker"
            return self._move(self._roulette(self.probabilities(), self.SN))
        self.phase = "employed"
        v = self._move(np.arange(self.SN, dtype=np.int64))
        if self.scout is not None:  # the scout's new source replaces that bee's move
            v[self.scout] = self.scout_x
        return v

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self.phase == "init":
            keep = np.argsort(f, kind="stable")[: self.SN]  # all rows if no init population
            self.x, self.fx = X[keep].copy(), f[keep].copy()
            self.trial = np.zeros(self.SN, dtype=np.int64)
        elif self.phase == "employed":
            better = f < self.fx  # greedy selection, strict improvement
            if self.scout is not None:
                better[self.scout] = True  # the abandoned source is replaced unconditionally
                self.scout = None
            self._select(better, X, f)
        else:
            self._tell_onlookers(X, f)
            self.cycles += 1
            self._send_scout()

    def _select(self, better: NDArray[np.bool_], X: FloatArray, f: FloatArray) -> None:
        self.x[better] = X[better]
        self.fx[better] = f[better]
        self.trial[better] = 0
        self.trial[~better] += 1

    def _tell_onlookers(self, X: FloatArray, f: FloatArray) -> None:
        SN, src = self.SN, self.source
        best = np.full(SN, np.inf)
        np.minimum.at(best, src, f)  # best candidate cost per source
        first = np.full(SN, len(f), dtype=np.int64)
        cand = np.flatnonzero(f == best[src])
        np.minimum.at(first, src[cand], cand)  # first candidate reaching it
        better = best < self.fx
        winners = first[better]
        self.x[better] = X[winners]
        self.fx[better] = f[winners]
        self.trial[better] = 0
        counts = np.bincount(src, minlength=SN)
        self.trial[~better] += counts[~better]

    def _send_scout(self) -> None:
        m = int(np.argmax(self.trial))  # the most-tried source (the first on ties)
        if self.trial[m] >= self.limit:
            self.scout = m
            self.scout_x = self.uniform(1)[0]
