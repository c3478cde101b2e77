"""The execution model: windows, the widened world, and the reservation table's separation under
take-off and speed errors, tested against brute force: sampled executions (never closer than
the table says) and a dense grid of the pairs of path times whose windows meet (the table's
bound is attained)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.io.plan_file import Trajectory
from uavplan.scenarios import resolve
from uavplan.verify.kinematics import heights_in_wind
from uavplan.world.dynamic import MovingObstacle, min_distances, robust_min_distances
from uavplan.world.execution import (
    DEFAULT,
    NOMINAL,
    ExecutionModel,
    default_for,
    height_lag,
    reach_rise,
    slope_wind,
    widened,
    windows,
)
from uavplan.world.reservations import ReservationTable, _split, window_min_dist2
from uavplan.world.terrain import Terrain


def _traj(rng: np.random.Generator, n: int = 7) -> tuple[np.ndarray, np.ndarray]:
    p = np.cumsum(rng.uniform(-40, 40, (n, 3)), axis=0) + 200.0
    dt = rng.uniform(0.5, 4.0, n - 1)
    dt[rng.random(n - 1) < 0.15] = rng.uniform(0.2, 2.0)  # some holds below
    t = rng.uniform(0, 10) + np.concatenate([[0.0], np.cumsum(dt)])
    hold = rng.random(n - 1) < 0.1
    for k in np.flatnonzero(hold):
        p[k + 1] = p[k]
    return p, t


def _at(p: np.ndarray, t: np.ndarray, when: np.ndarray) -> np.ndarray:
    return np.stack([np.interp(when, t, p[:, k]) for k in range(3)], axis=-1)


def _execute(p, t, d, s, grid):
    """Positions at the actual times ``grid`` of an execution: take-off ``d`` late, segment
    speed factors ``s``; outside the flight (before take-off, after landing) NaN."""
    actual = t[0] + d + np.concatenate([[0.0], np.cumsum(np.diff(t) / s)])
    pos = _at(p, actual, grid)
    pos[(grid < actual[0]) | (grid > actual[-1])] = np.nan
    return pos


def test_a_model_says_what_it_is_and_refuses_nonsense() -> None:
    assert NOMINAL.nominal and not DEFAULT.nominal and DEFAULT.timed
    assert DEFAULT.record()["takeoff_s"] == 2.0 and ExecutionModel.from_record(
        DEFAULT.record()) == DEFAULT  # fmt: skip
    assert DEFAULT.tracking_gap() == pytest.approx(np.hypot(6.0, 4.0))
    assert "take-off ±2 s" in DEFAULT.describe()
    for bad in ({"speed": 0.6}, {"takeoff_s": -1.0}, {"track_h": float("nan")}):
        with pytest.raises(ValueError, match="execution"):
            ExecutionModel(**bad)  # type: ignore[arg-type]
    assert ExecutionModel(speed=0.03, wind=2.0).rho(20.0) == pytest.approx(0.13)
    lo, hi = windows(10.0, 2.0, 0.05, np.array([10.0, 30.0]))
    assert lo[0] == 8.0 and hi[0] == 12.0 and lo[1] == pytest.approx(8 + 20 / 1.05)


def test_the_widened_world_keeps_every_clearance_wider() -> None:
    sc = resolve("ppswarm1")
    w = widened(sc, DEFAULT)
    assert w.execution is DEFAULT
    assert all(b.margin == a.margin + 3.0 for a, b in zip(sc.cylinders, w.cylinders, strict=True))
    assert sc.altitude is not None and w.altitude is not None
    # a band above the ground follows the terrain's grids, each moved by e_v (not twice)
    assert (w.altitude.min, w.altitude.max) == (sc.altitude.min, sc.altitude.max)
    assert sc.terrain is not None and w.terrain is not None
    assert (sc.terrain.x0, sc.terrain.y0, sc.terrain.dx, sc.terrain.dy) == (1, 1, 1, 1)
    rise = reach_rise(sc.terrain.heights, sc.terrain.dx, sc.terrain.dy, 3.0)
    fall = reach_rise(sc.terrain.heights, sc.terrain.dx, sc.terrain.dy, 3.0, up=False)
    x, y = 501.0, 501.0  # node (500, 500)
    g = float(sc.terrain.height(x, y))
    up, down = 2.0 + float(rise[500, 500]), 2.0 + float(fall[500, 500])  # node (500, 500)
    for dz, ok in ((sc.altitude.min + up - 0.1, False), (sc.altitude.min + up + 0.1, True),
                   (sc.altitude.max - down - 0.1, True),
                   (sc.altitude.max - down + 0.1, False)):  # fmt: skip
        why = [w_ for w_ in w.point_problems(np.array([x, y, g + dz])) if "band" in w_]
        assert (not why) == ok, (dz, why)
    op = resolve("open")  # an absolute band over no terrain is narrowed itself
    wo = widened(op, DEFAULT)
    assert op.altitude is not None and wo.altitude is not None
    assert (wo.altitude.min, wo.altitude.max) == (op.altitude.min + 2, op.altitude.max - 2)
    assert np.array_equal(w.terrain.heights, sc.terrain.heights + 2.0 + rise)
    assert np.array_equal(w.terrain.ceiling_heights, sc.terrain.heights - 2.0 - fall)
    assert (
        w.bounds.lower[0] == sc.bounds.lower[0] + 3 and w.bounds.upper[2] == sc.bounds.upper[2] - 2
    )
    assert widened(sc, NOMINAL).cylinders == sc.cylinders
    tight = ExecutionModel(track_v=60.0)
    with pytest.raises(ValueError, match="altitude band"):
        widened(sc, tight)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), delta0=st.sampled_from([0.0, 0.5, 2.0]),
       rho=st.sampled_from([0.0, 0.03, 0.1]))  # fmt: skip
def test_no_sampled_execution_comes_closer_than_the_table_says(
    seed: int, delta0: float, rho: float
) -> None:
    """Two timed trajectories, one reserved: 300 executions of both (take-off errors and speed
    factors drawn, extreme ones among them) are never closer at any instant of a fine grid than
    the table's minimum under the model; and a dense grid of the pairs of path times whose
    windows meet finds the table's minimum (within the grid's resolution)."""
    rng = np.random.default_rng(seed)
    if not (delta0 or rho):
        delta0 = 0.25
    pa, ta = _traj(rng)
    pb, tb = _traj(rng)
    table = ReservationTable(np.zeros(3) - 500, np.zeros(3) + 900, 500.0, timing=(delta0, rho))
    table.add("b", pb, tb)
    bound = float(table.min_distance(pa[None], ta[None])[0])
    lo = min(ta[0], tb[0]) - delta0 - 1
    hi = max(ta[-1], tb[-1]) * 1.2 + delta0 + 1
    grid = np.linspace(lo, hi, 4000)
    least = np.inf
    for _ in range(300):
        ends = rng.random() < 0.3
        da, db = rng.uniform(-delta0, delta0, 2) if not ends else rng.choice([-delta0, delta0], 2)
        sa = (rng.uniform(1 - rho, 1 + rho, len(ta) - 1) if not ends
              else rng.choice([1 - rho, 1 + rho], len(ta) - 1))  # fmt: skip
        sb = (rng.uniform(1 - rho, 1 + rho, len(tb) - 1) if not ends
              else rng.choice([1 - rho, 1 + rho], len(tb) - 1))  # fmt: skip
        d = np.linalg.norm(_execute(pa, ta, da, sa, grid) - _execute(pb, tb, db, sb, grid), axis=1)
        if np.isfinite(d).any():
            least = min(least, float(np.nanmin(d)))
    assert bound <= least + 1e-9
    # the bound is attained: the pairs of path times whose windows meet, on a dense grid
    tau_a, tau_b = np.linspace(ta[0], ta[-1], 900), np.linspace(tb[0], tb[-1], 900)
    la, ha = windows(ta[0], delta0, rho, tau_a)
    lb, hb = windows(tb[0], delta0, rho, tau_b)
    meet = (la[:, None] <= hb[None]) & (lb[None] <= ha[:, None])
    if meet.any():
        dist = np.linalg.norm(_at(pa, ta, tau_a)[:, None] - _at(pb, tb, tau_b)[None], axis=2)
        speed = max(
            np.max(np.linalg.norm(np.diff(p, axis=0), axis=1) / np.maximum(np.diff(t), 1e-9))
            for p, t in ((pa, ta), (pb, tb))
        )
        step = max((ta[-1] - ta[0]) / 899, (tb[-1] - tb[0]) / 899)
        assert bound <= float(dist[meet].min()) + 1e-9
        assert float(dist[meet].min()) - bound <= 2 * speed * step + 1e-6


def test_table_conflicts_agree_with_every_reserved_piece() -> None:
    """The table's bucketed search under a model finds exactly the conflicts a comparison of
    every candidate piece with every reserved piece finds (600 candidate paths)."""
    rng = np.random.default_rng(7)
    bad = 0
    for trial in range(20):
        delta0, rho = [(0.5, 0.0), (2.0, 0.03), (1.0, 0.1)][trial % 3]
        table = ReservationTable(np.zeros(3) - 500, np.zeros(3) + 900, 15.0, timing=(delta0, rho))
        for k in range(8):
            table.add(f"u{k}", *_traj(rng))
        cands = [_traj(rng) for _ in range(30)]
        P = np.array([c[0] for c in cands])
        T = np.array([c[1] for c in cands])
        found = table.conflicts(P, T)
        for q in range(len(P)):
            a0, a1, t0, t1, _ = _split(P[q], T[q], 1.0)
            d2 = min(
                window_min_dist2(a0[i], a1[i], t0[i], t1[i], table._p0[j], table._p1[j],
                                 table._t0[j], table._t1[j], T[q, 0], delta0, rho,
                                 table._take[j], delta0, rho)
                for i in range(len(t0)) for j in range(table.n_pieces)
            )  # fmt: skip
            bad += bool(found[q]) != bool(np.sqrt(d2) < 15.0)
    assert bad == 0


def test_the_timed_index_finds_every_pair_at_any_bucket_and_cell() -> None:
    """A timed table keys its entries by cell, then bucket: over bucket widths from a third of
    a second to 8 s, cells smaller than a piece, take-offs spread over minutes (some before
    time 0), its conflicts and its least distances within the separation equal those of every
    candidate piece against every reserved piece (480 candidate paths)."""
    rng = np.random.default_rng(11)
    bad = 0
    for trial in range(16):
        delta0, rho = [(0.5, 0.0), (2.0, 0.03), (1.0, 0.1), (0.0, 0.05)][trial % 4]
        dt = [0.3, 1.0, 4.0, 8.0][trial // 4]
        sep = 25.0
        table = ReservationTable(np.zeros(3) - 500, np.zeros(3) + 900, sep, dt=dt,
                                 cell=[20.0, 60.0][trial % 2], timing=(delta0, rho))  # fmt: skip
        shift = lambda: rng.choice([-30.0, 0.0, 40.0, 200.0])  # noqa: E731
        for k in range(8):
            p, t = _traj(rng)
            table.add(f"u{k}", p, t + shift())
        cands = [_traj(rng) for _ in range(30)]
        P = np.array([c[0] for c in cands])
        T = np.array([c[1] + shift() for c in cands])
        found = table.conflicts(P, T)
        least = table.min_distance(P, T)
        for q in range(len(P)):
            a0, a1, t0, t1, _ = _split(P[q], T[q], 1.0)
            d = np.sqrt(min(
                window_min_dist2(a0[i], a1[i], t0[i], t1[i], table._p0[j], table._p1[j],
                                 table._t0[j], table._t1[j], T[q, 0], delta0, rho,
                                 table._take[j], delta0, rho)
                for i in range(len(t0)) for j in range(table.n_pieces)
            ))  # fmt: skip
            bad += bool(found[q]) != bool(d < sep)
            if d < sep:
                bad += not abs(least[q] - d) <= 1e-9 * (1.0 + d)
    assert bad == 0


def test_for_scenario_widens_the_separation_by_the_tracking_gap() -> None:
    sc = resolve("ppswarm1")
    assert ReservationTable.for_scenario(sc).separation == sc.uav.s2
    t = ReservationTable.for_scenario(widened(sc, DEFAULT))
    assert t.timed and t.delta0 == 2.0 and t.rho == pytest.approx(0.03)
    assert t.separation == pytest.approx(sc.uav.s2 + np.hypot(6.0, 4.0))
    box = resolve("rscdwoa-mixed")
    tb = ReservationTable.for_scenario(widened(box, DEFAULT))
    assert tb.axes is None and tb.separation == pytest.approx(np.linalg.norm([56, 56, 24]))
    only = ReservationTable.for_scenario(widened(box, ExecutionModel(track_h=1.0)))
    assert only.axes == (52.0, 52.0, 20.0) and not only.timed


def test_moving_obstacles_under_a_drifting_schedule() -> None:
    o = MovingObstacle(5.0, np.array([0.0, 10.0, 20.0]), np.array([[0, 0, 100], [100, 0, 100],
                                                                  [200, 0, 100]]))  # fmt: skip
    P = np.array([[[80.0, -50, 100], [80.0, 50, 100]]])
    T = np.array([[3.0, 7.0]])
    nominal = min_distances([o], P, T)[0, 0, 0]
    assert robust_min_distances([o], P, T, 0.0, 0.0)[0, 0, 0] == pytest.approx(nominal)
    d1 = robust_min_distances([o], P, T, 1.0, 0.0)[0, 0, 0]
    d3 = robust_min_distances([o], P, T, 3.0, 0.0)[0, 0, 0]
    assert nominal > d1 > d3 == 0.0
    # brute force: the UAV at its path time tau at any actual time within 1 s of it
    tau = np.linspace(3.0, 7.0, 2001)[:, None]
    t = tau + np.linspace(-1.0, 1.0, 2001)[None]
    d = np.hypot(80.0 - np.clip(10.0 * t, 0, 200), -50.0 + 25.0 * (tau - 3.0))
    assert d1 <= d.min() + 1e-9 and d.min() - d1 < 0.05


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), how=st.sampled_from(["height", "slope", "least"]))
def test_the_ground_raised_by_its_reach_stands_above_the_ground_anywhere_within_it(
    seed: int, how: str
) -> None:
    """A horizontal tracking error moves the ground under a UAV: the raised floor (lowered
    ceiling) at any point bounds the original anywhere within the reach (brute force)."""
    rng = np.random.default_rng(seed)
    ny, nx = (int(v) for v in rng.integers(2, 9, 2))
    dx, dy = (float(v) for v in rng.uniform(0.3, 40.0, 2))
    H = rng.normal(0.0, 5.0, (ny, nx))
    reach = float(rng.uniform(0.0, 12.0))
    T = Terrain(H, 0.0, 0.0, dx, dy)
    hi = Terrain(H + reach_rise(H, dx, dy, reach, how=how), 0.0, 0.0, dx, dy)
    lo = Terrain(H - reach_rise(H, dx, dy, reach, up=False, how=how), 0.0, 0.0, dx, dy)
    for _ in range(100):
        p = rng.uniform([-3.0, -3.0], [dx * (nx - 1) + 3, dy * (ny - 1) + 3])
        a, d = rng.uniform(0, 2 * np.pi), rng.uniform(0, reach)
        q = p + d * np.array([np.cos(a), np.sin(a)])
        assert hi.height(*p) >= T.height(*q) - 1e-9
        assert lo.height(*p) <= T.height(*q) + 1e-9


def test_the_default_takes_a_named_airframes_calibrated_tracking_error() -> None:
    from types import SimpleNamespace

    from uavplan.world.airframes import AIRFRAMES
    from uavplan.world.execution import default_for

    assert default_for(SimpleNamespace(airframe=None, turn_radius=20.0)) is DEFAULT
    for af in AIRFRAMES.values():
        m = default_for(SimpleNamespace(airframe=af.name, speed=20.0, v_max=20.0))
        assert (m.takeoff_s, m.speed) == (DEFAULT.takeoff_s, DEFAULT.speed)
        assert m.track_h == max(3.0, af.track_h) and m.track_v == max(2.0, af.track_v)
        assert af.name in m.source or m is DEFAULT
        assert m.wind == 0.0  # every built-in airframe has the speed to spare for the wind


def test_a_larger_fleet_states_a_larger_tracking_error() -> None:
    """The stated error is the quantile a flight exceeds with probability 0.1 / n on the
    calibration's exponential tail above its 95th percentile, rounded up to half a metre,
    never below the airframe's 99th percentile (a fleet of up to ten); checked against the
    tail's own exceedance probability and by hand."""
    from dataclasses import replace
    from types import SimpleNamespace

    from uavplan.world.airframes import FLEET_ALPHA, SMALL_FIXED_WING, fleet_tracking

    af = replace(SMALL_FIXED_WING, track_h=6.0, track_v=8.0, tail_h=(3.5, 0.5),
                 tail_v=(6.0, 0.8))  # fmt: skip
    assert fleet_tracking(af, 1) == fleet_tracking(af, 10) == (6.0, 8.0)
    # 1,000 UAVs: u + scale * ln(0.05 * 1000 / 0.1): 3.5 + 3.11 = 6.61 -> 7.0;
    # 6.0 + 4.97 = 10.97 -> 11.0
    assert fleet_tracking(af, 1000) == (7.0, 11.0)
    for n in (40, 100, 500, 1000, 5000):
        h, v = fleet_tracking(af, n)
        for x, base, (u, scale) in ((h, 6.0, af.tail_h), (v, 8.0, af.tail_v)):

            def beyond(e: float, u: float = u, scale: float = scale, n: int = n) -> float:
                """The fleet's expected flights beyond ``e`` on the tail."""
                return n * 0.05 * math.exp(-(e - u) / scale)

            assert beyond(x) <= FLEET_ALPHA + 1e-12
            assert x == base or beyond(x - 0.5) > FLEET_ALPHA  # half a metre less would not do
    assert fleet_tracking(af, 500) <= fleet_tracking(af, 1000)
    assert fleet_tracking(replace(af, tail_h=None, tail_v=None), 1000) == (6.0, 8.0)
    uav = SimpleNamespace(airframe=af.name, speed=20.0, v_max=20.0)
    from uavplan.world import airframes

    saved = airframes.AIRFRAMES[af.name]
    airframes.AIRFRAMES[af.name] = af
    try:
        small, big = default_for(uav, 5), default_for(uav, 1000)
    finally:
        airframes.AIRFRAMES[af.name] = saved
    assert (small.track_h, small.track_v) == (6.0, 8.0) and "fleet" not in small.source
    assert (big.track_h, big.track_v) == (7.0, 11.0) and "for a fleet of 1000" in big.source


