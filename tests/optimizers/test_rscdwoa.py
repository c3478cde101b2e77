"""RSCDWOA (Zhang et al.): chaotic maps, reverse points, ring neighbourhood, lifespan, greedy
selection, evaluation counts, and a sanity comparison with random search.

The contract tests of every registered optimizer (``test_optimizers.py``) cover RSCDWOA as well.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from uavplan.optimizers import Budget, FunctionProblem, OptimizerError, get, minimize
from uavplan.optimizers.rscdwoa import (
    CHAOS_EPS,
    RSCDWOA,
    RSCDWOAConfig,
    chaos_seed,
    chaos_step,
    coefficient_a,
    logistic_map,
    reflection_reverse_point,
    ring_neighbourhood,
    ring_pairs,
    tent_map,
    two_others,
)

Fn = Callable[[np.ndarray], np.ndarray]


def sphere(X: np.ndarray) -> np.ndarray:
    """f1 of Table 4."""
    return np.sum(X**2, axis=1)


def rastrigin(X: np.ndarray) -> np.ndarray:
    """f7 of Table 4: sum x^2 - 10 cos(2 pi x) + 10; minimum 0 at the origin."""
    return np.sum(X**2 - 10.0 * np.cos(2.0 * np.pi * X) + 10.0, axis=1)


def shifted(f: Fn, c: np.ndarray) -> Fn:
    return lambda X: f(X - c)


def box(f: Fn, dim: int, half_width: float) -> FunctionProblem:
    return FunctionProblem(f, -half_width * np.ones(dim), half_width * np.ones(dim))


def step(opt: RSCDWOA) -> tuple[np.ndarray, np.ndarray]:
    X = opt.ask()
    f = opt.problem.evaluate(X)
    opt.tell(X, f)
    return X, f


def generation(opt: RSCDWOA) -> list[int]:
    """Run one whole generation (move batch and, if any, reverse batch); the batch sizes."""
    assert opt.phase == "move"
    t = opt.t
    sizes = []
    while opt.t == t:
        X, _ = step(opt)
        sizes.append(X.shape[0])
    return sizes


# ---------------------------------------------------------------------- configuration
def test_defaults_and_registry() -> None:
    cfg = RSCDWOAConfig()
    assert (cfg.pop_size, cfg.max_iterations, cfg.chaos, cfg.beta, cfg.mu, cfg.b) == (
        30,
        100,
        "tent",
        0.74,
        4.0,
        1.0,
    )
    assert (cfg.S, cfg.k, cfg.lam, cfg.F, cfg.omega, cfg.C_rate, cfg.alpha) == (
        10,
        None,
        1e-4,
        0.8,
        0.5,
        0.1,
        0.01,
    )
    assert cfg.ring_radius() == 3  # 10 % of 30 whales
    assert RSCDWOAConfig(pop_size=5).ring_radius() == 1
    assert RSCDWOAConfig(pop_size=100).ring_radius() == 10
    assert RSCDWOAConfig(pop_size=30, k=7).ring_radius() == 7
    assert get("rscdwoa") is RSCDWOA


@pytest.mark.parametrize(
    "bad",
    [
        {"pop_size": 2},
        {"max_iterations": 0},
        {"chaos": "sine"},
        {"beta": 1.0},
        {"beta": 0.0},
        {"mu": 4.5},
        {"S": -1},
        {"k": 15},  # > (30 - 1) / 2
        {"k": 0},
        {"lam": -1.0},
        {"F": 0.0},
        {"omega": 1.5},
        {"C_rate": -0.1},
        {"alpha": 2.0},
    ],
)
def test_bad_config_refused(bad: dict[str, object]) -> None:
    with pytest.raises(OptimizerError):
        RSCDWOAConfig(**bad)  # type: ignore[arg-type]


# ---------------------------------------------------------------------- chaotic maps
def test_maps_by_hand() -> None:
    assert tent_map(np.array([0.37]), 0.74)[0] == pytest.approx(0.5)  # 0.37 / 0.74
    assert tent_map(np.array([0.87]), 0.74)[0] == pytest.approx(0.5)  # 0.13 / 0.26
    assert logistic_map(np.array([0.25]), 4.0)[0] == pytest.approx(0.75)
    assert logistic_map(np.array([0.5]), 4.0)[0] == 1.0  # then 0 forever: must be guarded


@pytest.mark.parametrize("kind", ["tent", "logistic"])
def test_chaotic_sequences_do_not_collapse(kind: str) -> None:
    """10^5 steps of 16 orbits: always in (0, 1), never stuck, never repeating, and the guard
    never had to fire (the guarded orbit equals the bare map's)."""
    rng = np.random.default_rng(2024)
    w = chaos_seed(rng, 16)
    bare = w.copy()
    steps = 100_000
    traj = np.empty((steps, 16))
    for k in range(steps):
        w = chaos_step(w, kind, 0.74, 4.0, rng)  # type: ignore[arg-type]
        bare = tent_map(bare, 0.74) if kind == "tent" else logistic_map(bare, 4.0)
        traj[k] = w
    np.testing.assert_array_equal(w, bare)
    assert np.all((traj > 0.0) & (traj < 1.0))
    assert np.all(np.diff(traj, axis=0) != 0.0)  # no step is a fixed point
    for j in range(16):  # no short cycle either
        assert np.unique(traj[:, j]).size == steps
    hist = np.histogram(traj, bins=10, range=(0.0, 1.0))[0] / traj.size
    if kind == "tent":  # uniform invariant density
        np.testing.assert_allclose(hist, 0.1, atol=0.005)
    else:  # arcsine density 1 / (pi sqrt(w (1 - w))): heavy at both ends
        assert hist[0] == pytest.approx(hist[-1], abs=0.01)
        assert hist[0] > 2 * hist[5]


def test_guard_reseeds_degenerate_orbits() -> None:
    rng = np.random.default_rng(0)
    # the bare tent map with beta = 1/2 collapses to exactly 0 in floating point ...
    bare = chaos_seed(rng, 8)
    for _ in range(100):
        bare = tent_map(bare, 0.5)
    assert np.all(bare == 0.0)
    # ... the guarded one does not
    w = chaos_seed(rng, 8)
    for _ in range(1000):
        w = chaos_step(w, "tent", 0.5, 4.0, rng)
        assert np.all((w > CHAOS_EPS) & (w < 1.0 - CHAOS_EPS))
    # points that map to 1 (then 0), and the interior fixed points, are re-seeded
    beta = 0.74
    cases = [
        ("tent", np.array([beta, 1.0 / (2.0 - beta), 0.0, 1.0])),
        ("logistic", np.array([0.5, 0.75, 0.0, 1.0])),
    ]
    for kind, start in cases:
        nxt = chaos_step(start, kind, beta, 4.0, rng)  # type: ignore[arg-type]
        assert np.all((nxt > CHAOS_EPS) & (nxt < 1.0 - CHAOS_EPS))
        assert not np.any(np.isclose(nxt, 1.0 / (2.0 - beta), atol=1e-9))
        assert not np.any(np.isclose(nxt, 0.75, atol=1e-9))


def test_chaotic_coefficients_in_optimizer() -> None:
    opt = RSCDWOA(box(sphere, 5, 5.0), seed=3, S=10**6)
    step(opt)
    w_prev = opt.w.copy()
    assert np.all((w_prev > 0) & (w_prev < 1))
    for _ in range(5):
        step(opt)
        np.testing.assert_array_equal(opt.w, tent_map(w_prev, 0.74))  # one step per generation
        a = opt.a
        np.testing.assert_allclose(opt.A, 2 * a * opt.w[0] - a)  # Eq. 11
        np.testing.assert_allclose(opt.C, 2 * opt.w[1])  # Eq. 12
        np.testing.assert_array_equal(opt.l, opt.w[2])  # Eq. 15
        w_prev = opt.w.copy()


# ---------------------------------------------------------------------- a, moves
def test_coefficient_a() -> None:
    assert coefficient_a(0, 100) == 2.0
    assert coefficient_a(50, 100) == 1.0
    assert coefficient_a(100, 100) == 0.0
    assert coefficient_a(150, 100) == 0.0  # clamped beyond t_max


def test_a_follows_generations_not_batches() -> None:
    opt = RSCDWOA(box(sphere, 5, 5.0), seed=1, S=0, max_iterations=8)
    step(opt)
    for t in range(12):
        generation(opt)  # one or two batches
        assert opt.t == t + 1
        assert opt.a == coefficient_a(t, 8)
    assert opt.iterations > 13  # the reverse batches made more iterations than generations


def test_woa_moves_follow_the_equations() -> None:
    problem = box(sphere, 4, 100.0)  # wide box: nothing is clipped in the first moves
    opt = RSCDWOA(problem, seed=5, S=10**6)
    step(opt)
    for _ in range(3):
        x, x_star = opt.x.copy(), opt.x_star.copy()
        X = opt.ask()
        A, C, l, q = opt.A, opt.C, opt.l, opt.q
        exploit = (q < 0.5) & (np.abs(A) < 1)
        spiral = q >= 0.5
        D = np.abs(C[:, None] * x_star - x)
        expected = np.clip(x_star - A[:, None] * D, problem.lower, problem.upper)  # Eq. 3
        np.testing.assert_allclose(X[exploit], expected[exploit])
        Dp = np.abs(x_star - x)
        spiral_move = Dp * (np.exp(l) * np.cos(2 * np.pi * l))[:, None] + x_star  # Eq. 15
        expected = np.clip(spiral_move, problem.lower, problem.upper)
        np.testing.assert_allclose(X[spiral], expected[spiral])
        opt.tell(X, problem.evaluate(X))
        np.testing.assert_array_equal(opt.x, X)  # WOA moves replace unconditionally


# ---------------------------------------------------------------------- reverse search
def test_reflection_reverse_point_by_hand() -> None:
    X = np.array([[2.0, 9.0]])
    lo, hi = np.zeros(2), np.full(2, 10.0)  # centre h = 5
    np.testing.assert_allclose(
        reflection_reverse_point(X, lo, hi, np.array([[0.5, 0.25]])), [[3.5, 8.0]]
    )
    np.testing.assert_allclose(reflection_reverse_point(X, lo, hi, np.zeros((1, 2))), X)
    np.testing.assert_allclose(reflection_reverse_point(X, lo, hi, np.ones((1, 2))), [[5.0, 5.0]])
    # asymmetric box [-4, 2]: h = -1; x = 1, u = 0.5 -> 0
    out = reflection_reverse_point(
        np.array([[1.0]]), np.array([-4.0]), np.array([2.0]), np.full((1, 1), 0.5)
    )
    np.testing.assert_allclose(out, [[0.0]])


def test_reverse_batch_between_whale_and_centre() -> None:
    problem = FunctionProblem(rastrigin, np.array([-5.0, -1.0, 0.0]), np.array([5.0, 3.0, 10.0]))
    h = 0.5 * (problem.lower + problem.upper)
    opt = RSCDWOA(problem, seed=4, S=0)
    step(opt)
    seen = 0
    for _ in range(20):
        step(opt)  # move batch
        if opt.phase == "reverse":
            x = opt.x[opt.de_rows].copy()
            R = opt.ask()
            assert R.shape == x.shape
            lo, hi = np.minimum(x, h), np.maximum(x, h)
            assert np.all(lo <= R) and np.all(hi >= R)
            opt.tell(R, problem.evaluate(R))
            seen += 1
    assert seen > 10


# ---------------------------------------------------------------------- DE neighbourhoods
def test_ring_neighbourhood_indices() -> None:
    np.testing.assert_array_equal(
        ring_neighbourhood(5, 1),
        [[4, 0, 1], [0, 1, 2], [1, 2, 3], [2, 3, 4], [3, 4, 0]],
    )
    full = ring_neighbourhood(7, 3)
    assert full.shape == (7, 7)
    for i, row in enumerate(full):
        assert sorted(row) == list(range(7))
        assert row[3] == i
    with pytest.raises(OptimizerError):
        ring_neighbourhood(6, 3)  # k > (n - 1) / 2


def test_ring_pairs_and_population_pairs() -> None:
    rng = np.random.default_rng(7)
    n, k = 10, 2
    rows = np.repeat(np.arange(n), 400)
    p1, p2 = ring_pairs(rng, rows, n, k)
    assert np.all(p1 != p2) and np.all(p1 != rows) and np.all(p2 != rows)
    for i in range(n):
        ring = {(i + o) % n for o in (-2, -1, 1, 2)}
        sel = rows == i
        assert set(p1[sel]) == ring and set(p2[sel]) == ring  # all four, nothing else
    r1, r2 = two_others(rng, rows, n)
    assert np.all(r1 != r2) and np.all(r1 != rows) and np.all(r2 != rows)
    for i in range(n):
        sel = rows == i
        assert set(r1[sel]) | set(r2[sel]) == set(range(n)) - {i}
    # k = 1 on the smallest population: the two neighbours, in either order
    p1, p2 = ring_pairs(rng, np.zeros(50, dtype=np.int64), 3, 1)
    assert set(zip(p1.tolist(), p2.tolist(), strict=True)) == {(1, 2), (2, 1)}


# ---------------------------------------------------------------------- lifespan
def test_lifespan_counts_non_improving_generations() -> None:
    flat = FunctionProblem(lambda X: np.zeros(X.shape[0]), -np.ones(4), np.ones(4))
    S = 3
    opt = RSCDWOA(flat, seed=2, S=S, pop_size=10)
    step(opt)
    for g in range(8):
        assert opt.s == g  # X_* never improves on a flat function: one more per generation
        sizes = generation(opt)
        if g < S:  # lifespan not spent: WOA only, one batch
            assert opt.de_rows.size == 0 and sizes == [10]
        else:  # DE on the encircling branch (q < 0.5), then their reverse points
            np.testing.assert_array_equal(opt.de_rows, np.flatnonzero(opt.q < 0.5))
            m = opt.de_rows.size
            assert sizes == ([10, m] if m else [10])


def test_lifespan_not_spent_while_improving() -> None:
    opt = RSCDWOA(box(sphere, 5, 5.0), seed=8)
    step(opt)
    for _ in range(60):
        s, f_before = opt.s, opt.f_star
        generation(opt)
        assert opt.s == (s if opt.f_star < f_before else s + 1)
        if s < opt.config.S:
            assert opt.de_rows.size == 0


@pytest.mark.parametrize(("S", "expect_de"), [(0, True), (10**6, False)])
def test_lifespan_extremes(S: int, expect_de: bool) -> None:
    opt = RSCDWOA(box(rastrigin, 5, 5.12), seed=3, S=S)
    step(opt)
    any_de = False
    for _ in range(30):
        sizes = generation(opt)
        any_de |= len(sizes) == 2
        assert sizes[0] == opt.config.pop_size
    assert any_de == expect_de


# ---------------------------------------------------------------------- selection
def test_greedy_selection_never_worsens() -> None:
    problem = box(shifted(rastrigin, np.full(6, 1.3)), 6, 5.12)
    opt = RSCDWOA(problem, seed=11, S=0)
    step(opt)
    checked = 0
    for _ in range(40):
        x0, f0 = opt.x.copy(), opt.fx.copy()
        W = opt.ask()
        fW = problem.evaluate(W)
        opt.tell(W, fW)
        de = opt.de_rows
        woa = np.setdiff1d(np.arange(opt.config.pop_size), de)
        np.testing.assert_array_equal(opt.fx[de], np.minimum(f0[de], fW[de]))  # Eq. 23
        won = fW[de] <= f0[de]
        np.testing.assert_array_equal(opt.x[de[won]], W[de[won]])
        np.testing.assert_array_equal(opt.x[de[~won]], x0[de[~won]])
        np.testing.assert_array_equal(opt.x[woa], W[woa])
        if opt.phase == "reverse":
            x1, f1 = opt.x.copy(), opt.fx.copy()
            R = opt.ask()
            fR = problem.evaluate(R)
            opt.tell(R, fR)
            better = fR < f1[de]  # strict (Sect. 3.2)
            np.testing.assert_array_equal(opt.fx[de], np.where(better, fR, f1[de]))
            np.testing.assert_array_equal(opt.x[de[~better]], x1[de[~better]])
            assert np.all(opt.fx[de] <= f0[de])
            checked += de.size
        assert opt.f_star == pytest.approx(min(opt.fx.min(), opt.f_star))
    assert checked > 100


def test_best_so_far_is_the_base_best() -> None:
    res_opt = RSCDWOA(box(rastrigin, 5, 5.12), seed=6, S=2)
    for _ in range(60):
        step(res_opt)
        assert res_opt.f_star == res_opt.best_f
        np.testing.assert_array_equal(res_opt.x_star, res_opt.best_x)


# ---------------------------------------------------------------------- evaluations
def test_evaluation_counts_exact() -> None:
    counted = {"rows": 0, "calls": 0}

    def f(X: np.ndarray) -> np.ndarray:
        counted["rows"] += X.shape[0]
        counted["calls"] += 1
        return rastrigin(X)

    n = 20
    problem = box(f, 6, 5.12)
    opt = RSCDWOA(problem, seed=9, S=2, pop_size=n)
    step(opt)
    expected, generations = n, 0
    for _ in range(40):
        sizes = generation(opt)
        generations += 1
        assert sizes[0] == n
        assert sizes[1:] == ([opt.de_rows.size] if opt.de_rows.size else [])
        expected += sum(sizes)
    m_total = expected - n * (generations + 1)
    assert m_total > 0  # reverse batches did happen
    assert opt.evaluations == expected == counted["rows"]
    assert opt.iterations == counted["calls"]
    # and through minimize: the reported count is the number of rows evaluated
    counted["rows"] = counted["calls"] = 0
    res = minimize(problem, "rscdwoa", Budget(max_evaluations=1000), seed=9, S=2, pop_size=n)
    assert res.evaluations == counted["rows"] >= 1000
    assert res.evaluations - 1000 < n  # stopped at the first batch past the limit
    np.testing.assert_array_equal(np.diff(res.evaluations_history, prepend=0) > 0, True)
    assert res.evaluations_history[-1] == res.evaluations


# ---------------------------------------------------------------------- performance sanity
C10 = np.linspace(-2.5, 3.1, 10)


@pytest.mark.parametrize(
    ("name", "f", "half_width"),
    [
        ("sphere", sphere, 100.0),
        ("shifted-sphere", shifted(sphere, C10), 5.12),
        ("rastrigin", rastrigin, 5.12),
        ("shifted-rastrigin", shifted(rastrigin, C10), 5.12),
    ],
    ids=["sphere", "shifted-sphere", "rastrigin", "shifted-rastrigin"],
)
def test_beats_random_search(name: str, f: Fn, half_width: float) -> None:
    """Small budget (2000 evaluations, 10-D, t_max fitted to it): the median over 10 seeds is
    well below that of uniform random search with the same number of evaluations."""
    dim, budget = 10, 2000
    problem = box(f, dim, half_width)
    ours, rand = [], []
    for seed in range(10):
        res = minimize(
            problem, "rscdwoa", Budget(max_evaluations=budget), seed=seed, max_iterations=60
        )
        ours.append(res.f)
        X = np.random.default_rng(1000 + seed).uniform(-half_width, half_width, (budget, dim))
        rand.append(f(X).min())
    assert np.median(ours) < 0.5 * np.median(rand), (name, np.median(ours), np.median(rand))


@pytest.mark.parametrize("chaos", ["tent", "logistic"])
def test_both_maps_solve_sphere(chaos: str) -> None:
    res = minimize(box(sphere, 5, 5.0), "rscdwoa", 300, seed=1, chaos=chaos)
    assert res.f < 1e-6


def test_the_variants_draw_l_in_their_range_and_uniform_draws_are_not_chaotic() -> None:
    """``l_range="symmetric"`` puts the spiral's l in (-1, 1) (Sect. 2.2's WOA), the default
    in (0, 1) (Eq. 15); ``chaos="uniform"`` draws afresh each generation (no map orbit)."""
    from uavplan.optimizers.rscdwoa import chaos_step

    seen = {}
    for rng_l in ("unit", "symmetric"):
        opt = RSCDWOA(box(sphere, 5, 5.0), seed=3, S=10**6, pop_size=30, l_range=rng_l)
        step(opt)
        ls = []
        for _ in range(10):
            step(opt)
            ls.append(np.asarray(opt.l).copy())
        seen[rng_l] = np.concatenate(ls)
    assert seen["unit"].min() > 0 and seen["unit"].max() < 1
    assert seen["symmetric"].min() < -0.5 and seen["symmetric"].max() > 0.5
    rng = np.random.default_rng(0)
    w = np.full((3, 4), 0.3)
    w1 = chaos_step(w, "uniform", 0.74, 4.0, rng)
    assert w1.shape == w.shape and np.all((w1 > 0) & (w1 < 1)) and len(np.unique(w1)) == 12
    assert not np.allclose(w1, chaos_step(w, "tent", 0.74, 4.0, rng))
