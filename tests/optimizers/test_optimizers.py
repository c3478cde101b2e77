"""Contract tests for every registered optimizer, plus algorithm-specific checks.

The contract tests are parametrized over :func:`uavplan.optimizers.available`, so an optimizer
registered later is covered without editing this file.
"""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest

from uavplan.optimizers import (
    DE,
    GA,
    PSO,
    Budget,
    DEConfig,
    FunctionProblem,
    GAConfig,
    Optimizer,
    OptimizerError,
    PSOConfig,
    available,
    get,
    minimize,
)

DIM = 5
ALGORITHMS = available()


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum(X**2, axis=1)


def sphere_problem(dim: int = DIM, block: int = 1) -> FunctionProblem:
    return FunctionProblem(sphere, -5.0 * np.ones(dim), 5.0 * np.ones(dim), block=block)


def wall_problem() -> FunctionProblem:
    """Optimum outside the box on some axes: pushes populations against the walls."""
    c = np.array([7.0, -9.0, 0.0, 5.0, 100.0])
    return FunctionProblem(
        lambda X: np.sum((X - c) ** 2, axis=1), -5.0 * np.ones(5), 5 * np.ones(5)
    )


def takes_init(cls: type[Optimizer]) -> bool:
    return "init" in inspect.signature(cls.__init__).parameters


def step(opt: Optimizer) -> tuple[np.ndarray, np.ndarray]:
    X = opt.ask()
    f = opt.problem.evaluate(X)
    opt.tell(X, f)
    return X, f


# ---------------------------------------------------------------------- contract, every optimizer
@pytest.mark.parametrize("name", ALGORITHMS)
def test_solves_sphere(name: str) -> None:
    res = minimize(sphere_problem(), name, Budget(max_iterations=1000, max_time=5.0), seed=1)
    assert res.f < 1e-3, f"{name}: f = {res.f}"
    assert res.x.shape == (DIM,)
    assert res.f == pytest.approx(float(sphere(res.x[None])[0]))
    assert np.all(np.diff(res.history) <= 0)  # best-so-far never gets worse


@pytest.mark.parametrize("name", ALGORITHMS)
def test_deterministic_per_seed(name: str) -> None:
    a = minimize(sphere_problem(), name, 30, seed=123)
    b = minimize(sphere_problem(), name, 30, seed=123)
    np.testing.assert_array_equal(a.history, b.history)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.evaluations == b.evaluations


@pytest.mark.parametrize("name", ALGORITHMS)
def test_different_across_seeds(name: str) -> None:
    a = minimize(sphere_problem(), name, 30, seed=1)
    b = minimize(sphere_problem(), name, 30, seed=2)
    assert not np.array_equal(a.x, b.x)
    assert not np.array_equal(a.history, b.history)


@pytest.mark.parametrize("name", ALGORITHMS)
@pytest.mark.parametrize("problem", [sphere_problem(), wall_problem()], ids=["sphere", "wall"])
def test_bounds_respected(name: str, problem: FunctionProblem) -> None:
    opt = get(name)(problem, seed=7)
    for _ in range(30):
        X, _ = step(opt)
        assert X.ndim == 2 and X.shape[1] == problem.dim and X.shape[0] >= 1
        assert np.all(np.isfinite(X))
        assert np.all(problem.lower <= X) and np.all(problem.upper >= X)


@pytest.mark.parametrize("name", ALGORITHMS)
@pytest.mark.parametrize("case", ["shape", "length", "nan"])
def test_malformed_tell_refused(name: str, case: str) -> None:
    opt = get(name)(sphere_problem(), seed=0)
    step(opt)
    X = opt.ask()
    f = sphere(X)
    bad_X, bad_f = X, f.copy()
    if case == "shape":
        bad_X = X[:, :-1]
    elif case == "length":
        bad_f = f[:-1]
    else:
        bad_f[0] = np.nan
    with pytest.raises(OptimizerError):
        opt.tell(bad_X, bad_f)
    opt.tell(X, f)  # a refused tell leaves the ask pending: the correct tell still works
    assert opt.iterations == 2


