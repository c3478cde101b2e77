"""Real-coded genetic algorithm (GA) for waypoint paths, vectorized over the population.

In the spirit of Roberge, Tarbouchi & Labonté, "Comparison of parallel genetic algorithm and
particle swarm optimization for real-time UAV path planning", IEEE Trans. Ind. Informatics 9(1),
132-141, 2013, the GA baseline of RGG-PSO+ (Liu et al. 2024, Sect. 5.2.2, ref. [40]): a
chromosome is the list of waypoints, each waypoint one gene block of ``block`` real genes
(``problem.block``; 1 means gene-wise operators).

One generation, from the population ``P`` with costs ``f`` (``N = pop_size``):

1. **Elitism**: the ``elite`` lowest-cost individuals of ``P`` pass unchanged to the next
   generation and are not re-evaluated; only the ``N - elite`` offspring are asked for.
2. **Tournament selection**: each parent is the lowest-cost of ``tournament_size`` individuals
   drawn uniformly with replacement from ``P`` (ties: the first drawn).
3. **Single-point crossover between waypoints**: with probability ``crossover_rate`` a pair of
   parents ``(p_1, p_2)`` is cut after waypoint ``c``, ``c`` uniform in ``{1, ..., n_w - 1}``
   (``n_w`` waypoints), giving ``(p_1[:c] + p_2[c:], p_2[:c] + p_1[c:])``; otherwise the
   children are copies of the parents.
4. **Gaussian mutation**: each gene ``j`` of a child is, with probability ``mutation_rate``
   (``p_m``), moved by ``N(0, sigma_j^2)``, ``sigma_j = mutation_scale * (upper_j - lower_j)``.
5. Children are clipped to the box.

Hyperparameters: the papers we implement cite Roberge et al. for the GA baseline but give none of
its rates (RGG-PSO+ only says "the same as the original paper"), and Roberge et al.'s exact
operators and rates are not given in our papers, so they are not reproduced here. We chose
common real-coded GA values: ``pop_size = 100`` (the swarm size of RGG-PSO+ Sect. 5.2.2),
``elite = 2``, ``tournament_size = 2`` (binary tournament), ``crossover_rate = 0.9``,
``mutation_rate = 1 / dim`` (one mutated gene per child on average; ``None`` selects it),
``mutation_scale = 0.1``.

The evaluated ``X`` handed to :meth:`tell` is taken as the offspring (a caller may repair points
before evaluating them).
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


def offspring_reference(
    P: FloatArray,
    f: FloatArray,
    entrants: np.ndarray,
    cut: np.ndarray,
    gene_block: np.ndarray,
    n_off: int,
    mutate: np.ndarray,
    z: FloatArray,
    sigma: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
) -> FloatArray:
    """The children from the drawn numbers (tournament ``entrants``, crossover ``cut`` per pair,
    ``mutate`` mask and normals ``z``): the NumPy form :func:`offspring` computes in one pass."""
    n_pairs = len(cut)
    winners = entrants[np.arange(2 * n_pairs), np.argmin(f[entrants], axis=1)]
    p1, p2 = P[winners[:n_pairs]], P[winners[n_pairs:]]
    head = gene_block[None, :] < cut[:, None]  # genes taken from the own parent
    children = np.concatenate([np.where(head, p1, p2), np.where(head, p2, p1)])[:n_off]
    children = children + mutate * z * sigma
    return np.minimum(np.maximum(children, lower), upper)


@njit(cache=True)
def offspring(
    P, f, entrants, cut, gene_block, n_off, mutate, z, sigma, lower, upper
):  # pragma: no cover
    """:func:`offspring_reference` in one loop."""
    n_pairs = cut.shape[0]
    T = entrants.shape[1]
    D = P.shape[1]
    winners = np.empty(2 * n_pairs, dtype=np.int64)
    for k in range(2 * n_pairs):
        w = entrants[k, 0]
        for t in range(1, T):  # the first of the least costs, as np.argmin
            if f[entrants[k, t]] < f[w]:
                w = entrants[k, t]
        winners[k] = w
    out = np.empty((n_off, D))
    for c in range(n_off):
        q = c % n_pairs  # children of pair q: own head first (c < n_pairs), then the other's
        a, b = (
            (winners[q], winners[n_pairs + q])
            if c < n_pairs
            else (winners[n_pairs + q], winners[q])
        )
        for j in range(D):
            g = P[a, j] if gene_block[j] < cut[q] else P[b, j]
            g = g + (mutate[c, j] * z[c, j]) * sigma[j]
            out[c, j] = min(max(g, lower[j]), upper[j])
    return out


@dataclass(frozen=True)
class GAConfig(OptimizerConfig):
    """GA hyperparameters (our choices; see the module docstring)."""

    pop_size: int = option(100, "population size", low=1)
    elite: int = option(2, "individuals copied unchanged to the next generation (< pop_size)",
                        low=0)  # fmt: skip
    tournament_size: int = option(2, "tournament size (2: binary tournament)", low=1)
    crossover_rate: float = option(0.9, "probability that a parent pair is crossed", low=0,
                                   high=1)  # fmt: skip
    mutation_rate: float | None = option(
        None, "per-gene mutation probability p_m (None: 1 / dim)", low=0, high=1
    )
    mutation_scale: float = option(0.1, "mutation sigma as a fraction of the box width per gene",
                                   low=0)  # fmt: skip

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.elite < self.pop_size:
            raise OptimizerError(f"elite must be below pop_size {self.pop_size}, got {self.elite}")


@register
class GA(Optimizer):
    """Elitist real-coded GA: tournament selection, waypoint crossover, Gaussian mutation.

    The first :meth:`ask` returns ``pop_size`` individuals, later ones the ``pop_size - elite``
    offspring (the elite keep their known costs).

    Args:
        init: optional first population (pop_size, dim) used instead of uniform random points
            (e.g. paths seeded by RRT* or RGG); clipped to the box.
    """

    name: ClassVar[str] = "ga"
    Config: ClassVar[type[OptimizerConfig]] = GAConfig
    config: GAConfig

    def _setup(self) -> None:
        cfg = self.config
        self.p_m = cfg.mutation_rate if cfg.mutation_rate is not None else 1.0 / self.dim
        self.sigma = cfg.mutation_scale * (self.upper - self.lower)
        # waypoint index of each gene; the number of waypoints n_w
        self.gene_block = np.arange(self.dim) // max(self.block, 1)
        self.n_waypoints = int(self.gene_block[-1]) + 1 if self.dim > 0 else 0
        self.population: FloatArray = np.empty((cfg.pop_size, self.dim))
        self.fitness: FloatArray = np.full(cfg.pop_size, np.inf)  # costs of ``population``
        self.elite_x: FloatArray = np.empty((0, self.dim))
        self.elite_f: FloatArray = np.empty(0)

    def _initialize(self) -> FloatArray:
        return self.initial_population()

    def _ask(self) -> FloatArray:
        cfg = self.config
        rng = self.rng
        P, f = self.population, self.fitness
        N = P.shape[0]
        n_off = cfg.pop_size - cfg.elite
        n_pairs = (n_off + 1) // 2

        # tournament selection: 2 parents per pair
        entrants = rng.integers(N, size=(2 * n_pairs, cfg.tournament_size))
        # single-point crossover between waypoints
        cross = rng.random(n_pairs) < cfg.crossover_rate
        if self.n_waypoints >= 2:
            c = rng.integers(1, self.n_waypoints, size=n_pairs)  # cut after waypoint c
        else:
            c = np.full(n_pairs, self.n_waypoints)  # one waypoint: nothing to cut
        c = np.where(cross, c, self.n_waypoints)  # no crossover: cut after the last waypoint
        # Gaussian mutation, gene-wise with probability p_m
        mutate = rng.random((n_off, self.dim)) < self.p_m
        z = rng.standard_normal((n_off, self.dim))
        return np.asarray(
            offspring(P, f, entrants, np.asarray(c, dtype=np.int64), self.gene_block, n_off,
                      mutate, z, self.sigma, self.lower, self.upper)
        )  # fmt: skip

    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        if self.iterations == 0:
            P, F = X.copy(), f.copy()
        else:
            P = np.concatenate([self.elite_x, X])
            F = np.concatenate([self.elite_f, f])
        self.population, self.fitness = P, F
        order = np.argsort(F, kind="stable")[: self.config.elite]
        self.elite_x, self.elite_f = P[order].copy(), F[order].copy()
