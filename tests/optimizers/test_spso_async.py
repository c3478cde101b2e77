"""SPSO's asynchronous global-best update (``update="async"``, the order of the authors'
``SPSO_MAIN.m``): the batched form gives exactly what moving and evaluating one particle at a
time gives, with the same random numbers."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.optimizers import Budget, minimize
from uavplan.optimizers.base import FunctionProblem, OptimizerError
from uavplan.optimizers.pso import move
from uavplan.optimizers.spso import SPSO, SPSOConfig


def sequential(problem, cfg: SPSOConfig, seed: int, iterations: int):
    """SPSO_MAIN.m's loop, one particle at a time: move it against the current global best,
    evaluate it alone, replace its personal best and then the global best on a strict
    improvement; the random numbers drawn per iteration as the optimizer draws them."""
    rng = np.random.default_rng(seed)
    lo, hi = problem.lower, problem.upper
    n, d = cfg.pop_size, problem.dim
    v_max = cfg.velocity_fraction * (hi - lo)
    evaluations = 0
    for _ in range(cfg.max_init_attempts):  # re-initialized while every cost is infinite
        x = lo + rng.random((n, d)) * (hi - lo)
        f = problem.evaluate(x)
        evaluations += n
        if np.isfinite(f).any():
            break
    v = np.zeros((n, d))
    pbest_x, pbest_f = x.copy(), f.copy()
    g = int(np.argmin(f))
    gbest_x, gbest_f = x[g].copy(), float(f[g])
    w = cfg.w
    while evaluations < iterations * n:
        r1, r2 = rng.random((n, d)), rng.random((n, d))
        for i in range(n):
            xi, vi = move(x[i : i + 1], v[i : i + 1], pbest_x[i : i + 1], gbest_x, r1[i : i + 1],
                          r2[i : i + 1], w, cfg.c1, cfg.c2, v_max, lo, hi)  # fmt: skip
            x[i], v[i] = xi[0], vi[0]
            fi = float(problem.evaluate(x[i : i + 1])[0])
            evaluations += 1
            if fi < pbest_f[i]:
                pbest_x[i], pbest_f[i] = x[i], fi
                if fi < gbest_f:
                    gbest_x, gbest_f = x[i].copy(), fi
        w *= cfg.w_damp
    return gbest_x, gbest_f, pbest_f, x


def plateau(X: np.ndarray) -> np.ndarray:
    """A bowl with an infinite region and a plateau (ties between particles)."""
    f = np.round(np.sum((X - 0.3) ** 2, axis=1), 2)
    return np.where(X[:, 0] > 0.8, np.inf, f)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_async_batches_equal_one_particle_at_a_time(seed: int) -> None:
    problem = FunctionProblem(plateau, np.full(4, -1.0), np.full(4, 1.0))
    cfg = SPSOConfig(pop_size=25, update="async")
    opt = SPSO(problem, cfg, seed=seed)
    res = minimize(problem, SPSO, 30, seed=seed, config=cfg)
    gx, gf, pf, x = sequential(problem, cfg, seed, 30)
    opt = SPSO(problem, cfg, seed=seed)
    for _ in range(30):
        X = opt.ask()
        opt.tell(X, problem.evaluate(X))
    assert res.f == gf == opt.gbest_f
    np.testing.assert_array_equal(res.x, gx)
    np.testing.assert_array_equal(opt.pbest_f, pf)
    np.testing.assert_array_equal(opt.x, x)
    assert opt.evaluations == 30 * 25  # the algorithm's, not the re-evaluations
    assert opt.speculative_evaluations > 0


def test_async_on_the_spso_scenario_equals_the_sequential_loop() -> None:
    from uavplan.problems import PathProblem
    from uavplan.problems.encoding import SphericalEncoding
    from uavplan.scenarios import load_builtin

    enc = SphericalEncoding(PathProblem(load_builtin("spso")))
    cfg = SPSOConfig(pop_size=30, update="async")
    res = minimize(enc, SPSO, 12, seed=4, config=cfg)
    gx, gf, _, _ = sequential(enc, cfg, 4, 12)
    assert np.isfinite(gf) and res.f == gf
    np.testing.assert_array_equal(res.x, gx)


def test_async_keeps_what_it_took_and_differs_from_sync() -> None:
    problem = FunctionProblem(plateau, np.full(4, -1.0), np.full(4, 1.0))
    a = SPSO(problem, SPSOConfig(pop_size=20, update="async"), seed=3)
    for _ in range(6):
        X = a.ask()
        a.tell(X, problem.evaluate(X))
        # the particles as taken, with their costs: what the best and feasibility records see
        np.testing.assert_array_equal(a.last_x, a.x)
        np.testing.assert_array_equal(a.last_f, problem.evaluate(a.last_x))
        assert a.best_f == a.gbest_f == float(np.min(a.pbest_f))
    sync = minimize(problem, "spso", 6, seed=3, pop_size=20)
    assert not np.array_equal(sync.x, a.best_x)


def test_update_must_be_known() -> None:
    with pytest.raises(OptimizerError, match=r"update must be one of \['sync', 'async'\]"):
        SPSOConfig(update="parallel")


def test_async_through_the_planner_counts_and_reports() -> None:
    from uavplan.planners import get_planner
    from uavplan.scenarios import load_builtin

    sc = load_builtin("spso")
    planner = get_planner("spso", pop_size=40, update="async")
    r = planner.plan(sc, budget=Budget(max_iterations=8), seed=1)
    assert r.evaluations == 8 * 40
    assert r.info["speculative_evaluations"] > 0
    assert len(r.feasible_history) == 8
