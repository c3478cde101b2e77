"""The verifier under an execution model: a plan fine as flown exactly but not under the model is
rejected with a record that names the pair and the time; margins have their closed-form values
on a case worked by hand; a fleet planned under the default model meets it, its margins are in
plan.json and on the console, and random executions drawn from the model break nothing."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import Trajectory, read_plan_file
from uavplan.scenarios import resolve
from uavplan.verify import verify_trajectories
from uavplan.verify.executions import sample_fleet
from uavplan.verify.robust import Timing, separation_under
from uavplan.world.execution import DEFAULT, ExecutionModel


def _crossing(gap: float) -> list[Trajectory]:
    """A flies east through (500, 500) at t = 10, B north through it at t = 10 + gap, both at
    20 m/s, 150 m up, taking off at t = 0."""
    t = np.linspace(0.0, 20.0, 41)
    a = np.column_stack([300 + 20 * t, np.full_like(t, 500), np.full_like(t, 150)])
    b = np.column_stack([np.full_like(t, 500), 300 - 20 * gap + 20 * t, np.full_like(t, 150)])
    return [Trajectory("a", a, t), Trajectory("b", b, t)]


def test_a_pair_safe_as_planned_fails_under_the_model_with_its_margin() -> None:
    """Crossing 4 s apart at 20 m/s with S2 = 10 m: apart by 56.6 m at worst when flown exactly.
    With take-off errors of d each, the points at path times u apart can meet when |u| <= 2 d,
    so the least distance is 20 (4 - 2 d) / sqrt 2 and S2 fails beyond d = 2 - 0.25 sqrt 2 =
    1.646 s: the margin the verifier measures."""
    trajs = _crossing(4.0)
    found, margins = separation_under(trajs, 10.0, Timing(2.0, 0.0, 0.0, 0.0))
    assert len(found) == 1 and found[0].kind == "separation" and found[0].uavs == ("a", "b")
    assert "can come" in found[0].message and "take-off ±1.6" in found[0].message
    m = margins[0]
    assert m.takeoff_s == pytest.approx(2 - 0.25 * math.sqrt(2), abs=0.05)
    assert m.distance == pytest.approx(0.0, abs=1e-6)  # d = 2 s makes them meet exactly
    assert 9.0 < m.time < 13.0 and m.where
    _, ok = separation_under(trajs, 10.0, Timing(1.0, 0.0, 0.0, 0.0))
    assert ok[0].ok and ok[0].distance == pytest.approx(20 * 2 / math.sqrt(2), abs=1e-6)
    assert ok[0].takeoff_s == pytest.approx(1.646, abs=0.05)
    # speed error alone: at t = 10 the path times run (10 / 1.03, 10 / 0.97): the margin is
    # where 10 rho / (1 - rho^2) ... leaves room; monotone, and below 30 %
    assert 0.05 < ok[0].speed < 0.3


def test_the_report_carries_the_model_margins_and_typed_records() -> None:
    sc = resolve("open")
    trajs = _crossing(4.0)
    model = ExecutionModel(2.0, 0.0, 0.0, 0.0)
    report = verify_trajectories(trajs, sc, kinematics=False, model=model)
    assert not report.ok and report.model is not None
    assert [v.uavs for v in report.violations if v.kind == "separation"] == [("a", "b")]
    assert {m.uav for m in report.uav_margins} == {"a", "b"}
    assert report.pair_margins[0].takeoff_s == pytest.approx(1.646, abs=0.05)
    nominal = verify_trajectories(trajs, sc, kinematics=False)
    assert nominal.ok and nominal.model is None and not nominal.uav_margins
    d = report.to_dict()
    assert d["format"] == "uavplan.verify/3" and d["pair_margins"][0]["ok"] is False


def test_static_clearances_under_tracking() -> None:
    """A path 2 m inside the band's floor margin: fine exactly, below the model's vertical
    tracking error of 3 m; its vertical margin is the 2 m it has."""
    sc = resolve("open")  # flat ground, absolute band 100-200 m
    t = np.linspace(0.0, 10.0, 11)
    p = np.column_stack([100 + 20 * t, np.full_like(t, 400), np.full_like(t, 102.0)])
    tr = Trajectory("u", p, t)
    report = verify_trajectories([tr], sc, kinematics=False, model=ExecutionModel(track_v=3.0))
    assert [v.kind for v in report.violations] == ["altitude"]
    assert report.uav_margins[0].track_v == pytest.approx(2.0)
    assert report.uav_margins[0].limited_by["track_v"] == "altitude band's floor"


@pytest.fixture(scope="module")
def robust_fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("fleet")
    r = CliRunner().invoke(app, ["plan", "ppswarm1@8", "-a", "ppswarm", "--out", str(out),
                                 "--param", "n_restart=1", "--iterations", "8", "--pop-size",
                                 "60"])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "execution model: take-off ±2 s, speed ±3 %" in r.output
    assert "margin: the fleet tolerates " in r.output
    assert " take-off error (model: 2 s: meets" in r.output
    return out


def test_a_fleet_planned_under_the_default_model_meets_it(robust_fleet: Path) -> None:
    doc = json.loads((robust_fleet / "plan.json").read_text())
    assert doc["format"] == "uavplan.plan/4"
    # ppswarm1's UAV is a small fixed wing: the default takes its calibrated tracking error
    assert doc["execution"]["takeoff_s"] == 2.0 and doc["execution"]["track_h"] == 6.0
    assert doc["execution"]["track_v"] == 8.0 and "small-fixed-wing" in doc["execution"]["source"]
    uavs = doc["margins"]["uavs"]
    assert len(uavs) == 8
    for m in uavs:
        for key, need in (("takeoff_s", 2.0), ("speed", 0.03), ("track_h", 6.0), ("track_v", 8.0)):
            assert m[key] is None or m[key] >= need - 1e-6, (m, key)
    v = CliRunner().invoke(app, ["verify", str(robust_fleet), "ppswarm1@8"])
    assert v.exit_code == 0 and "margin: the fleet tolerates" in v.output
    assert "execution model: take-off ±2 s" in v.output
    n = CliRunner().invoke(app, ["verify", str(robust_fleet), "ppswarm1@8", "--nominal"])
    assert n.exit_code == 0 and "margin:" not in n.output


def test_sampled_executions_of_a_robust_plan_break_nothing(robust_fleet: Path) -> None:
    """300 random executions of the fleet (take-off errors, speed factors, tracking offsets
    drawn from the model, a third of them at the model's extremes): none comes closer than S2,
    nor breaks an obstacle, the terrain or the band."""
    sc = resolve("ppswarm1@8")
    pf = read_plan_file(robust_fleet / "plan.json", 3)
    trajs = pf.trajectories("flown")
    rng = np.random.default_rng(0)
    timing = Timing(DEFAULT.takeoff_s, DEFAULT.speed, DEFAULT.track_h, DEFAULT.track_v)
    bad = 0
    for k in range(300):
        executed = sample_fleet(trajs, timing, rng, extremes=k % 3 == 0)
        report = verify_trajectories(executed, sc, kinematics=False, speed=False)
        assert "speed" not in {v.kind for v in report.violations}  # faster is the model's
        bad += bool(report.violations)
    assert bad == 0


def test_a_format_3_plan_reads_as_nominal(robust_fleet: Path, tmp_path: Path) -> None:
    doc = json.loads((robust_fleet / "plan.json").read_text())
    doc["format"] = "uavplan.plan/3"
    del doc["execution"], doc["margins"]
    (tmp_path / "plan.json").write_text(json.dumps(doc))
    pf = read_plan_file(tmp_path / "plan.json", 3)
    assert pf.execution is None and pf.margins is None


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), delta0=st.sampled_from([0.0, 0.3, 1.0, 2.0]),
       rho=st.sampled_from([0.0, 0.03, 0.1]), snap=st.booleans())  # fmt: skip
def test_the_verifier_and_the_planners_table_agree(
    seed: int, delta0: float, rho: float, snap: bool
) -> None:
    """Two implementations of the separation under a model (the verifier's polygon clipping,
    the table's half-plane clipping; neither imports the other) give the same least distance
    on random pairs, with times on a common grid (``snap``: degenerate windows) or not."""
    from uavplan.world.reservations import ReservationTable

    rng = np.random.default_rng(seed)
    if not (delta0 or rho):
        delta0 = 0.5

    def traj() -> tuple[np.ndarray, np.ndarray]:
        n = int(rng.integers(3, 9))
        p = np.cumsum(rng.uniform(-30, 30, (n, 3)), axis=0) + 300.0
        dt = rng.uniform(0.5, 3.0, n - 1)
        if snap:
            dt = np.round(dt * 2) / 2 + 0.5
        t0 = float(rng.integers(0, 6)) if snap else rng.uniform(0, 6)
        return p, t0 + np.concatenate([[0.0], np.cumsum(dt)])

    (pa, ta), (pb, tb) = traj(), traj()
    table = ReservationTable(np.zeros(3), np.full(3, 900.0), 200.0, timing=(delta0, rho))
    table.add("b", pb, tb)
    planner = float(table.min_distance(pa[None], ta[None])[0])
    _, margins = separation_under([Trajectory("a", pa, ta), Trajectory("b", pb, tb)], 40.0,
                                  Timing(delta0, rho, 0.0, 0.0))  # fmt: skip
    verifier = margins[0].distance if margins else math.inf
    if planner < 50.0 or verifier < 50.0:  # within both searches
        assert verifier == pytest.approx(planner, abs=1e-6)


def test_a_horizontal_tracking_error_moves_the_ground_under_the_uav() -> None:
    """Over a slope the band's floor is above the ground within the horizontal error, not
    only below the track: a flight 15 m above a 0.5-gradient ramp with the band's floor at
    10 m keeps 5 m vertically with no horizontal error, and with 3 m of it at most 3.5 m (the
    ramp rises 1.5 m within 3 m); the verifier's bound is never looser than that, and a plan
    whose vertical margin only held without the horizontal error is rejected under the
    model."""
    from dataclasses import replace

    from uavplan.verify.robust import vertical_clearance
    from uavplan.verify.terrain import terrain_clearance_extrema, within_reach
    from uavplan.world.obstacles import AltitudeBand
    from uavplan.world.scenario import Bounds
    from uavplan.world.terrain import Terrain

    xs = np.arange(0.0, 101.0)
    H = np.tile(0.5 * xs, (101, 1))
    sc = resolve("spso")
    sc = replace(sc, terrain=Terrain(H, 0.0, 0.0, 1.0, 1.0, "ramp"), cylinders=(),
                 altitude=AltitudeBand(10.0, 100.0, "ground"),
                 bounds=Bounds((0.0, 0.0, 0.0), (100.0, 100.0, 500.0)))  # fmt: skip
    x = np.linspace(20.0, 80.0, 7)
    P = np.column_stack([x, np.full(7, 50.0), 0.5 * x + 15.0])
    tr = Trajectory("u", P, np.linspace(0.0, 6.0, 7), True)
    ev0, _ = vertical_clearance(tr, sc, None, terrain_clearance_extrema, 0.0, within_reach)
    ev3, by = vertical_clearance(tr, sc, None, terrain_clearance_extrema, 3.0, within_reach)
    assert ev0 == pytest.approx(5.0)
    assert ev3 <= 3.5 + 1e-9 and ev3 >= 5.0 - 0.5 * (3.0 + 2.0) - 1e-9 and "floor" in by
    model = ExecutionModel(0.0, 0.0, 3.0, 2.0)
    ok = verify_trajectories([tr], sc, kinematics=False, model=ExecutionModel(0.0, 0.0, 0.0, 2.0))
    assert ok.ok, ok.violations[:2]
    P2 = P.copy()
    P2[:, 2] = 0.5 * x + 12.5  # 2.5 m above the floor: enough without a horizontal error only
    tight = Trajectory("u", P2, tr.times, True)
    assert verify_trajectories([tight], sc, kinematics=False,
                               model=ExecutionModel(0.0, 0.0, 0.0, 2.0)).ok  # fmt: skip
    assert not verify_trajectories([tight], sc, kinematics=False, model=model).ok


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), how=st.sampled_from(["height", "slope"]))
def test_the_verifiers_ground_within_reach_bounds_it_brute_force(seed: int, how: str) -> None:
    from uavplan.verify.terrain import bilinear_height, within_reach
    from uavplan.world.terrain import Terrain

    rng = np.random.default_rng(seed)
    ny, nx = (int(v) for v in rng.integers(2, 9, 2))
    du, dv = (float(v) for v in rng.uniform(0.3, 40.0, 2))
    H = rng.normal(0.0, 5.0, (ny, nx))
    reach = float(rng.uniform(0.01, 12.0))
    T = Terrain(H, 0.0, 0.0, du, dv)
    hi = Terrain(within_reach(H, du, dv, reach, True, how), 0.0, 0.0, du, dv)
    lo = Terrain(within_reach(H, du, dv, reach, False, how), 0.0, 0.0, du, dv)
    p = rng.uniform([-3.0, -3.0], [du * (nx - 1) + 3, dv * (ny - 1) + 3], (200, 2))
    a, d = rng.uniform(0, 2 * np.pi, 200), rng.uniform(0, reach, 200)
    q = p + d[:, None] * np.column_stack([np.cos(a), np.sin(a)])
    at_q = bilinear_height(T, q[:, 0], q[:, 1])
    assert np.all(bilinear_height(hi, p[:, 0], p[:, 1]) >= at_q - 1e-9)
    assert np.all(bilinear_height(lo, p[:, 0], p[:, 1]) <= at_q + 1e-9)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_the_ground_within_reach_at_a_flights_nodes_is_the_whole_grids(seed: int) -> None:
    """The margins read the ground moved within reach at the nodes under one flight, from a
    table of block extremes, not a filter of the whole grid: the same values bit for bit as
    the filter's (any window, at the grid's edges too), and the same clearances along a
    random flight that leaves the grid, as the whole filtered grid (cut to the flight's cells)
    gives."""
    from dataclasses import replace

    from uavplan.verify.robust import _cells_under, _Grid, vertical_clearance
    from uavplan.verify.terrain import terrain_clearance_extrema, within_reach
    from uavplan.world.obstacles import AltitudeBand
    from uavplan.world.scenario import Bounds
    from uavplan.world.terrain import Terrain

    rng = np.random.default_rng(seed)
    ny, nx = (int(v) for v in rng.integers(2, 40, 2))
    du, dv = (float(v) for v in rng.uniform(0.3, 5.0, 2))
    H = rng.normal(0.0, 5.0, (ny, nx))
    for how in ("height", "slope"):
        for highest in (True, False):
            reach = float(rng.choice([rng.uniform(0.01, 3.0), rng.uniform(3.0, 60.0), 1000.0]))
            rows, cols = rng.integers(0, ny, 50), rng.integers(0, nx, 50)
            whole = within_reach(H, du, dv, reach, highest, how)
            got = within_reach(H, du, dv, reach, highest, how, nodes=(rows, cols))
            assert np.array_equal(got, whole[rows, cols])
    m = int(rng.integers(2, 30))
    span = np.array([du * (nx - 1), dv * (ny - 1)])
    xy = rng.uniform(-0.2 * span, 1.2 * span, (m, 2))
    if rng.random() < 0.3:  # on the grid's lines
        xy = np.round(xy / [du, dv]) * [du, dv]
    P = np.column_stack([xy, rng.uniform(20.0, 40.0, m)])
    tr = Trajectory("u", P, np.arange(m, dtype=np.float64), True)
    T = Terrain(H, 0.0, 0.0, du, dv)
    sc = replace(resolve("spso"), terrain=T, cylinders=(),
                 altitude=AltitudeBand(5.0, 60.0, "ground"),
                 bounds=Bounds((-1e4, -1e4, -100.0), (1e4, 1e4, 100.0)))  # fmt: skip
    for reach in (0.0, float(rng.uniform(0.1, 3.0)), float(rng.uniform(3.0, 50.0))):
        got = vertical_clearance(tr, sc, None, terrain_clearance_extrema, reach, within_reach, {})
        low, high = -math.inf, math.inf
        cut = _cells_under(P, T)  # the kernels read the grid cut to the flight's cells
        for how in ("height", "slope") if reach > 0 else ("",):
            floor = within_reach(H, du, dv, reach, True, how) if how else H
            top = within_reach(H, du, dv, reach, False, how) if how else H
            ends = (P[:-1], P[1:])
            low = max(low, float(np.min(terrain_clearance_extrema(*ends, _Grid(
                floor[cut], T, cut))[:, 0])))  # fmt: skip
            high = min(high, float(np.max(terrain_clearance_extrema(*ends, _Grid(
                top[cut], T, cut))[:, 2])))  # fmt: skip
        z = P[:, 2]
        want = min((float(min(np.min(z + 100.0), np.min(100.0 - z))), "bounds"),
                   (low, "terrain"), (low - 5.0, "altitude band's floor"),
                   (60.0 - high, "altitude band's ceiling"))  # fmt: skip
        assert got == (max(want[0], 0.0), want[1])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), moving=st.booleans())
def test_the_compiled_margin_bisection_is_the_python_one(seed: int, moving: bool) -> None:
    """A pair's take-off and speed margins, bisected in one compiled call, equal the Python
    bisection (``_largest`` over the same check) for two random crossing flights under random
    models, whether the pair passes with the model's errors or not."""
    from uavplan.verify.robust import (
        SPEED_CAP,
        TAKEOFF_CAP,
        _fails_at,
        _largest,
        _largest_tolerated,
        _pack,
    )  # fmt: skip

    rng = np.random.default_rng(seed)
    m = int(rng.integers(2, 8))
    a = Trajectory(
        "a",
        np.column_stack([np.linspace(0.0, 400.0, m), np.full(m, 200.0), np.full(m, 50.0)]),
        np.linspace(0.0, 40.0, m),
        True,
    )
    y = rng.uniform(0.0, 400.0, (m, 1))
    b_pts = np.column_stack([np.full(m, 200.0) + rng.normal(0, 20, m), np.sort(y[:, 0]),
                             np.full(m, 50.0) + rng.normal(0, 5, m)])  # fmt: skip
    b = Trajectory("b", b_pts, np.linspace(0.0, 40.0, m) + rng.uniform(-15, 15), True)
    P, T, owner, valid = _pack([a, b])
    take = np.where(owner == 0, a.times[0], b.times[0]).astype(np.float64)
    ia, ib = np.flatnonzero(valid & (owner == 0)), np.flatnonzero(valid & (owner == 1))
    pairs = np.ascontiguousarray(
        np.stack(np.meshgrid(ia, ib, indexing="ij"), axis=-1).reshape(-1, 2), dtype=np.int64
    )
    below = float(rng.uniform(5.0, 60.0))
    d0, r0 = float(rng.choice([0.0, rng.uniform(0, 5)])), float(rng.choice([0.0, 0.03]))

    def fails(delta: float, rho: float) -> bool:
        return bool(_fails_at(P, T, pairs, take, 0, len(pairs), delta, rho, moving, below))

    passes = not fails(d0, r0)
    want_t = _largest(lambda x: fails(x, r0), TAKEOFF_CAP, d0 if passes else 0.0)
    want_s = _largest(lambda x: fails(d0, x), SPEED_CAP, r0 if passes else 0.0)
    got_t = _largest_tolerated(P, T, pairs, take, 0, len(pairs), d0, r0, moving, below,
                               d0 if passes else 0.0, TAKEOFF_CAP, False)  # fmt: skip
    got_s = _largest_tolerated(P, T, pairs, take, 0, len(pairs), d0, r0, moving, below,
                               r0 if passes else 0.0, SPEED_CAP, True)  # fmt: skip
    assert (got_t, got_s) == (want_t, want_s)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_whether_the_ground_fails_is_what_the_clearance_says(seed: int) -> None:
    """The margins' bisection asks only whether the ground checks fail at a horizontal error,
    skipping the second bound of a side the first settles: the same answer as the clearance
    (``vertical_clearance(...) < need``) over random terrains, flights, reaches and needs,
    with a band above the ground, an absolute band, or none, and without terrain."""
    from dataclasses import replace

    from uavplan.verify.robust import vertical_clearance, vertical_fails
    from uavplan.verify.terrain import terrain_clearance_extrema, within_reach
    from uavplan.world.obstacles import AltitudeBand
    from uavplan.world.scenario import Bounds
    from uavplan.world.terrain import Terrain

    rng = np.random.default_rng(seed)
    ny, nx = (int(v) for v in rng.integers(2, 30, 2))
    du, dv = (float(v) for v in rng.uniform(0.5, 5.0, 2))
    H = rng.normal(0.0, float(rng.choice([0.5, 5.0])), (ny, nx))
    m = int(rng.integers(2, 20))
    span = np.array([du * (nx - 1), dv * (ny - 1)])
    P = np.column_stack([rng.uniform(-0.1 * span, 1.1 * span, (m, 2)),
                         rng.uniform(2.0, 30.0, m)])  # fmt: skip
    tr = Trajectory("u", P, np.arange(m, dtype=np.float64), True)
    bands = (None, AltitudeBand(5.0, 25.0, "ground"), AltitudeBand(4.0, 28.0, "absolute"))
    band = bands[int(rng.integers(3))]
    terrain = None if rng.random() < 0.2 else Terrain(H, 0.0, 0.0, du, dv)
    sc = replace(resolve("spso"), terrain=terrain, cylinders=(), altitude=band,
                 bounds=Bounds((-1e4, -1e4, -1.0), (1e4, 1e4, 31.0)))  # fmt: skip
    seen = set()
    for _ in range(6):
        reach = float(rng.choice([0.0, rng.uniform(0.1, 3.0), rng.uniform(3.0, 40.0)]))
        scratch: dict[str, object] = {}
        ev, _ = vertical_clearance(tr, sc, None, terrain_clearance_extrema, reach, within_reach,
                                   scratch)  # fmt: skip
        for need in (0.5 * ev, ev, np.nextafter(ev, np.inf), 2.0 * ev + 0.1, 1.0, 3.0):
            if not need > 0:
                continue
            got = vertical_fails(tr, sc, terrain_clearance_extrema, reach, float(need),
                                 within_reach, scratch)  # fmt: skip
            assert got == (ev < need), (reach, need, ev)
            seen.add(got)
    assert seen  # each example asks at least once


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), chunk=st.sampled_from([1, 2, 3, 8]))
def test_the_close_pairs_are_every_pair_near_in_space_and_time_once(seed: int, chunk: int) -> None:
    """The verifier's pair search (a grid in space and time over runs of ``chunk`` segments,
    each pair of runs taken in the first cell it shares) finds exactly the segment pairs of
    different UAVs closer than the gap whose windows under the search's take-off and speed
    limits meet, each once, as a brute force over every pair does."""
    from uavplan.verify.robust import _close_pairs, _pack, _seg_dist2

    rng = np.random.default_rng(seed)
    trajs = []
    for k in range(int(rng.integers(2, 7))):
        m = int(rng.integers(2, 20))
        P = np.cumsum(rng.normal(0.0, 25.0, (m, 3)), axis=0) + rng.uniform(0, 80, 3)
        t = float(rng.uniform(-50.0, 300.0)) + np.cumsum(rng.uniform(0.5, 20.0, m))
        trajs.append(Trajectory(f"u{k}", P, t))
    P, T, owner, valid = _pack(trajs)
    take = np.array([t.times[0] for t in trajs])[np.maximum(owner, 0)]
    gap, cell, dcap, rcap = float(rng.uniform(5, 60)), float(rng.uniform(20, 80)), 20.0, 0.1
    got = _close_pairs(P, owner, valid, gap, max(cell, gap), T, take, dcap, rcap, chunk)
    lo = take - dcap + (T - take) / (1 + rcap)
    hi = take + dcap + (np.roll(T, -1) - take) / (1 - rcap)
    want = [(i, j) for i in range(len(P) - 1) for j in range(i + 1, len(P) - 1)
            if valid[i] and valid[j] and owner[i] != owner[j]
            and lo[i] <= hi[j] and lo[j] <= hi[i] and _seg_dist2(P, i, j) < gap * gap]  # fmt: skip
    assert [tuple(r) for r in got.tolist()] == sorted(want)


