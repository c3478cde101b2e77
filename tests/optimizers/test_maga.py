"""MAGA / P-MAGA (HR-MAGA Sect. III, Alg. 1): lattice, competition, genetic behaviours,
smoothing, self-learning, evaluation bookkeeping, and a sanity check against random search.

The contract tests of every registered optimizer (``test_optimizers.py``) cover MAGA as well.
"""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.optimizers import Budget, FunctionProblem, OptimizerError, get, minimize
from uavplan.optimizers.maga import (
    MAGA,
    MAGAConfig,
    competition,
    lattice_shape,
    mutate_adjacent,
    single_point_crossover,
    smooth,
    smooth_reference,
    torus_neighbours,
    turn_cosines,
)


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum(X**2, axis=1)


def rastrigin(X: np.ndarray) -> np.ndarray:
    """Rastrigin, 10 n + sum(x^2 - 10 cos(2 pi x)); minimum 0 at the origin, on [-5.12, 5.12]^n."""
    return 10.0 * X.shape[1] + np.sum(X**2 - 10.0 * np.cos(2.0 * np.pi * X), axis=1)


def problem(f=sphere, dim: int = 5, bound: float = 5.0, block: int = 1) -> FunctionProblem:
    return FunctionProblem(f, -bound * np.ones(dim), bound * np.ones(dim), block=block)


class Counting:
    """A problem that counts the rows it evaluates."""

    def __init__(self, inner: FunctionProblem) -> None:
        self.inner = inner
        self.dim, self.lower, self.upper = inner.dim, inner.lower, inner.upper
        self.block = inner.block
        self.rows = 0
        self.calls = 0

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        self.rows += X.shape[0]
        self.calls += 1
        return self.inner.evaluate(X)


def step(opt: MAGA) -> tuple[np.ndarray, np.ndarray]:
    X = opt.ask()
    f = opt.problem.evaluate(X)
    opt.tell(X, f)
    return X, f


def run_generation(opt: MAGA) -> list[int]:
    """Step until one more generation of Alg. 1 has finished; the batch sizes."""
    g = opt.generation
    sizes = []
    while opt.generation == g:
        X, _ = step(opt)
        sizes.append(X.shape[0])
    return sizes


def path_thetas(X: np.ndarray, block: int) -> np.ndarray:
    return turn_cosines(X.reshape(X.shape[0], -1, block))


# ---------------------------------------------------------------------- config
def test_defaults_from_table_1() -> None:
    cfg = MAGAConfig()
    assert (cfg.pop_size, cfg.P_c, cfg.P_m) == (49, 0.5, 0.3)  # Table I: 7 x 7, P_c, P_m
    assert cfg.lattice_shape == (7, 7) and cfg.L_size == 7
    assert (cfg.self_learning, cfg.self_learning_rate, cfg.sL_size) == ("winners", 0.5, 3)
    assert cfg.sGen == 10 and cfg.smooth and cfg.elitism
    assert get("maga") is MAGA


@pytest.mark.parametrize(
    "bad",
    [
        {"pop_size": 1},
        {"P_c": 1.5},
        {"P_m": -0.1},
        {"self_learning_rate": 2.0},
        {"mutation_step": 0.0},
        {"self_learning": "all"},
        {"sL_size": 1},
        {"sGen": -1},
        {"smooth_passes": -1},
    ],
)
def test_bad_config_refused(bad: dict) -> None:
    with pytest.raises(OptimizerError):
        MAGAConfig(**bad)


@pytest.mark.parametrize(
    ("n", "shape"),
    [(49, (7, 7)), (40, (5, 8)), (20, (4, 5)), (12, (3, 4)), (13, (1, 13)), (2, (1, 2))],
)
def test_lattice_shape(n: int, shape: tuple[int, int]) -> None:
    assert lattice_shape(n) == shape
    assert MAGAConfig(pop_size=n).lattice_shape == shape
    assert MAGAConfig(pop_size=n).L_size == (shape[0] if shape[0] == shape[1] else None)


@pytest.mark.parametrize("n", [40, 13, 2])
def test_non_square_pop_sizes_run(n: int) -> None:
    res = minimize(problem(), "maga", Budget(max_evaluations=3000), seed=0, pop_size=n)
    assert np.isfinite(res.f) and res.f < sphere(np.full((1, 5), 2.0))[0]


