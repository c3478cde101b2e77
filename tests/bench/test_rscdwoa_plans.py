"""The RSCDWOA application's report helpers: Wilson intervals, Table 3's deviation, Fig. 14's
curvature profile."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from uavplan.bench.papers.rscdwoa import PROFILE, _uav_frame, curvature_profile, deviation, wilson


def test_wilson_interval_brackets_the_rate() -> None:
    lo, hi = wilson(0, 80)
    assert lo == pytest.approx(0.0, abs=1e-12) and hi == pytest.approx(0.0458, abs=1e-3)
    lo, hi = wilson(64, 64)
    assert hi == pytest.approx(1.0) and lo == pytest.approx(0.943, abs=1e-3)
    lo, hi = wilson(30, 60)
    assert lo < 0.5 < hi


def test_curvature_profile_of_a_circle_and_a_line() -> None:
    R = 2000.0
    th = np.linspace(0.0, np.pi, 400)
    arc = np.column_stack([R * np.cos(th), R * np.sin(th), np.full_like(th, 1000.0)])
    k, dk = curvature_profile(arc)
    assert len(k) == len(dk) == PROFILE
    inner = np.asarray(k)[5:-5]
    np.testing.assert_allclose(inner, 1000.0 / R, rtol=1e-3)  # 0.5 per km
    assert max(dk[5:-5]) < 1e-6  # constant curvature
    line = np.column_stack([np.linspace(0, 1e4, 50), np.zeros(50), np.zeros(50)])
    k, dk = curvature_profile(line)
    assert max(k) == 0.0 and max(dk) == 0.0


def test_deviation_from_a_reference_polyline() -> None:
    ref = np.array([[0.0, 0.0], [1000.0, 0.0]])
    pts = np.array([[0.0, 30.0, 0.0], [1000.0, 30.0, 0.0]])
    d = deviation(pts, np.array([0.0, 20.0]), ref)
    assert d.shape == (20,)
    np.testing.assert_allclose(d, 30.0)


def test_per_uav_columns_missing_from_older_runs_are_nan() -> None:
    """Runs stored before a per-UAV column existed (None or NaN in the merged table) give NaN
    for their UAVs instead of breaking the report."""
    df = pd.DataFrame({
        "status": ["ok", "ok", "ok"], "algorithm": ["apf", "apf", "ppswarm"],
        "run_index": [0, 1, 0],
        "uav_uav": [np.array(["a", "b"]), np.array(["a", "b"]), np.array(["a", "b"])],
        "uav_plan_s": [None, np.nan, np.array([1.0, 2.0])],
    })  # fmt: skip
    u = _uav_frame(df)
    assert len(u) == 6
    assert u["plan_s"].isna().sum() == 4 and u["plan_s"].dropna().tolist() == [1.0, 2.0]
