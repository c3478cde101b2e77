"""The artificial potential field planner: caught in the cup of ``rscdwoa-static`` as the
classical APF is in the RSCDWOA paper's Fig. 12(a); around a moving obstacle that crosses its
straight line; other UAVs' flights as moving obstacles."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.planners import get_planner
from uavplan.planners.potential.apf import field_params, fly_field
from uavplan.problems.path_problem import PathProblem
from uavplan.scenarios import resolve
from uavplan.world import UAV, Bounds, Scenario, Task
from uavplan.world.dynamic import MovingObstacle
from uavplan.world.reservations import ReservationTable


def test_classical_apf_is_caught_in_the_cup_of_the_static_layout() -> None:
    sc = resolve("rscdwoa-static")
    for task in sc.tasks:
        r = get_planner("apf").plan(sc, task, seed=0)
        assert r.info["status"] == "stalled" and not r.feasible
        assert "local_minimum" in r.violations
        stall = np.asarray(r.info["stall_point"])
        # in the cup: within its 9 km opening around [50, 50] km, short of the obstacles
        assert np.linalg.norm(stall[:2] - [50_000, 50_000]) < 9_000
        assert np.linalg.norm(stall[:2] - task.goal[:2]) > 40_000


def crossing(moving: bool = True) -> Scenario:
    """A 1 km square; the UAV flies west to east at 20 m/s; a disc of radius 40 m crosses its
    straight line from north to south and is at its midpoint when the UAV would be."""
    obs = (MovingObstacle(40.0, [0.0, 50.0], [[500.0, 1000.0], [500.0, 0.0]]),) if moving else ()
    return Scenario(
        "crossing",
        Bounds((0.0, 0.0), (1000.0, 1000.0)),
        (Task("uav0", (10.0, 500.0), (990.0, 500.0)),),
        moving_obstacles=obs,
        uav=UAV(speed=20.0),
        cost="length2d",
    )


def test_apf_gives_way_to_a_moving_obstacle_on_its_straight_line() -> None:
    sc = crossing()
    straight = np.array([[[10.0, 500.0], [990.0, 500.0]]])
    assert not PathProblem(sc).evaluate(straight).feasible[0]  # the straight line collides
    r = get_planner("apf").plan(sc, seed=0)
    assert r.info["status"] == "arrived" and r.feasible, r.violations
    d = sc.moving_obstacles[0].min_distance(r.waypoints[None], r.times[None])
    assert d.min() > 40.0
    # without the obstacle the field leads straight to the goal
    free = get_planner("apf").plan(crossing(moving=False), seed=0)
    assert free.feasible and free.length < 1.01 * 980.0


def test_other_uavs_flights_repel_only_while_they_fly() -> None:
    sc = crossing(moving=False)
    prm = field_params(get_planner("apf").config, sc, 980.0)
    start, goal = np.array([10.0, 500.0]), np.array([990.0, 500.0])
    alone = fly_field(sc, start, goal, prm, 5000)
    # a UAV flying north to south through the midpoint when this one gets there
    other = (np.array([[500.0, 1000.0, 0.0], [500.0, 0.0, 0.0]]), np.array([0.0, 49.0]))
    near = fly_field(sc, start, goal, prm, 5000, others=[other], separation=10.0)
    assert alone.status == near.status == "arrived"
    assert np.abs(alone.points[:, 1] - 500.0).max() < 1e-6  # straight
    assert np.abs(near.points[:, 1] - 500.0).max() > 10.0  # made way
    # the same flight long over (it landed at t = 49 s): no effect
    gone = (other[0], other[1] - 1000.0)
    later = fly_field(sc, start, goal, prm, 5000, others=[gone], separation=10.0)
    np.testing.assert_array_equal(later.points, alone.points)


def test_reservation_table_gives_back_its_trajectories() -> None:
    tab = ReservationTable(np.zeros(3), np.full(3, 1000.0), 10.0, dt=1.0)
    p = np.array([[0.0, 0, 0], [100, 0, 0], [100, 100, 0]])
    t = np.array([0.0, 5.0, 10.0])
    tab.add("a", p, t)
    ((q, s),) = tab.trajectories()
    assert q[0].tolist() == p[0].tolist() and q[-1].tolist() == p[-1].tolist()
    assert s[0] == 0.0 and s[-1] == 10.0 and np.all(np.diff(s) > 0)


def test_fused_apf_escapes_the_cup_that_catches_the_classical_one() -> None:
    from uavplan.planners.potential.apf_fused import curvature

    sc = resolve("rscdwoa-static")
    r = get_planner("rscdwoa-apf", pop_size=10).plan(sc, 0, budget=5, seed=0)
    assert r.info["status"] == "arrived" and r.feasible and r.flown_ok, r.violations
    assert np.allclose(r.waypoints[-1], sc.tasks[0].goal)
    # flown as planned, within the turn radius everywhere
    assert r.flown_kind == "polyline"
    assert curvature(r.waypoints).max() <= 1.0 / sc.uav.turn_radius


@pytest.mark.parametrize("name", ["woa-apf", "rscdwoa-apf"])
def test_fused_apf_fits_the_optimizers_schedule_to_the_run(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sub-goal optimizer's schedule ends with the run: WOA's ``a`` reaches 0 at the
    run's last iteration, not at the optimizer's default t_max of 100."""
    import uavplan.planners.potential.apf_fused as fused

    made = []
    real = fused.get_optimizer

    def spy(opt_name: str) -> type:
        cls = real(opt_name)

        class Spy(cls):  # type: ignore[valid-type, misc]
            def _ask(self) -> np.ndarray:
                X = super()._ask()
                made.append((self.config.max_iterations, float(self.a)))
                return X

        return Spy

    monkeypatch.setattr(fused, "get_optimizer", spy)
    sc = resolve("rscdwoa-static")
    get_planner(name, pop_size=6).plan(sc, 0, budget=6, seed=0)
    assert made and all(t_max == 6 for t_max, _ in made)
    # the t-th move (from 0) has a = 2 - 2 t / 6; at the old t_max of 100 it stayed above 1.9
    assert [a for _, a in made] == pytest.approx([2 - 2 * t / 6 for t in range(len(made))])
    assert made[-1][1] < 1.0
    # an explicit t_max is kept
    made.clear()
    get_planner(name, pop_size=6, optimizer_options={"max_iterations": 50}).plan(
        sc, 0, budget=6, seed=0
    )
    assert made and all(t_max == 50 for t_max, _ in made)


