"""A planned polyline's flight (planners/core/flight.py): timing within the UAV's speed range."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from uavplan.planners.core.flight import fly, pose_times
from uavplan.problems.validity import speed_violations
from uavplan.scenarios import resolve


def test_pose_times_keep_a_degenerate_speed_range_on_the_samples() -> None:
    """A constant-speed UAV (min_speed == v_max): a curve is longer than its chords, so the
    curve's length at v_max and the samples' at v_min cross; the samples are what is flown, so
    each piece takes its samples' length at that one speed (it took the curve's before, and
    the flight failed its own speed check by ~1e-7)."""
    Lc = np.array([100.0, 250.0, 80.0])
    Ls = Lc * (1 - 2.6e-7)  # chords of arcs sampled at h = R / 400
    t = pose_times(Lc, Ls, np.array([0.0, 1.0, 2.0, 3.0]), 50.0, 50.0, 50.0, "planned")
    assert np.allclose(np.diff(t), Ls / 50.0, rtol=0, atol=1e-12)
    # a range wide enough for the curve keeps the previous rule: no sooner than the curve at v_max
    t2 = pose_times(Lc, Ls, np.array([0.0, 0.0, 0.0, 0.0]), 40.0, 50.0, 50.0, "planned")
    assert np.allclose(np.diff(t2), Lc / 50.0)


@pytest.mark.parametrize("scenario", ["rscdwoa-static"])
def test_a_constant_speed_uav_flies_within_its_speed_range(scenario: str) -> None:
    """The fixed-wing UAVs of the RSCDWOA layouts (50 m/s, min_speed 50, turn radius 2 km): a
    Dubins flight of a polyline with turns is timed at exactly that speed along its samples and
    passes the speed check (every such flight failed it before, 'NO: speed')."""
    sc = resolve(scenario)
    task = sc.tasks[0]
    s, g = np.asarray(task.start), np.asarray(task.goal)
    mid = 0.5 * (s + g) + np.array([8000.0, -8000.0, 0.0])
    wp = np.array([s, mid, g])
    seg = np.linalg.norm(np.diff(wp, axis=0), axis=1)
    times = np.concatenate([[0.0], np.cumsum(seg)]) / sc.uav.speed
    uav = sc.uav
    assert uav.min_speed == uav.v_max
    flight = fly(dataclasses.replace(sc, moving_obstacles=()), task, wp, times)
    assert flight.kind == "smoothed"
    assert not speed_violations(flight.points[None], flight.times[None], uav.min_speed,
                                uav.v_max)[0]  # fmt: skip
    assert "speed" not in flight.violations


@pytest.mark.parametrize("timing", [None, (2.0, 0.03)])
def test_take_off_slots_answer_as_the_table_does_in_any_order(timing) -> None:
    """:class:`ClearAt` answers, for every wait asked, in increasing order (as
    :func:`first_clear` asks) or shuffled, whether the flight moved that much later conflicts
    in the table (:meth:`ReservationTable.conflicts`, one wait at a time)."""
    from uavplan.planners.core.flight import ClearAt, Flight
    from uavplan.world.reservations import ReservationTable

    rng = np.random.default_rng(3)
    table = ReservationTable(np.zeros(3), np.full(3, 400.0), 15.0, timing=timing)
    for k in range(10):
        p = rng.uniform(0, 400, (5, 3))
        p[:, 2] = rng.uniform(40, 60, 5)
        t = rng.uniform(0, 60) + np.concatenate([[0.0], np.cumsum(rng.uniform(5, 15, 4))])
        table.add(f"u{k}", p, t)
    waits = np.arange(0.0, 150.0, 5.0)
    checked = 0
    for q in range(6):
        p = rng.uniform(0, 400, (4, 3))
        p[:, 2] = 50.0
        f = Flight(p, np.array([0.0, 10.0, 20.0, 30.0]), "polyline", "polyline", ())
        want = ~table.conflicts(np.broadcast_to(p, (len(waits), 4, 3)), f.times + waits[:, None])
        for order in (np.arange(len(waits)), rng.permutation(len(waits))):
            slots = ClearAt(table, waits, 7)
            got = np.zeros(len(waits), dtype=bool)
            for i in order:
                got[i] = slots.clear(q, f, int(i))
            np.testing.assert_array_equal(got, want)
            checked += int((~want).sum())
    assert checked > 20  # blocked waits were asked