def _fixed_wing_world(ramp_deg: float = 0.0) -> Any:
    """The open map (a small fixed wing, 30 degree climb and descent limits) over a ground
    rising along x at ``ramp_deg`` from x = 300 m to 600 m, the band 100-200 m above it."""
    from uavplan.world.obstacles import AltitudeBand
    from uavplan.world.scenario import Bounds
    from uavplan.world.terrain import Terrain

    sc = resolve("open")
    x = np.arange(0.0, 1101.0, 10.0)
    row = np.clip(x - 300.0, 0.0, 300.0) * math.tan(math.radians(ramp_deg))
    ground = Terrain(np.tile(row, (91, 1)), 0.0, 0.0, 10.0, 10.0)
    return dataclasses.replace(
        sc, terrain=ground, altitude=AltitudeBand(100.0, 200.0, "ground"),
        bounds=Bounds((1.0, 1.0, 0.0), (1045.0, 879.0, 700.0)),
    )  # fmt: skip


def _timed(x: np.ndarray, z: np.ndarray, v: float = 13.0) -> Trajectory:
    p = np.column_stack([x, np.full_like(x, 400.0), z])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1))])
    return Trajectory("uav0", p, s / v)  # v over the ground, as a mission's speeds


def test_a_descent_steeper_than_the_airframe_flies_in_the_wind_ends_above_its_goal() -> None:
    """At 13 m/s over the ground with 3 m/s behind it the small fixed wing descends at most
    23.9 degrees over the ground (30 through the air): a 28.6 degree descent of 140 m into
    the goal leaves it 14 m above the goal, beyond the model's 8 m, so the verifier refuses it
    under the model (not as flown exactly), and so does the planners' validator in the
    widened world; with a level leg after it, where it gets down, neither does."""
    from uavplan.problems.validity import MotionValidator
    from uavplan.world.execution import default_for, widened

    sc = _fixed_wing_world()
    model = default_for(sc.uav)
    g = math.tan(math.radians(28.6))
    steep = _timed(np.array([100.0, 300.0, 440.0]), np.array([190.0, 190.0, 190.0 - 140 * g]))
    level = _timed(np.array([100.0, 300.0, 440.0, 700.0]),
                   np.array([190.0, 190.0, 190.0 - 140 * g, 190.0 - 140 * g]))  # fmt: skip
    report = verify_trajectories([steep], sc, model=model)
    assert [v.kind for v in report.violations] == ["climb"]
    assert "above the goal" in report.violations[0].message
    assert report.violations[0].value == pytest.approx(140 * (g - 10 / 13 * math.tan(
        math.radians(30))), abs=0.01)  # fmt: skip
    assert not verify_trajectories([steep], sc).violations  # flown exactly: fine
    assert not verify_trajectories([level], sc, model=model).violations
    world = widened(sc, model)
    task = dataclasses.replace(world.tasks[0], start=tuple(steep.points[0]),
                               goal=tuple(steep.points[-1]))  # fmt: skip
    mv = MotionValidator(world, task, strict_altitude=True, kinematics=True)
    for tr, bad in ((steep, True), (level, False)):
        b = mv.batch(tr.points[None], tr.times[None])
        assert bool(mv.violations(b)["climb"][0]) is bad
        assert (mv.passing(b).size == 0) is bad


