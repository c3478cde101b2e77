"""Prioritized fleet planning (PPSwarm and its baselines): separation, verification, seeding."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import plan_document
from uavplan.optimizers.constraints import Constrained
from uavplan.planners import PlannerError, get_planner
from uavplan.planners.core.base import separated_problem
from uavplan.planners.fleet.fleet_plan import FleetPlan, plan_all
from uavplan.planners.fleet.prioritized import (
    polyline_with_n_vertices,
    resample_by_length,
)
from uavplan.problems.encoding import CartesianEncoding
from uavplan.scenarios import resolve
from uavplan.verify import verify_plan
from uavplan.world import Scenario, Task
from uavplan.world.fleet_tasks import with_fleet
from uavplan.world.reservations import ReservationTable

SMALL = {"pop_size": 24, "n_iter": 6, "n_restart": 2, "rrt_iterations": 2000}


@pytest.fixture(scope="module")
def fleet3() -> Scenario:
    return with_fleet(resolve("ppswarm1"), 3, seed=0)


def test_polyline_keeps_its_vertices_and_shape() -> None:
    p = np.array([[0.0, 0, 0], [10, 0, 0], [10, 30, 5], [12, 31, 5]])
    q = polyline_with_n_vertices(p, 11)
    assert q.shape == (11, 3)
    for v in p:  # every original vertex is still there, in order
        assert np.any(np.all(np.isclose(q, v), axis=1))
    L = lambda a: np.linalg.norm(np.diff(a, axis=0), axis=1).sum()  # noqa: E731
    assert L(q) == pytest.approx(L(p))
    assert np.allclose(resample_by_length(p, 2), p[[0, -1]])
    with pytest.raises(ValueError):
        polyline_with_n_vertices(p, 3)


def test_fast_cost_equals_full_evaluation(fleet3: Scenario) -> None:
    import dataclasses

    fleet3 = dataclasses.replace(fleet3, cylinders=fleet3.cylinders[:1])
    rng = np.random.default_rng(3)
    task = fleet3.tasks[0]
    table = ReservationTable(fleet3.bounds.lo, fleet3.bounds.hi, fleet3.uav.s2)
    other = fleet3.tasks[1]
    line = np.linspace(other.start, other.goal, 6)
    table.add(other.id, line, np.linspace(0, 40, 6))
    problem = separated_problem(fleet3, task, table)
    paths = np.linspace(task.start, task.goal, 8)[None].repeat(200, axis=0)
    paths[:, 1:-1, :2] += rng.normal(0, 60, size=(200, 6, 2))
    xy = paths[:, 1:-1, :2]
    paths[:, 1:-1, 2] = fleet3.ground(xy[..., 0], xy[..., 1]) + rng.normal(150, 25, (200, 6))
    ev = problem.evaluate(paths)
    fast, cv = problem.evaluate_cv(paths, exact=False)
    want = np.where(ev.feasible, ev.cost, np.inf)
    np.testing.assert_array_equal(fast, want)
    assert 0 < np.isfinite(fast).sum() < 200
    np.testing.assert_array_equal(cv > 0, ~ev.feasible)  # 1 exactly where a check fails
    # the exact form: the same cost where feasible, a graded violation for the others
    f, cv_exact = problem.evaluate_cv(paths, exact=True)
    np.testing.assert_array_equal(f[ev.feasible], ev.cost[ev.feasible])
    np.testing.assert_array_equal(cv_exact, ev.cv)
    assert np.all(cv_exact[ev.feasible] == 0) and np.all(cv_exact[~ev.feasible] >= 100)


def test_small_fleet_is_feasible_verified_and_deterministic(fleet3: Scenario) -> None:
    a = get_planner("ppswarm", **SMALL).plan_fleet(fleet3, seed=5)
    b = get_planner("ppswarm", **SMALL).plan_fleet(fleet3, seed=5)
    c = get_planner("ppswarm", **SMALL).plan_fleet(fleet3, seed=6)
    assert a.flown_feasible and np.isfinite(a.cost)
    for ra, rb in zip(a.results, b.results, strict=True):
        assert np.array_equal(ra.waypoints, rb.waypoints)
    assert any(
        not np.array_equal(ra.waypoints, rc.waypoints)
        for ra, rc in zip(a.results, c.results, strict=True)
    )
    assert a.cost == pytest.approx(sum(r.cost for r in a.results))
    assert len(a.restart_costs) == 2 and a.cost == pytest.approx(np.min(a.restart_costs))
    assert len(a.history) == 2 * SMALL["n_iter"]
    d = plan_document(FleetPlan(fleet3, "ppswarm", {}, 5, a.results, a))
    # the default mode guarantees the flights: each UAV flies a Dubins-smoothed, timed path
    # (turn radius 20 m) that the verifier passes with the kinematic limits, and the planned
    # polylines the flights were made from are clear too
    assert all(r.flown_kind == "smoothed" and r.flown_ok for r in a.results)
    assert verify_plan(d, fleet3).ok and verify_plan(d, fleet3, trajectory="planned").ok
    assert a.info["flights"]["not_clear"] == []


def test_head_on_swap_is_separated() -> None:
    base = resolve("ppswarm1")
    z = 150.0
    g = lambda x, y: (x, y, float(base.ground(np.array(x), np.array(y))) + z)  # noqa: E731
    # two UAVs swap ends of the same straight line at the same time: the straight lines meet
    tasks = (Task("a", g(60.0, 440.0), g(990.0, 440.0)), Task("b", g(990.0, 440.0), g(60.0, 440.0)))
    sc = base.__class__(**{**base.__dict__, "tasks": tasks, "cylinders": ()})
    r = get_planner("ppswarm", **SMALL).plan_fleet(sc, seed=0)
    assert r.flown_feasible
    d = plan_document(FleetPlan(sc, "ppswarm", {}, 0, r.results, r))
    rep = verify_plan(d, sc)
    assert rep.ok and rep.min_separation >= sc.uav.s2


def test_priority_orders(fleet3: Scenario) -> None:
    lengths = {t.id: float(np.linalg.norm(np.subtract(t.goal, t.start))) for t in fleet3.tasks}
    opts = {**SMALL, "seeding": "uniform", "n_restart": 1, "n_iter": 2, "flight": "none"}
    lh = get_planner("prioritized", **{**opts, "order": "lh"}).plan_fleet(fleet3, seed=1)
    sh = get_planner("prioritized", **{**opts, "order": "sh"}).plan_fleet(fleet3, seed=1)
    assert list(lh.priority) == sorted(lengths, key=lambda k: -lengths[k])
    assert list(sh.priority) == sorted(lengths, key=lambda k: lengths[k])


@pytest.mark.parametrize("opt", ["de", "spso"])
def test_any_optimizer_runs_the_low_level(fleet3: Scenario, opt: str) -> None:
    r = get_planner("prioritized", optimizer=opt, pop_size=12, n_iter=3, flight="none").plan_fleet(
        fleet3, seed=0
    )
    assert len(r.results) == 3 and all(x.evaluations == 36 for x in r.results)


def test_bad_options() -> None:
    with pytest.raises(PlannerError, match="unknown option"):
        get_planner("ppswarm", bogus=1)
    with pytest.raises(PlannerError, match="order"):
        get_planner("ppswarm", order="tallest")
    with pytest.raises(PlannerError, match="none of the tasks"):
        get_planner("ppswarm").plan_fleet(resolve("ppswarm1"), tasks=("nope",))
    with pytest.raises(PlannerError, match="smooth_timing"):
        get_planner("ppswarm", smooth_timing="fast")
    with pytest.raises(PlannerError, match="separation_margin"):
        get_planner("ppswarm", separation_margin=-1.0)


@pytest.mark.parametrize("timing", ["planned", "constant"])
def test_flights_keep_their_timing_and_agree_with_the_verifier(
    fleet3: Scenario, timing: str
) -> None:
    r = get_planner("ppswarm", **SMALL, smooth_timing=timing).plan_fleet(fleet3, seed=5)
    uav = fleet3.uav
    for u in r.results:
        p, t = u.flown_trajectory()
        speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
        assert t[0] == pytest.approx(u.times[0]) and u.flown_kind == "smoothed"
        if timing == "constant":
            np.testing.assert_allclose(speed, uav.speed, rtol=1e-9)
        else:  # within the UAV's speed range
            assert np.all(speed <= uav.v_max * (1 + 1e-9))
            assert np.all(speed >= uav.min_speed * (1 - 1e-9))
    d = plan_document(FleetPlan(fleet3, "ppswarm", {}, 5, r.results, r))
    assert verify_plan(d, fleet3).ok == r.flown_feasible == all(u.flown_ok for u in r.results)


@pytest.mark.parametrize("timing", ["planned", "constant"])
def test_paper_mode_smooths_after_and_declares_the_polylines(fleet3: Scenario, timing: str) -> None:
    r = get_planner("ppswarm", **SMALL, smooth_timing=timing, flight="after").plan_fleet(
        fleet3, seed=5
    )
    v = fleet3.uav.speed
    for u in r.results:
        t, p = np.asarray(u.smoothed_times), np.asarray(u.smoothed)
        speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
        assert t[0] == pytest.approx(u.times[0])
        if timing == "constant":
            np.testing.assert_allclose(speed, v, rtol=1e-9)
        else:  # never faster than the UAV, never earlier than planned at the goal
            assert np.all(speed <= v * (1 + 1e-9))
            assert t[-1] >= u.times[-1] - 1e-9
        # what is declared flown is the polyline, and a 20 m turn radius cannot fly its corners
        assert u.flown_kind == "polyline" and u.flown_ok is False
        assert any("turn" in v for v in u.flown_violations)
    assert r.info["smoothing"]["timing"] == timing
    assert r.planned_feasible and not r.flown_feasible
    d = plan_document(FleetPlan(fleet3, "ppswarm", {}, 5, r.results, r))
    assert verify_plan(d, fleet3, smoothed=True).ok == all(u.smoothed_ok for u in r.results)
    assert verify_plan(d, fleet3, trajectory="planned").ok
    assert not verify_plan(d, fleet3).ok and d["feasible"] is False


def test_separation_margin_plans_wider_than_s2() -> None:
    base = resolve("ppswarm1")
    g = lambda x, y: (x, y, float(base.ground(np.array(x), np.array(y))) + 150.0)  # noqa: E731
    # a head-on swap: the margin, not the optimizer, keeps them S2 + margin apart
    tasks = (Task("a", g(60.0, 440.0), g(990.0, 440.0)), Task("b", g(990.0, 440.0), g(60.0, 440.0)))
    sc = base.__class__(**{**base.__dict__, "tasks": tasks, "cylinders": ()})
    seps = {}
    for margin in (0.0, 100.0):
        r = get_planner("ppswarm", **SMALL, separation_margin=margin, flight="none").plan_fleet(
            sc, seed=0
        )
        assert r.planned_feasible and not r.flown_feasible  # polylines only: never called flyable
        d = plan_document(FleetPlan(sc, "ppswarm", {}, 0, r.results, r))
        rep = verify_plan(d, sc, trajectory="planned")
        assert rep.ok and not verify_plan(d, sc).ok
        seps[margin] = rep.min_separation
    assert seps[100.0] >= sc.uav.s2 + 100.0 - 1e-6
    assert seps[0.0] < sc.uav.s2 + 100.0  # the margin is what made the difference


def test_plan_and_verify_cli(tmp_path, fleet3: Scenario) -> None:
    from uavplan.io.scenario_file import save_scenario

    f = tmp_path / "fleet.yaml"
    save_scenario(fleet3, f)
    out = tmp_path / "out"
    runner = CliRunner()
    args = ["plan", str(f), "-a", "ppswarm", "--out", str(out)]
    for k, v in SMALL.items():
        args += ["--param", f"{k}={v}"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    plan = json.loads((out / "plan.json").read_text())
    assert plan["separation_checked"] and plan["fleet"]["feasible"]
    assert all(u["flown"]["kind"] == "smoothed" and u["flown"]["feasible"] for u in plan["uavs"])
    res = runner.invoke(app, ["verify", str(out / "plan.json"), str(f)])
    assert res.exit_code == 0, res.output
    # a single-UAV planner plans the fleet in the prioritized frame, never UAVs alone
    fp = plan_all(fleet3, get_planner("pso", pop_size=10), 2, 0)
    doc = plan_document(fp)
    assert doc["separation_checked"] is True and fp.fleet is not None
    assert doc["feasible"] == fp.feasible == verify_plan(doc, fleet3).ok
    with pytest.raises(PlannerError, match="rrt-star"):
        plan_all(fleet3, get_planner("rrt-star"), 2, 0)


@pytest.mark.parametrize("name", ["ppswarm2", "ppswarm4"])
@pytest.mark.parametrize("planner", ["ppswarm", "prioritized"])
def test_every_feasible_fleet_passes_the_verifier(name: str, planner: str) -> None:
    sc = with_fleet(resolve(name), 5, seed=2)
    opts = {**SMALL, "n_restart": 1} if planner == "ppswarm" else {"pop_size": 40, "n_iter": 8}
    r = get_planner(planner, **opts).plan_fleet(sc, seed=3)
    d = plan_document(FleetPlan(sc, planner, {}, 3, r.results, r))
    rep = verify_plan(d, sc)
    if r.flown_feasible:
        assert rep.ok, [v.message for v in rep.violations]
    # and per UAV: every UAV the planner calls feasible has no violation of its own, except
    # separation from a UAV that is itself infeasible (planned later paths avoid earlier ones)
    bad_uavs = {u for v in rep.violations for u in v.uavs if v.kind != "separation"}
    assert not bad_uavs & {x.uav_id for x in r.results if x.feasible}


def test_departure_delay_retries_until_a_later_take_off_is_clear(monkeypatch, fleet3) -> None:
    """A UAV whose low level finds nothing conflict-free tries later take-offs (max_delays)."""
    from uavplan.planners.fleet.prioritized import PrioritizedPlanner

    real = PrioritizedPlanner._low_level
    calls: list[float] = []

    def blocked_until_10s(self, scenario, task, *args):  # type: ignore[no-untyped-def]
        res, pop, cands = real(self, scenario, task, *args)
        calls.append(task.start_time)
        if task.id == "uav1" and task.start_time < 10.0:
            res = dataclasses.replace(res, feasible=False, violations=("separation",))
            cands = [res]
        return res, pop, cands

    monkeypatch.setattr(PrioritizedPlanner, "_low_level", blocked_until_10s)
    opts = {**SMALL, "n_restart": 1, "flight": "none", "delay_step": 5.0}
    plain = get_planner("ppswarm", **opts, max_delays=0).plan_fleet(fleet3, seed=0)
    assert not plain.planned_feasible and plain.info["delayed"] == {}
    calls.clear()
    waited = get_planner("ppswarm", **opts, max_delays=3).plan_fleet(fleet3, seed=0)
    assert waited.planned_feasible and waited.info["delayed"] == {"uav1": 10.0}
    assert sorted(calls) == [0.0, 0.0, 0.0, 5.0, 10.0]  # two refusals, then take-off at 10 s
    b = next(r for r in waited.results if r.uav_id == "uav1")
    assert b.times[0] == pytest.approx(10.0)
    d = plan_document(FleetPlan(fleet3, "ppswarm", {}, 0, waited.results, waited))
    assert verify_plan(d, fleet3, trajectory="planned").ok


def test_graded_cost_keeps_f_for_feasible_and_orders_infeasible(fleet3: Scenario) -> None:
    task = fleet3.tasks[0]
    table = ReservationTable(fleet3.bounds.lo, fleet3.bounds.hi, fleet3.uav.s2)
    problem = separated_problem(fleet3, task, table)
    enc = CartesianEncoding(problem, 6)
    inf_p, graded = Constrained(enc, "inf"), Constrained(enc, "feasibility-first")
    rng = np.random.default_rng(0)
    paths = np.linspace(task.start, task.goal, 8)[None].repeat(300, axis=0)
    paths[:, 1:-1, :2] += rng.normal(0, 80, size=(300, 6, 2))
    xy = paths[:, 1:-1, :2]
    paths[:, 1:-1, 2] = fleet3.ground(xy[..., 0], xy[..., 1]) + rng.normal(150, 40, (300, 6))
    genes = enc.encode(paths)
    a, b = inf_p.evaluate(genes), graded.evaluate(genes)
    fin = np.isfinite(a)
    np.testing.assert_array_equal(a[fin], b[fin])  # feasible: exactly F
    assert np.all(np.isfinite(b)) and np.all(b[~fin] >= 1e7) and (~fin).sum() > 10
    assert b[~fin].max() > b[~fin].min()  # infeasible ones are told apart
    if fin.any():
        assert b[fin].max() < b[~fin].min()


def test_graded_baseline_finds_feasible_paths_where_inf_does_not(fleet3: Scenario) -> None:
    opts = {"pop_size": 60, "n_iter": 25, "flight": "none"}
    a = get_planner("prioritized", **opts).plan_fleet(fleet3, seed=1)
    graded = get_planner("prioritized", **opts, constraints="feasibility-first")
    b = graded.plan_fleet(fleet3, seed=1)
    n_a = sum(r.feasible for r in a.results)
    n_b = sum(r.feasible for r in b.results)
    assert n_b >= n_a and n_b >= 2


def test_swarm_seeding_follows_eqs_15_and_16(fleet3: Scenario) -> None:
    """Eq. 15: particle 1 is the RRT* path, the others (1 - alpha) P + alpha randpath; Eq. 16:
    the first rho N_pop particles are random paths, the rest the previous positions."""

    planner = get_planner("ppswarm", pop_size=20, alpha=0.1, rho=0.25)
    seen: list[np.ndarray] = []
    real = planner.optimizer_cls

    class Spy(real):  # type: ignore[misc, valid-type]
        def __init__(self, *a, init=None, **k):  # type: ignore[no-untyped-def]
            seen.append(np.array(init))
            super().__init__(*a, init=init, **k)

    planner.optimizer_cls = Spy
    task = fleet3.tasks[0]
    table = ReservationTable(fleet3.bounds.lo, fleet3.bounds.hi, fleet3.uav.s2)
    P = np.linspace(task.start, task.goal, 12)
    P[1:-1, 2] = fleet3.ground(P[1:-1, 0], P[1:-1, 1]) + 150.0
    rng = np.random.default_rng(0)
    _, last, _ = planner._low_level(fleet3, task, table, P, None, 0, 2, 10, rng)
    enc = CartesianEncoding(separated_problem(fleet3, task, table), 10)
    P_gene = enc.encode(P[None])[0]
    init = seen[0]
    np.testing.assert_allclose(init[0], P_gene)
    span = enc.upper - enc.lower
    assert np.all(np.abs(init[1:] - P_gene) <= 0.1 * span + 1e-9)
    assert np.all(np.abs(init[1:] - P_gene).max(axis=0) > 0.01 * span)  # really randomized
    planner._low_level(fleet3, task, table, P, last, 1, 2, 10, rng)
    init2 = seen[1]
    n_rand = int(0.25 * 20)
    np.testing.assert_array_equal(init2[n_rand:], last[n_rand:])
    assert not np.any(np.all(init2[:n_rand] == last[:n_rand], axis=1))


def test_shortcut_drops_waypoints_only_where_the_straight_segment_is_clear() -> None:
    from uavplan.problems.path_problem import PathProblem
    from uavplan.problems.validity import greedy_shortcut
    from uavplan.world.reservations import ReservationTable

    base = resolve("ppswarm1")
    (cx, cy), rad = base.cylinders[0].center, base.cylinders[0].radius
    xy = np.array([[cx - 2.5 * rad, cy], [cx - rad, cy + 1.6 * rad], [cx, cy + 1.8 * rad],
                   [cx + rad, cy + 1.6 * rad], [cx + 2.5 * rad, cy]])  # fmt: skip
    z = float(np.max(base.ground(xy[:, 0], xy[:, 1]))) + 120.0
    wp = np.column_stack([xy, np.full(len(xy), z)])
    tasks = (Task("a", tuple(wp[0]), tuple(wp[-1])),)
    sc = base.__class__(**{**base.__dict__, "tasks": tasks})
    table = ReservationTable(np.asarray(sc.bounds.lo), np.asarray(sc.bounds.hi), sc.uav.s2)
    problem = PathProblem(sc, tasks[0], strict_altitude=True, reservations=table)
    assert problem.evaluate(wp[None]).feasible[0]  # the detour itself is clear
    assert not problem.evaluate(wp[[0, -1]][None]).feasible[0]  # the straight line is not
    t = np.cumsum(np.r_[0.0, np.linalg.norm(np.diff(wp, axis=0), axis=1)]) / sc.uav.speed
    w2, t2, _ = greedy_shortcut(problem.validator, wp, t)
    assert t2 is not None
    assert np.array_equal(w2[0], wp[0]) and np.array_equal(w2[-1], wp[-1])
    assert 2 < len(w2) < len(wp)  # the collinear-ish middle goes, the detour stays
    assert problem.evaluate(w2[None]).feasible[0]
    assert set(map(float, t2)) <= set(map(float, t))  # kept poses keep their planned times
    # a UAV reserved on the shortcut's segment forbids it
    mid = 0.5 * (w2[0] + w2[1])
    tm = float(np.interp(0.5, [0, 1], t2[:2]))
    up = np.array([0.0, 0.0, 50.0])
    table.add("other", np.stack([mid - up, mid + up]), np.array([tm - 2.5, tm + 2.5]))
    w3, _, _ = greedy_shortcut(problem.validator, wp, t)
    assert not np.array_equal(w3[:2], w2[:2])


@pytest.mark.parametrize("planner", ["ppswarm", "pso"])
@pytest.mark.parametrize("turn_radius", [0.0, 2.0])
def test_2d_fleets_fly_what_they_plan(planner: str, turn_radius: float) -> None:
    """A 2-D fleet (PPSwarm, or a single-UAV planner in the prioritized frame): polylines
    without a turn radius, Dubins flights with one; the verdict is the verifier's."""
    sc = resolve("simple2d")
    uav = dataclasses.replace(sc.uav, s1=2.0, s2=3.0, turn_radius=turn_radius)
    sc = with_fleet(dataclasses.replace(sc, uav=uav), 4, seed=0, min_spacing=6.0)
    fp = plan_all(sc, get_planner(planner, pop_size=60), 60, 0)
    assert fp.fleet is not None and fp.fleet.info["separated"] == "flights"
    want = "smoothed" if turn_radius else "polyline"
    assert all(r.flown_kind == want for r in fp.results)
    d = plan_document(fp)
    rep = verify_plan(d, sc)
    assert rep.ok == fp.feasible == all(r.flown_feasible for r in fp.results)
    assert sum(r.flown_feasible for r in fp.results) >= 3
    for r in fp.results:
        assert np.asarray(r.flown_trajectory()[0]).shape[1] == 2