@pytest.mark.parametrize("name", ALGORITHMS)
def test_tell_without_ask_refused(name: str) -> None:
    opt = get(name)(sphere_problem(), seed=0)
    n = opt.config.pop_size
    with pytest.raises(OptimizerError):
        opt.tell(np.zeros((n, DIM)), np.zeros(n))
    step(opt)
    with pytest.raises(OptimizerError):
        opt.tell(np.zeros((n, DIM)), np.zeros(n))


@pytest.mark.parametrize("name", ALGORITHMS)
def test_ask_twice_refused(name: str) -> None:
    opt = get(name)(sphere_problem(), seed=0)
    opt.ask()
    with pytest.raises(OptimizerError):
        opt.ask()


@pytest.mark.parametrize("name", ALGORITHMS)
def test_all_infinite_costs(name: str) -> None:
    problem = FunctionProblem(lambda X: np.full(X.shape[0], np.inf), -np.ones(4), np.ones(4))
    opt = get(name)(problem, seed=3)
    for _ in range(20):
        X, _ = step(opt)
        assert np.all(np.isfinite(X))
        assert np.all(problem.lower <= X) and np.all(problem.upper >= X)
    res = minimize(problem, name, 20, seed=3)
    assert res.f == np.inf
    assert res.x.shape == (4,)
    assert np.all(np.isinf(res.history))


@pytest.mark.parametrize("name", ALGORITHMS)
def test_unknown_override_refused(name: str) -> None:
    with pytest.raises(OptimizerError):
        get(name)(sphere_problem(), no_such_parameter=1)
    with pytest.raises(OptimizerError):
        minimize(sphere_problem(), name, 3, seed=0, no_such_parameter=1)


@pytest.mark.parametrize("name", ALGORITHMS)
def test_init_population_used(name: str) -> None:
    cls = get(name)
    if not takes_init(cls):
        pytest.skip(f"{name} takes no init population")
    problem = sphere_problem()
    n = cls.Config().pop_size
    init = np.random.default_rng(99).uniform(-5.0, 5.0, size=(n, DIM))
    opt = cls(problem, seed=0, init=init)
    np.testing.assert_array_equal(opt.ask(), init)
    # minimize passes it through as well
    res = minimize(problem, name, 1, seed=0, init=init)
    assert res.f == pytest.approx(sphere(init).min())
    with pytest.raises(OptimizerError):
        cls(problem, seed=0, init=init[:-1])
    with pytest.raises(OptimizerError):
        cls(problem, seed=0, init=init[:, :-1])


@pytest.mark.parametrize("name", ALGORITHMS)
def test_config_defaults_and_records(name: str) -> None:
    res = minimize(sphere_problem(), name, 2, seed=0)
    assert res.algorithm == name
    expected = dataclasses.asdict(get(name).Config())  # the defaults are recorded ...
    if "max_iterations" in expected:  # ... but an a-schedule spans the budget
        expected["max_iterations"] = 2
    assert res.config == expected


@pytest.mark.parametrize("name", ALGORITHMS)
def test_every_hyperparameter_is_documented_and_checked(name: str) -> None:
    """Each field of an optimizer's config has a line of documentation (what ``uavplan
    planners NAME`` prints), its default passes its own declaration, and a value out of a
    declared range or choices is refused naming the field."""
    from uavplan.params import describe_options

    cfg_cls = get(name).Config
    for o in describe_options(cfg_cls):
        assert o["doc"], f"{name}.{o['name']} has no documentation"
    cfg_cls()  # the defaults are valid
    for f in dataclasses.fields(cfg_cls):
        m = f.metadata
        if m.get("choices") is not None:
            bad: object = "no-such-choice"
        elif m.get("low") is not None:
            bad = m["low"] - 1
        else:
            continue
        with pytest.raises(OptimizerError, match=f"^{f.name} must be"):
            cfg_cls(**{f.name: bad})