# ---------------------------------------------------------------------- lattice, Eq. (10)
def eq10(i: int, j: int, L: int) -> list[tuple[int, int]]:
    """Eq. (10) literally, 1-based: (i', j), (i, j'), (i'', j), (i, j'')."""
    ip = i - 1 if i != 1 else L
    jp = j - 1 if j != 1 else L
    ipp = i + 1 if i != L else 1
    jpp = j + 1 if j != L else 1
    return [(ip, j), (i, jp), (ipp, j), (i, jpp)]


@pytest.mark.parametrize(
    ("i", "j"),
    [(1, 1), (1, 7), (7, 1), (7, 7), (1, 4), (4, 1), (7, 4), (4, 7), (4, 4)],
    ids=["c11", "c17", "c71", "c77", "top", "left", "bottom", "right", "inside"],
)
def test_torus_neighbours_eq10(i: int, j: int) -> None:
    L = 7
    nb = torus_neighbours(L, L)
    flat = [(a - 1) * L + (b - 1) for a, b in eq10(i, j, L)]
    assert nb[(i - 1) * L + (j - 1)].tolist() == flat


def test_torus_neighbours_corners_wrap() -> None:
    nb = torus_neighbours(7, 7)
    assert nb[0].tolist() == [42, 6, 7, 1]  # (0,0): up wraps to (6,0), left wraps to (0,6)
    assert nb[48].tolist() == [41, 47, 6, 42]  # (6,6): down wraps to (0,6), right to (6,0)
    assert nb[3].tolist() == [45, 2, 10, 4]  # top edge (0,3)
    assert nb[27].tolist() == [20, 26, 34, 21]  # right edge (3,6)


@pytest.mark.parametrize(("rows", "cols"), [(7, 7), (5, 8), (3, 3), (2, 3), (1, 5)])
def test_torus_neighbours_symmetric_never_self(rows: int, cols: int) -> None:
    nb = torus_neighbours(rows, cols)
    n = rows * cols
    assert nb.shape == (n, 4)
    assert np.all(nb != np.arange(n)[:, None])
    A = np.zeros((n, n), dtype=bool)
    A[np.repeat(np.arange(n), 4), nb.ravel()] = True
    assert np.array_equal(A, A.T)  # a neighbour's neighbour is me
    if rows >= 3 and cols >= 3:
        assert all(len(set(r)) == 4 for r in nb.tolist())


# ---------------------------------------------------------------------- competition, Eq. (11)
def test_competition_eq11() -> None:
    rng = np.random.default_rng(0)
    nb = torus_neighbours(7, 7)
    for _ in range(20):
        F = rng.integers(0, 10, size=49).astype(float)  # many ties
        Min, winner = competition(F, nb)
        for a in range(49):
            assert F[Min[a]] == F[nb[a]].min()
            assert Min[a] == nb[a][np.argmin(F[nb[a]])]  # ties: first in Eq. (10)'s order
            assert winner[a] == (F[a] < F[nb[a]].min())  # strict: a tie is a loss
        # of two neighbours at most one wins; the unique best always wins
        assert not np.any(winner[:, None] & winner[nb])
    F = np.arange(49.0)[::-1].copy()
    assert competition(F, nb)[1][48]


def test_competition_stacked_lattices() -> None:
    rng = np.random.default_rng(1)
    nb = torus_neighbours(3, 3)
    F = rng.random((4, 9))
    Min, winner = competition(F, nb)
    for t in range(4):
        m, w = competition(F[t], nb)
        assert np.array_equal(Min[t], m) and np.array_equal(winner[t], w)


def test_winners_keep_their_place_losers_are_replaced() -> None:
    """Eq. (11): a winner (better than its best neighbour) lives on; a loser's point gets
    New_ij, built from L_ij and Min_ij (here: crossover only, so each gene comes from one)."""
    opt = MAGA(
        problem(rastrigin, 6, 5.12), seed=3, self_learning_rate=0.0, P_c=1.0, P_m=0.0, elitism=False
    )
    step(opt)
    for _ in range(10):
        L0, F0 = opt.L.copy(), opt.F.copy()
        Min, winner = competition(F0, opt.neighbours)
        step(opt)
        assert opt.phase == "lattice"  # no self-learning: one batch per generation
        np.testing.assert_array_equal(opt.L[winner], L0[winner])
        np.testing.assert_array_equal(opt.F[winner], F0[winner])
        for a in np.flatnonzero(~winner):
            child, p1, p2 = opt.L[a], L0[a], L0[Min[a]]
            from_p1 = child == p1
            c = int(np.argmin(from_p1)) if not from_p1.all() else len(child)
            assert np.all(from_p1[:c]) and np.array_equal(child[c:], p2[c:])  # P1 head, P2 tail


