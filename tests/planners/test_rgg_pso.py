"""RGG-PSO / RGG-PSO+ (Liu et al. 2024): Alg. 1-4 and the two planners."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.planners import PlannerError, get_planner
from uavplan.planners.sampling.rgg import feasibility_problem, rgg_candidates
from uavplan.planners.sampling.rgg_pso import conquer, fit_interior, initial_swarm
from uavplan.problems import PathProblem
from uavplan.problems.validity import shortest_subsequence
from uavplan.problems.variable_length import (
    VariableLengthEncoding,
    evaluate_paths,
    particle_to_path,
    path_to_particle,
)
from uavplan.scenarios import load_builtin
from uavplan.world import Bounds, Circle, Scenario, Task

from .test_rgg import walled_scene


@st.composite
def paths_and_n(draw):
    """A path without consecutive duplicates (non-consecutive repeats allowed), and N >= k."""
    d = draw(st.sampled_from([2, 3]))
    pool_size = draw(st.integers(2, 6))
    seed = draw(st.integers(0, 2**32 - 1))
    pool = np.random.default_rng(seed).uniform(-50, 50, (pool_size, d)).round(3)
    first = draw(st.integers(0, pool_size - 1))
    idx = [first]
    for step in draw(st.lists(st.integers(1, pool_size - 1), max_size=11)):
        idx.append((idx[-1] + step) % pool_size)  # never equal to the previous index
    n = draw(st.integers(len(idx), 40))
    return pool[idx], n, seed


@settings(max_examples=150, deadline=None)
@given(paths_and_n())
def test_alg1_alg2_round_trip(args) -> None:
    path, n, seed = args
    particle = path_to_particle(path, n, np.random.default_rng(seed))
    assert particle.shape == (n, path.shape[1])
    assert np.array_equal(particle_to_path(particle), path)  # exact, in order
    # every node kept, each N_dup or N_dup + 1 times in a run of its own
    k = len(path)
    n_dup = -(-(n - k) // k)
    change = np.flatnonzero(np.any(particle[1:] != particle[:-1], axis=1)) + 1
    runs = np.diff(np.concatenate([[0], change, [n]]))
    assert len(runs) == k
    assert set(runs.tolist()) <= {n_dup, n_dup + 1} and runs.min() >= 1
    assert np.sum(runs == n_dup + 1) == n - k * n_dup


def test_alg1_paper_example() -> None:
    """Fig. 4: 7 waypoints into 10 slots: 3 random nodes doubled."""
    path = np.arange(14, dtype=float).reshape(7, 2)
    for seed in range(5):
        p = path_to_particle(path, 10, np.random.default_rng(seed))
        assert len(p) == 10
        _, counts = np.unique(p, axis=0, return_counts=True)
        assert sorted(counts.tolist()) == [1, 1, 1, 1, 2, 2, 2]
    # different draws give different duplications (diversity of the swarm)
    draws = {path_to_particle(path, 10, np.random.default_rng(s)).tobytes() for s in range(10)}
    assert len(draws) > 1


def test_alg1_more_nodes_than_slots_subsamples_in_order() -> None:
    path = np.arange(30, dtype=float).reshape(15, 2)
    p = path_to_particle(path, 4, np.random.default_rng(0))
    assert p.shape == (4, 2)
    rows = [int(r[0]) // 2 for r in p]
    assert rows == sorted(set(rows))


def test_alg2_drops_only_consecutive_duplicates() -> None:
    a, b = [0.0, 0.0], [1.0, 2.0]
    p = np.array([a, a, b, b, b, a, b])
    assert np.array_equal(particle_to_path(p), np.array([a, b, a, b]))


def test_decoded_equals_direct_for_length2d() -> None:
    sc = load_builtin("simple2d")
    prob = PathProblem(sc)
    enc = VariableLengthEncoding(prob, 20)
    cands = rgg_candidates(sc, np.random.default_rng(0), n_candidates=4)
    feas = feasibility_problem(sc)
    inner = [fit_interior(p, 20, feas)[0] for p in cands.paths]
    X = initial_swarm(enc, inner, 12, np.random.default_rng(1))
    X = np.vstack([X, np.random.default_rng(2).uniform(0, 100, (5, enc.dim))])
    f_decoded = enc.evaluate(X)
    f_direct = prob.cost(enc.decode(X))
    assert np.allclose(f_decoded, f_direct, rtol=1e-12, atol=1e-9)
    # the RGG-seeded particles decode to their candidates exactly and are feasible
    for i in range(4):
        assert np.array_equal(enc.path(X[i]), cands.paths[i])
    assert enc.best_feasible_x is not None and enc.feasible_history[-1] < np.inf


def test_shortcut_fits_long_candidates() -> None:
    sc = load_builtin("simple2d")
    feas = feasibility_problem(sc)
    cands = rgg_candidates(sc, np.random.default_rng(0), n_candidates=3, n_samples=400)
    path = max(cands.paths, key=len)
    assert len(path) - 2 > 2
    short, checks = shortest_subsequence(feas, path, 2)
    assert checks > 0
    if short is not None:
        assert len(short) - 2 <= 2
        assert feas.evaluate(short[None]).feasible[0]
        length = lambda p: np.linalg.norm(np.diff(p, axis=0), axis=1).sum()  # noqa: E731
        assert length(short) <= length(path) + 1e-9
    inner, _ = fit_interior(path, 2, feas)
    assert 1 <= len(inner) <= 2


# --------------------------------------------------------------------------- Alg. 4
def disc_scene() -> Scenario:
    return Scenario(
        "disc",
        Bounds((0.0, 0.0), (100.0, 100.0)),
        (Task("uav0", (10.0, 50.0), (90.0, 50.0)),),
        circles=(Circle((50.0, 50.0), 15.0),),
        cost="length2d",
        n_waypoints=5,
    )


@st.composite
def halves(draw):
    """Two halves detouring above the disc (some shortcuts cross it), jittered at random."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n1 = draw(st.integers(0, 4))
    n2 = draw(st.integers(0, 4))
    split = np.array([50.0, 75.0]) + rng.uniform(-5, 5, 2) * draw(st.sampled_from([0.0, 1.0]))
    x1 = np.sort(rng.uniform(12, 48, n1))
    x2 = np.sort(rng.uniform(52, 88, n2))
    y1 = 50 + (x1 - 10) / 40 * 25 + rng.uniform(-20, 10, n1)
    y2 = 50 + (90 - x2) / 40 * 25 + rng.uniform(-20, 10, n2)
    p1 = np.vstack([[10.0, 50.0], np.c_[x1, y1], split])
    p2 = np.vstack([split, np.c_[x2, y2], [90.0, 50.0]])
    return p1, p2


