"""The RGG-PSO+ paper's measures on small hand-made run tables (values worked out by hand)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from uavplan.bench.papers import rggpso
from uavplan.bench.report import write_report
from uavplan.bench.runner import run_sweep


def _row(scenario: str, alg: str, length: float, feasible: bool, ffi: float, fh: list[float]):
    return {
        "status": "ok",
        "run_id": f"{scenario}/{alg}/{len(fh)}/{length}",
        "scenario": scenario,
        "algorithm": alg,
        "path_length": length,
        "feasible": feasible,
        "first_feasible_iteration": ffi,
        "feasible_history": np.asarray(fh, dtype=float),
        "reference_length": 10.0,
        "wall_time": 0.1,
        "evaluations": 100,
    }


INF = math.inf


@pytest.fixture()
def table() -> pd.DataFrame:
    rows = [
        # scene A: finals 10, 12 (rgg-pso), 14, and an infeasible pso run
        _row("rgg-n05-i000", "rgg-pso", 10.0, True, 1, [11.0, 10.0, 10.0]),
        _row("rgg-n05-i000", "rgg-pso", 12.0, True, 1, [12.0, 12.0, 12.0]),
        _row("rgg-n05-i000", "pso", 14.0, True, 2, [INF, 18.0, 14.0]),
        _row("rgg-n05-i000", "pso", 30.0, False, np.nan, [INF, INF, INF]),
        # scene B: all equal finals -> every finite value normalizes to 0
        _row("rgg-n06-i000", "rgg-pso", 20.0, True, 1, [20.0, 20.0, 20.0]),
        _row("rgg-n06-i000", "pso", 20.0, True, 3, [INF, INF, 20.0]),
    ]
    return pd.DataFrame(rows)


def test_measures_follow_the_definitions(table: pd.DataFrame) -> None:
    m = rggpso.measures(table).set_index("run_id")
    a = m[m["scenario"] == "rgg-n05-i000"]
    # Eq. 2 over finals {10, 12, 14} (the infeasible run is excluded and scores 5)
    assert list(a["normalized_length"]) == pytest.approx([0.0, 0.5, 1.0, 5.0])
    assert list(a["f_measure"].fillna(-1)) == [0.0, 0.0, 1.0, -1.0]
    # first feasible lengths 11, 12, 18 -> (x - 10) / 4; none -> penalty
    assert list(a["first_feasible_normalized"]) == pytest.approx([0.25, 0.5, 2.0, 5.0])
    assert list(a["reference_ratio"][:3]) == pytest.approx([1.0, 1.2, 1.4])
    assert math.isinf(a["reference_ratio"].iloc[3])
    b = m[m["scenario"] == "rgg-n06-i000"]
    assert list(b["normalized_length"]) == [0.0, 0.0]
    assert list(b["first_feasible_normalized"]) == [0.0, 0.0]
    assert set(m["n_obstacles"]) == {5.0, 6.0}


def test_tables_and_fig5(table: pd.DataFrame) -> None:
    m = rggpso.measures(table)
    t1 = rggpso.table1(m)
    # pso F-Measure over the runs that found a feasible path: 1 (scene A) and 2 (scene B)
    assert t1.loc["pso", "F-Measure mean"] == pytest.approx(1.5)
    assert t1.loc["pso", "F-Measure var"] == pytest.approx(0.5)
    assert t1.loc["pso", "runs never feasible"] == 1
    assert t1.loc["rgg-pso", "share feasible at iteration 0"] == 1.0
    assert t1.loc["pso", "paper F-Measure mean"] == 13.984
    t2 = rggpso.table2(m)
    assert t2.loc["rgg-pso", "normalized length mean"] == pytest.approx((0 + 0.5 + 0) / 3)
    assert t2.loc["pso", "normalized length mean"] == pytest.approx((1 + 5 + 0) / 3)
    assert t2.loc["pso", "runs without a feasible path"] == 1
    curves = rggpso.fig5_curves(m)
    # iteration 0: rgg-pso (11-10)/4, (12-10)/4 and 0 in scene B; pso: penalty everywhere
    assert curves.loc[0, "rgg-pso"] == pytest.approx((0.25 + 0.5 + 0.0) / 3)
    assert curves.loc[0, "pso"] == pytest.approx(5.0)
    assert curves.loc[2, "pso"] == pytest.approx((1.0 + 5.0 + 0.0) / 3)


def test_ordering_test_detects_a_true_and_a_false_claim() -> None:
    rng = np.random.default_rng(0)
    rows = []
    for s in range(30):
        for _ in range(3):
            base = 10.0 + rng.random()
            rows.append(_row(f"rgg-n05-i{s:03d}", "rgg-pso", base, True, 1, [base]))
            rows.append(_row(f"rgg-n05-i{s:03d}", "pso", base + 2.0, True, 5, [base + 2.0]))
    m = rggpso.measures(pd.DataFrame(rows))
    claims = [("normalized_length", "rgg-pso", "pso"), ("normalized_length", "pso", "rgg-pso")]
    t = rggpso.ordering_tests(m, claims)
    assert bool(t.loc["rgg-pso < pso", "holds"]) and t.loc["rgg-pso < pso", "better wins"] == 30
    assert not bool(t.loc["pso < rgg-pso", "holds"])
    assert t.loc["rgg-pso < pso", "rank-biserial"] == pytest.approx(-1.0)


def test_rgg_report_has_the_paper_tables(tmp_path: Path) -> None:
    from uavplan.bench.catalog import get_plan

    run_sweep(get_plan("rggpso-rq1"), tmp_path, scale="smoke", executor="serial")
    _, md = write_report(tmp_path)
    text = md.read_text()
    assert "Final normalized path length as in the paper's Table 2 (RQ3)" in text
    assert "F-Measure and first feasible path as in the paper's Table 1 (RQ2)" in text
    assert "The paper's orderings, tested" in text
    assert (tmp_path / "figures" / "fig5.png").exists()
