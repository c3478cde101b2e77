"""Algorithm-specific tests for ABC, GWO and WOA (the contract tests in test_optimizers.py cover
them as well, through the registry)."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.optimizers import (
    ABC,
    GWO,
    WOA,
    ABCConfig,
    Budget,
    FunctionProblem,
    GWOConfig,
    Optimizer,
    OptimizerError,
    WOAConfig,
    get,
    minimize,
)
from uavplan.optimizers.abc import abc_fitness
from uavplan.optimizers.functions import function_problem

DIM = 5


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum(X**2, axis=1)


def sphere_problem(dim: int = DIM) -> FunctionProblem:
    return FunctionProblem(sphere, -5.0 * np.ones(dim), 5.0 * np.ones(dim))


def constant_problem(dim: int = 4) -> FunctionProblem:
    """No move ever improves: every food source fails every trial."""
    return FunctionProblem(lambda X: np.ones(X.shape[0]), -np.ones(dim), np.ones(dim))


def step(opt: Optimizer) -> tuple[np.ndarray, np.ndarray]:
    X = opt.ask()
    f = opt.problem.evaluate(X)
    opt.tell(X, f)
    return X, f


# ---------------------------------------------------------------------- defaults, registry
def test_defaults_and_registry() -> None:
    assert get("abc") is ABC and get("gwo") is GWO and get("woa") is WOA
    cfg = ABCConfig()
    assert (cfg.pop_size, cfg.limit) == (300, None)  # PPSwarm Table 2: N_pop 300, FoodNumber 150
    abc = ABC(sphere_problem())
    assert abc.SN == 150 and abc.limit == 150 * DIM  # limit = SN * D (Karaboga & Basturk 2007)
    assert ABC(sphere_problem(), limit=7).limit == 7
    g = GWOConfig()
    assert (g.pop_size, g.max_iterations) == (300, 100)  # PPSwarm Table 2
    w = WOAConfig()
    assert (w.pop_size, w.max_iterations, w.b) == (30, 100, 1.0)
    for bad in (
        lambda: ABCConfig(pop_size=3),
        lambda: ABCConfig(limit=0),
        lambda: GWOConfig(pop_size=2),
        lambda: GWOConfig(max_iterations=0),
        lambda: WOAConfig(pop_size=1),
        lambda: WOAConfig(max_iterations=0),
    ):
        with pytest.raises(OptimizerError):
            bad()


# ---------------------------------------------------------------------- a schedule (GWO, WOA)
@pytest.mark.parametrize("cls", [GWO, WOA])
def test_a_decreases_linearly_then_clamps(cls: type[GWO] | type[WOA]) -> None:
    T = 10
    opt = cls(sphere_problem(), seed=0, pop_size=6, max_iterations=T)
    step(opt)  # iteration 1: the initial population, no move
    seen = []
    for k in range(1, 16):  # move k follows k - 1 earlier moves
        X = opt.ask()
        seen.append(opt.a)
        assert opt.a == pytest.approx(max(0.0, 2.0 - 2.0 * (k - 1) / T), abs=1e-15)
        opt.tell(X, sphere(X))
    assert seen[0] == 2.0 and seen[T] == 0.0 and all(a == 0.0 for a in seen[T:])
    assert np.all(np.diff(seen) <= 0)
    # a run of max_iterations iterations uses a = 2, 2 - 2/T, ..., 4/T on its T - 1 moves
    res = minimize(sphere_problem(), cls, T, seed=0, pop_size=6, max_iterations=T)
    assert res.iterations == T


# ---------------------------------------------------------------------- GWO
def test_gwo_leaders_are_three_best_so_far() -> None:
    opt = GWO(sphere_problem(), seed=1, pop_size=8, max_iterations=30)
    costs: list[float] = []
    for _ in range(30):
        _, f = step(opt)
        costs.extend(f.tolist())
        np.testing.assert_array_equal(opt.leaders_f, np.sort(costs)[:3])
        assert opt.leaders_f[0] == opt.best_f
        np.testing.assert_array_equal(opt.alpha, opt.best_x)
        np.testing.assert_array_equal(sphere(opt.leaders_x), opt.leaders_f)


def test_gwo_move_follows_equations() -> None:
    problem = sphere_problem()
    opt = GWO(problem, seed=2, pop_size=7, max_iterations=20)
    step(opt)
    for _ in range(25):
        X_prev, L = opt.X.copy(), opt.leaders_x.copy()
        X = opt.ask()
        A, C = opt.A, opt.C
        assert A.shape == C.shape == (3, 7, DIM)
        assert np.all(np.abs(A) <= opt.a + 1e-12) and np.all((C >= 0) & (C <= 2))
        X_123 = L[:, None, :] - A * np.abs(C * L[:, None, :] - X_prev)  # Eqs. (3.5)-(3.6)
        np.testing.assert_allclose(X, np.clip(X_123.mean(axis=0), -5, 5), rtol=1e-12)
        opt.tell(X, sphere(X))
    assert opt.a == 0.0  # past max_iterations: A = 0, the pack sits on its leaders' centroid
    X = opt.ask()
    np.testing.assert_allclose(X, np.tile(opt.leaders_x.mean(axis=0), (7, 1)))
    opt.tell(X, sphere(X))


# ---------------------------------------------------------------------- WOA
def test_woa_move_follows_equations() -> None:
    opt = WOA(sphere_problem(), seed=3, pop_size=12, max_iterations=15)
    step(opt)
    cases = {"encircle": 0, "search": 0, "spiral": 0}
    for _ in range(20):
        X_prev, X_star = opt.X.copy(), opt.X_star.copy()
        X = opt.ask()
        A, C, p, l, rand = opt.A, opt.C, opt.p, opt.l, opt.rand
        assert np.all(rand != np.arange(12))  # another whale
        assert np.all((l >= -1) & (l <= 1)) and np.all(np.abs(A) <= opt.a + 1e-12)
        for i in range(12):
            x = X_prev[i]
            if p[i] < 0.5 and abs(A[i]) < 1:
                want = X_star - A[i] * np.abs(C[i] * X_star - x)  # Eqs. (2)-(3)
                cases["encircle"] += 1
            elif p[i] < 0.5:
                X_rand = X_prev[rand[i]]
                want = X_rand - A[i] * np.abs(C[i] * X_rand - x)  # Eqs. (9)-(10)
                cases["search"] += 1
            else:
                D = np.abs(X_star - x)
                want = D * np.exp(l[i]) * np.cos(2 * np.pi * l[i]) + X_star  # Eq. (7), b = 1
                cases["spiral"] += 1
            np.testing.assert_allclose(X[i], np.clip(want, -5, 5), rtol=1e-12, atol=1e-15)
        opt.tell(X, sphere(X))
        assert opt.f_star == opt.best_f
        np.testing.assert_array_equal(opt.X_star, opt.best_x)
    assert min(cases.values()) > 0  # all three moves were exercised
    # a = 0: A = 0, so no search for prey and every encircling whale lands on X_*
    assert opt.a == 0.0
    X = opt.ask()
    enc = opt.p < 0.5
    assert enc.any()
    np.testing.assert_array_equal(X[enc], np.tile(opt.X_star, (enc.sum(), 1)))
    opt.tell(X, sphere(X))


# ---------------------------------------------------------------------- ABC
def test_abc_fitness() -> None:
    np.testing.assert_array_equal(abc_fitness(np.array([0.0, 1.0, -2.0, np.inf])), [1, 0.5, 3, 0])


def test_abc_phases_batches_and_evaluations() -> None:
    opt = ABC(sphere_problem(), seed=0, pop_size=20)
    SN = 10
    phases = []
    for _ in range(9):
        X, _ = step(opt)
        assert X.shape == (SN, DIM)
        phases.append(opt.phase)
    assert phases == ["init"] + ["employed", "onlooker"] * 4
    assert opt.cycles == 4 and opt.evaluations == SN * 9
    # N cycles = 2 N + 1 iterations = SN + N * pop_size evaluations
    res = minimize(sphere_problem(), "abc", 2 * 7 + 1, seed=0, pop_size=20)
    assert res.evaluations == SN + 7 * 20


def test_abc_moves_one_gene_and_selects_greedily() -> None:
    opt = ABC(sphere_problem(), seed=4, pop_size=16, limit=10**9)  # no scouts
    step(opt)
    SN = 8
    for _ in range(40):
        x_old, fx_old, trial_old = opt.x.copy(), opt.fx.copy(), opt.trial.copy()
        V = opt.ask()
        src, k, j = opt.source, opt.k, opt.j
        assert np.all(k != src)
        if opt.phase == "employed":
            np.testing.assert_array_equal(src, np.arange(SN))
        changed = x_old[src] != V
        assert np.all(changed.sum(axis=1) <= 1)  # v differs from x_src in dimension j only
        assert np.all(changed[np.arange(SN), j] | ~changed.any(axis=1))
        fV = sphere(V)
        opt.tell(V, fV)
        # greedy: each source keeps the best of itself and its candidates (strictly better wins)
        best = fx_old.copy()
        np.minimum.at(best, src, fV)
        np.testing.assert_array_equal(opt.fx, best)
        np.testing.assert_array_equal(sphere(opt.x), opt.fx)
        improved = best < fx_old
        assert np.all(opt.trial[improved] == 0)
        counts = np.bincount(src, minlength=SN)
        np.testing.assert_array_equal(opt.trial[~improved], (trial_old + counts)[~improved])


def test_abc_onlookers_prefer_better_sources() -> None:
    opt = ABC(sphere_problem(), seed=5, pop_size=8)
    step(opt)
    opt.fx = np.array([0.0, 3.0, 9.0, np.inf])
    p = opt.probabilities()
    np.testing.assert_allclose(p, np.array([1, 0.25, 0.1, 0]) / 1.35)
    counts = np.bincount(opt._roulette(p, 20000), minlength=4)
    np.testing.assert_allclose(counts / 20000, p, atol=0.02)
    assert counts[3] == 0
    opt.fx = np.full(4, np.inf)  # no information: uniform
    np.testing.assert_array_equal(opt.probabilities(), np.full(4, 0.25))


def test_abc_scout_replaces_exhausted_source() -> None:
    problem = constant_problem()
    limit = 3
    opt = ABC(problem, seed=6, pop_size=10, limit=limit)
    step(opt)
    scouts = 0
    for _ in range(30):  # cycles
        step(opt)  # employed
        step(opt)  # onlooker, then the scout decision
        assert opt.phase == "onlooker"
        m = int(np.argmax(opt.trial))
        if opt.trial[m] >= limit:
            assert opt.scout == m  # one scout per cycle: the most-tried source
            s, new, old = m, opt.scout_x.copy(), opt.x[m].copy()
            others = np.arange(5) != s
            trial_others = opt.trial[others].copy()
            V = opt.ask()
            np.testing.assert_array_equal(V[s], new)  # the scout's random source is evaluated
            assert np.all(V[s] != old)
            opt.tell(V, problem.evaluate(V))
            # accepted although not better (equal cost), trials reset; the others failed once
            np.testing.assert_array_equal(opt.x[s], new)
            assert opt.trial[s] == 0 and opt.scout is None
            np.testing.assert_array_equal(opt.trial[others], trial_others + 1)
            step(opt)  # onlooker
            scouts += 1
        else:
            assert opt.scout is None
    assert scouts >= 10
    # with a limit never reached nothing is abandoned
    opt = ABC(problem, seed=6, pop_size=10, limit=10**6)
    for _ in range(41):
        step(opt)
        assert opt.scout is None


def test_abc_init_population_keeps_best_half() -> None:
    problem = sphere_problem()
    init = np.random.default_rng(8).uniform(-5, 5, size=(12, DIM))
    opt = ABC(problem, seed=0, pop_size=12, init=init)
    X = opt.ask()
    np.testing.assert_array_equal(X, init)
    opt.tell(X, sphere(X))
    best6 = init[np.argsort(sphere(init), kind="stable")[:6]]
    np.testing.assert_array_equal(opt.x, best6)
    assert opt.ask().shape == (6, DIM)


# ---------------------------------------------------------------------- better than random search
@pytest.mark.parametrize("name", ["abc", "gwo", "woa"])
@pytest.mark.parametrize("ref", ["f1:10", "f9:10"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_beats_random_search(name: str, ref: str, seed: int) -> None:
    extra = {"max_iterations": 100} if name in ("gwo", "woa") else {}
    problem = function_problem(ref)
    res = minimize(problem, name, Budget(max_evaluations=3000), seed=seed, pop_size=30, **extra)
    rng = np.random.default_rng(1000 + seed)
    samples = problem.lower + rng.random((res.evaluations, problem.dim)) * (
        problem.upper - problem.lower
    )
    random_best = float(problem.evaluate(samples).min())
    assert res.evaluations == 3000
    assert res.f < 0.5 * random_best, f"{name} on {ref}: {res.f} vs random {random_best}"