# ---------------------------------------------------------------------- genetic behaviours
def test_single_point_crossover_cuts_between_waypoints() -> None:
    rng = np.random.default_rng(2)
    block, n_w = 3, 5
    P1 = rng.random((200, block * n_w))
    P2 = rng.random((200, block * n_w)) + 10.0
    C = single_point_crossover(P1, P2, 1.0, block, rng)
    cuts = set()
    for c1, p1, p2 in zip(C, P1, P2, strict=True):
        head = (c1 == p1).reshape(n_w, block)
        assert np.all(head.all(axis=1) | (~head).all(axis=1))  # whole waypoints
        c = int(head.all(axis=1).sum())
        assert 1 <= c <= n_w - 1
        np.testing.assert_array_equal(c1[: c * block], p1[: c * block])
        np.testing.assert_array_equal(c1[c * block :], p2[c * block :])
        cuts.add(c)
    assert cuts == {1, 2, 3, 4}
    np.testing.assert_array_equal(single_point_crossover(P1, P2, 0.0, block, rng), P2)


def test_mutation_moves_one_waypoint_to_an_adjacent_point() -> None:
    rng = np.random.default_rng(4)
    block, n_w = 3, 4
    lo, hi = np.zeros(block * n_w), np.full(block * n_w, 10.0)
    h = 0.05 * (hi - lo)
    X = rng.uniform(1.0, 9.0, size=(500, block * n_w))
    Y = mutate_adjacent(X, 1.0, h, block, lo, hi, rng)
    moved = (Y != X).reshape(500, n_w, block).any(axis=2)
    assert np.all(moved.sum(axis=1) == 1)  # exactly one waypoint
    assert np.all(np.abs(Y - X) <= h)  # to a point within one step
    np.testing.assert_array_equal(mutate_adjacent(X, 0.0, h, block, lo, hi, rng), X)
    frac = np.mean((mutate_adjacent(X, 0.3, h, block, lo, hi, rng) != X).any(axis=1))
    assert 0.2 < frac < 0.4  # P_m per new agent
    at_wall = mutate_adjacent(np.full((50, block * n_w), 10.0), 1.0, h, block, lo, hi, rng)
    assert np.all(lo <= at_wall) and np.all(at_wall <= hi)  # clipped to the box


# ---------------------------------------------------------------------- smoothing, Eq. (5)
def test_turn_cosines_eq5() -> None:
    P = np.array([[[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 1, 0], [-1, 1, 0]]])
    theta = turn_cosines(P)
    np.testing.assert_allclose(theta[0, :2], [0.0, 0.0])  # right angles
    assert theta[0, 2] == 1.0 and theta[0, 3] == 1.0  # zero-length segment: no turn
    back = np.array([[[0.0, 0], [2, 0], [1, 0.1]]])
    assert turn_cosines(back)[0, 0] < -0.9


def test_smoothing_removes_turn_backs_of_a_zigzag() -> None:
    # a 3-D zig-zag that folds back at every interior waypoint
    P = np.array(
        [
            [0.0, 0.0, 10.0],
            [10.0, 1.0, 11.0],
            [2.0, 2.0, 12.0],
            [12.0, 3.0, 11.0],
            [4.0, 4.0, 13.0],
            [14.0, 5.0, 12.0],
            [6.0, 6.0, 14.0],
            [16.0, 7.0, 13.0],
        ]
    )
    X = P.reshape(1, -1)
    assert np.all(path_thetas(X, 3) <= 0)
    Y = smooth(X, 3, passes=30)
    assert np.all(path_thetas(Y, 3) > 0)
    np.testing.assert_array_equal(Y[0, :3], X[0, :3])  # first and last free waypoint stay
    np.testing.assert_array_equal(Y[0, -3:], X[0, -3:])
    assert np.all((P.min(axis=0) <= Y.reshape(-1, 3)) & (Y.reshape(-1, 3) <= P.max(axis=0)))