def test_blocked_flight_waits_on_the_ground_before_replanning(monkeypatch, fleet3) -> None:
    """In-loop, a UAV whose flights are all blocked tries, for each later take-off, first its
    best candidates re-timed (no new low-level run), then a re-plan from there; the wait is
    what the plan declares and the verifier checks."""
    import uavplan.planners.fleet.prioritized as pr

    real_fly, real_low = pr.fly, pr.PrioritizedPlanner._low_level
    lows: list[float] = []

    def blocked_fly(scenario, task, waypoints, times, *a, **k):  # type: ignore[no-untyped-def]
        f = real_fly(scenario, task, waypoints, times, *a, **k)
        if task.id == "uav1" and float(np.asarray(times)[0]) < 10.0:
            f = dataclasses.replace(f, violations=("separation: blocked by the test",))
        return f

    def counting_low(self, scenario, task, *args):  # type: ignore[no-untyped-def]
        lows.append(task.start_time)
        return real_low(self, scenario, task, *args)

    monkeypatch.setattr(pr, "fly", blocked_fly)
    monkeypatch.setattr(pr.PrioritizedPlanner, "_low_level", counting_low)
    r = get_planner("ppswarm", **{**SMALL, "n_restart": 1}, delay_step=5.0).plan_fleet(
        fleet3, seed=0
    )
    u1 = next(x for x in r.results if x.uav_id == "uav1")
    assert r.info["delayed"] == {"uav1": 10.0} and u1.info["rescue"] == "wait"
    # 5 s: the candidates re-timed are still blocked, and so is a re-plan from 5 s; 10 s:
    # the candidates re-timed pass, with no new low-level run
    assert sorted(lows) == [0.0, 0.0, 0.0, 5.0]
    assert u1.times[0] == pytest.approx(10.0) and u1.flown_trajectory()[1][0] == pytest.approx(10.0)
    assert r.info["flights"]["rescue"]["wait"] == 1
    d = plan_document(FleetPlan(fleet3, "ppswarm", {}, 0, r.results, r))
    assert r.flown_feasible and verify_plan(d, fleet3).ok