@settings(max_examples=60, deadline=None)
@given(halves())
def test_conquer_never_returns_infeasible(args) -> None:
    p1, p2 = args
    prob = PathProblem(disc_scene())
    res = conquer(prob, p1, p2)
    assert res.evaluations == len(particle_to_path(p1)) * len(particle_to_path(p2))
    # brute force over every merge
    merges = [
        particle_to_path(np.vstack([p1[: i + 1], p2[j:]]))
        for i in range(len(p1))
        for j in range(len(p2))
    ]
    cost, feas = evaluate_paths(prob, merges)
    if not feas.any():
        assert res.best is None
    else:
        assert res.best is not None
        ev = prob.evaluate(res.best.path[None])
        assert ev.feasible[0]
        assert ev.cost[0] == pytest.approx(res.best.cost)
        assert res.best.cost == pytest.approx(cost[feas].min())
        assert np.array_equal(res.best.path[0], p1[0])
        assert np.array_equal(res.best.path[-1], p2[-1])
    cat = particle_to_path(np.vstack([p1, p2[1:]]))
    assert np.array_equal(res.concatenation.path, cat)
    if res.concatenation.feasible:
        assert res.best is not None and res.best.cost <= res.concatenation.cost + 1e-12


def test_conquer_takes_a_shortcut() -> None:
    prob = PathProblem(disc_scene())
    p1 = np.array([[10.0, 50.0], [20.0, 80.0], [50.0, 80.0]])
    p2 = np.array([[50.0, 80.0], [80.0, 80.0], [90.0, 50.0]])
    res = conquer(prob, p1, p2)
    assert res.best is not None and res.concatenation.feasible
    assert res.best.cost < res.concatenation.cost
    assert (res.best.i, res.best.j) != (2, 0)


