"""The verifier's kinematic checks (``uavplan.verify.kinematics``, the minimum speed of
``uavplan.verify.timing.check_speed``) and which trajectories ``verify_plan`` / ``uavplan verify``
check.

The property tests sample known curves (a straight lead-in, a circular arc or helix of radius
rho, a straight lead-out; constant climb angle and speed) at a spacing of at most rho / 4, round
them as plan files do, and compare each check's verdict with the curve's analytic radius, climb
angle and speed, a few percent away from the limit on either side; 10 times denser samples of
the same curve must give the same verdicts.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.verify import KINDS, Trajectory, verify_plan, verify_trajectories
from uavplan.verify.kinematics import check_climb, check_turn, stretches, turn_estimates
from uavplan.verify.timing import check_speed
from uavplan.world import UAV, Bounds, Scenario, Task
from uavplan.world.tolerances import ANGLE_TOL_DEG, MAX_SAMPLE_TURN_DEG, TURN_RTOL

runner = CliRunner()


def traj(points: Any, times: Any, uid: str = "a") -> Trajectory:
    return Trajectory(uid, np.asarray(points, dtype=float), np.asarray(times, dtype=float))


def arc(rho: float, sweep: float, n: int, z0: float = 50.0, dz: float = 0.0) -> np.ndarray:
    """n samples of an arc (a helix if dz != 0) of radius rho around the origin, equal spacing."""
    a = np.linspace(0.0, sweep, n)
    return np.stack([rho * np.cos(a), rho * np.sin(a), z0 + dz * a / sweep], axis=1)


def timed(points: np.ndarray, speed: float) -> Trajectory:
    """Points flown at ``speed`` along their polyline."""
    d = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return traj(points, np.concatenate([[0.0], np.cumsum(d / speed)]))


def test_kinds_order() -> None:
    assert KINDS[:4] == ("times", "speed", "turn", "climb")


def test_tolerances() -> None:
    assert (TURN_RTOL, MAX_SAMPLE_TURN_DEG, ANGLE_TOL_DEG) == (0.01, 30.0, 1e-4)


# ---------------------------------------------------------------------------- the UAV's limits
def test_uav_limits_and_their_validation() -> None:
    u = UAV()
    assert (u.turn_radius, u.min_speed, u.max_speed) == (0.0, 0.0, None)
    assert u.max_climb_angle is None and u.max_descent_angle is None and u.v_max == 20.0
    assert UAV(speed=15, max_speed=25).v_max == 25.0
    UAV(speed=20, min_speed=20, max_speed=20, max_climb_angle=90, max_descent_angle=0.5)
    for kw, message in [
        ({"min_speed": 25.0}, "min_speed 25 m/s is above speed 20 m/s"),
        ({"max_speed": 15.0}, "max_speed 15 m/s is below speed 20 m/s"),
        ({"min_speed": -1.0}, "min_speed must be a finite number >= 0"),
        ({"max_speed": math.inf}, "max_speed must be a finite number"),
        ({"max_climb_angle": 0.0}, r"max_climb_angle must be in \(0, 90\]"),
        ({"max_descent_angle": 91.0}, r"max_descent_angle must be in \(0, 90\]"),
        ({"max_climb_angle": math.nan}, "max_climb_angle must be in"),
        ({"speed": 0.0}, "speed must be a finite number > 0"),
        ({"turn_radius": -1.0}, "turn_radius must be a finite number >= 0"),
    ]:
        with pytest.raises(ValueError, match=message):
            UAV(**kw)


# ---------------------------------------------------------------------------- speed
def test_speed_too_low_too_high_and_hover() -> None:
    t = traj([[0, 0, 0], [10, 0, 0], [10, 0, 0], [100, 0, 0], [103, 0, 0], [110, 0, 0]],
             [0, 1, 3, 4, 5, 5])  # fmt: skip
    vs = check_speed(t, 20.0, 5.0)
    # segment 1 hovers (0 m/s), 2 is too fast, 3 too slow, 4 a jump; 0 is fine
    assert [v.message.split(" at ")[0] for v in vs] == [f"a: segment {k}" for k in (1, 2, 3, 4)]
    assert [v.value for v in vs] == [0.0, pytest.approx(90.0), pytest.approx(3.0), math.inf]
    assert [v.required for v in vs] == [5.0, 20.0, 5.0, 20.0]
    assert "(minimum 5 m/s)" in vs[0].message and "(limit 20 m/s)" in vs[1].message
    assert check_speed(t, 20.0) == [vs[1], vs[3]]  # without a minimum: the maximum only
    # a segment of zero duration that stays put is no motion at all
    assert check_speed(traj([[0, 0], [0, 0], [10, 0]], [0, 0, 1]), 20.0, 5.0) == []


def test_minimum_speed_slack_for_rounding() -> None:
    # exactly at the minimum, and 1e-6 m short (rounding), both pass; 1 mm short fails
    assert check_speed(traj([[0, 0, 0], [10, 0, 0]], [0, 1]), 20.0, 10.0) == []
    assert check_speed(traj([[0, 0, 0], [9.999999, 0, 0]], [0, 1]), 20.0, 10.0) == []
    assert len(check_speed(traj([[0, 0, 0], [9.999, 0, 0]], [0, 1]), 20.0, 10.0)) == 1


# ---------------------------------------------------------------------------- climb
@pytest.mark.parametrize(
    ("dz", "climb", "descent", "bad"),
    [
        (5.0, 30.0, None, False),  # 26.6 deg up, limit 30
        (6.0, 30.0, None, True),  # 31.0 deg up
        (6.0, None, 30.0, False),  # no climb limit
        (-6.0, 30.0, None, False),  # no descent limit
        (-6.0, 45.0, 30.0, True),  # 31.0 deg down
        (-5.0, 45.0, 30.0, False),
        (10.0, 45.0, None, False),  # exactly 45 deg passes
        (0.0, 1.0, 1.0, False),  # level
    ],
)
def test_climb_and_descent(
    dz: float, climb: float | None, descent: float | None, bad: bool
) -> None:
    t = traj([[0, 0, 100], [10, 0, 100 + dz]], [0, 1])
    vs = check_climb(t, climb, descent)
    assert bool(vs) == bad
    if bad:
        v = vs[0]
        assert v.kind == "climb" and v.value == pytest.approx(math.degrees(math.atan2(abs(dz), 10)))
        assert v.required == (climb if dz > 0 else descent)
        assert ("climbs" if dz > 0 else "descends") in v.message and "limit 30 deg" in v.message


def test_climb_vertical_and_still_segments() -> None:
    t = traj([[0, 0, 0], [0, 0, 0], [0, 0, 10], [0, 0, 10]], [0, 1, 2, 3])
    vs = check_climb(t, 89.0, None)  # the vertical segment climbs at 90 deg; still ones skipped
    assert [v.value for v in vs] == [90.0] and "segment 1 climbs" in vs[0].message
    assert check_climb(t, 90.0, None) == []


def test_climb_one_violation_per_stretch_at_the_steepest() -> None:
    pts = [[0, 0, 0], [10, 0, 8], [20, 0, 18], [30, 0, 26], [40, 0, 26], [50, 0, 16]]
    vs = check_climb(traj(pts, range(6)), 30.0, 30.0)
    assert len(vs) == 2
    assert "segment 1 climbs at 45.000 deg" in vs[0].message
    assert "steepest of segments 0-2" in vs[0].message
    assert "segment 4 descends at 45.000 deg" in vs[1].message
    assert vs[0].where == ((10.0, 0.0, 8.0), (20.0, 0.0, 18.0)) and vs[0].time == 1.0


def test_climb_is_3d_only_and_for_declared_limits() -> None:
    assert check_climb(traj([[0, 0], [10, 0]], [0, 1]), 1.0, 1.0) == []
    assert check_climb(traj([[0, 0, 0], [1, 0, 100]], [0, 1]), None, None) == []


# ---------------------------------------------------------------------------- turn
def test_ninety_degree_kink() -> None:
    t = traj([[0, 0, 10], [100, 0, 10], [100, 100, 10]], [0, 5, 10])
    vs = check_turn(t, 20.0)
    assert len(vs) == 1
    v = vs[0]
    assert v.kind == "turn" and v.required == 20.0 and v.time == 5.0
    assert v.where == ((100.0, 0.0, 10.0),)
    assert "point 1 has a turn of 90.0 deg at one point" in v.message
    # the same corner is no violation without a turn radius
    assert check_turn(t, 0.0) == []


def test_arc_radius_against_the_limit() -> None:
    # samples of an arc 1 m apart (h <= R / 4)
    tight = timed(arc(18.0, math.pi, 58), 20.0)
    vs = check_turn(tight, 20.0)
    assert len(vs) == 1  # one stretch: the whole arc
    assert vs[0].value == pytest.approx(18.0, rel=3e-3) and vs[0].value < 18.0
    assert "estimated turn radius of 17.99" in vs[0].message
    assert "minimum radius 20 m (worst of points 1-56)" in vs[0].message
    assert check_turn(timed(arc(20.5, math.pi, 65), 20.0), 20.0) == []
    # the estimate's slack: 1 % below the limit passes, 2 % below fails
    assert check_turn(timed(arc(19.85, math.pi, 63), 20.0), 20.0) == []
    assert check_turn(timed(arc(19.6, math.pi, 63), 20.0), 20.0) != []


def test_turn_of_a_2d_trajectory_and_a_helix() -> None:
    flat = arc(18.0, 2.0, 40)[:, :2]
    assert len(check_turn(timed(flat, 10.0), 20.0)) == 1
    assert check_turn(timed(flat, 10.0), 17.5) == []
    # the horizontal track counts: a helix of radius 25 climbing steeply still turns at 25 m
    helix = arc(25.0, 4 * math.pi, 400, dz=500.0)
    assert check_turn(timed(helix, 20.0), 24.5) == []
    assert check_turn(timed(helix, 20.0), 26.0) != []


def test_turn_drops_repeated_xy_and_ends_are_free() -> None:
    # hovering, then climbing vertically, at the corner: the repeated x, y are one point
    pts = [[0, 0, 0], [50, 0, 0], [50, 0, 0], [50, 0, 20], [100, 0, 20]]
    assert check_turn(traj(pts, range(5)), 20.0) == []
    idx, theta, _ = turn_estimates(np.asarray(pts, dtype=float))
    assert idx.tolist() == [1] and theta[0] == pytest.approx(0.0)
    # going back on itself at the corner is a 180 degree turn
    back = traj([[0, 0], [50, 0], [50, 0], [0, 0]], range(4))
    vs = check_turn(back, 1.0)
    assert len(vs) == 1 and "a turn of 180.0 deg" in vs[0].message and "point 1" in vs[0].message
    # two points, or the same point throughout: nothing to check
    assert check_turn(traj([[0, 0], [5, 5]], [0, 1]), 20.0) == []
    assert check_turn(traj([[1, 1], [1, 1], [1, 1]], [0, 1, 2]), 20.0) == []


def test_a_corner_rounded_by_an_arc() -> None:
    # a 90 degree corner rounded by a 20.5 m arc sampled every 15 deg passes a 20 m limit ...
    a = np.radians(np.arange(0.0, 91.0, 15.0))
    rounded = np.concatenate(
        [
            [[-100.0, 0.0]],
            np.stack([20.5 * np.sin(a), 20.5 - 20.5 * np.cos(a)], axis=1),
            [[20.5, 120.5]],
        ]
    )
    assert check_turn(timed(rounded, 10.0), 20.0) == []
    # ... but not a 25 m one
    assert len(check_turn(timed(rounded, 10.0), 25.0)) == 1
    # one step of 35 degrees cannot be checked from the samples, whatever the radius
    coarse = traj([[0, 0], [10, 0], [10 + 10 * math.cos(0.61), 10 * math.sin(0.61)]], [0, 1, 2])
    vs = check_turn(coarse, 1.0)
    assert len(vs) == 1 and "a turn of 35.0 deg at one point" in vs[0].message


def test_stretches() -> None:
    bad = np.array([True, True, False, True, False, False, True, True, True])
    assert stretches(bad) == [(0, 2), (3, 4), (6, 9)]
    key = np.array([0, 1, 0, 0, 0, 0, 1, 1, 0])
    assert stretches(bad, key) == [(0, 1), (1, 2), (3, 4), (6, 8), (8, 9)]
    assert stretches(np.zeros(3, dtype=bool)) == []


# ---------------------------------------------------------------------------- property tests
@dataclass(frozen=True)
class Curve:
    """A straight lead-in, an arc (a helix with a climb) and a straight lead-out: C1, horizontal
    curvature 0 or 1 / rho, constant climb angle ``gamma`` (degrees) and speed ``v``."""

    rho: float
    sweep: float
    turn: int
    gamma: float
    v: float
    lead_in: float
    lead_out: float
    heading: float
    spacing: float  # horizontal, <= rho / 4

    @property
    def length(self) -> float:
        """Horizontal length, m."""
        return self.lead_in + self.rho * self.sweep + self.lead_out

    def xy(self, s: np.ndarray) -> np.ndarray:
        h0, r, a = self.heading, self.rho, self.lead_in
        u0 = np.array([math.cos(h0), math.sin(h0)])
        n0 = self.turn * np.array([-math.sin(h0), math.cos(h0)])
        p_a = a * u0
        c = p_a + r * n0
        out = np.empty((s.size, 2))
        s1 = np.minimum(s, a)
        out[:] = s1[:, None] * u0
        on_arc = s > a
        phi = self.turn * (np.minimum(s[on_arc], a + r * self.sweep) - a) / r
        start = p_a - c
        cos, sin = np.cos(phi), np.sin(phi)
        out[on_arc] = c + np.stack(
            [cos * start[0] - sin * start[1], sin * start[0] + cos * start[1]], axis=1
        )
        h1 = h0 + self.turn * self.sweep
        after = s > a + r * self.sweep
        out[after] += (s[after] - a - r * self.sweep)[:, None] * np.array(
            [math.cos(h1), math.sin(h1)]
        )
        return out

    def sample(self, dense: int = 1) -> Trajectory:
        """Samples at horizontal spacing at most ``spacing / dense``, rounded to 6 decimals; the
        denser samples include the coarser ones."""
        n = math.ceil(self.length / self.spacing)
        s = np.linspace(0.0, self.length, n * dense + 1)
        z = 100.0 + s * math.tan(math.radians(self.gamma))
        t = s / (self.v * math.cos(math.radians(self.gamma)))
        pts = np.column_stack([self.xy(s), z])
        shift = np.array([1000.0, 1000.0, 0.0])  # away from the origin, as real coordinates
        return traj(np.round(pts + shift, 6), np.round(t, 6))


@st.composite
def curves(draw: Any) -> Curve:
    rho = draw(st.floats(5.0, 200.0))
    return Curve(
        rho=rho,
        # at least 0.75 rad, so that the arc holds 3 consecutive samples (spacing <= rho / 4)
        sweep=draw(st.floats(0.75, 3 * math.pi)),
        turn=draw(st.sampled_from([-1, 1])),
        gamma=draw(st.one_of(st.floats(-60.0, -0.5), st.floats(0.5, 60.0))),
        v=draw(st.floats(1.0, 60.0)),
        lead_in=draw(st.one_of(st.just(0.0), st.floats(0.0, 3.0))) * rho,
        lead_out=draw(st.one_of(st.just(0.0), st.floats(0.0, 3.0))) * rho,
        heading=draw(st.floats(0.0, 2 * math.pi)),
        # at most rho / 4; at least rho / 10, so that the 10x denser samples stay rho / 100
        # apart and the rounding to micrometres stays far below the curvature estimate's slack
        spacing=draw(st.floats(0.4, 1.0)) * rho / 4,
    )


#: A factor a few percent away from 1: below (the curve breaks the limit) or above.
factors = st.one_of(st.floats(0.3, 0.97), st.floats(1.03, 3.0))


@settings(max_examples=150, deadline=None)
@given(curves(), factors)
def test_turn_verdict_matches_the_radius(c: Curve, f: float) -> None:
    r_min = c.rho / f  # f > 1: the curve is wider than the limit
    for dense in (1, 10):
        assert (check_turn(c.sample(dense), r_min) == []) == (f > 1), dense


@settings(max_examples=150, deadline=None)
@given(curves(), factors, st.one_of(st.none(), st.floats(1.0, 90.0)))
def test_climb_verdict_matches_the_angle(c: Curve, f: float, other: float | None) -> None:
    limit = min(90.0, abs(c.gamma) * f)
    climb, descent = (limit, other) if c.gamma > 0 else (other, limit)
    for dense in (1, 10):
        vs = check_climb(c.sample(dense), climb, descent)
        assert (vs == []) == (f > 1), dense
        if vs:
            assert all(v.value == pytest.approx(abs(c.gamma), rel=3e-3) for v in vs)


@settings(max_examples=150, deadline=None)
@given(curves(), factors)
def test_speed_verdict_matches_the_speed(c: Curve, f: float) -> None:
    for dense in (1, 10):
        tr = c.sample(dense)
        assert (check_speed(tr, c.v * f) == []) == (f > 1), dense
        assert (check_speed(tr, 100.0 * c.v, c.v * f) == []) == (f < 1), dense


@settings(max_examples=60, deadline=None)
@given(curves(), factors, factors, factors)
def test_the_verifier_agrees_with_the_curve(c: Curve, fr: float, fa: float, fv: float) -> None:
    """All limits at once through ``verify_trajectories``; without kinematics only the maximum
    speed is checked."""
    up = c.gamma > 0
    limit = min(90.0, abs(c.gamma) * fa)
    uav = UAV(
        speed=c.v * 1.05,
        max_speed=c.v * 1.05,
        min_speed=min(c.v * fv, c.v * 1.05),
        turn_radius=c.rho / fr,
        max_climb_angle=limit if up else None,
        max_descent_angle=None if up else limit,
    )
    sc = Scenario(
        "open",
        Bounds((-10_000.0, -10_000.0, -20_000.0), (12_000.0, 12_000.0, 20_000.0)),
        (Task("a", (1000.0, 1000.0, 100.0), (1000.0, 1000.0, 100.0)),),
        uav=uav,
    )
    for dense in (1, 10):
        tr = c.sample(dense)
        counts = verify_trajectories([tr], sc).counts
        assert (counts["turn"] == 0) == (fr > 1)
        assert (counts["climb"] == 0) == (fa > 1)
        assert (counts["speed"] == 0) == (fv < 1)
        geo = verify_trajectories([tr], sc, kinematics=False)
        assert geo.ok and not geo.kinematics and geo.trajectory == "planned"


# ---------------------------------------------------------------------------- plans
def kinematic_scenario() -> Scenario:
    return Scenario(
        "kin",
        Bounds((-200.0, -200.0, 0.0), (200.0, 200.0, 200.0)),
        (Task("u0", (0.0, 0.0, 50.0), (100.0, 100.0, 50.0)),
         Task("u1", (0.0, 100.0, 50.0), (100.0, 200.0, 50.0))),
        uav=UAV(speed=20.0, turn_radius=20.0, min_speed=10.0, max_climb_angle=30.0,
                max_descent_angle=30.0, s2=10.0),
    )  # fmt: skip


def _timed_block(points: np.ndarray, speed: float) -> dict[str, Any]:
    t = timed(points, speed)
    return {"points": np.round(t.points, 6).tolist(), "times": np.round(t.times, 6).tolist()}


def kinematic_plan(flown_for_u1: bool = True) -> dict[str, Any]:
    """Two UAVs whose planned polylines turn 90 degrees at a corner and whose flown
    trajectories round it with a 30 m arc, at 20 m/s (u1's optionally not declared)."""
    uavs = []
    for k, y0 in enumerate((0.0, 100.0)):
        corner = [[0.0, y0, 50.0], [100.0, y0, 50.0], [100.0, y0 + 100.0, 50.0]]
        # the arc around (70, y0 + 30) from heading east to heading north
        a = np.linspace(-math.pi / 2, 0.0, 20)
        rounded = np.concatenate(
            [
                [[0.0, y0, 50.0]],
                np.stack([70 + 30 * np.cos(a), y0 + 30 + 30 * np.sin(a), np.full(20, 50.0)], 1),
                [[100.0, y0 + 100.0, 50.0]],
            ]
        )
        pl = timed(np.asarray(corner), 20.0)
        rec: dict[str, Any] = {
            "id": f"u{k}",
            "waypoints": corner,
            "times": pl.times.tolist(),
            "feasible": True,
        }
        if k == 0 or flown_for_u1:
            rec["flown"] = {"kind": "smoothed", "feasible": True, **_timed_block(rounded, 20.0)}
        uavs.append(rec)
    return {"scenario": "kin", "uavs": uavs}


def test_verify_plan_trajectory_kinds() -> None:
    sc = kinematic_scenario()
    plan = kinematic_plan()
    flown = verify_plan(plan, sc)
    assert flown.ok, [v.message for v in flown.violations]
    assert (flown.trajectory, flown.kinematics, flown.smoothed) == ("flown", True, False)
    # the planned polylines, geometrically: the corners are no violation
    planned = verify_plan(plan, sc, trajectory="planned")
    assert planned.ok and (planned.trajectory, planned.kinematics) == ("planned", False)
    d = planned.to_dict()
    assert (d["trajectory"], d["kinematics"]) == ("planned", False)
    assert json.loads(json.dumps(flown.to_dict()))["trajectory"] == "flown"
    # u1 declares no flown trajectory: its planned polyline is what it flies, and its corner
    # breaks the turn radius
    partial = verify_plan(kinematic_plan(flown_for_u1=False), sc)
    assert [(v.kind, v.uavs) for v in partial.violations] == [("turn", ("u1",))]
    assert "point 1 has a turn of 90.0 deg" in partial.violations[0].message
    assert any("u1: the plan calls it feasible" in w for w in partial.warnings)
    # a format-1 plan (no flown blocks at all) is flown as planned
    bare = {"uavs": [{k: v for k, v in u.items() if k != "flown"} for u in plan["uavs"]]}
    assert verify_plan(bare, sc).counts["turn"] == 2
    assert verify_plan(bare, sc, trajectory="planned").ok


def test_verify_plan_smoothed_and_bad_arguments() -> None:
    sc = kinematic_scenario()
    plan = kinematic_plan()
    for u in plan["uavs"]:
        u["smoothed"] = dict(u["flown"])
        u["smoothed"]["times"] = [2 * t for t in u["smoothed"]["times"]]  # 10 m/s: fine
    for rep in (verify_plan(plan, sc, smoothed=True), verify_plan(plan, sc, trajectory="smoothed")):
        assert rep.ok and (rep.trajectory, rep.kinematics, rep.smoothed) == ("smoothed", True, True)
    for u in plan["uavs"]:
        u["smoothed"]["times"] = [4 * t for t in u["flown"]["times"]]  # 5 m/s: too slow
    slow = verify_plan(plan, sc, trajectory="smoothed")
    assert slow.counts["speed"] == 2 * 21 and all(v.required == 10.0 for v in slow.violations)
    with pytest.raises(ValueError, match="trajectory must be one of flown, planned, smoothed"):
        verify_plan(plan, sc, trajectory="dense")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="smoothed=True"):
        verify_plan(plan, sc, smoothed=True, trajectory="planned")


