"""Benchmark functions (vectorized: ``f(X (pop, dim)) -> (pop,)``) as optimization problems."""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import FunctionProblem, OptimizerError

FloatArray = NDArray[np.float64]


def sphere(X: FloatArray) -> FloatArray:
    """Sphere, sum x_i^2; minimum 0 at the origin."""
    return np.asarray(np.sum(np.asarray(X) ** 2, axis=1))


#: name -> (function, lower bound, upper bound)
FUNCTIONS = {
    "sphere": (sphere, -100.0, 100.0),
}


def function_problem(ref: str) -> FunctionProblem:
    """``NAME`` or ``NAMEdim`` (e.g. ``sphere10``) -> a box-bounded problem (default 30-D)."""
    m = re.fullmatch(r"([a-z_]+?)(\d+)?", ref)
    if not m or m.group(1) not in FUNCTIONS:
        raise OptimizerError(f"unknown benchmark function {ref!r}; known: {sorted(FUNCTIONS)}")
    f, lo, hi = FUNCTIONS[m.group(1)]
    d = int(m.group(2) or 30)
    return FunctionProblem(f, np.full(d, lo), np.full(d, hi), name=ref)