# --------------------------------------------------------------------------- planners
@pytest.mark.parametrize("name", ["rgg-pso", "rgg-pso+"])
def test_planners_simple2d(name: str) -> None:
    sc = load_builtin("simple2d")
    a = get_planner(name, pop_size=30).plan(sc, budget=30, seed=3)
    b = get_planner(name, pop_size=30).plan(sc, budget=30, seed=3)
    assert a.feasible and a.first_feasible_iteration == 1
    assert np.array_equal(a.waypoints, b.waypoints)
    assert np.array_equal(a.history, b.history)
    assert a.evaluations == b.evaluations == a.evaluations_history[-1]
    assert len(a.history) == len(a.feasible_history) == len(a.evaluations_history) == 30
    assert np.all(np.diff(a.history) <= 0) and np.all(np.diff(a.evaluations_history) > 0)
    assert np.isfinite(a.feasible_history[0])
    assert a.cost == pytest.approx(a.length)  # feasible under length2d: cost = length
    assert a.cost >= a.history[-1] - 1e-9
    assert a.info["edge_checks"] > 0
    assert len(a.waypoints) <= sc.n_waypoints + 2
    assert not np.any(np.all(a.waypoints[1:] == a.waypoints[:-1], axis=1))


def test_rgg_pso_plus_no_worse_than_pre_divide() -> None:
    sc = load_builtin("simple2d")
    for seed in range(3):
        # a dense, densified graph: every swarm starts feasible, so the merge rules are tested
        r = get_planner("rgg-pso+", pop_size=30, n_samples=100, max_doublings=3).plan(
            sc, budget=30, seed=seed
        )
        run = r.info
        assert run["pre_divide_feasible"] and run["divided_at"] == 15
        assert r.feasible
        assert r.cost <= run["pre_divide_cost"] + 1e-9
        assert run["merge"] in {"shortcut", "concatenation", "pre-divide"}
        # the whole phase's 15 iterations of 30 evaluations, then two sub-swarms per iteration
        assert r.evaluations_history[14] == 15 * 30
        assert r.evaluations > 15 * 30 + 15 * 60


def test_rgg_pso_plus_depth_and_early_stop() -> None:
    sc = load_builtin("simple2d")
    r = get_planner("rgg-pso+", pop_size=20, depth=2).plan(sc, budget=20, seed=1)
    assert r.feasible and r.iterations == 20
    assert r.cost <= r.info["pre_divide_cost"] + 1e-9
    assert 3 <= len(r.info["rgg_samples"]) <= 7  # 1 + 2 (+ up to 4) swarms
    from uavplan.optimizers import Budget

    # an evaluation budget plans T = 500 / (20 * 1.5) = 16 iterations, divided at 8
    s = get_planner("rgg-pso+", pop_size=20).plan(sc, budget=Budget(max_evaluations=500), seed=1)
    assert s.feasible and s.iterations <= 16 and s.info["divided_at"] == 8
    assert s.evaluations == s.evaluations_history[-1]
    stop = get_planner("rgg-pso+", pop_size=20).plan(
        sc, budget=40, seed=1, callback=lambda it, best: it >= 25
    )
    assert stop.iterations == 25 and stop.feasible


def test_disconnected_falls_back_to_uniform_swarm() -> None:
    sc = walled_scene()
    r = get_planner("rgg-pso", pop_size=10, n_samples=30).plan(sc, budget=3, seed=0)
    assert not r.feasible and r.info["uniform_seeded"] == ["uav0"]
    assert r.iterations == 3


def test_parameters() -> None:
    with pytest.raises(PlannerError, match="unknown option"):
        get_planner("rgg-pso", bogus=1)
    for name in ("rgg", "rgg-pso", "rgg-pso+"):  # the benchmark runner's common option
        get_planner(name, track_feasibility=True)
    with pytest.raises(PlannerError, match="unknown option"):
        get_planner("rgg-pso+", bogus=1)
    with pytest.raises(PlannerError):
        get_planner("rgg-pso+", whole_fraction=1.0)
    with pytest.raises(PlannerError):
        get_planner("rgg-pso", pop_size=0)
    p = get_planner("rgg-pso")
    d = p.describe()["optimizer_config"]
    assert (d["pop_size"], d["w"], d["w_damp"], d["c1"], d["c2"]) == (100, 1.0, 0.98, 1.5, 1.5)
    assert get_planner("rgg-pso+").describe()["whole_fraction"] == 0.5


