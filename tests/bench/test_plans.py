"""Every built-in plan runs end to end at smoke scale (what CI runs), with its report."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from uavplan.bench.catalog import available_plans, get_plan
from uavplan.bench.report import write_report
from uavplan.bench.runner import run_sweep

#: plans whose smoke sweep takes 25-100 s here: in the slow set (their golden records, which run
#: the same sweep and compare its numbers, stay in the default run)
SLOW = {"fleet-scale", "hrmaga-compare", "rscdwoa-dynamic", "functions", "functions-iterations"}


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in available_plans()],
)
def test_plan_runs_at_smoke_scale(name: str, tmp_path: Path) -> None:
    plan = get_plan(name)
    summary = run_sweep(plan, tmp_path, scale="smoke", executor="serial")
    assert summary.failed == 0, summary.failures
    assert summary.executed == len(plan.runs("smoke"))
    df = pd.read_parquet(tmp_path / "runs")
    assert set(df["algorithm"]) == {a.label for a in plan.algorithms}
    assert set(df["scenario"]) == set(plan.scales["smoke"].scenarios or plan.scenarios)
    assert (df["evaluations"] > 0).all()
    scale = plan.scales["smoke"]
    if scale.evaluations:  # an evaluation budget is respected up to one batch
        assert (df["evaluations"] >= scale.evaluations).all()
    if plan.kind == "fleet":  # never unsafe called safe: every verdict the verifier's too
        ok = df[df["status"] == "ok"]
        flown = ok["flown_feasible"].astype(bool)
        assert not (flown & ~ok["flown_verified"].astype(bool)).any()
        # the paper's mode (polylines planned apart): its polylines are what is verified
        apart = ok["verified"].notna()
        assert not (ok["feasible"].astype(bool) & apart & ~ok["verified"].astype("boolean")).any()
        assert (flown | (ok["flown_not_ok"] > 0)).all()  # a failed fleet names its UAVs
    html, md = write_report(tmp_path)
    text = html.read_text()
    assert "<table>" in text and "data:image/png;base64," in text
    if plan.reference and len(plan.algorithms) > 1:
        assert "rank-sum" in md.read_text()


def test_run_counts_match_the_runs_of_every_plan_and_scale() -> None:
    """``bench list`` counts runs with ExperimentPlan.n_runs (no seeds derived): the same
    numbers as the runs themselves, for every registered plan and scale."""
    for name in available_plans():
        plan = get_plan(name)
        for scale in plan.scales:
            assert plan.n_runs(scale) == len(plan.runs(scale)), (name, scale)