def test_a_climb_steeper_than_the_airframe_flies_in_the_wind_sinks_into_the_bands_floor() -> None:
    """Over ground rising at 25 degrees (steeper than the 23.9 the small fixed wing climbs in
    the calibration's wind), a flight 115 m above it falls behind its plan by 0.022 m a metre:
    6.7 m over 300 m, inside the band's floor under the model's 8 m of vertical error (the
    band 100 m above the ground), although the planned flight keeps 15 m (12 m from the
    ground within the model's 6 m horizontally)."""
    from uavplan.problems.validity import MotionValidator
    from uavplan.world.execution import default_for, widened

    sc = _fixed_wing_world(25.0)
    model = default_for(sc.uav)
    r = math.tan(math.radians(25.0))
    x = np.array([100.0, 300.0, 600.0, 620.0])
    z = 115.0 + np.maximum(x - 300.0, 0.0) * r
    z[-1] = z[-2]  # level off (its goal within the model's error of where it gets to)
    tr = _timed(x, z)
    report = verify_trajectories([tr], sc, model=model)
    assert [v.kind for v in report.violations] == ["altitude"], report.violations
    assert "below its plan" in report.violations[0].message
    assert not verify_trajectories([tr], sc).violations
    world = widened(sc, model)
    mv = MotionValidator(world, world.tasks[0], strict_altitude=True, kinematics=True)
    b = mv.batch(tr.points[None], tr.times[None])
    assert mv.violations(b)["climb"][0] and mv.passing(b).size == 0
    assert not mv.violations(b)["altitude"][0]  # the planned flight itself clears the floor


