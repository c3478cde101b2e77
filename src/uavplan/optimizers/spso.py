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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from uavplan.optimizers.base import FloatArray, OptimizerConfig, OptimizerError, register
from uavplan.optimizers.pso import PSO, PSOConfig


@dataclass(frozen=True)
class SPSOConfig(PSOConfig):
    """SPSO hyperparameters (Phung & Ha 2021 and its reference code)."""

    pop_size: int = 500  # SPSO's swarm size on its benchmark
    max_init_attempts: int = 100  # re-initializations while every cost is infinite

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.max_init_attempts < 1:
            raise OptimizerError(f"max_init_attempts must be >= 1, got {self.max_init_attempts}")


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

    def _ask(self) -> FloatArray:
        if self._reinit:
            self._reinit = False
            self.x = self.uniform(self.config.pop_size)
            self.v = np.zeros_like(self.x)
            return self.x.copy()
        return super()._ask()

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if not self._initializing:
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
