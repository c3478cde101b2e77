"""Benchmark functions f1-f9 (RSCDWOA Table 4) and the ``function_problem`` reference syntax."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.optimizers import OptimizerError, minimize
from uavplan.optimizers.functions import (
    FUNCTIONS,
    ackley,
    function_problem,
    griewank,
    quartic,
    quartic_noise,
    rastrigin,
    rosenbrock,
    schwefel_2_22,
    sphere,
    step,
    sum_squares,
)

TABLE4 = [f"f{i}" for i in range(1, 10)]

#: name -> (lower, upper, minimizer coordinate), Yao, Liu & Lin 1999 Table I (f2: [-10, 10])
EXPECTED = {
    "f1": (-100.0, 100.0, 0.0),
    "f2": (-10.0, 10.0, 0.0),
    "f3": (-100.0, 100.0, 0.0),
    "f4": (-1.28, 1.28, 0.0),
    "f5": (-30.0, 30.0, 1.0),
    "f6": (-10.0, 10.0, 0.0),
    "f7": (-5.12, 5.12, 0.0),
    "f8": (-600.0, 600.0, 0.0),
    "f9": (-32.0, 32.0, 0.0),
}


def noise_free(name: str):  # the function without f4's noise
    return quartic if name == "f4" else FUNCTIONS[name].f


def test_registry_has_table4_and_sphere() -> None:
    assert set(TABLE4) | {"sphere"} <= set(FUNCTIONS)
    for name, (lo, hi, x_min) in EXPECTED.items():
        b = FUNCTIONS[name]
        assert (b.lower, b.upper, b.x_min, b.f_min) == (lo, hi, x_min, 0.0)
    assert FUNCTIONS["f4"].noisy and not any(FUNCTIONS[n].noisy for n in TABLE4 if n != "f4")


@pytest.mark.parametrize("name", [*TABLE4, "sphere"])
@pytest.mark.parametrize("dim", [2, 10, 30])
def test_minimum_at_minimizer(name: str, dim: int) -> None:
    b = FUNCTIONS[name]
    X = np.tile(b.minimizer(dim), (4, 1))  # a batch of copies of the minimizer
    np.testing.assert_allclose(noise_free(name)(X), np.full(4, b.f_min), rtol=0, atol=1e-12)
    f = b.function(noise_seed=0)(X)
    assert f.shape == (4,)
    if b.noisy:
        assert np.all((f >= 0.0) & (f < 1.0)) and len(set(f)) == 4  # one draw per row
    else:
        np.testing.assert_allclose(f, b.f_min, atol=1e-12)


@pytest.mark.parametrize("name", TABLE4)
def test_minimum_is_a_lower_bound_and_shapes(name: str) -> None:
    b = FUNCTIONS[name]
    rng = np.random.default_rng(0)
    for dim in (2, 7, 30):
        X = rng.uniform(b.lower, b.upper, size=(50, dim))
        f = b.function(noise_seed=1)(X)
        assert f.shape == (50,) and f.dtype == np.float64
        assert np.all(np.isfinite(f)) and np.all(f >= b.f_min)
        # vectorized = row by row
        rows = np.array([noise_free(name)(x[None])[0] for x in X])
        np.testing.assert_allclose(noise_free(name)(X), rows, rtol=1e-12)


def test_known_values() -> None:
    x = np.ones((1, 5))
    assert sphere(2 * x)[0] == 20.0
    assert sum_squares(x)[0] == 15.0  # 1 + 2 + 3 + 4 + 5
    assert quartic(2 * x)[0] == 16.0 * 15
    assert rosenbrock(0 * x)[0] == 4.0  # (n - 1) * (0 - 1)^2
    assert rosenbrock(np.array([[1.0, 2.0]]))[0] == 100.0
    assert schwefel_2_22(-x)[0] == 6.0  # |.| sum 5 + prod 1 (Table 4 without |.| gives -6)
    assert rastrigin(x)[0] == pytest.approx(5.0)  # integer points: x^2 each
    assert griewank(0 * x)[0] == pytest.approx(0.0, abs=1e-15)
    assert griewank(np.array([[np.pi * 2]]))[0] == pytest.approx(4 * np.pi**2 / 4000)
    assert ackley(x)[0] == pytest.approx(-20 * np.exp(-0.2) + 20.0)  # cos(2 pi) = 1
    # the step function is flat on [-0.5, 0.5) and steps at half-integers
    assert step(np.array([[0.49, -0.5, 0.0]]))[0] == 0.0
    assert step(np.array([[0.5, -0.51, 1.2]]))[0] == 1.0 + 1.0 + 1.0
    with pytest.raises(OptimizerError):
        sphere(np.zeros(3))  # (pop, dim) only


def test_quartic_noise_rng_explicit_and_reproducible() -> None:
    X = np.zeros((1000, 3))
    a = quartic_noise(X, np.random.default_rng(5))
    b = quartic_noise(X, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    assert np.all((a >= 0) & (a < 1)) and 0.45 < a.mean() < 0.55
    # a problem owns its noise stream: same seed -> same values, re-evaluation -> new noise
    p, q = function_problem("f4"), function_problem("f4")
    Y = np.full((6, 30), 0.3)
    first = p.evaluate(Y)
    np.testing.assert_array_equal(first, q.evaluate(Y))
    assert not np.array_equal(first, p.evaluate(Y))
    assert not np.array_equal(first, function_problem("f4", noise_seed=1).evaluate(Y))
    noise = first - quartic(Y)
    assert np.all((noise >= 0) & (noise < 1))
    # so an optimizer run on f4 is reproducible per seed
    r1 = minimize(function_problem("f4:5"), "pso", 10, seed=3)
    r2 = minimize(function_problem("f4:5"), "pso", 10, seed=3)
    np.testing.assert_array_equal(r1.history, r2.history)


@pytest.mark.parametrize("name", TABLE4)
def test_function_problem_dims_and_bounds(name: str) -> None:
    lo, hi, _ = EXPECTED[name]
    p = function_problem(name)
    assert p.dim == 30
    np.testing.assert_array_equal(p.lower, np.full(30, lo))
    np.testing.assert_array_equal(p.upper, np.full(30, hi))
    q = function_problem(f"{name}:10")
    assert q.dim == 10 and q.name == f"{name}:10"
    assert q.evaluate(np.zeros((3, 10))).shape == (3,)


def test_reference_syntax() -> None:
    assert function_problem("sphere").dim == 30
    assert function_problem("sphere10").dim == 10  # legacy NAMEDIM still works
    assert function_problem("sphere:7").dim == 7
    assert function_problem("F3:4").dim == 4  # case-insensitive
    assert function_problem("f1").evaluate(np.ones((2, 30)))[0] == 30.0
    for bad in ("f10", "f1:0", "f1:x", "f1:", "nosuch", "nosuch5", ":5", "sphere0", "f5:1"):
        with pytest.raises(OptimizerError):
            function_problem(bad)


@pytest.mark.parametrize("name", [f"f{i}" for i in range(1, 10)])
def test_shifted_functions_move_the_optimum_off_the_centre(name: str) -> None:
    from uavplan.optimizers.functions import FUNCTIONS, function_problem, shift_vector

    b = FUNCTIONS[name]
    o = shift_vector(b, 30)
    half = 0.5 * (b.upper - b.lower)
    assert np.all(np.abs(o) >= 0.19 * half) and np.all(np.abs(o) <= 0.41 * half)
    plain, shifted = (
        function_problem(name, noise_seed=3),
        function_problem(f"{name}s", noise_seed=3),
    )
    x = b.minimizer(30)
    assert shifted.evaluate((x + o)[None])[0] == pytest.approx(plain.evaluate(x[None])[0])
    centre = np.zeros((1, 30))
    if name not in ("f3", "f4"):  # Step is flat near 0; Quartic is nearly so
        assert shifted.evaluate(centre)[0] > plain.evaluate(centre)[0] + 1e-6
