"""Every built-in plan runs end to end at smoke scale, with its report, and gives the numbers of
its golden record (``tests/golden/smoke.json``): one sweep per plan checks both. The default run
takes one run per configuration of each plan; ``pytest -m slow`` (``.ci/nightly``) every run."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pandas as pd
import pytest

from golden.record import GOLDEN, differences, plan_rows
from uavplan.bench.catalog import available_plans, get_plan
from uavplan.bench.plans import ExperimentPlan
from uavplan.bench.report import write_report
from uavplan.bench.runner import run_sweep
from uavplan.bench.store import ResultStore

WANT = json.loads(GOLDEN.read_text())


def sampled(plan: ExperimentPlan) -> ExperimentPlan:
    """``plan`` at smoke scale cut to its first scenario and first run, every configuration:
    the same run ids, seeds and results as those runs of the whole smoke scale (seeds depend
    on the run, not on the plan's size)."""
    scale = plan.scales["smoke"]
    first = (scale.scenarios or plan.scenarios)[:1]
    return dataclasses.replace(
        plan, scales={**plan.scales, "smoke": dataclasses.replace(scale, scenarios=first, runs=1)}
    )


@pytest.mark.parametrize("name", available_plans())
def test_plan_runs_a_sample_at_smoke_scale(name: str, tmp_path: Path) -> None:
    """Every plan, one run per configuration (its first scenario and run) against the golden
    record's rows for those runs; the whole smoke scale runs in ``pytest -m slow``."""
    check_smoke(get_plan(name), sampled(get_plan(name)), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", available_plans())
def test_plan_runs_at_smoke_scale(name: str, tmp_path: Path) -> None:
    """One test per plan, so that the plans run in parallel (the longest is 15-40 s)."""
    plan = get_plan(name)
    check_smoke(plan, plan, tmp_path)


def check_smoke(whole: ExperimentPlan, plan: ExperimentPlan, tmp_path: Path) -> None:
    """Run ``plan`` (``whole`` or a part of it) at smoke scale: its rows equal the golden
    record's (every recorded row when ``plan`` is ``whole``), and the sweep, the verifier's gate
    and the report hold."""
    name = whole.name
    summary = run_sweep(plan, tmp_path, scale="smoke", executor="serial")
    got = plan_rows(ResultStore(tmp_path).read())
    want = WANT["plans"][name]
    if plan is not whole:
        assert got and set(got) <= set(want), sorted(set(got) - set(want))[:5]
        want = {k: v for k, v in want.items() if k in got}
    diffs = differences(want, got, f"/plans/{name}")
    assert not diffs, "golden record differs:\n" + "\n".join(diffs[:40])
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
    assert_gate(plan.kind, df)
    html, md = write_report(tmp_path)
    text = html.read_text()
    assert "<table>" in text and "data:image/png;base64," in text
    if plan.reference and len(plan.algorithms) > 1:
        assert "rank-sum" in md.read_text()


def assert_gate(kind: str, df: pd.DataFrame) -> None:
    """The verifier as a gate (issue 19 item 6): every run that calls its plan feasible
    (``feasible``: the path, the fleet's polylines, the mission as flown, and ``flown_feasible``
    where the row has it) has the independent verifier's verdict on it, and the verifier
    passes it (it also passes everything else the run calls feasible: ``verifier_ok`` is never
    False). Benchmark functions plan nothing."""
    if kind == "function":
        return
    ok = df[df["status"] == "ok"]
    assert "verifier_ok" in ok.columns, f"run kind {kind!r} records no verifier verdict"
    verdict = ok["verifier_ok"].astype("boolean")
    claimed = ok["feasible"].astype(bool)
    if "flown_feasible" in ok.columns:
        claimed |= ok["flown_feasible"].astype(bool)
    unchecked = ok[claimed & verdict.isna()]
    assert unchecked.empty, f"called feasible, not verified: {unchecked['run_id'].tolist()}"
    rejected = ok[verdict.fillna(True) == False]  # noqa: E712 - a nullable boolean column
    assert rejected.empty, "called feasible, rejected by the verifier:\n" + "\n".join(
        f"{r.run_id}: {r.verifier_rejects}" for r in rejected.itertuples()
    )


def test_run_counts_match_the_runs_of_every_plan_and_scale() -> None:
    """``bench list`` counts runs with ExperimentPlan.n_runs (no seeds derived): the same
    numbers as the runs themselves, for every registered plan and scale."""
    for name in available_plans():
        plan = get_plan(name)
        for scale in plan.scales:
            assert plan.n_runs(scale) == len(plan.runs(scale)), (name, scale)