# ---------------------------------------------------------------------- PSO
def test_pso_defaults() -> None:
    cfg = PSOConfig()
    assert (cfg.pop_size, cfg.w, cfg.w_damp, cfg.c1, cfg.c2, cfg.velocity_fraction) == (
        100,
        1.0,
        0.98,
        1.5,
        1.5,
        0.5,
    )
    assert get("pso") is PSO


@pytest.mark.parametrize(("w", "w_damp"), [(1.0, 0.98), (0.7, 0.9)])
def test_pso_inertia_damping(w: float, w_damp: float) -> None:
    opt = PSO(sphere_problem(), seed=0, w=w, w_damp=w_damp)
    step(opt)  # the initial swarm: evaluated, not moved
    assert opt.w == w
    for k in range(1, 21):
        step(opt)  # one move with the current w, then w *= w_damp
        assert opt.w == pytest.approx(w * w_damp**k, rel=1e-12)


def test_pso_velocity_clamped() -> None:
    problem = wall_problem()
    opt = PSO(problem, seed=4, velocity_fraction=0.1)
    v_max = 0.1 * (problem.upper - problem.lower)
    X_prev, _ = step(opt)
    assert np.all(opt.v == 0)  # velocities start at zero
    for _ in range(30):
        X, _ = step(opt)
        assert np.all(np.abs(opt.v) <= v_max + 1e-12)
        assert np.all(np.abs(X - X_prev) <= v_max + 1e-12)
        X_prev = X


def test_pso_mirrors_velocity_at_walls() -> None:
    problem = wall_problem()  # optimum at +100 on the last axis: particles hit the upper wall
    opt = PSO(problem, seed=5)
    step(opt)
    hit = False
    for _ in range(10):
        x_before = opt.x.copy()
        X = opt.ask()
        # genes stopped at the upper wall that a move of length |v| would have carried past it
        out = (problem.upper == X) & (x_before + np.abs(opt.v) > problem.upper)
        if np.any(out):
            hit = True
            # the velocity that carried the gene out of the box now points back inside
            assert np.all(opt.v[out] < 0)
        opt.tell(X, problem.evaluate(X))
    assert hit


def test_pso_strict_improvement_keeps_pbest_on_ties() -> None:
    problem = FunctionProblem(lambda X: np.zeros(X.shape[0]), -np.ones(3), np.ones(3))
    opt = PSO(problem, seed=0)
    X0, _ = step(opt)
    for _ in range(5):
        step(opt)
    np.testing.assert_array_equal(opt.pbest_x, X0)
    np.testing.assert_array_equal(opt.gbest_x, X0[0])


# ---------------------------------------------------------------------- DE
def test_de_defaults() -> None:
    cfg = DEConfig()
    assert (cfg.pop_size, cfg.F, cfg.CR) == (100, 0.8, 0.9)
    assert get("de") is DE
    with pytest.raises(OptimizerError):
        DEConfig(pop_size=3)


@pytest.mark.parametrize("CR", [0.0, 0.5, 0.9])
def test_de_trial_differs_from_target(CR: float) -> None:
    opt = DE(sphere_problem(), seed=2, CR=CR)
    step(opt)
    for _ in range(5):
        target = opt.x.copy()
        U = opt.ask()
        differs = target != U
        assert np.all(differs.any(axis=1))  # at least one gene per row (j_rand)
        assert np.all(differs[np.arange(len(U)), opt.j_rand])
        if CR == 0.0:
            assert np.all(differs.sum(axis=1) == 1)  # exactly j_rand
        opt.tell(U, sphere(U))


def test_de_donors_distinct() -> None:
    opt = DE(sphere_problem(), seed=8, pop_size=6)
    step(opt)
    for _ in range(50):
        U = opt.ask()
        r = opt.r
        i = np.arange(6)
        assert np.all(r[:, 0] != r[:, 1]) and np.all(r[:, 0] != r[:, 2])
        assert np.all(r[:, 1] != r[:, 2])
        assert np.all(r != i[:, None])
        opt.tell(U, sphere(U))


