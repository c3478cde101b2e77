"""Grey Wolf Optimizer (GWO), vectorized over the pack.

Mirjalili, Mirjalili & Lewis, "Grey Wolf Optimizer", Advances in Engineering Software 69, 46-61,
2014. The three best solutions found so far lead the hunt: alpha, beta and delta. Every wolf
``X`` moves to the mean of three points, one per leader (Eqs. 3.5-3.7)::

    D_alpha = |C_1 X_alpha - X|,   X_1 = X_alpha - A_1 D_alpha     (and beta -> X_2, delta -> X_3)
    X(t+1) = (X_1 + X_2 + X_3) / 3

with ``A = 2 a r_1 - a`` and ``C = 2 r_2`` (Eqs. 3.3-3.4), ``r_1``, ``r_2`` uniform in [0, 1] per
wolf, gene and leader, and ``a`` decreasing linearly from 2 to 0 over the run.

Schedule: ``a = max(0, 2 - 2 t / max_iterations)`` for the move made after ``t`` earlier moves
(``t = 0, 1, ...``), which is the reference MATLAB code's ``a = 2 - l * (2 / Max_iter)`` with its
loop counter ``l``; a run of ``max_iterations`` iterations of the base class (the first evaluates
the initial pack) is exactly the reference code's ``Max_iter`` evaluated packs. ``a`` is clamped at
0 if the run goes on longer (the pack then contracts onto its leaders). ``max_iterations`` is a
hyperparameter, not the budget: planners and experiments should set it to their iteration budget.

Hyperparameters (:class:`GWOConfig`): ``pop_size = 300`` and ``max_iterations = 100``, PPSwarm
Table 2 (Meng, Chen & Qu, Drones 2024; the GWO paper itself uses 30 wolves and 500 iterations).

Details (our reading): alpha, beta and delta are the three best points ever evaluated (the
leaders of the last iteration compete with the new pack; ties keep the older leader, so only a
strict improvement displaces one), which is the paper's "the first three best solutions obtained
so far"; the reference code can lose the old alpha when a new one arrives, we demote it to beta.
Positions outside the box are clipped to it, as in the reference code. The evaluated ``X`` handed
to :meth:`tell` is taken as the pack's positions (a caller may repair points before evaluating).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from uavplan.optimizers.base import (
    FloatArray,
    Optimizer,
    OptimizerConfig,
    register,
)
from uavplan.params import option


@dataclass(frozen=True)
class GWOConfig(OptimizerConfig):
    """GWO hyperparameters; PPSwarm Table 2 (N_pop = 300, N_iter = 100)."""

    pop_size: int = option(300, "wolves: alpha, beta, delta and the rest (PPSwarm Table 2)",
                           low=3)  # fmt: skip
    max_iterations: int = option(
        100, "length of the a: 2 -> 0 schedule (set to the run's iteration budget)", low=1
    )


def linear_a(t: int, max_iterations: int) -> float:
    """``a = 2 - 2 t / max_iterations``, clamped at 0 (GWO Eq. 3.3, WOA Eq. 2.3 / RSCDWOA Eq. 6)."""
    return max(0.0, 2.0 - 2.0 * t / max_iterations)


@register
class GWO(Optimizer):
    """Grey Wolf Optimizer: alpha, beta, delta leaders; ``a`` linear from 2 to 0.

    State: positions ``X`` (n, D); ``leaders_x`` (3, D) and ``leaders_f`` (3,) for alpha, beta,
    delta; ``a``, ``A`` and ``C`` (3, n, D) of the last move.

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random positions
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "gwo"
    Config: ClassVar[type[OptimizerConfig]] = GWOConfig
    config: GWOConfig

    def _setup(self) -> None:
        n, D = self.config.pop_size, self.dim
        self.X: FloatArray = np.empty((n, D))
        self.leaders_x: FloatArray = np.empty((3, D))  # alpha, beta, delta
        self.leaders_f: FloatArray = np.full(3, np.inf)
        self.a = 2.0
        self.A: FloatArray = np.zeros((3, n, D))
        self.C: FloatArray = np.zeros((3, n, D))

    @property
    def alpha(self) -> FloatArray:
        return self.leaders_x[0]

    @property
    def beta(self) -> FloatArray:
        return self.leaders_x[1]

    @property
    def delta(self) -> FloatArray:
        return self.leaders_x[2]

    def _initialize(self) -> FloatArray:
        return self.initial_population()

    def _ask(self) -> FloatArray:
        t = self.iterations - 1  # moves made so far (iteration 1 evaluated the initial pack)
        a = self.a = linear_a(t, self.config.max_iterations)
        X = self.X
        shape = (3, *X.shape)
        r_1 = self.rng.random(shape)
        r_2 = self.rng.random(shape)
        A = self.A = 2.0 * a * r_1 - a  # Eq. (3.3)
        C = self.C = 2.0 * r_2  # Eq. (3.4)
        L = self.leaders_x[:, None, :]  # (3, 1, D)
        D = np.abs(C * L - X)  # Eq. (3.5): D_alpha, D_beta, D_delta
        X_123 = L - A * D  # Eq. (3.6): X_1, X_2, X_3
        return self.clip(X_123.mean(axis=0))  # Eq. (3.7)

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        self.X = X.copy()
        if self.iterations == 0:
            pool_x, pool_f = X, f
        else:  # the current leaders first: ties keep them
            pool_x = np.concatenate([self.leaders_x, X])
            pool_f = np.concatenate([self.leaders_f, f])
        best = np.argsort(pool_f, kind="stable")[:3]
        self.leaders_x = pool_x[best].copy()
        self.leaders_f = pool_f[best].copy()