def test_a_fleet_whose_smoothing_fails_is_declared_and_verified_as_it_would_fly() -> None:
    """A turn radius of 150 m among ppswarm2's cylinders: some UAVs' flights cannot keep clear.
    The plan says so (not feasible, those UAVs named), the verifier fails exactly those UAVs'
    declared flights, and the UAVs the plan calls ok pass it together."""
    from uavplan.io.plan_file import parse_plan
    from uavplan.verify import verify_trajectories

    base = resolve("ppswarm2")
    uav = dataclasses.replace(base.uav, turn_radius=150.0)
    sc = with_fleet(dataclasses.replace(base, uav=uav), 6, seed=1)
    opts = {**SMALL, "n_restart": 1, "max_delays": 1}
    fr = get_planner("ppswarm", **opts).plan_fleet(sc, seed=0)
    bad = {r.uav_id for r in fr.results if not r.flown_feasible}
    assert bad and not fr.flown_feasible and len(bad) < len(fr.results)
    d = plan_document(FleetPlan(sc, "ppswarm", {}, 0, fr.results, fr))
    assert d["feasible"] is False
    rep = verify_plan(d, sc)
    assert not rep.ok
    own = {u for v in rep.violations if v.kind != "separation" for u in v.uavs}
    assert own <= bad  # no UAV the plan calls ok breaks a check of its own
    assert all(set(v.uavs) & bad for v in rep.violations if v.kind == "separation")
    good = [t for t in parse_plan(d).trajectories("flown") if t.id not in bad]
    rep_ok = verify_trajectories(good, sc, sc.name, kinematics=True, trajectory="flown")
    assert rep_ok.ok, [v.message for v in rep_ok.violations][:3]


