"""Global-best particle swarm optimization (PSO), vectorized over the swarm.

Update rule, Liu et al. 2024 (RGG-PSO+) Eq. (1) and Meng, Chen & Qu 2024 (PPSwarm) Eq. (14)::

    v_i^{k+1} = w v_i^k + c_1 r_1 (pbest_i^k - x_i^k) + c_2 r_2 (gbest^k - x_i^k)
    x_i^{k+1} = x_i^k + v_i^{k+1}

with ``r_1``, ``r_2`` uniform in [0, 1], drawn per particle and per gene.

Hyperparameters (:class:`PSOConfig`): RGG-PSO+ Sect. 5.2.2 runs all PSO variants with
``w = 1`` damped by 0.98 per iteration, ``c_1 = c_2 = 1.5`` (its eta_1, eta_2) and 100 particles;
the same values are SPSO's (Phung & Ha, Applied Soft Computing 107, 2021) and PPSwarm Table 1.
The velocity is clamped to ``[-v_max, v_max]`` with ``v_max = velocity_fraction * (upper - lower)``
and ``velocity_fraction = 0.5``, as in the SPSO reference code.

Implementation follows the usual Yarpiz-style global-best PSO that SPSO's code builds on:

* velocities start at zero; positions are uniform in the box (or the ``init`` population);
* after the move, a particle gene that left the box has its velocity mirrored (``v = -v``) and its
  position clipped to the box;
* ``pbest`` / ``gbest`` are replaced only on a strict improvement (``<``), so infeasible
  (``inf``) costs never displace a known point; when every cost so far is ``inf``, ``pbest`` is the
  initial position and ``gbest`` the first particle's;
* ``w`` is multiplied by ``w_damp`` after every swarm move, so the first move uses ``w = 1``
  and after ``k`` moves ``w = w_0 w_damp^k``. The evaluation of the initial swarm is iteration 1
  of the base class's count but not a move, so it does not damp ``w``.

The evaluated ``X`` handed to :meth:`tell` is taken as the particle positions (a caller may repair
points before evaluating them).
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
    register,
)
from uavplan.params import option


def move_reference(
    x: FloatArray,
    v: FloatArray,
    pbest: FloatArray,
    gbest: FloatArray,
    r1: FloatArray,
    r2: FloatArray,
    w: float,
    c1: float,
    c2: float,
    v_max: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """One swarm move, Eq. (1), with the velocity clamp and mirrored walls: the NumPy form that
    :func:`move` computes in one pass (tests compare the two)."""
    v = w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)
    v = np.minimum(np.maximum(v, -v_max), v_max)
    x = x + v
    outside = (x < lower) | (x > upper)
    v = np.where(outside, -v, v)
    return np.minimum(np.maximum(x, lower), upper), v


@njit(cache=True)
def move(x, v, pbest, gbest, r1, r2, w, c1, c2, v_max, lower, upper):  # pragma: no cover
    """:func:`move_reference` fused into one loop (the hot path of every PSO variant)."""
    n, d = x.shape
    x_new = np.empty((n, d))
    v_new = np.empty((n, d))
    for i in range(n):
        for j in range(d):
            xj = x[i, j]
            vj = w * v[i, j] + c1 * r1[i, j] * (pbest[i, j] - xj) + c2 * r2[i, j] * (gbest[j] - xj)
            vj = min(max(vj, -v_max[j]), v_max[j])
            xj = xj + vj
            if xj < lower[j] or xj > upper[j]:
                vj = -vj
            x_new[i, j] = min(max(xj, lower[j]), upper[j])
            v_new[i, j] = vj
    return x_new, v_new


@njit(cache=True)
def update_bests(X, f, pbest_x, pbest_f):  # pragma: no cover - numba
    """Personal bests replaced, in place, where ``f`` is strictly lower; returns the index of
    the least personal best (the first of equals, as ``np.argmin``)."""
    n, d = X.shape
    best = 0
    for i in range(n):
        if f[i] < pbest_f[i]:
            pbest_f[i] = f[i]
            for j in range(d):
                pbest_x[i, j] = X[i, j]
        if pbest_f[i] < pbest_f[best]:
            best = i
    return best


@dataclass(frozen=True)
class PSOConfig(OptimizerConfig):
    """PSO hyperparameters; defaults from RGG-PSO+ Sect. 5.2.2 / SPSO (Phung & Ha 2021)."""

    pop_size: int = option(100, "particles", low=1)
    w: float = option(1.0, "inertia weight w, initial value (RGG-PSO+ Sect. 5.2.2, SPSO)")
    w_damp: float = option(0.98, "w <- w x w_damp after each iteration", low=0, low_open=True)
    c1: float = option(1.5, "cognitive coefficient c_1 (eta_1 in RGG-PSO+)", low=0)
    c2: float = option(1.5, "social coefficient c_2 (eta_2 in RGG-PSO+)", low=0)
    velocity_fraction: float = option(
        0.5, "velocity clamp: v_max = velocity_fraction x (upper - lower) (SPSO's code)", low=0,
        low_open=True,
    )  # fmt: skip


@register
class PSO(Optimizer):
    """Global-best PSO with inertia damping, velocity clamping and mirrored walls.

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random positions
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "pso"
    Config: ClassVar[type[OptimizerConfig]] = PSOConfig
    config: PSOConfig

    def _setup(self) -> None:
        n, d = self.config.pop_size, self.dim
        self.v_max = self.config.velocity_fraction * (self.upper - self.lower)
        self.w = float(self.config.w)
        self.x: FloatArray = np.empty((n, d))
        self.v: FloatArray = np.zeros((n, d))
        self.pbest_x: FloatArray = np.empty((n, d))
        self.pbest_f: FloatArray = np.full(n, np.inf)
        self.gbest_x: FloatArray = np.empty(d)
        self.gbest_f = np.inf

    def _initialize(self) -> FloatArray:
        self.x = self.initial_population()
        self.v = np.zeros_like(self.x)
        return self.x.copy()

    def _ask(self) -> FloatArray:
        cfg = self.config
        x, v = self.x, self.v
        r1 = self.rng.random(x.shape)
        r2 = self.rng.random(x.shape)
        x, v = move(
            x,
            v,
            self.pbest_x,
            self.gbest_x,
            r1,
            r2,
            self.w,
            cfg.c1,
            cfg.c2,
            self.v_max,
            self.lower,
            self.upper,
        )
        self.x, self.v = x, v
        return x  # tell() keeps a copy of what was evaluated

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        first = self.iterations == 0
        self.x = X.copy()  # a caller may have repaired the points it evaluated
        if first:
            self.pbest_x = X.copy()
            self.pbest_f = f.copy()
            i = int(np.argmin(self.pbest_f))
        else:
            i = int(update_bests(X, f, self.pbest_x, self.pbest_f))
        if first or self.pbest_f[i] < self.gbest_f:
            self.gbest_x = self.pbest_x[i].copy()
            self.gbest_f = float(self.pbest_f[i])
        if not first:  # the swarm moved with the current w: damp it for the next move
            self.w *= self.config.w_damp