def test_a_pair_is_held_apart_by_each_uav_s_height_lag() -> None:
    """Two level flights 20 m apart with S2 = 10 m pass; with one UAV's heights lagging up to
    25 m they do not, and the message says why; the tracking error they tolerate is what the
    lag leaves."""
    t = np.array([0.0, 50.0])
    a = Trajectory("a", np.array([[0.0, 0.0, 100.0], [1000.0, 0.0, 100.0]]), t)
    b = Trajectory("b", np.array([[0.0, 20.0, 100.0], [1000.0, 20.0, 100.0]]), t)
    timing = Timing(0.0, 0.0, 1.0, 1.0)  # takes 2 sqrt(2) m
    found, margins = separation_under([a, b], 10.0, timing)
    assert not found and margins[0].track_h == pytest.approx((20.0 - 10.0) / (2 * 2**0.5))
    found, margins = separation_under([a, b], 10.0, timing, [25.0, 0.0])
    assert len(found) == 1 and "a's heights lagging up to 25.000 m" in found[0].message
    assert margins[0].required == pytest.approx(10.0 + 2 * 2**0.5 + 25.0)
    assert margins[0].track_h == 0.0
    found, _ = separation_under([a, b], 10.0, timing, [3.0, 2.0])  # 20 > 10 + 2.83 + 5
    assert not found