def test_smoothing_leaves_smooth_paths_and_functions_alone() -> None:
    rng = np.random.default_rng(5)
    t = np.sort(rng.random((20, 6)), axis=1)
    X = np.stack([t, t**2, np.sqrt(t)], axis=2).reshape(20, -1)  # monotone: no turn-back
    assert np.all(path_thetas(X, 3) > 0)
    np.testing.assert_array_equal(smooth(X, 3, 30), X)
    Z = rng.random((10, 7))
    np.testing.assert_array_equal(smooth(Z, 1, 30), Z)  # block 1: genes are not waypoints


def test_random_paths_smoothed() -> None:
    rng = np.random.default_rng(6)
    X = rng.random((1000, 5 * 3))
    Y = smooth(X, 3, 30)
    assert np.all(path_thetas(Y, 3) > 0)


def test_new_agents_are_smoothed_on_paths_only() -> None:
    path = problem(sphere, dim=4 * 3, bound=10.0, block=3)
    opt = MAGA(path, seed=7)
    for _ in range(15):
        step(opt)
    P1 = opt.uniform(300)
    P2 = opt.uniform(300)
    New = opt.new_agents(P1, P2)
    assert np.all(path_thetas(New, 3) > 0)
    assert np.any(path_thetas(P1, 3) <= 0)  # random parents do turn back
    off = MAGA(path, seed=7, smooth=False).new_agents(P1, P2)
    assert np.any(path_thetas(off, 3) <= 0)
    flat = MAGA(problem(sphere, dim=12), seed=7)
    F1, F2 = flat.uniform(300), flat.uniform(300)
    New = flat.new_agents(F1, F2)
    # block 1: a child is a crossover of its parents plus at most one moved gene, no smoothing
    assert np.all(np.sum((New != F1) & (New != F2), axis=1) <= 1)


# ---------------------------------------------------------------------- self-learning
def test_self_learning_never_returns_worse() -> None:
    opt = MAGA(problem(rastrigin, 8, 5.12), seed=8)
    step(opt)
    seen = 0
    for _ in range(15):
        F_before = opt.F.copy()
        X = opt.ask()  # lattice phase: picks the targets
        opt.tell(X, opt.problem.evaluate(X))
        targets = opt.targets.copy()
        s_best = opt.s_best_f.copy() if len(targets) else None
        while opt.phase == "self_learning":
            step(opt)
            assert np.all(opt.s_best_f <= s_best)  # elite retention: never worse
            np.testing.assert_array_equal(opt.sF.min(axis=1), opt.s_best_f)  # kept in L_new
            s_best = opt.s_best_f.copy()
        assert np.all(opt.F[targets] <= F_before[targets])
        seen += len(targets)
    assert seen > 0


def test_self_learning_lattice_layout() -> None:
    opt = MAGA(problem(rastrigin, 6, 5.12), seed=9, sGen=0)
    step(opt)
    L0 = opt.L.copy()
    X = opt.ask()
    opt.tell(X, opt.problem.evaluate(X))
    T = len(opt.targets)
    assert T > 0
    assert opt.sL.shape == (T, 9, 6)  # the agent and its 8 mutants
    np.testing.assert_array_equal(opt.sL[:, 0], L0[opt.targets])
    moved = (opt.sL[:, 1:] != opt.sL[:, :1]).sum(axis=2)
    assert np.all(moved <= 1)  # each mutant moved one gene (block 1)
    assert opt.phase == "lattice" and opt.generation == 1  # sGen = 0: done at once


def test_self_learning_targets() -> None:
    opt = MAGA(problem(), seed=10, self_learning="best", self_learning_rate=1.0)
    step(opt)
    for _ in range(5):
        b = int(np.argmin(opt.F))
        X = opt.ask()
        assert opt.targets.tolist() == [b]
        opt.tell(X, opt.problem.evaluate(X))
        while opt.phase == "self_learning":
            step(opt)
    opt = MAGA(problem(), seed=11, self_learning_rate=1.0)
    step(opt)
    _, winner = competition(opt.F, opt.neighbours)
    opt.ask()
    assert opt.targets.tolist() == np.flatnonzero(winner).tolist()  # every winner (Alg. 1)
    opt = MAGA(problem(), seed=11, self_learning_rate=0.0)
    step(opt)
    opt.ask()
    assert len(opt.targets) == 0


