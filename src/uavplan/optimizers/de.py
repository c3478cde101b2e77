"""Differential evolution DE/rand/1/bin, vectorized over the population.

Storn & Price, "Differential evolution - a simple and efficient heuristic for global
optimization over continuous spaces", J. Global Optimization 11, 341-359, 1997. With the target
vectors ``x_i`` (``i = 1..NP``):

* mutation (Eq. 2): ``v_i = x_r1 + F (x_r2 - x_r3)``, ``r1, r2, r3`` distinct and distinct from
  ``i``; drawn for all rows at once by :func:`distinct_indices` (uniform, O(NP));
* binomial crossover (Eq. 4): ``u_ij = v_ij`` if ``randb(j) <= CR`` or ``j = rnbr(i)``
  (``j_rand``, one guaranteed mutant gene per row), else ``x_ij``;
* selection: ``u_i`` replaces ``x_i`` if ``f(u_i) <= f(x_i)`` (greedy, one-to-one; ``<=`` lets
  the population drift across plateaus, including all-``inf`` ones).

Hyperparameters (:class:`DEConfig`): ``F = 0.8``, ``CR = 0.9`` as in PPSwarm Table 2 (Meng, Chen &
Qu, Drones 2024); ``NP = pop_size = 100``, the population size of RGG-PSO+ Sect. 5.2.2.

Bounds (not part of the 1997 paper; our choice): a mutant gene outside the box is **bounced
back** between the base vector and the violated bound, ``v_ij = x_r1,j + rand (lower_j - x_r1,j)``
(resp. ``upper_j``), the "bounce-back" rule of Price, Storn & Lampinen (Differential Evolution,
2005), which keeps diversity near the walls better than clipping; the result is then clipped as a
safeguard, so every trial vector lies in the box.

Ask/tell: the first :meth:`ask` returns the initial population, every later one the trial
population ``u``; the evaluated ``X`` handed to :meth:`tell` is taken as that population.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from uavplan.optimizers.base import (
    FloatArray,
    Optimizer,
    OptimizerConfig,
    OptimizerError,
    register,
)
from uavplan.params import option


def distinct_indices(rng: np.random.Generator, n: int, k: int) -> np.ndarray:
    """For every row ``i`` of ``n``, ``k`` distinct indices in ``[0, n)`` all different from ``i``,
    uniformly, as an (n, k) int64 array (sequential sampling without replacement: draw from the
    ``n - 1 - m`` indices left and step over the ones already taken, in increasing order).

    The NumPy form; :func:`distinct_indices_fast` draws the same numbers and steps over the
    taken indices in one Numba loop (tests compare the two)."""
    if k > n - 1:
        raise OptimizerError(f"need at least {k + 1} individuals, got {n}")
    taken = np.arange(n, dtype=np.int64)[:, None]  # (n, 1): i itself
    out = np.empty((n, k), dtype=np.int64)
    for m in range(k):
        r = rng.integers(0, n - 1 - m, size=n)
        for c in np.sort(taken, axis=1).T:  # step over taken indices, smallest first
            r = r + (r >= c)
        out[:, m] = r
        taken = np.concatenate([taken, r[:, None]], axis=1)
    return out


def distinct_indices_fast(rng: np.random.Generator, n: int, k: int) -> np.ndarray:
    """:func:`distinct_indices`: the same draws, in the same order, the same result."""
    if k > n - 1:
        raise OptimizerError(f"need at least {k + 1} individuals, got {n}")
    draws = np.empty((k, n), dtype=np.int64)
    for m in range(k):
        draws[m] = rng.integers(0, n - 1 - m, size=n)
    return np.asarray(_step_over(draws))


@njit(cache=True)
def _step_over(draws):  # pragma: no cover - numba
    k, n = draws.shape
    out = np.empty((n, k), dtype=np.int64)
    taken = np.empty(k + 1, dtype=np.int64)  # the row's taken indices, in increasing order
    for i in range(n):
        taken[0] = i
        for m in range(k):
            r = draws[m, i]
            for t in range(m + 1):  # step over the taken ones, smallest first
                if r >= taken[t]:
                    r += 1
            out[i, m] = r
            t = m + 1  # insert r in order
            while t > 0 and taken[t - 1] > r:
                taken[t] = taken[t - 1]
                t -= 1
            taken[t] = r
    return out


def trial_reference(
    x: FloatArray,
    r: np.ndarray,
    F: float,
    u: FloatArray,
    c: FloatArray,
    CR: float,
    j_rand: np.ndarray,
    lower: FloatArray,
    upper: FloatArray,
) -> FloatArray:
    """DE/rand/1/bin's trial vectors with bounce-back, from the drawn numbers (``u`` for the
    bounce, ``c`` against ``CR``): the NumPy form :func:`trial` computes in one pass."""
    x_r1 = x[r[:, 0]]
    v = x_r1 + F * (x[r[:, 1]] - x[r[:, 2]])
    v = np.where(v < lower, x_r1 + u * (lower - x_r1), v)
    v = np.where(v > upper, x_r1 + u * (upper - x_r1), v)
    v = np.minimum(np.maximum(v, lower), upper)
    take = c <= CR
    take[np.arange(len(x)), j_rand] = True
    return np.where(take, v, x)


@njit(cache=True)
def trial(x, r, F, u, c, CR, j_rand, lower, upper):  # pragma: no cover - numba
    """:func:`trial_reference` in one loop."""
    NP, D = x.shape
    out = np.empty((NP, D))
    for i in range(NP):
        for j in range(D):
            if c[i, j] <= CR or j == j_rand[i]:
                b = x[r[i, 0], j]
                v = b + F * (x[r[i, 1], j] - x[r[i, 2], j])
                if v < lower[j]:
                    v = b + u[i, j] * (lower[j] - b)
                if v > upper[j]:
                    v = b + u[i, j] * (upper[j] - b)
                out[i, j] = min(max(v, lower[j]), upper[j])
            else:
                out[i, j] = x[i, j]
    return out


@dataclass(frozen=True)
class DEConfig(OptimizerConfig):
    """DE/rand/1/bin hyperparameters; F and CR from PPSwarm Table 2."""

    pop_size: int = option(100, "NP, the population (r1, r2, r3 and i distinct)", low=4)
    F: float = option(0.8, "differential weight, the mutation scale factor (PPSwarm Table 2)",
                      low=0, low_open=True)  # fmt: skip
    CR: float = option(0.9, "crossover probability (PPSwarm Table 2)", low=0, high=1)


@register
class DE(Optimizer):
    """DE/rand/1/bin with bounce-back bound handling and greedy one-to-one selection.

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random points
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "de"
    Config: ClassVar[type[OptimizerConfig]] = DEConfig
    config: DEConfig

    def _setup(self) -> None:
        NP = self.config.pop_size
        self.x: FloatArray = np.empty((NP, self.dim))  # target vectors
        self.fx: FloatArray = np.full(NP, np.inf)  # their costs
        self.r = np.zeros((NP, 3), dtype=np.int64)  # r1, r2, r3 of the last trial, per row
        self.j_rand = np.zeros(NP, dtype=np.int64)  # guaranteed mutant gene of the last trial

    def _initialize(self) -> FloatArray:
        return self.initial_population()

    def _ask(self) -> FloatArray:
        cfg = self.config
        rng = self.rng
        x = self.x
        NP, D = x.shape
        r = self.r = distinct_indices_fast(rng, NP, 3)
        u = rng.random((NP, D))  # bounce back between the base vector and the violated bound
        c = rng.random((NP, D))  # binomial crossover with one guaranteed mutant gene j_rand
        self.j_rand = np.asarray(rng.integers(D, size=NP), dtype=np.int64)
        return np.asarray(trial(x, r, cfg.F, u, c, cfg.CR, self.j_rand, self.lower, self.upper))

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self.iterations == 0:
            self.x, self.fx = X.copy(), f.copy()
            return
        replace = f <= self.fx
        self.x[replace] = X[replace]
        self.fx[replace] = f[replace]
