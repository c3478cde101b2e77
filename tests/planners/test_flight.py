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
