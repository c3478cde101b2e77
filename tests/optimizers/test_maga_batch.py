"""The batched P-MAGA (:class:`MAGABatch`, Numba) against the reference (:class:`MAGA`, one
object per lattice): NumPy's PCG64 stream draw for draw, each operator on fixed inputs, and
whole runs lattice by lattice, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.optimizers import FunctionProblem, OptimizerError
from uavplan.optimizers import _maga_kernels as mk
from uavplan.optimizers.maga import (
    MAGA,
    MAGABatch,
    MAGAConfig,
    ReferenceMAGA,
    competition,
    mutate_adjacent,
    single_point_crossover,
    smooth,
    torus_neighbours,
)


def row(seed: int) -> np.ndarray:
    return mk.pcg64_row(np.random.PCG64(seed))


# ---------------------------------------------------------------------- the random stream
@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**63),
    draws=st.lists(
        st.tuples(st.integers(0, 2), st.integers(0, 5), st.integers(1, 2**32)), max_size=40
    ),
)
def test_pcg64_draws_as_numpy(seed: int, draws: list[tuple[int, int, int]]) -> None:
    """random(), integers(low, high) (buffered 32-bit halves, Lemire) and uniform(-1, 1),
    interleaved in any order, give NumPy's numbers, and the state ends as NumPy's."""
    g = np.random.default_rng(seed)
    st_row = mk.pcg64_row(g.bit_generator)
    kinds = np.array([k for k, _, _ in draws], dtype=np.int64)
    args = np.array([(lo, lo + w) for _, lo, w in draws], dtype=np.int64).reshape(-1, 2)
    want = []
    for k, (lo, hi) in zip(kinds, args, strict=True):
        if k == 0:
            want.append(g.random())
        elif k == 1:
            want.append(float(g.integers(lo, hi)))
        else:
            want.append(g.uniform(-1.0, 1.0))
    got = mk.draw_sequence(st_row, kinds, args)
    np.testing.assert_array_equal(got, np.array(want))
    np.testing.assert_array_equal(st_row, mk.pcg64_row(g.bit_generator))


def test_pcg64_state_round_trip() -> None:
    g = np.random.default_rng(3)
    g.integers(5, size=3)  # leaves a buffered 32-bit half
    r = mk.pcg64_row(g.bit_generator)
    bg = np.random.PCG64(0)
    mk.set_pcg64_row(bg, r)
    assert bg.state == g.bit_generator.state


# ---------------------------------------------------------------------- operators, fixed inputs
@pytest.mark.parametrize(("D", "block"), [(6, 3), (12, 3), (5, 1), (3, 3), (8, 2)])
def test_crossover_and_mutation_as_the_reference(D: int, block: int) -> None:
    rng = np.random.default_rng(D * 10 + block)
    n = 40
    P1, P2 = rng.uniform(-3, 3, (n, D)), rng.uniform(-3, 3, (n, D))
    lo, hi = -2.0 * np.ones(D), 2.5 * np.ones(D)
    h = 0.3 * (hi - lo)
    g = np.random.default_rng(5)
    s = mk.pcg64_row(g.bit_generator)
    flags, picks = np.empty(n, dtype=bool), np.empty(n, dtype=np.int64)
    out = np.empty((n, D))
    mk.crossover(s, P1, P2, n, 0.5, block, out, flags, picks)
    want = single_point_crossover(P1, P2, 0.5, block, g)
    np.testing.assert_array_equal(out, want)
    mk.mutate(s, out, 0, n, 0.6, h, block, lo, hi, flags, picks)  # clips the crossed rows too
    want = mutate_adjacent(want, 0.6, h, block, lo, hi, g)
    np.testing.assert_array_equal(out, want)
    np.testing.assert_array_equal(s, mk.pcg64_row(g.bit_generator))


def test_smoothing_and_clip_as_the_reference() -> None:
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (60, 27))
    lo, hi = -0.9 * np.ones(27), 0.8 * np.ones(27)
    Y = X.copy()
    mk.smooth_and_clip(Y, len(Y), 3, 30, True, lo, hi)
    np.testing.assert_array_equal(Y, np.minimum(np.maximum(smooth(X, 3, 30), lo), hi))


def test_competition_and_known_costs_as_the_reference() -> None:
    rng = np.random.default_rng(2)
    nb = torus_neighbours(7, 7)
    F = rng.integers(0, 5, 49).astype(float)  # many ties
    F[3] = np.inf
    Min, winner = np.empty(49, dtype=np.int64), np.empty(49, dtype=bool)
    mk.compete(F, nb, Min, winner)
    want_min, want_winner = competition(F, nb)
    np.testing.assert_array_equal(Min, want_min)
    np.testing.assert_array_equal(winner, want_winner)
    x = rng.uniform(size=(3, 6))
    # rows equal to parent 1, to both, to parent 2, to neither
    X = np.stack([x[0], x[0], x[0], x[0]])
    P1 = np.stack([x[0], x[0], x[1], x[1]])
    P2 = np.stack([x[2], x[0], x[0], x[2]])
    got = [mk.known_cost(X[k], P1[k], 1.0, P2[k], 2.0) for k in range(4)]
    want = ReferenceMAGA._known_costs(X, P1, np.ones(4), P2, 2 * np.ones(4))
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(want, [1.0, 2.0, 2.0, np.nan])


# ---------------------------------------------------------------------- whole runs
def bumpy(X: np.ndarray) -> np.ndarray:
    return np.sum((X - 0.3) ** 2, axis=1) + np.sum(np.sin(5 * X), axis=1)


def run_both(S: int, D: int, block: int, steps: int, G: int = 10**9, **kw: object) -> MAGABatch:
    """Step a batch and one MAGA per lattice together (lattices stop at ``G`` generations, as
    HR-MAGA's); every ask, lattice, cost, best and count equal after every step."""
    cfg = MAGAConfig(**kw)  # type: ignore[arg-type]
    rng = np.random.default_rng(S * D)
    lo = rng.uniform(-5, 0, (S, D))
    hi = lo + rng.uniform(1, 5, (S, D))
    seqs = np.random.SeedSequence(42).spawn(S)
    refs = [
        ReferenceMAGA(
            FunctionProblem(bumpy, lo[s], hi[s], block=block), cfg, seed=np.random.default_rng(q)
        )
        for s, q in enumerate(seqs)
    ]
    b = MAGABatch(lo, hi, block, cfg, list(seqs))
    for _ in range(steps):
        live = b.generation < G
        X, owner = b.ask(live)
        f = bumpy(X)
        for s in np.flatnonzero(live):
            Xr = refs[s].ask()
            np.testing.assert_array_equal(Xr, X[owner == s])
            refs[s].tell(Xr, f[owner == s])
        b.tell(f)
        for s, o in enumerate(refs):
            np.testing.assert_array_equal(o.L, b.L[s])
            np.testing.assert_array_equal(o.F, b.F[s])
            assert (o.best_f, o.generation, o.evaluations, o.iterations) == (
                b.best_f[s],
                b.generation[s],
                b.evaluations[s],
                b.iterations[s],
            )
            if o.best_x is not None:
                np.testing.assert_array_equal(o.best_x, b.best_x[s])
    return b


@pytest.mark.parametrize(
    ("S", "D", "block", "kw"),
    [
        (5, 6, 3, {}),  # HR-MAGA's sub-problems: 2 free waypoints
        (2, 27, 3, {"P_c": 0.9, "P_m": 0.8}),  # 9 waypoints: smoothing acts
        (2, 5, 1, {}),  # a plain function
        (3, 9, 3, {"self_learning": "best", "self_learning_rate": 1.0, "sGen": 3}),
        (3, 9, 3, {"sGen": 0, "pop_size": 12}),
        (2, 6, 3, {"smooth": False, "elitism": False, "pop_size": 13}),
    ],
)
def test_batch_gives_the_reference_numbers(S: int, D: int, block: int, kw: dict) -> None:
    b = run_both(S, D, block, 60, G=4, **kw)
    assert np.all(b.generation == 4)  # the lattices stopped at G, as HR-MAGA stops them


def test_batch_refuses_misuse() -> None:
    cfg = MAGAConfig()
    b = MAGABatch(np.zeros((2, 3)), np.ones((2, 3)), 3, cfg, [0, 1])
    with pytest.raises(OptimizerError, match="without a pending"):
        b.tell(np.zeros(3))
    X, _ = b.ask()
    with pytest.raises(OptimizerError, match="twice"):
        b.ask()
    with pytest.raises(OptimizerError, match="one cost per asked row"):
        b.tell(np.zeros(len(X) - 1))
    with pytest.raises(OptimizerError, match="PCG64"):
        MAGABatch(
            np.zeros((1, 3)), np.ones((1, 3)), 3, cfg, [np.random.Generator(np.random.MT19937(0))]
        )


@pytest.mark.parametrize(("D", "block", "kw"), [(12, 3, {}), (5, 1, {"pop_size": 20})])
def test_registered_maga_is_the_reference_stepped_in_numba(D: int, block: int, kw: dict) -> None:
    """``maga`` (one-lattice batch) and :class:`ReferenceMAGA` step for step: the same asks,
    lattices and stream (the generator continues where the kernels stopped), also when the
    caller changes the asked rows before telling them; a generator other than PCG64 runs the
    reference code."""
    prob = FunctionProblem(bumpy, -2 * np.ones(D), 3 * np.ones(D), block=block)
    cfg = MAGAConfig(**kw)
    a = MAGA(prob, cfg, seed=np.random.default_rng(8))
    b = ReferenceMAGA(prob, cfg, seed=np.random.default_rng(8))
    assert a._engine is not None
    for it in range(40):
        Xa, Xb = a.ask(), b.ask()
        np.testing.assert_array_equal(Xa, Xb)
        if it % 7 == 3:  # a caller's repair of the asked rows: they become the agents
            Xa = np.clip(Xa * 0.9, prob.lower, prob.upper)
            Xb = Xa.copy()
        a.tell(Xa, bumpy(Xa))
        b.tell(Xb, bumpy(Xb))
        np.testing.assert_array_equal(a.L, b.L)
        np.testing.assert_array_equal(a.F, b.F)
        assert (a.generation, a.phase, a.best_f) == (b.generation, b.phase, b.best_f)
        np.testing.assert_array_equal(a.targets, b.targets)
        assert a.rng.random() == b.rng.random()  # the same stream after every step
    mt = MAGA(prob, cfg, seed=np.random.Generator(np.random.MT19937(1)))
    assert mt._engine is None
    X = mt.ask()
    mt.tell(X, bumpy(X))
    assert mt.iterations == 1