def test_climb_in_a_plan() -> None:
    sc = kinematic_scenario()
    steep = [[0.0, 0.0, 50.0], [50.0, 0.0, 100.0], [100.0, 0.0, 100.0]]  # 45 deg up
    plan = {"uavs": [{"id": "u0", "waypoints": steep, "times": [0, 4, 7]}]}
    rep = verify_plan(plan, sc)
    assert [v.kind for v in rep.violations] == ["climb"]
    assert rep.violations[0].value == pytest.approx(45.0) and rep.violations[0].required == 30.0
    assert verify_plan(plan, sc, trajectory="planned").ok


# ---------------------------------------------------------------------------- CLI
def _files(tmp_path: Path, flown_for_u1: bool = True) -> tuple[Path, Path]:
    scenario = {
        "name": "kin",
        "bounds": {"lower": [-200, -200, 0], "upper": [200, 200, 200]},
        "uav": {"speed": 20, "turn_radius": 20, "min_speed": 10, "max_climb_angle": 30,
                "max_descent_angle": 30},
        "tasks": [{"id": "u0", "start": [0, 0, 50], "goal": [100, 100, 50]},
                  {"id": "u1", "start": [0, 100, 50], "goal": [100, 200, 50]}],
    }  # fmt: skip
    sc = tmp_path / "kin.json"
    sc.write_text(json.dumps(scenario))
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(kinematic_plan(flown_for_u1)))
    return plan, sc