def test_duplicate_invariant_presets_score_particles_like_decoded_paths() -> None:
    """The one-batch shortcut for length2d gives exactly the grouped Alg. 2 result."""
    from uavplan.problems import PathProblem
    from uavplan.problems.variable_length import DUPLICATE_INVARIANT, evaluate_decoded
    from uavplan.scenarios import load_builtin

    problem = PathProblem(load_builtin("simple2d"))
    assert problem.cost_name in DUPLICATE_INVARIANT
    rng = np.random.default_rng(3)
    full = rng.uniform(0, 100, (40, 12, 2))
    full[:, 0], full[:, -1] = problem.start, problem.goal
    full[::3, 4] = full[::3, 3]  # consecutive duplicates
    full[1::4, 7:10] = full[1::4, 6:7]
    fast_cost, fast_feas = evaluate_decoded(problem, full)
    problem.cost_name = "custom"  # force the grouped Alg. 2 path
    slow_cost, slow_feas = evaluate_decoded(problem, full)
    assert np.allclose(fast_cost, slow_cost, rtol=1e-12, atol=1e-9)
    assert np.array_equal(fast_feas, slow_feas)


def test_rgg_pso_samples_n_nodes_by_default_as_the_paper_says() -> None:
    """Sect. 4.2.1: "Sample N random nodes ... N denotes the PSO particle vector's length"; a
    graph that does not connect is not densified (max_doublings = 0) and the swarm starts
    uniform."""
    sc = load_builtin("simple2d")
    r = get_planner("rgg-pso", pop_size=20, n_waypoints=7).plan(sc, budget=3, seed=0)
    assert r.info["rgg_samples"] == [7]
    assert r.config["n_samples"] is None and r.config["max_doublings"] == 0
    dense = get_planner("rgg-pso", pop_size=20, n_samples=50, max_doublings=2)
    assert dense.plan(sc, budget=3, seed=0).info["rgg_samples"][0] >= 50
    seeded = uniform = 0
    for seed in range(12):
        run = get_planner("rgg-pso", pop_size=20, n_waypoints=3).plan(sc, budget=2, seed=seed)
        if run.info["uniform_seeded"]:
            uniform += 1
        else:
            seeded += 1
    assert seeded > 0 and uniform > 0  # 3 samples connect the task only sometimes


def test_halves_evaluated_together_give_what_each_alone_gives(monkeypatch) -> None:
    """evaluate_many: two encodings of two tasks in one world evaluate in one call, with the
    costs, bests and histories of separate calls; a problem with other answers (another cost
    model) is evaluated apart."""
    from uavplan.problems.variable_length import evaluate_many, same_answers
    from uavplan.scenarios import resolve

    sc = resolve("rgg-n09-i004")
    t1, t2 = Task("a", (6.0, 6.0), (50.0, 40.0)), Task("b", (50.0, 40.0), (93.0, 92.0))
    rng = np.random.default_rng(0)

    def encodings() -> list[VariableLengthEncoding]:
        return [VariableLengthEncoding(PathProblem(sc, t), 12) for t in (t1, t2)]

    Xs = [rng.uniform(0, 100, (30, 24)), rng.uniform(0, 100, (30, 24))]
    Xs[0][::3, 2:4] = Xs[0][::3, :2]  # duplicated waypoints
    alone, together = encodings(), encodings()
    assert same_answers(alone[0].problem, alone[1].problem)
    want = [e.evaluate(X) for e, X in zip(alone, Xs, strict=True)]
    calls = []
    original = PathProblem.evaluate

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(PathProblem, "evaluate", counted)
    got = evaluate_many(together, Xs)
    assert len(calls) == 1
    for a, b, w, g in zip(alone, together, want, got, strict=True):
        np.testing.assert_array_equal(g, w)
        assert a.feasible_history == b.feasible_history and a.evaluations == b.evaluations
        assert a.best_f == b.best_f and a.best_feasible_f == b.best_feasible_f
        np.testing.assert_array_equal(a.best()[0], b.best()[0])
    other = VariableLengthEncoding(PathProblem(sc, t1, cost="length"), 12)
    assert not same_answers(together[0].problem, other.problem)
    calls.clear()
    evaluate_many([together[0], other], Xs)
    assert len(calls) == 2