def test_de_greedy_selection() -> None:
    opt = DE(sphere_problem(), seed=3)
    step(opt)
    for _ in range(10):
        x_old, f_old = opt.x.copy(), opt.fx.copy()
        U = opt.ask()
        fU = sphere(U)
        opt.tell(U, fU)
        won = fU <= f_old
        np.testing.assert_array_equal(opt.x[won], U[won])
        np.testing.assert_array_equal(opt.x[~won], x_old[~won])
        np.testing.assert_array_equal(opt.fx, np.minimum(fU, f_old))


# ---------------------------------------------------------------------- GA
def test_ga_defaults() -> None:
    cfg = GAConfig()
    assert (cfg.pop_size, cfg.elite, cfg.tournament_size, cfg.crossover_rate) == (100, 2, 2, 0.9)
    assert cfg.mutation_rate is None and cfg.mutation_scale == 0.1
    assert get("ga") is GA
    assert GA(sphere_problem()).p_m == pytest.approx(1 / DIM)
    with pytest.raises(OptimizerError):
        GAConfig(elite=100)


def test_ga_keeps_elite() -> None:
    opt = GA(wall_problem(), seed=6, elite=3)
    step(opt)
    for _ in range(20):
        elite_x, elite_f = opt.elite_x.copy(), opt.elite_f.copy()
        best_before = opt.best_f
        X, _ = step(opt)
        assert X.shape[0] == opt.config.pop_size - 3  # only the offspring are evaluated
        assert opt.population.shape[0] == opt.config.pop_size
        np.testing.assert_array_equal(opt.population[:3], elite_x)  # elite carried over
        np.testing.assert_array_equal(opt.fitness[:3], elite_f)
        assert opt.best_f <= best_before
        assert opt.fitness.min() == opt.best_f  # the best-so-far is in the population
        assert opt.elite_f[0] == opt.best_f


def test_ga_crossover_cuts_between_waypoints() -> None:
    block = 3
    problem = sphere_problem(dim=4 * block, block=block)
    opt = GA(problem, seed=11, crossover_rate=1.0, mutation_rate=0.0)
    step(opt)
    P = opt.population.reshape(len(opt.population), 4, block)
    children = opt.ask().reshape(-1, 4, block)
    mixed = False
    for child in children:
        # every waypoint of a child is the same waypoint of some parent: no cut inside a block
        sources = [
            np.flatnonzero(np.all(P[:, w] == child[w], axis=1)) for w in range(child.shape[0])
        ]
        assert all(len(s) > 0 for s in sources)
        mixed |= len(set.intersection(*(set(s) for s in sources))) == 0
    assert mixed  # some children really are recombined


def test_ga_mutation_off_and_no_crossover_copies_parents() -> None:
    opt = GA(sphere_problem(), seed=12, crossover_rate=0.0, mutation_rate=0.0)
    step(opt)
    P = opt.population
    children = opt.ask()
    for child in children:
        assert np.any(np.all(child == P, axis=1))


def test_schedule_follows_the_budget() -> None:
    """GWO/WOA/RSCDWOA's a-schedule spans the budget unless set explicitly."""
    from uavplan.optimizers.base import Budget, fit_schedule
    from uavplan.optimizers.gwo import GWOConfig
    from uavplan.optimizers.pso import PSOConfig

    assert fit_schedule(GWOConfig(), 250).max_iterations == 250  # type: ignore[attr-defined]
    assert fit_schedule(GWOConfig(max_iterations=7), 250).max_iterations == 7  # type: ignore[attr-defined]
    assert fit_schedule(GWOConfig(), 250, {"max_iterations": 100}).max_iterations == 100  # type: ignore[attr-defined]
    assert fit_schedule(GWOConfig(), Budget(max_evaluations=500)) == GWOConfig()
    assert fit_schedule(PSOConfig(), 250) == PSOConfig()