def test_each_pair_of_segments_is_held_apart_by_its_own_lags() -> None:
    """Lags given per segment: a flight whose heights lag 25 m on its first segment only
    passes 20 m beside another on its second (S2 10 m), where the whole flight's lag would
    refuse it; beside the first it fails, the message naming that segment's lag. A moving
    obstacle beside the second segment likewise."""
    from uavplan.verify.robust import moving_under
    from uavplan.world.dynamic import MovingObstacle

    a = Trajectory("a", np.array([[0.0, 0.0, 100.0], [1000.0, 0.0, 100.0],
                                  [2000.0, 0.0, 100.0]]), np.array([0.0, 50.0, 100.0]))  # fmt: skip
    seg = np.array([25.0, 0.0])
    timing = Timing(0.0, 0.0, 0.0, 0.0)
    for x, ok in ((1200.0, True), (200.0, False)):
        b = Trajectory("b", np.array([[x, 20.0, 100.0], [x + 600.0, 20.0, 100.0]]),
                       np.array([x / 20.0, (x + 600.0) / 20.0]))  # fmt: skip
        found, margins = separation_under([a, b], 10.0, timing, [seg, np.zeros(1)])
        assert (not found) == ok, x
        whole, _ = separation_under([a, b], 10.0, timing, [25.0, 0.0])
        assert len(whole) == 1
        if not ok:
            assert "a's heights lagging up to 25.000 m" in found[0].message
            assert margins[0].required == pytest.approx(35.0)
        obs = MovingObstacle(5.0, b.times, b.points)  # radius 5 + lag 25 > 20 beside seg 1
        got, _ = moving_under(a, [obs], timing, seg)
        assert (not got) == ok, x
        assert len(moving_under(a, [obs], timing, 25.0)[0]) == 1


