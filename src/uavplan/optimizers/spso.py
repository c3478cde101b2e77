"""Spherical vector-based PSO (SPSO), Phung & Ha, "Safety-enhanced UAV path planning with
spherical vector-based particle swarm optimization", Applied Soft Computing 107, 2021.

SPSO is PSO run on the spherical-vector encoding of a path (each segment's magnitude ``r``,
elevation ``psi`` and azimuth ``phi`` relative to the previous node; see
:class:`uavplan.problems.encoding.SphericalEncoding`, which planners pair with this optimizer).
The swarm update is the PSO of :mod:`uavplan.optimizers.pso` with SPSO's settings: ``w = 1``
damped by 0.98, ``c1 = c2 = 1.5``, velocities clamped to ``0.5`` of each variable's range and
mirrored at the bounds (the reference code's ``alpha = 0.5`` and its bound handling).

One more detail from the reference code: the swarm is re-initialized until at least one particle
has a finite cost (``while ~isInit``). Here every such re-initialization is an evaluated
population and counts as an iteration and its evaluations (an honest budget), up to
``max_init_attempts``; after that the swarm proceeds from its last initial population.
On a problem without infinite costs SPSO behaves exactly as PSO.

**Global-best update** (``update``). The reference code (``SPSO_MAIN.m``) moves and evaluates
the particles one at a time and replaces the global best as soon as one improves on it, so the
particles after it in the same iteration already follow the new best (an asynchronous PSO).
``update="sync"`` (the default, :class:`~uavplan.optimizers.pso.PSO`'s) moves the whole swarm
against the global best of the previous iteration and evaluates it as one batch.
``update="async"`` reproduces the reference's order exactly while still evaluating in batches:
the swarm is moved against the current global best and evaluated; the first particle that
improves on the global best becomes it, and every particle after it is moved again (the same
random numbers, the new global best) and re-evaluated; and so on to the end of the swarm. The
result is that of moving and evaluating one particle at a time (a test compares the two); the
re-evaluations are work the batching costs, not evaluations of the algorithm: they are counted
apart (:attr:`SPSO.speculative_evaluations`), the budget and histories count ``pop_size`` per
iteration, and the best point and the tracked feasibility see only the particles as the
algorithm took them (:attr:`~uavplan.optimizers.base.Optimizer.last_x`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from uavplan.optimizers.base import FloatArray, OptimizerConfig, OptimizerError, register
from uavplan.optimizers.pso import PSO, PSOConfig, move
from uavplan.params import option

#: :class:`SPSOConfig` ``update``: the global best per iteration or per particle
UPDATES = ("sync", "async")


@dataclass(frozen=True)
class SPSOConfig(PSOConfig):
    """SPSO hyperparameters (Phung & Ha 2021 and its reference code)."""

    pop_size: int = option(500, "particles (SPSO's swarm on its benchmark)", low=1)
    max_init_attempts: int = option(
        100, "re-initializations of the swarm while every cost is infinite (SPSO's code)", low=1
    )
    update: str = option(
        "sync", "sync: the swarm moves against the previous iteration's global best; async: "
        "the global best replaced particle by particle, as SPSO_MAIN.m", choices=UPDATES,
    )  # fmt: skip


@register
class SPSO(PSO):
    """PSO with SPSO's settings and initialization; planners use it with the spherical
    encoding."""

    name: ClassVar[str] = "spso"
    Config: ClassVar[type[OptimizerConfig]] = SPSOConfig
    config: SPSOConfig
    #: the path encoding planners use with this optimizer
    encoding: ClassVar[str] = "spherical"

    def _setup(self) -> None:
        super()._setup()
        self._init_attempts = 0
        self._initializing = True  # every evaluated population so far was an initial swarm
        self._reinit = False
        #: asynchronous update: particles evaluated again after a new global best (batching's
        #: extra work, not counted in ``evaluations``)
        self.speculative_evaluations = 0
        self._move_from: tuple[FloatArray, ...] | None = None

    def _ask(self) -> FloatArray:
        if self._reinit:
            self._reinit = False
            self.x = self.uniform(self.config.pop_size)
            self.v = np.zeros_like(self.x)
            return self.x.copy()
        if self.config.update == "sync":
            return super()._ask()
        r1 = self.rng.random(self.x.shape)
        r2 = self.rng.random(self.x.shape)
        self._move_from = (self.x, self.v, r1, r2)
        self.x, self.v = self._move(0, self.x, self.v, r1, r2)
        return self.x

    def _move(
        self, start: int, x: FloatArray, v: FloatArray, r1: FloatArray, r2: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The particles ``start:`` of ``x``, ``v`` moved against the current global best."""
        c, s = self.config, slice(start, None)
        return move(x[s], v[s], self.pbest_x[s], self.gbest_x, r1[s], r2[s], self.w, c.c1, c.c2,
                    self.v_max, self.lower, self.upper)  # fmt: skip

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if not self._initializing:
            if self.config.update == "async":
                self._tell_async(X, f)
            else:
                super()._tell(X, f)
            return
        # X is an initial swarm: it replaces the previous (all-infinite) one
        self._init_attempts += 1
        self.x = X.copy()
        self.v = np.zeros_like(X)
        self.pbest_x = X.copy()
        self.pbest_f = f.copy()
        i = int(np.argmin(f))
        self.gbest_x = X[i].copy()
        self.gbest_f = float(f[i])
        if np.isfinite(self.gbest_f) or self._init_attempts >= self.config.max_init_attempts:
            self._initializing = False
        else:
            self._reinit = True

    def _tell_async(self, X: FloatArray, f: FloatArray) -> None:
        """Take the particles in order; at the first that improves on the global best, replace
        it, move the rest again against it and evaluate them again (see the module)."""
        assert self._move_from is not None
        x0, v0, r1, r2 = self._move_from
        self._move_from = None
        X, f, V = X.copy(), f.copy(), self.v.copy()
        n = len(f)
        start = 0
        while start < n:
            ahead = np.flatnonzero(f[start:] < self.gbest_f)  # gbest_f <= every pbest_f
            stop = start + int(ahead[0]) if ahead.size else n
            rows = slice(start, stop)
            better = start + np.flatnonzero(f[rows] < self.pbest_f[rows])
            self.pbest_x[better] = X[better]
            self.pbest_f[better] = f[better]
            if stop == n:
                break
            self.pbest_x[stop] = X[stop]
            self.pbest_f[stop] = f[stop]
            self.gbest_x = X[stop].copy()
            self.gbest_f = float(f[stop])
            start = stop + 1
            if start < n:  # the rest follow the new global best: moved and evaluated again
                X[start:], V[start:] = self._move(start, x0, v0, r1, r2)
                f[start:] = np.asarray(self.problem.evaluate(X[start:]), dtype=np.float64)
                self.speculative_evaluations += n - start
                if np.any(np.isnan(f[start:])):
                    raise OptimizerError(f"{self.name}: NaN costs (use inf for infeasible)")
        self.x, self.v = X, V
        self.last_x, self.last_f = X, f
        self.w *= self.config.w_damp