def test_fused_pso_move_matches_its_numpy_reference() -> None:
    from uavplan.optimizers.pso import move, move_reference

    rng = np.random.default_rng(5)
    n, d = 30, 7
    lower, upper = np.full(d, -1.0), np.linspace(1.0, 3.0, d)
    x = rng.uniform(lower, upper, (n, d))
    v = rng.normal(0.0, 2.0, (n, d))
    pbest, gbest = rng.uniform(lower, upper, (n, d)), rng.uniform(lower, upper)
    r1, r2 = rng.random((n, d)), rng.random((n, d))
    v_max = 0.5 * (upper - lower)
    args = (x, v, pbest, gbest, r1, r2, 0.9, 1.5, 1.5, v_max, lower, upper)
    got_x, got_v = move(*args)
    want_x, want_v = move_reference(*args)
    np.testing.assert_allclose(got_x, want_x, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(got_v, want_v, rtol=1e-14, atol=1e-14)
    assert np.any(got_x == upper) and np.any(got_v == -v_max)  # clamp and walls exercised


@pytest.mark.parametrize("n", [4, 5, 17, 300])
def test_distinct_indices_fast_draws_and_returns_the_same(n: int) -> None:
    from uavplan.optimizers.de import distinct_indices, distinct_indices_fast

    for seed in range(5):
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        want, got = distinct_indices(a, n, 3), distinct_indices_fast(b, n, 3)
        np.testing.assert_array_equal(got, want)
        assert a.random() == b.random()  # the same numbers drawn
        rows = np.arange(n)[:, None]
        assert np.all(got != rows) and np.all(got[:, 0] != got[:, 1])
        assert np.all(got[:, 1] != got[:, 2]) and np.all(got[:, 0] != got[:, 2])


def test_de_trial_kernel_matches_its_numpy_reference() -> None:
    from uavplan.optimizers.de import distinct_indices, trial, trial_reference

    rng = np.random.default_rng(2)
    NP, D = 40, 9
    lower, upper = np.full(D, -1.0), np.linspace(0.5, 3.0, D)
    x = rng.uniform(lower, upper, (NP, D))
    r = distinct_indices(rng, NP, 3)
    u, c = rng.random((NP, D)), rng.random((NP, D))
    j_rand = rng.integers(D, size=NP)
    for F in (0.8, 2.5):  # 2.5: many mutants outside the box, bounced back
        args = (x, r, F, u, c, 0.7, j_rand, lower, upper)
        got, want = trial(*args), trial_reference(*args)
        np.testing.assert_array_equal(got, want)
    assert np.any(got == x) and np.any(got != x)


def test_ga_offspring_kernel_matches_its_numpy_reference() -> None:
    from uavplan.optimizers.ga import offspring, offspring_reference

    rng = np.random.default_rng(4)
    N, D, n_off = 30, 12, 27
    n_pairs = (n_off + 1) // 2
    lower, upper = np.zeros(D), np.full(D, 10.0)
    P = rng.uniform(lower, upper, (N, D))
    f = rng.choice([1.0, 2.0, 3.0, np.inf], N)  # ties: the first of equals wins
    entrants = rng.integers(N, size=(2 * n_pairs, 3))
    cut = np.where(rng.random(n_pairs) < 0.8, rng.integers(1, 4, n_pairs), 4)
    block = np.arange(D) // 3
    mutate = rng.random((n_off, D)) < 0.3
    z = rng.standard_normal((n_off, D)) * 20.0  # some leave the box
    sigma = np.full(D, 1.0)
    args = (P, f, entrants, cut, block, n_off, mutate, z, sigma, lower, upper)
    np.testing.assert_array_equal(offspring(*args), offspring_reference(*args))


def test_pso_best_update_kernel_matches_numpy() -> None:
    from uavplan.optimizers.pso import update_bests

    rng = np.random.default_rng(8)
    X = rng.random((50, 4))
    f = rng.choice([0.5, 1.0, np.inf], 50)
    pbest_x, pbest_f = rng.random((50, 4)), rng.choice([0.5, 1.0, 2.0, np.inf], 50)
    want_x, want_f = pbest_x.copy(), pbest_f.copy()
    better = f < want_f
    want_x[better], want_f[better] = X[better], f[better]
    i = update_bests(X, f, pbest_x, pbest_f)
    np.testing.assert_array_equal(pbest_x, want_x)
    np.testing.assert_array_equal(pbest_f, want_f)
    assert i == np.argmin(want_f)