# ---------------------------------------------------------------------- bookkeeping
@pytest.mark.parametrize(
    "kw",
    [{}, {"P_c": 0.0, "P_m": 0.0}, {"sGen": 0}, {"pop_size": 13}],
    ids=["default", "copies-only", "sGen0", "ring"],
)
def test_evaluation_counts_exact(kw: dict) -> None:
    prob = Counting(problem(rastrigin, 6, 5.12))
    opt = MAGA(prob, seed=12, **kw)
    asked = 0
    for _ in range(60):
        X, _ = step(opt)
        assert X.shape[0] >= 1
        asked += X.shape[0]
        assert prob.rows == asked == opt.evaluations
        assert prob.calls == opt.iterations
    # every stored cost is the cost of its agent: reused costs of copies are right
    np.testing.assert_array_equal(opt.F, rastrigin(opt.L))
    res = minimize(Counting(problem(rastrigin, 6, 5.12)), "maga", 25, seed=12, **kw)
    assert res.evaluations == res.evaluations_history[-1]


def test_generation_is_one_plus_sgen_batches() -> None:
    prob = problem(rastrigin, 6, 5.12)
    opt = MAGA(prob, seed=13, sGen=4)
    step(opt)
    for _ in range(5):
        n_losers = int(np.sum(~competition(opt.F, opt.neighbours)[1]))
        sizes = run_generation(opt)
        T = len(opt.targets)
        assert len(sizes) == (1 + 4 if T else 1)
        assert sizes[0] <= n_losers + 8 * T  # copies are not re-asked
    np.testing.assert_array_equal(opt.F, rastrigin(opt.L))


def test_lattice_keeps_the_best_so_far() -> None:
    opt = MAGA(problem(rastrigin, 6, 5.12), seed=14)
    step(opt)
    for _ in range(10):
        run_generation(opt)
        assert opt.F.min() == opt.best_f  # elite retention: the best agent stays on the lattice


def test_copies_only_still_asks() -> None:
    """P_c = P_m = 0 on a plain function: every new agent is a copy of Min_ij, all costs are
    known; the batch is still evaluated (an ask is never empty)."""
    opt = MAGA(problem(), seed=15, P_c=0.0, P_m=0.0, self_learning_rate=0.0)
    step(opt)
    for _ in range(5):
        Min, winner = competition(opt.F, opt.neighbours)
        L0 = opt.L.copy()
        X, _ = step(opt)
        np.testing.assert_array_equal(X, L0[Min[~winner]])  # the copies, evaluated


# ---------------------------------------------------------------------- performance sanity
def random_search(prob: FunctionProblem, evaluations: int, seed: int) -> float:
    rng = np.random.default_rng(seed)
    X = prob.lower + rng.random((evaluations, prob.dim)) * (prob.upper - prob.lower)
    return float(prob.evaluate(X).min())


@pytest.mark.parametrize(
    ("f", "bound"), [(sphere, 5.0), (rastrigin, 5.12)], ids=["sphere", "rastrigin"]
)
def test_beats_random_search(f, bound: float) -> None:
    prob = problem(f, dim=10, bound=bound)
    budget = 3000
    maga = [minimize(prob, "maga", Budget(max_evaluations=budget), seed=s).f for s in range(5)]
    rand = [random_search(prob, budget, seed=s) for s in range(5)]
    assert max(maga) < min(rand), (maga, rand)


def test_planner_pop_size_accepted() -> None:
    """Planners and benches set ``pop_size`` for every optimizer; any size >= 2 makes a lattice."""
    cfg = MAGAConfig(pop_size=40)
    assert cfg.lattice_shape == (5, 8)
    opt = MAGA(problem(), cfg, seed=0)
    X, _ = step(opt)
    assert X.shape == (40, 5)


@pytest.mark.parametrize("block", [2, 3])
def test_numba_smoothing_is_bit_identical_to_the_numpy_reference(block: int) -> None:
    rng = np.random.default_rng(11)
    for n_w in (3, 4, 9, 27):
        X = rng.random((200, n_w * block))
        X[:20] = np.round(X[:20] * 3) / 3  # repeated points: zero-length segments
        X[20:40, block : 2 * block] = X[20:40, :block]
        for passes in (1, 2, 30):
            np.testing.assert_array_equal(
                smooth(X, block, passes), smooth_reference(X, block, passes)
            )
