"""The sweep runner: resumable, identical across executors, errors recorded."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from uavplan.bench.catalog import get_plan
from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, derive_seed
from uavplan.bench.runner import SweepInterrupted, run_sweep
from uavplan.bench.store import ResultStore

PLAN = ExperimentPlan(
    name="t-sphere",
    description="test",
    scenarios=("sphere5", "sphere8"),
    algorithms=(Algorithm("pso", "pso"), Algorithm("de", "de")),
    scales={
        "smoke": Scale(runs=6, iterations=8, pop_size=12),
        "paper": Scale(runs=6, iterations=8, pop_size=12),
    },
    kind="function",
)


def _results(folder: Path) -> pd.DataFrame:
    df = ResultStore(folder).read()
    return df.sort_values("run_id").reset_index(drop=True)


def test_seeds_depend_only_on_identity() -> None:
    a = derive_seed(0, "p", "s", "a", 3)
    assert a == derive_seed(0, "p", "s", "a", 3)
    assert len({derive_seed(0, "p", "s", "a", i) for i in range(100)}) == 100
    assert a != derive_seed(1, "p", "s", "a", 3)
    assert a != derive_seed(0, "p", "s", "b", 3)


@pytest.mark.slow  # a Dask cluster and two process pools: 60-90 s
def test_serial_process_and_dask_give_identical_results(tmp_path: Path) -> None:
    serial = run_sweep(PLAN, tmp_path / "serial", executor="serial")
    assert serial.executed == 24 and serial.failed == 0
    run_sweep(PLAN, tmp_path / "proc", executor="process", workers=2)
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        run_sweep(PLAN, tmp_path / "dask", executor="dask", dask_client=client)
    a, b, c = (_results(tmp_path / n) for n in ("serial", "proc", "dask"))
    assert len(a) == len(b) == len(c) == 24
    for col in ("run_id", "seed", "best_cost", "evaluations"):
        assert a[col].tolist() == b[col].tolist() == c[col].tolist(), col
    for h1, h2, h3 in zip(a.history, b.history, c.history, strict=True):
        assert np.array_equal(h1, h2) and np.array_equal(h1, h3)
    # worker processes ran their runs (host metadata recorded)
    assert set(b.host) and b.python.notna().all()


def test_resume_skips_finished_runs(tmp_path: Path) -> None:
    first = run_sweep(PLAN, tmp_path, executor="serial", runs=3)
    assert first.executed == 12
    second = run_sweep(PLAN, tmp_path, executor="serial", runs=6)
    assert second.skipped == 12 and second.executed == 12
    third = run_sweep(PLAN, tmp_path, executor="serial", runs=6)
    assert third.executed == 0 and third.skipped == 24
    df = _results(tmp_path)
    assert len(df) == 24 and df.run_id.is_unique


def test_every_finished_chunk_is_on_disk_before_the_next(tmp_path: Path) -> None:
    """A kill -9 between chunks loses no finished run: each chunk's rows are written when it
    ends, not when the store's timer next fires (which kept all but a chunk's first row in
    memory for as long as the next chunk ran)."""
    seen: list[tuple[int, int]] = []

    def check(pr) -> None:  # type: ignore[no-untyped-def]
        seen.append((pr.done, len(ResultStore(tmp_path).finished_ids())))

    run_sweep(PLAN, tmp_path, executor="serial", progress=check)
    assert len(seen) > 2 and all(done == on_disk for done, on_disk in seen), seen


def test_interrupt_saves_finished_runs(tmp_path: Path) -> None:
    seen = []

    def boom(pr) -> None:  # type: ignore[no-untyped-def]
        seen.append(pr.done)
        if pr.done >= 5:
            raise KeyboardInterrupt

    with pytest.raises(SweepInterrupted, match="resume"):
        run_sweep(PLAN, tmp_path, executor="serial", progress=boom)
    saved = ResultStore(tmp_path).finished_ids()
    assert len(saved) >= 5
    rest = run_sweep(PLAN, tmp_path, executor="serial")
    assert rest.skipped == len(saved) and rest.skipped + rest.executed == 24
    assert _results(tmp_path).run_id.is_unique


def test_failing_runs_are_recorded_and_sweep_goes_on(tmp_path: Path) -> None:
    plan = ExperimentPlan(
        "t-fail",
        "t",
        ("sphere4", "nosuchfunction"),
        (Algorithm("pso", "pso"),),
        {
            "smoke": Scale(runs=2, iterations=3, pop_size=5),
            "paper": Scale(runs=2, iterations=3, pop_size=5),
        },
        kind="function",
    )
    s = run_sweep(plan, tmp_path, executor="serial")
    assert s.executed == 4 and s.failed == 2
    assert all("nosuchfunction" in f for f in s.failures)
    df = _results(tmp_path)
    assert set(df.status) == {"ok", "error"}
    assert df[df.status == "error"].error.str.contains("unknown benchmark function").all()
    # errored runs count as finished unless retried
    assert run_sweep(plan, tmp_path, executor="serial").executed == 0
    assert run_sweep(plan, tmp_path, executor="serial", retry_failed=True).executed == 2


def test_results_readable_by_duckdb(tmp_path: Path) -> None:
    run_sweep(PLAN, tmp_path, executor="serial", runs=2)
    duckdb = pytest.importorskip("duckdb")
    con = duckdb.connect()
    rows = con.execute(f"SELECT count(*) FROM read_parquet('{tmp_path}/runs/*.parquet')").fetchall()
    assert rows[0][0] == 8


def test_builtin_plans_have_both_scales() -> None:
    for name in ("spso-small", "overhead"):
        p = get_plan(name)
        assert {"smoke", "paper"} <= set(p.scales)
        assert len(p.runs("smoke")) >= 1


def test_shards_share_one_schema(tmp_path: Path) -> None:
    """A column that is all null in one shard and set in another must still read as one
    dataset (pandas on the folder, as the docs say)."""
    store = ResultStore(tmp_path)
    base = {"plan": "p", "scenario": "s", "algorithm": "a", "status": "error", "error": "boom"}
    store.add(
        {
            **base,
            "run_id": "1",
            "run_index": 1,
            "first_feasible_iteration": None,
            "best_cost": None,
            "feasible": None,
            "history": None,
            "uav_min_clear_m": [None, None],  # a kind's own metrics, none this time
            "min_separation": None,
            "verified": None,
        }
    )
    store.flush()
    store.add(
        {
            **base,
            "run_id": "2",
            "run_index": 2,
            "status": "ok",
            "error": None,
            "first_feasible_iteration": 7,
            "best_cost": 1.5,
            "feasible": True,
            "history": [3.0, 1.5],
            "uav_min_clear_m": [12.5, 40.0],
            "min_separation": 61.0,
            "verified": True,
        }
    )
    store.flush()
    # and null again after the type is known: it takes the known type
    store.add({**base, "run_id": "3", "run_index": 3, "uav_min_clear_m": [None],
               "min_separation": None, "verified": None})  # fmt: skip
    store.flush()
    assert len(store.shards()) == 3
    df = pd.read_parquet(tmp_path / "runs").sort_values("run_id")
    assert df.verified.tolist()[1] == 1  # a bool column, though null in the first shard
    assert len(store.read()) == 3  # the store's own reader too
    assert df.first_feasible_iteration.tolist()[1] == 7
    assert np.isnan(df.best_cost.tolist()[0]) and df.best_cost.tolist()[1] == 1.5
    assert df.min_separation.tolist()[1] == 61.0
    assert list(df.uav_min_clear_m.tolist()[1]) == [12.5, 40.0]


def test_report_uses_the_runs_the_last_sweep_asked_for(tmp_path) -> None:
    from uavplan.bench.catalog import get_plan
    from uavplan.bench.report import write_report
    from uavplan.bench.runner import run_sweep

    plan = get_plan("spso-small")
    run_sweep(plan, tmp_path, scale="smoke", executor="serial", runs=2)
    run_sweep(plan, tmp_path, scale="smoke", executor="serial", runs=1)
    _, md = write_report(tmp_path)
    text = md.read_text()
    assert "| runs finished | 3 |" in text  # one run per cell of the three algorithms


def test_only_runs_the_chosen_configurations_and_keeps_the_rest(tmp_path: Path) -> None:
    first = run_sweep(PLAN, tmp_path, executor="serial", runs=2, only=["de"])
    assert first.executed == 4 and first.skipped == 0
    assert set(_results(tmp_path).algorithm) == {"de"}
    second = run_sweep(PLAN, tmp_path, executor="serial", runs=2)
    assert second.skipped == 4 and second.executed == 4
    assert len(_results(tmp_path)) == 8
    with pytest.raises(ValueError, match="no configuration 'ga'; choose from pso, de"):
        run_sweep(PLAN, tmp_path, executor="serial", only=["ga"])


def test_cli_only_refuses_an_unknown_configuration(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from uavplan.cli import app

    res = CliRunner().invoke(
        app, ["bench", "run", "ppswarm-table4", "--only", "ppswarm-r9", "--out", str(tmp_path)]
    )
    assert res.exit_code == 2
    assert "--only: plan 'ppswarm-table4' has no configuration 'ppswarm-r9'" in res.output
    assert "ppswarm-r5-flown" in res.output and not (tmp_path / "runs").exists()


def test_cli_does_not_print_an_overhead_figure_for_a_short_sweep(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from uavplan.cli import app

    res = CliRunner().invoke(
        app, ["bench", "run", "functions", "--only", "pso", "--runs", "1", "--out", str(tmp_path),
              "--executor", "serial", "--no-report"],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "runner overhead: not measured" in res.output and "%" not in res.output


def test_bench_list_piped_gives_whole_descriptions() -> None:
    from typer.testing import CliRunner

    from uavplan.bench.catalog import available_plans, get_plan
    from uavplan.cli import app

    res = CliRunner().invoke(app, ["bench", "list"])
    assert res.exit_code == 0
    lines = res.output.splitlines()
    for name in available_plans():
        line = next(x for x in lines if x.startswith(f"{name}: "))
        assert line.endswith(get_plan(name).description)


def test_convergence_figure_says_when_nothing_is_finite() -> None:
    import numpy as np
    import pandas as pd

    from uavplan.bench.plots import convergence_figure

    df = pd.DataFrame({"status": ["ok", "ok"], "scenario": ["s", "s"], "algorithm": ["a", "b"],
                       "history": [np.full(5, np.inf), np.full(5, np.inf)]})  # fmt: skip
    fig = convergence_figure(df)
    assert fig is not None
    ax = fig.axes[0]
    assert ax.get_legend() is None and not ax.lines
    assert any("every run infeasible" in t.get_text() for t in ax.texts)