def test_fleet_keeps_a_per_axis_separation_as_flown() -> None:
    """With ``uav.s2_axes`` the planner's reservation table and the verifier both use the box
    (the RSCDWOA paper's per-axis minimal distance); a fleet called feasible passes it."""
    base = with_fleet(resolve("ppswarm2"), 5, seed=2)
    sc = dataclasses.replace(base, uav=dataclasses.replace(base.uav, s2_axes=(30.0, 30.0, 8.0)))
    r = get_planner("ppswarm", **{**SMALL, "n_restart": 1}).plan_fleet(sc, seed=3)
    rep = verify_plan(plan_document(FleetPlan(sc, "ppswarm", {}, 3, r.results, r)), sc)
    assert rep.s2_axes == (30.0, 30.0, 8.0) and rep.s2 == 30.0
    if r.flown_feasible:
        assert rep.ok, [v.message for v in rep.violations]
        assert rep.min_separation >= 30.0 - 1e-6
    bad_uavs = {u for v in rep.violations for u in v.uavs if v.kind != "separation"}
    assert not bad_uavs & {x.uav_id for x in r.results if x.feasible}


def test_rrt_seeding_steps_in_proportion_to_a_large_map() -> None:
    """On ``rscdwoa-static`` (100 km across, goals 90 km off) PPSwarm's RRT* seeding with its
    lengths scaled to the map finds every UAV a path; the 50 m default step finds none. On
    the PPSwarm maps the scaled lengths are the defaults."""
    from uavplan.planners.sampling.rrt_star import RRTStarConfig, map_scaled_lengths

    sc = resolve("rscdwoa-static")
    _, found = get_planner("ppswarm")._initial_paths(sc, 10, np.random.SeedSequence(0))
    assert found == [True] * len(sc.tasks)
    planner = get_planner("ppswarm", rrt_iterations=1000, rrt_params={"step": 50.0})
    assert planner._initial_paths(sc, 10, np.random.SeedSequence(0))[1] == [False] * 4
    d = RRTStarConfig()
    assert map_scaled_lengths(resolve("ppswarm1")) == {
        "step": d.step,
        "goal_radius": d.goal_radius,
        "near_radius": d.near_radius,
    }