def _invoke(*args: str) -> Any:
    result = runner.invoke(app, ["verify", *args])
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result


def test_cli_trajectory_options(tmp_path: Path) -> None:
    plan, sc = _files(tmp_path, flown_for_u1=False)
    r = _invoke(str(plan), str(sc))
    assert r.exit_code == 1
    assert "(flown trajectories, with kinematic limits)" in r.output
    assert "turn: u1: point 1 has a turn of 90.0 deg" in r.output
    assert "violations: 1 (turn 1)" in r.output
    out = tmp_path / "report.json"
    r = _invoke(str(plan), str(sc), "--polylines", "--json", str(out))
    assert r.exit_code == 0, r.output
    assert "(planned polylines, geometric, no kinematic limits)" in r.output
    rep = json.loads(out.read_text())
    assert (rep["trajectory"], rep["kinematics"], rep["ok"]) == ("planned", False, True)
    plan, sc = _files(tmp_path)
    r = _invoke(str(plan), str(sc))
    assert r.exit_code == 0 and "violations: none" in r.output
    r = _invoke(str(plan), str(sc), "--smoothed")
    assert r.exit_code == 2 and "uavs[0] (u0): no smoothed path" in r.output
    r = _invoke(str(plan), str(sc), "--smoothed", "--polylines")
    assert r.exit_code == 2 and "--smoothed and --polylines" in r.output


def test_cli_smoothed(tmp_path: Path) -> None:
    plan, sc = _files(tmp_path)
    data = json.loads(plan.read_text())
    for u in data["uavs"]:
        u["smoothed"] = {"points": u["waypoints"], "times": u["times"]}  # the corner again
    plan.write_text(json.dumps(data))
    r = _invoke(str(plan), str(sc), "--smoothed")
    assert r.exit_code == 1
    assert "(smoothed paths, with kinematic limits)" in r.output
    assert "violations: 2 (turn 2)" in r.output