def test_fused_apf_sub_goals_in_a_corridor_and_the_share_that_arrives(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import uavplan.planners.potential.apf_fused as fused

    sc = resolve("rscdwoa-static")
    task = sc.tasks[0]
    a, b = np.asarray(task.start, float), np.asarray(task.goal, float)
    L_h = float(np.linalg.norm((b - a)[:2]))
    seen: list[np.ndarray] = []
    real = fused.fly_field

    def spy(*args: object, **kw: object) -> object:
        seen.append(np.asarray(kw["via"]))
        return real(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(fused, "fly_field", spy)
    r = get_planner("rscdwoa-apf", pop_size=6, subgoal_corridor=0.1).plan(sc, 0, budget=4, seed=0)
    assert r.info["subgoal_corridor_m"] == pytest.approx(0.1 * L_h)
    V = np.concatenate(seen)[:, :2]
    u = (b - a)[:2] / L_h
    off = (V - a[:2]) @ np.array([-u[1], u[0]])  # across the line
    t = (V - a[:2]) @ u / L_h  # along it
    assert np.abs(off).max() <= 0.1 * L_h + 1e-6 and np.abs(off).max() > 0.05 * L_h
    assert t.min() >= -1e-9 and t.max() <= 1 + 1e-9
    shares = r.info["arrived_history"]
    assert shares[0] == 0.0  # the classical APF's own flight: caught in the trap
    assert len(shares) == 1 + len(r.info["fitness_history"]) and all(0 <= x <= 1 for x in shares)


def test_kernel_force_matches_the_numpy_reference() -> None:
    import dataclasses

    from uavplan.planners.potential.apf import force_at, force_reference

    rng = np.random.default_rng(3)
    for name in ("rscdwoa-mixed", "rscdwoa-static", "hrmaga-virtual", "ppswarm1"):
        sc = resolve(name)
        if name == "hrmaga-virtual":  # a moving obstacle over terrain, a band and polygons
            sc = dataclasses.replace(sc, moving_obstacles=resolve("rscdwoa-mixed").moving_obstacles)
        prm = field_params(get_planner("apf").config, sc, 1e4)
        lo, hi = sc.bounds.lo, sc.bounds.hi
        for _ in range(200):
            p = lo + rng.random(sc.dim) * (hi - lo)
            vel = rng.normal(size=sc.dim) * sc.uav.speed
            goal = lo + rng.random(sc.dim) * (hi - lo)
            t = float(rng.uniform(0, 2000))
            a = force_at(sc, prm, p, vel, t, goal)
            b = force_reference(sc, prm, p, vel, t, goal)
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(b).max()))


def test_a_moving_obstacle_with_many_samples_is_found_on_the_right_interval() -> None:
    """The kernel finds a moving obstacle's sample interval by bisection (other UAVs' flights
    have thousands of samples). On a curved, unevenly sampled motion, the force at time t
    must equal the force with only the two samples around t (a wrong interval puts the
    obstacle elsewhere on the curve)."""
    import dataclasses

    from uavplan.planners.potential.apf import force_at

    sc = resolve("rscdwoa-mixed")
    o = sc.moving_obstacles[0]
    rng = np.random.default_rng(8)
    T = np.sort(np.concatenate([[0.0, 1200.0], rng.uniform(0, 1200, 2999)]))
    ang = T / 1200 * np.pi
    P = np.stack([50e3 + 20e3 * np.cos(ang), 50e3 + 20e3 * np.sin(ang), 4000 + 0 * T], axis=1)
    curved = dataclasses.replace(
        sc, moving_obstacles=(dataclasses.replace(o, times=T, positions=P),)
    )
    prm = field_params(get_planner("apf").config, sc, 1e4)
    for t in rng.uniform(1.0, 1199.0, 80):
        k = int(np.searchsorted(T, t, side="right")) - 1
        two = dataclasses.replace(o, times=T[k : k + 2], positions=P[k : k + 2])
        pair = dataclasses.replace(sc, moving_obstacles=(two,))
        near = np.interp(t, T, P[:, 0]), np.interp(t, T, P[:, 1])
        q = np.array([near[0] + rng.normal(0, 2000), near[1] + rng.normal(0, 2000), 4000.0])
        vel = rng.normal(size=3) * sc.uav.speed
        goal = np.array([90e3, 90e3, 0.0])
        a = force_at(curved, prm, q, vel, float(t), goal)
        b = force_at(pair, prm, q, vel, float(t), goal)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(b).max()))