def test_a_fixed_wing_without_speed_to_spare_plans_for_the_wind(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The default model's wind is the calibration's wind the airframe cannot make up by
    flying faster (or slower) than planned: with none to spare, all of it (a headwind makes it
    late, a tailwind early)."""
    from dataclasses import replace
    from types import SimpleNamespace

    from uavplan.world.airframes import QUADROTOR, SMALL_FIXED_WING, top_speed
    from uavplan.world.execution import default_for

    uav = SimpleNamespace(airframe="small-fixed-wing", speed=20.0, v_max=20.0)
    assert top_speed(SMALL_FIXED_WING, uav) == pytest.approx(26.0)
    assert top_speed(SMALL_FIXED_WING, SimpleNamespace(speed=20.0, v_max=30.0)) == 30.0
    from uavplan.world.airframes import AIRFRAMES

    tight = replace(SMALL_FIXED_WING, speed_margin=0.05)  # 1 m/s to spare at 20 m/s
    monkeypatch.setitem(AIRFRAMES, "small-fixed-wing", tight)
    m = default_for(uav)
    assert m.wind == pytest.approx(tight.turn_wind - 1.0)
    assert m.rho(20.0) == pytest.approx(0.03 + 2.0 / 20.0)
    monkeypatch.setitem(AIRFRAMES, "small-fixed-wing", replace(tight, speed_margin=0.0))
    assert default_for(uav).wind == pytest.approx(tight.turn_wind)
    # a multirotor's controller holds its ground velocity: no wind share
    assert default_for(SimpleNamespace(airframe=QUADROTOR.name, speed=10.0, v_max=10.0)).wind == 0
    # a fixed wing that cannot fly slower than planned runs early with the wind behind it:
    # RSCDWOA's UAV of one airspeed (50-50 m/s) gets the whole wind, one with 1 m/s below its
    # cruise the rest, one with room both ways none
    fast = SimpleNamespace(airframe="fast-fixed-wing", speed=50.0, v_max=50.0, min_speed=50.0)
    assert default_for(fast).wind == pytest.approx(AIRFRAMES["fast-fixed-wing"].turn_wind)
    assert default_for(fast).rho(50.0) == pytest.approx(0.03 + 3.0 / 50.0)
    near = SimpleNamespace(airframe="fast-fixed-wing", speed=50.0, v_max=50.0, min_speed=49.0)
    assert default_for(near).wind == pytest.approx(AIRFRAMES["fast-fixed-wing"].turn_wind - 1.0)
    free = SimpleNamespace(airframe="fast-fixed-wing", speed=50.0, v_max=50.0, min_speed=40.0)
    assert default_for(free).wind == 0


def test_default_plans_turn_no_tighter_than_the_airframe_flies_in_wind() -> None:
    from uavplan.scenarios import resolve
    from uavplan.world.airframes import (
        SMALL_FIXED_WING,
        l1_distance,
        planned_turn_radius,
        turn_radius_in_wind,
    )
    from uavplan.world.execution import flyable_turns

    sc = resolve("ppswarm1@4")
    banked = turn_radius_in_wind(SMALL_FIXED_WING, float(sc.uav.speed))
    # 23 m/s over the ground at a 65 degree bank: 25.2 m, above the scenario's 20 m
    assert banked == pytest.approx(23.0**2 / (9.80665 * np.tan(np.radians(65.0))))
    # and the L1 guidance at 23 m/s (6 s period, 0.75 damping) aims 32.9 m ahead: the larger
    r = l1_distance(SMALL_FIXED_WING, 23.0)
    assert r == pytest.approx(0.75 * 6.0 * 23.0 / np.pi) and r > banked
    assert planned_turn_radius(SMALL_FIXED_WING, float(sc.uav.speed)) == pytest.approx(r)
    # a quicker guidance (a 3 s period) leaves the bank limit the binding one
    quick = dataclasses.replace(SMALL_FIXED_WING, l1_period=3.0)
    assert planned_turn_radius(quick, 20.0) == pytest.approx(banked)
    wider, planned = flyable_turns(sc)
    assert planned == pytest.approx(r) and wider.uav.turn_radius == pytest.approx(r) and r > 20.0
    from uavplan.strategy.world import planning_world

    line = planning_world(sc, "ppswarm1@4").turns_line()
    assert line is not None and line.startswith("turns planned at 32.9 m radius, not 20 m")
    assert "L1 guidance's look-ahead at 23 m/s" in line and "allows 25.2 m" in line
    assert wider.uav.speed == sc.uav.speed and wider.tasks == sc.tasks
    # a UAV that names no airframe keeps its turns
    unnamed = dataclasses.replace(sc, uav=dataclasses.replace(sc.uav, airframe=None))
    assert flyable_turns(unnamed) == (unnamed, 0.0)
    assert turn_radius_in_wind(SMALL_FIXED_WING, 20.0, wind=0.0) < 20.0


def test_a_multirotor_plans_its_corners_as_curves_it_flies_at_speed() -> None:
    """A multicopter's mission slows down for a corner; uavplan's default plans its corners as
    curves of radius v^2 / turn_accel, which it flies at its cruise speed."""
    from uavplan.scenarios import resolve
    from uavplan.world.airframes import QUADROTOR, planned_turn_radius
    from uavplan.world.execution import flyable_turns

    sc = resolve("quadrotors@4")
    assert float(sc.uav.turn_radius) == 0.0 and sc.uav.airframe == "quadrotor"
    wider, r = flyable_turns(sc)
    assert r == pytest.approx(10.0**2 / QUADROTOR.turn_accel)
    assert wider.uav.turn_radius == pytest.approx(r) and wider.uav.speed == sc.uav.speed
    assert planned_turn_radius(dataclasses.replace(QUADROTOR, turn_accel=0.0), 10.0) == 0.0
    # a fixed wing whose scenario sets no turn radius keeps none
    fw = dataclasses.replace(sc, uav=dataclasses.replace(sc.uav, airframe="small-fixed-wing"))
    assert flyable_turns(fw) == (fw, 0.0)


def test_a_fixed_wing_plans_no_slower_than_it_flies_with_the_wind_behind_it() -> None:
    """Its slowest ground speed with ``turn_wind`` behind it is its minimum airspeed plus the
    wind: uavplan's default plans no slower (a multirotor, or a UAV whose minimum is its
    cruise speed, keeps the scenario's)."""
    from uavplan.world.airframes import SMALL_FIXED_WING
    from uavplan.world.execution import flyable_speeds

    sc = resolve("ppswarm1@4")
    faster, v = flyable_speeds(sc)
    assert v == pytest.approx(float(sc.uav.min_speed) + SMALL_FIXED_WING.turn_wind) and v < 20
    assert faster.uav.min_speed == pytest.approx(v) and faster.uav.speed == sc.uav.speed
    assert flyable_speeds(resolve("quadrotors@4"))[1] == 0.0
    assert flyable_speeds(resolve("rscdwoa-static"))[1] == 0.0  # min speed = cruise: no room


def test_a_fixed_wing_lags_its_plan_where_it_descends_steeper_than_it_flies_in_wind() -> None:
    """A 28.6 degree descent at 13 m/s over the ground with 3 m/s behind: flown at 10 m/s
    through the air at the 30 degree limit, it descends at most 10/13 tan 30 over the ground,
    so it falls behind by the difference per metre, and a level leg after it gives that back
    at the same rate (never below the plan); in still air, or within the limit, no lag."""
    g = math.tan(math.radians(28.6))
    w = 10.0 / 13.0 * math.tan(math.radians(30.0))
    x = np.array([0.0, 100.0, 500.0, 550.0, 900.0])
    z = np.array([300.0, 300.0, 300.0 - 400.0 * g, 300.0 - 400.0 * g, 300.0 - 400.0 * g])
    p = np.column_stack([x, np.zeros_like(x), z])
    t = x / 13.0
    off = height_lag(p[None], t[None], 3.0, 30.0, 30.0)[0]
    lag = 400.0 * (g - w)
    assert off == pytest.approx([0.0, 0.0, lag, lag - 50.0 * w, 0.0])
    assert not height_lag(p[None], t[None], 0.0, 30.0, 30.0).any()  # still air: 30 degrees
    assert height_lag(p[None], t[None], 3.0, None, None) == pytest.approx(0.0)
    climb = p * np.array([1.0, 1.0, -1.0]) + np.array([0.0, 0.0, 600.0])  # the mirror image
    assert height_lag(climb[None], t[None], 3.0, 30.0, 30.0)[0] == pytest.approx(-off)


def test_a_flights_lag_extent_is_its_largest_lag_and_each_segments_larger_end() -> None:
    """The descent above: the largest ``|lag|`` of the flight and per segment the larger of
    its ends' (the lag's extremes lie at the points); a lag within ``LAG_TOL`` counts as none."""
    from uavplan.world.execution import lag_extents
    from uavplan.world.tolerances import LAG_TOL

    g = math.tan(math.radians(28.6))
    x = np.array([0.0, 100.0, 500.0, 550.0, 900.0])
    z = np.array([300.0, 300.0, 300.0 - 400.0 * g, 300.0 - 400.0 * g, 300.0 - 400.0 * g])
    p = np.column_stack([x, np.zeros_like(x), z])[None]
    t = (x / 13.0)[None]
    off = np.abs(height_lag(p, t, 3.0, 30.0, 30.0))[0]
    top, seg = lag_extents(p, t, 3.0, 30.0, 30.0)
    assert top[0] == pytest.approx(off.max()) and off.max() > 30.0
    assert seg[0] == pytest.approx(np.maximum(off[:-1], off[1:]))
    shallow = p.copy()
    shallow[0, 2:, 2] = 300.0 - 400.0 * math.tan(math.radians(23.9)) - LAG_TOL / 2
    top, seg = lag_extents(shallow, t, 3.0, 30.0, 30.0)
    assert top[0] == 0.0 and not seg.any()


@given(st.integers(0, 2**31 - 1))
@settings(max_examples=25, deadline=None)
def test_the_height_lag_is_a_finely_stepped_pursuit_of_the_plan(seed: int) -> None:
    """Against brute force: a UAV stepped every few centimetres along random timed 3-D paths,
    each step changing height toward the plan's as far as its slope over the ground allows
    there; a population at once is each path alone, and the verifier's own walk
    (:func:`uavplan.verify.kinematics.heights_in_wind`) is the same."""
    rng = np.random.default_rng(seed)
    pop, n, wind = 3, 6, float(rng.uniform(0.0, 5.0))
    p = np.zeros((pop, n, 3))
    p[:, 1:, :2] = np.cumsum(rng.uniform(20.0, 120.0, (pop, n - 1, 2)), axis=1)
    p[:, :, 2] = 300.0 + np.cumsum(rng.uniform(-60.0, 60.0, (pop, n)), axis=1)
    L = np.hypot(*np.diff(p[..., :2], axis=1).transpose(2, 0, 1))
    t = np.concatenate([np.zeros((pop, 1)), np.cumsum(L / rng.uniform(8.0, 20.0, L.shape), 1)], 1)
    off = height_lag(p, t, wind, 25.0, 35.0)
    for i in range(pop):
        assert off[i] == pytest.approx(height_lag(p[i : i + 1], t[i : i + 1], wind, 25.0, 35.0)[0])
        own = heights_in_wind(Trajectory("u", p[i], t[i]), wind, 25.0, 35.0)  # the verifier's
        assert off[i] == pytest.approx(own, abs=1e-9)
        zu, want = p[i, 0, 2], [0.0]
        for k in range(n - 1):
            v = L[i, k] / (t[i, k + 1] - t[i, k])
            share = max(v - wind, 0.0) / v
            up, down = share * math.tan(math.radians(25)), share * math.tan(math.radians(35))
            m = 4000
            ds = L[i, k] / m
            for j in range(1, m + 1):
                zp = p[i, k, 2] + (p[i, k + 1, 2] - p[i, k, 2]) * j / m
                zu += min(max(zp - zu, -down * ds), up * ds)
            want.append(zu - p[i, k + 1, 2])
        assert off[i] == pytest.approx(want, abs=0.02)  # the steps: 4,000 a segment


def test_a_step_straight_up_is_flown_as_a_gap_by_both_walks() -> None:
    """No height changes without a distance flown: a vertical step opens the whole step as a
    gap, which the next level leg closes at the UAV's slope (both implementations)."""
    p = np.array([[0.0, 0, 100], [0.0, 0, 120], [400.0, 0, 120]])
    t = np.array([0.0, 1.0, 31.0])
    want = [0.0, -20.0, min(-20.0 + 400 * math.tan(math.radians(30)) * (1 - 3 / (400 / 30)), 0)]
    assert height_lag(p[None], t[None], 3.0, 30.0, 30.0)[0] == pytest.approx(want)
    assert heights_in_wind(Trajectory("u", p, t), 3.0, 30.0, 30.0) == pytest.approx(want)


def test_the_wind_a_flights_heights_are_checked_in() -> None:
    """A named fixed wing under a model: its calibration's wind (or the model's, if larger);
    nominal, a multirotor, or a UAV without an airframe: none."""
    sc = resolve("ppswarm1@4")
    model = default_for(sc.uav)
    assert slope_wind(sc.uav, model) == pytest.approx(3.0)
    assert slope_wind(sc.uav, model.record()) == pytest.approx(3.0)
    assert slope_wind(sc.uav, dataclasses.replace(model, wind=5.0)) == pytest.approx(5.0)
    assert slope_wind(sc.uav, NOMINAL) == 0.0 and slope_wind(sc.uav, None) == 0.0
    q = resolve("quadrotors@4")
    assert slope_wind(q.uav, default_for(q.uav)) == 0.0
    assert slope_wind(dataclasses.replace(sc.uav, airframe=None), DEFAULT) == 0.0


def test_an_airframe_whose_tracking_error_is_not_calibrated_is_planned_loudly(
    tmp_path, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    """An airframe whose tracking error is not calibrated on its plans' flights (no fitted
    tail; the fast fixed wing with the figures it had before its calibration, here):
    `uavplan plan` of its fleet under uavplan's default model says so in the model's source,
    warns on the console and exits 1 (the plan written); the built-in airframes, calibrated,
    say they are; a scenario that states its model (the built-in, nominal) is not warned."""
    from typer.testing import CliRunner

    from uavplan.cli import app
    from uavplan.scenarios import builtin_path
    from uavplan.world import airframes as A
    from uavplan.world.execution import UNCALIBRATED, default_for

    for ref, n in (("ppswarm1", 40), ("rscdwoa-mixed", 4), ("quadrotors", 40)):
        assert "calibrated in flight simulation" in default_for(resolve(ref).uav, n).source
    assert all(af.tail_h is not None for af in A.AIRFRAMES.values())
    assumed = dataclasses.replace(A.FAST_FIXED_WING, track_h=8.5, track_v=12.5, tail_h=None,
                                  tail_v=None)  # fmt: skip
    monkeypatch.setitem(A.AIRFRAMES, "fast-fixed-wing", assumed)
    fast = default_for(resolve("rscdwoa-mixed").uav, 4)
    assert UNCALIBRATED in fast.source
    text = builtin_path("rscdwoa-mixed").read_text()
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith("execution:"))
    text = text.replace("goal: [90000, 90000, 1000]", "goal: [90000, 90000, 1020]")
    (tmp_path / "rmix.yaml").write_text(text)
    r = CliRunner().invoke(app, ["plan", str(tmp_path / "rmix.yaml"), "--iterations", "1",
                                 "-o", str(tmp_path / "out")])  # fmt: skip
    assert r.exit_code == 1, r.output
    assert "WARNING: this airframe's tracking error" in r.output
    assert "NOT GUARANTEED as flown" in r.output
    assert (tmp_path / "out" / "plan.json").exists()
    r = CliRunner().invoke(app, ["plan", "rscdwoa-mixed", "--iterations", "1",
                                 "-o", str(tmp_path / "nominal")])  # fmt: skip
    assert "WARNING: this airframe" not in r.output
