"""Whale Optimization Algorithm (WOA), vectorized over the pod.

Mirjalili & Lewis, "The Whale Optimization Algorithm", Advances in Engineering Software 95, 51-67,
2016, as the RSCDWOA paper (Zhang et al., Sect. 2.2, Eqs. 2-10) presents it. ``X_*`` is the best
solution found so far; each whale ``X_i`` draws ``p`` (RSCDWOA's ``q``) and moves by

* shrinking encircling, ``p < 0.5`` and ``|A| < 1`` (Eqs. 2-3)::

      D = |C X_* - X_i|,          X_i(t+1) = X_* - A D

* search for prey, ``p < 0.5`` and ``|A| >= 1``, around a random other whale (Eqs. 9-10)::

      D = |C X_rand - X_i|,       X_i(t+1) = X_rand - A D

* spiral bubble-net attack, ``p >= 0.5`` (Eqs. 7-8)::

      D = |X_* - X_i|,            X_i(t+1) = D e^(b l) cos(2 pi l) + X_*

with ``A = 2 a r - a`` and ``C = 2 r`` (Eqs. 4-5), ``a = 2 - 2 t / t_max`` (Eq. 6), ``b = 1`` and
``l`` uniform in [-1, 1].

Our reading where the text leaves room (each matches the authors' reference MATLAB code unless
said otherwise):

* ``r`` is "a random number" (Eqs. 4-5), so ``A`` and ``C`` are scalars drawn per whale and
  iteration, which makes the ``|A| < 1`` test well defined; ``A`` and ``C`` use two independent
  draws ``r`` (the code's ``r1``, ``r2``);
* the spiral distance is ``D = |X_* - X_i|`` without ``C``: WOA Eq. (2.5)'s ``D'``, and the form
  RSCDWOA itself uses in its convergence proof (Eq. 33); its Eq. (7) reuses the symbol ``D_i``;
* ``l`` is uniform in [-1, 1] as RSCDWOA and the WOA paper state (the reference code draws it from
  ``[a_2, 1]`` with ``a_2`` going from -1 to -2);
* ``X_rand`` is one random whale other than ``i`` ("another whale", RSCDWOA), drawn per whale (the
  reference code draws any whale, per gene);
* schedule: ``a = max(0, 2 - 2 t / max_iterations)`` for the move made after ``t`` earlier moves
  (``t = 0, 1, ...``), the reference code's ``a = 2 - t * (2 / Max_iter)``: a run of
  ``max_iterations`` iterations of the base class (the first evaluates the initial pod) is the
  code's ``Max_iter`` evaluated pods. ``a`` is clamped at 0 if the run goes on longer.
  ``max_iterations`` is a hyperparameter, not the budget: planners and experiments should set it
  to their iteration budget;
* positions outside the box are clipped to it, as in the reference code (our choice of bound
  handling, which the papers do not discuss).

Hyperparameters (:class:`WOAConfig`): ``pop_size = 30`` search agents (the WOA paper's
experiments, Mirjalili & Lewis 2016), ``max_iterations = 100`` (the iteration count of RSCDWOA
Table 4), ``b = 1`` (RSCDWOA Sect. 2.2 and WOA). The evaluated ``X`` handed to :meth:`tell` is
taken as the pod's positions (a caller may repair points before evaluating them).
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
from uavplan.optimizers.gwo import linear_a
from uavplan.params import option


@dataclass(frozen=True)
class WOAConfig(OptimizerConfig):
    """WOA hyperparameters; Mirjalili & Lewis 2016 and RSCDWOA Sect. 2.2 / Table 4."""

    pop_size: int = option(30, "whales, search agents (X_rand != X_i needs 2)", low=2)
    max_iterations: int = option(
        100, "t_max of a = 2 - 2 t / t_max (set to the run's iteration budget)", low=1
    )
    b: float = option(1.0, "logarithmic spiral shape constant (Mirjalili & Lewis 2016)")


@register
class WOA(Optimizer):
    """Whale Optimization Algorithm: encircling, search for prey and spiral bubble-net moves.

    State: positions ``X`` (n, D); best so far ``X_star``, ``f_star``; the last move's ``a`` and
    per-whale ``A``, ``C``, ``p``, ``l`` (n,) and ``rand`` (n,) indices of ``X_rand``.

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random positions
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "woa"
    Config: ClassVar[type[OptimizerConfig]] = WOAConfig
    config: WOAConfig

    def _setup(self) -> None:
        n, D = self.config.pop_size, self.dim
        self.X: FloatArray = np.empty((n, D))
        self.X_star: FloatArray = np.empty(D)
        self.f_star = np.inf
        self.a = 2.0
        self.A: FloatArray = np.zeros(n)
        self.C: FloatArray = np.zeros(n)
        self.p: FloatArray = np.zeros(n)
        self.l: FloatArray = np.zeros(n)
        self.rand: NDArray[np.int64] = np.zeros(n, dtype=np.int64)

    def _initialize(self) -> FloatArray:
        return self.initial_population()

    def _ask(self) -> FloatArray:
        cfg, rng = self.config, self.rng
        X, X_star = self.X, self.X_star
        n = X.shape[0]
        t = self.iterations - 1  # moves made so far (iteration 1 evaluated the initial pod)
        a = self.a = linear_a(t, cfg.max_iterations)  # Eq. (6)
        r_1 = rng.random((n,))
        r_2 = rng.random((n,))
        A = self.A = 2.0 * a * r_1 - a  # Eq. (4)
        C = self.C = 2.0 * r_2  # Eq. (5)
        p = self.p = rng.random((n,))
        l = self.l = rng.uniform(-1.0, 1.0, size=(n,))
        i = np.arange(n)
        k = np.asarray(rng.integers(0, n - 1, size=n), dtype=np.int64)
        self.rand = k + (k >= i)  # another whale
        X_rand = X[self.rand]
        b = cfg.b

        A_, C_ = A[:, None], C[:, None]
        encircle = ((p < 0.5) & (np.abs(A) < 1.0))[:, None]
        search = ((p < 0.5) & (np.abs(A) >= 1.0))[:, None]
        D_star = np.abs(C_ * X_star - X)  # Eq. (2)
        D_rand = np.abs(C_ * X_rand - X)  # Eq. (10)
        D_spiral = np.abs(X_star - X)  # D' of WOA Eq. (2.5)
        X_new = np.where(
            encircle,
            X_star - A_ * D_star,  # Eq. (3)
            np.where(
                search,
                X_rand - A_ * D_rand,  # Eq. (9)
                D_spiral * np.exp(b * l[:, None]) * np.cos(2.0 * np.pi * l[:, None])
                + X_star,  # Eq. (7)
            ),
        )
        return self.clip(X_new)

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        self.X = X.copy()
        i = int(np.argmin(f))
        if self.iterations == 0 or f[i] < self.f_star:
            self.X_star = X[i].copy()
            self.f_star = float(f[i])