def test_the_verifier_holds_a_pair_apart_by_the_lag_of_their_descents_in_the_wind() -> None:
    """Two small fixed wings 15 m apart side by side descend 87 m over 160 m (28.6 degrees,
    their limit 30) at 20 m/s along the path, 17.6 m/s over the ground: with the calibration's
    3 m/s behind them they descend at most (17.6 - 3) / 17.6 tan 30 over the ground and lag
    their plan by 10.6 m at the bottom. With S2 = 10 m and
    no tracking error the pair fails, each UAV's lag named; UAVs of no named airframe (no
    lag) pass."""
    sc = resolve("open")
    g = math.tan(math.radians(28.6))
    x = np.array([100.0, 200.0, 360.0, 600.0])
    z = np.array([190.0, 190.0, 190.0 - 160.0 * g, 190.0 - 160.0 * g])
    p = np.column_stack([x, np.zeros_like(x), z])
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]) / 20.0
    trajs = [Trajectory(u, p + np.array([0.0, y, 0.0]), t) for u, y in (("a", 400.0), ("b", 415.0))]
    model = ExecutionModel(track_h=0.01)
    report = verify_trajectories(trajs, sc, kinematics=False, model=model)
    sep = [v for v in report.violations if v.kind == "separation"]
    v = 20.0 * math.cos(math.atan(g))
    lag = 160.0 * (g - (v - 3.0) / v * math.tan(math.radians(30.0)))
    assert len(sep) == 1 and sep[0].required == pytest.approx(10.0 + 0.02 + 2 * lag, abs=0.05)
    assert "a's heights lagging up to" in sep[0].message and "b's heights" in sep[0].message
    plain = dataclasses.replace(sc, uav=dataclasses.replace(sc.uav, airframe=None))
    assert verify_trajectories(trajs, plain, kinematics=False, model=model).ok
