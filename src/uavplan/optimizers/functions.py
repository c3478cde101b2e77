"""Benchmark functions (vectorized: ``f(X (pop, dim)) -> (pop,)``) as optimization problems.

``f1`` - ``f9`` are the nine functions of RSCDWOA Table 4 (Zhang et al.; unimodal ``f1`` - ``f6``,
multimodal ``f7`` - ``f9``; 30 dimensions, 100 iterations there). Table 4 gives neither bounds nor
optima and has typos; each function below is the standard definition the table intends, with the
standard search box and optimum: those of Yao, Liu & Lin, "Evolutionary programming made faster",
IEEE Trans. Evolutionary Computation 3(2), 1999, Table I, which the WOA (Mirjalili & Lewis 2016)
and GWO (Mirjalili et al. 2014) papers use as well:

======  ==============  =======================================================  ==============
name    function        formula                                                  box
======  ==============  =======================================================  ==============
f1      Sphere          sum x_i^2                                                [-100, 100]
f2      Sum squares     sum i x_i^2                                              [-10, 10]
f3      Step            sum floor(x_i + 0.5)^2                                   [-100, 100]
f4      Quartic+noise   sum i x_i^4 + random[0, 1)                               [-1.28, 1.28]
f5      Rosenbrock      sum_{i<n} 100 (x_{i+1} - x_i^2)^2 + (x_i - 1)^2          [-30, 30]
f6      Schwefel 2.22   sum |x_i| + prod |x_i|                                   [-10, 10]
f7      Rastrigin       sum x_i^2 - 10 cos(2 pi x_i) + 10                        [-5.12, 5.12]
f8      Griewank        sum x_i^2 / 4000 - prod cos(x_i / sqrt(i)) + 1           [-600, 600]
f9      Ackley          -20 exp(-0.2 sqrt(mean x_i^2)) - exp(mean cos 2 pi x_i)  [-32, 32]
                        + 20 + e
======  ==============  =======================================================  ==============

Every minimum is 0 (for ``f4``: of its noise-free part), at the origin except Rosenbrock's (at
``(1, ..., 1)``); Step is 0 on the whole cube ``[-0.5, 0.5)^n``. Table 4's typos, fixed here:

* ``f5`` (Rosenbrock) lacks the square on ``100 (x_{i+1} - x_i^2)``; without it the function is
  unbounded below. Yao et al. f5.
* ``f6`` (Schwefel 2.22) lacks the absolute values ``|x_i|``; without them it is unbounded below.
  Yao et al. f2.
* ``f3`` (Step) writes ``[x_i + 0.5]^2``: the brackets are the floor of Yao et al. f6. (The
  MATLAB code published with the WOA and GWO papers computes ``sum |x_i + 0.5|^2`` instead, a
  shifted sphere; we follow the published definition.)
* ``f2`` (Sum squares) is not in Yao et al.; its box ``[-10, 10]`` is the usual one (Karaboga &
  Akay, "A comparative study of Artificial Bee Colony algorithm", Applied Mathematics and
  Computation 214, 2009; Jamil & Yang, "A literature survey of benchmark functions for global
  optimization problems", 2013).

Noise (``f4``): ``quartic_noise(X, rng)`` adds one ``U[0, 1)`` draw per row from the generator it
is given (a required argument: there is no hidden global random state). :func:`function_problem`
binds a fresh ``np.random.default_rng(noise_seed)`` (``noise_seed = 0`` by default) to each problem
it builds, so a run on ``function_problem("f4")`` is reproducible bit for bit given the optimizer
seed, while evaluating the same point twice still gives two different values (true noise, as in
Yao et al. and the WOA code's ``+ rand``). Build one problem per run: runs that share a problem
share its noise stream.

Names: ``NAME`` is the 30-D problem (``f5``), ``NAME:DIM`` any other dimension (``f5:10``). The
older ``NAMEDIM`` form (``sphere10``) still works for names without digits.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import FunctionProblem, OptimizerError

FloatArray = NDArray[np.float64]

DEFAULT_DIM = 30


def _as2d(X: FloatArray) -> FloatArray:
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2:
        raise OptimizerError(f"benchmark functions take X of shape (pop, dim), got {X.shape}")
    return X


def _i(n: int) -> FloatArray:
    """The 1-based coordinate indices ``i = 1..n`` as floats, (n,)."""
    return np.arange(1, n + 1, dtype=np.float64)


def sphere(X: FloatArray) -> FloatArray:
    """Sphere (f1), ``sum x_i^2``; minimum 0 at the origin. Yao et al. 1999 f1."""
    X = _as2d(X)
    return np.asarray(np.sum(X**2, axis=1))


def sum_squares(X: FloatArray) -> FloatArray:
    """Sum squares (f2), ``sum_i i x_i^2``; minimum 0 at the origin (Karaboga & Akay 2009)."""
    X = _as2d(X)
    return np.asarray(np.sum(_i(X.shape[1]) * X**2, axis=1))


def step(X: FloatArray) -> FloatArray:
    """Step (f3), ``sum floor(x_i + 0.5)^2``; minimum 0 on ``[-0.5, 0.5)^n``. Yao et al. f6."""
    X = _as2d(X)
    return np.asarray(np.sum(np.floor(X + 0.5) ** 2, axis=1))


def quartic(X: FloatArray) -> FloatArray:
    """The noise-free part of f4, ``sum_i i x_i^4``; minimum 0 at the origin."""
    X = _as2d(X)
    return np.asarray(np.sum(_i(X.shape[1]) * X**4, axis=1))


def quartic_noise(X: FloatArray, rng: np.random.Generator) -> FloatArray:
    """Quartic with noise (f4), ``sum_i i x_i^4 + random[0, 1)``: one uniform draw per row from
    ``rng``. Yao et al. f7. The noise-free minimum is 0 at the origin (:func:`quartic`)."""
    q = quartic(X)
    return np.asarray(q + rng.random(q.shape[0]))


def rosenbrock(X: FloatArray) -> FloatArray:
    """Rosenbrock (f5), ``sum_{i=1}^{n-1} 100 (x_{i+1} - x_i^2)^2 + (x_i - 1)^2``; minimum 0 at
    ``(1, ..., 1)``. Yao et al. f5 (Table 4 drops the square of the first term)."""
    X = _as2d(X)
    x, x_next = X[:, :-1], X[:, 1:]
    return np.asarray(np.sum(100.0 * (x_next - x**2) ** 2 + (x - 1.0) ** 2, axis=1))


def schwefel_2_22(X: FloatArray) -> FloatArray:
    """Schwefel 2.22 (f6), ``sum |x_i| + prod |x_i|``; minimum 0 at the origin. Yao et al. f2
    (Table 4 drops the absolute values)."""
    A = np.abs(_as2d(X))
    return np.asarray(np.sum(A, axis=1) + np.prod(A, axis=1))


def rastrigin(X: FloatArray) -> FloatArray:
    """Rastrigin (f7), ``sum x_i^2 - 10 cos(2 pi x_i) + 10``; minimum 0 at the origin. Yao et al.
    f9."""
    X = _as2d(X)
    return np.asarray(np.sum(X**2 - 10.0 * np.cos(2.0 * np.pi * X) + 10.0, axis=1))


def griewank(X: FloatArray) -> FloatArray:
    """Griewank (f8), ``sum x_i^2 / 4000 - prod cos(x_i / sqrt(i)) + 1``; minimum 0 at the origin.
    Yao et al. f11."""
    X = _as2d(X)
    return np.asarray(
        np.sum(X**2, axis=1) / 4000.0 - np.prod(np.cos(X / np.sqrt(_i(X.shape[1]))), axis=1) + 1.0
    )


def ackley(X: FloatArray) -> FloatArray:
    """Ackley (f9), ``-20 exp(-0.2 sqrt(mean x_i^2)) - exp(mean cos(2 pi x_i)) + 20 + e``; minimum
    0 at the origin. Yao et al. f10."""
    X = _as2d(X)
    return np.asarray(
        -20.0 * np.exp(-0.2 * np.sqrt(np.mean(X**2, axis=1)))
        - np.exp(np.mean(np.cos(2.0 * np.pi * X), axis=1))
        + 20.0
        + np.e
    )


@dataclass(frozen=True)
class Benchmark:
    """A registered benchmark function: the function, its box ``[lower, upper]^dim``, its known
    minimum ``f_min`` and a minimizer ``x_min * (1, ..., 1)``.

    ``noisy`` functions take a ``rng`` keyword (see :meth:`function`); ``f_min`` is then the
    minimum of the noise-free part.
    """

    f: Callable[..., FloatArray]
    lower: float
    upper: float
    f_min: float = 0.0
    x_min: float = 0.0
    title: str = ""
    noisy: bool = False
    min_dim: int = 1

    def function(self, noise_seed: int | None = 0) -> Callable[[FloatArray], FloatArray]:
        """``f(X) -> (pop,)``; for a noisy function bound to a fresh generator from
        ``noise_seed``."""
        if self.noisy:
            return partial(self.f, rng=np.random.default_rng(noise_seed))
        return self.f

    def minimizer(self, dim: int) -> FloatArray:
        """A global minimizer in ``dim`` dimensions, (dim,)."""
        return np.full(dim, self.x_min)


#: name -> benchmark (f1-f9: RSCDWOA Table 4; bounds and optima as in the module docstring)
FUNCTIONS: dict[str, Benchmark] = {
    "sphere": Benchmark(sphere, -100.0, 100.0, title="Sphere"),
    "f1": Benchmark(sphere, -100.0, 100.0, title="Sphere"),
    "f2": Benchmark(sum_squares, -10.0, 10.0, title="Sum squares"),
    "f3": Benchmark(step, -100.0, 100.0, title="Step"),
    "f4": Benchmark(quartic_noise, -1.28, 1.28, title="Quartic with noise", noisy=True),
    "f5": Benchmark(rosenbrock, -30.0, 30.0, x_min=1.0, title="Rosenbrock", min_dim=2),
    "f6": Benchmark(schwefel_2_22, -10.0, 10.0, title="Schwefel 2.22"),
    "f7": Benchmark(rastrigin, -5.12, 5.12, title="Rastrigin"),
    "f8": Benchmark(griewank, -600.0, 600.0, title="Griewank"),
    "f9": Benchmark(ackley, -32.0, 32.0, title="Ackley"),
}


#: How far the shifted functions (``f1s`` - ``f9s``) move the optimum: this fraction of the
#: box's half-width, per coordinate, with a fixed sign pattern (:func:`shift_vector`).
SHIFT = 0.4


def shift_vector(b: Benchmark, dim: int) -> FloatArray:
    """The offset of a shifted function's optimum: ``SHIFT`` times the half-width, the signs and
    magnitudes (0.5-1) fixed by a constant seed, so the optimum is off the box's centre in
    every coordinate (reverse search towards the centre gains nothing by it)."""
    g = np.random.default_rng(20_240_101).uniform(0.5, 1.0, dim)
    sign = np.where(np.arange(dim) % 2 == 0, 1.0, -1.0)
    return SHIFT * 0.5 * (b.upper - b.lower) * g * sign


def _shifted(f: Callable[..., FloatArray], o: FloatArray) -> Callable[..., FloatArray]:
    def g(X: FloatArray, **kw: Any) -> FloatArray:
        return f(np.asarray(X, dtype=np.float64) - o, **kw)

    return g


def parse_ref(ref: str) -> tuple[str, int]:
    """``NAME`` (30-D), ``NAME:DIM``, or the legacy ``NAMEDIM`` for digit-free names
    (``sphere10``) -> ``(name, dim)``."""
    s = ref.strip().lower()
    known = sorted(FUNCTIONS)
    if ":" in s:
        name, _, d = s.partition(":")
        if name not in FUNCTIONS or not d.isdigit():
            raise OptimizerError(
                f"unknown benchmark function {ref!r}; use NAME or NAME:DIM with NAME in {known}"
            )
        dim = int(d)
    elif s in FUNCTIONS:
        name, dim = s, DEFAULT_DIM
    else:
        m = re.fullmatch(r"([a-z_]+)(\d+)", s)  # legacy: letters then the dimension
        if not m or m.group(1) not in FUNCTIONS:
            raise OptimizerError(
                f"unknown benchmark function {ref!r}; use NAME or NAME:DIM with NAME in {known}"
            )
        name, dim = m.group(1), int(m.group(2))
    b = FUNCTIONS[name]
    if dim < b.min_dim:
        raise OptimizerError(f"{name} needs at least {b.min_dim} dimension(s), got {dim}")
    return name, dim


def function_problem(ref: str, noise_seed: int | None = 0) -> FunctionProblem:
    """A box-bounded benchmark problem from a reference string.

    ``ref``: ``NAME`` for the 30-D problem (``"f5"``, ``"sphere"``), ``NAME:DIM`` for another
    dimension (``"f5:10"``), or the older ``NAMEDIM`` (``"sphere10"``) for names without digits.
    ``noise_seed`` seeds the noise of a noisy function (``f4``); each call gets a fresh generator.
    """
    shifted = bool(re.fullmatch(r"f[1-9]s(:\d+)?", ref.strip().lower()))
    name, dim = parse_ref(ref.strip().lower().replace("s", "", 1) if shifted else ref)
    b = FUNCTIONS[name]
    f = b.function(noise_seed)
    if shifted:  # the same function, its optimum moved off the box's centre
        f = _shifted(f, shift_vector(b, dim))
    return FunctionProblem(f, np.full(dim, b.lower), np.full(dim, b.upper), name=ref)
