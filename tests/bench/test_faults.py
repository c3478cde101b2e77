"""Sweeps under faults (issue 19 item 4): kill -9 the runner or a worker at random moments, a
Dask worker, a disk that fills up during a shard write: nothing lost, nothing twice, no shard
corrupt, no orphaned worker, and the resumed sweep equals an uninterrupted one
(``tests/bench/faults.py`` is the harness). The default run injects a few faults; ``-m slow``
20 of each (``benchmarks/sweep_faults.py`` prints the same campaign)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from bench import faults
from uavplan.bench import runner
from uavplan.bench.catalog import get_plan
from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale
from uavplan.bench.runner import SweepStopped, run_sweep
from uavplan.bench.store import ResultStore

#: the default run's sweep: short runs, one worker (each start of a worker costs 1-2 s of CPU
#: on imports and kernels), kills soon after a shard is stored
QUICK: dict[str, Any] = {"runs": 600, "iterations": 80, "within": 0.5, "workers": 1}
#: the slow campaign's: long enough for 20 kills
LONG: dict[str, Any] = {"runs": 6000, "iterations": 40, "within": 1.0}


def _reference(factory: pytest.TempPathFactory, size: dict[str, Any]) -> pd.DataFrame:
    cmd = faults.SweepCommand(factory.mktemp("unused") / "x", **size)
    return cmd.reference(factory.mktemp("reference"))


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    """The uninterrupted sweep of QUICK."""
    return _reference(tmp_path_factory, QUICK)


@pytest.fixture(scope="module")
def long_reference(tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    """The uninterrupted sweep of LONG."""
    return _reference(tmp_path_factory, LONG)


def _assert_ok(outcome: faults.Outcome, kills: int) -> None:
    assert outcome.kills == kills, (outcome.line(), outcome.notes)
    assert outcome.ok, "\n".join([outcome.line(), *outcome.problems[:20], *outcome.notes])


def test_runner_killed_twice_loses_nothing_and_leaves_no_worker(
    tmp_path: Path, reference: pd.DataFrame
) -> None:
    cmd = faults.SweepCommand(tmp_path / "out", **QUICK)
    _assert_ok(faults.kill_runner(cmd, reference, 2, np.random.default_rng(1)), 2)


def test_worker_killed_the_sweep_goes_on(tmp_path: Path, reference: pd.DataFrame) -> None:
    cmd = faults.SweepCommand(tmp_path / "out", **QUICK)
    _assert_ok(faults.kill_workers(cmd, reference, 1, np.random.default_rng(2)), 1)


def test_disk_full_stops_with_one_line_and_resumes(tmp_path: Path, reference: pd.DataFrame) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    cmd = faults.SweepCommand(tmp_path / "out", **{**QUICK, "executor": "serial"})
    try:
        with faults.small_tmpfs(cmd.out, 1024):
            outcome = faults.disk_full(cmd, reference, np.random.default_rng(3))
    except PermissionError as exc:
        pytest.skip(str(exc))
    _assert_ok(outcome, 1)


@pytest.mark.slow  # 20 kills of each kind: 5-20 minutes each on 2 shared cores
@pytest.mark.parametrize("what", ["runner", "workers", "dask"])
def test_twenty_kills_lose_nothing(what: str, tmp_path: Path, long_reference: pd.DataFrame) -> None:
    executor = "dask" if what == "dask" else "process"
    cmd = faults.SweepCommand(tmp_path / "out", executor=executor, workers=2, **LONG)
    rng = np.random.default_rng(19)
    kill = faults.kill_runner if what == "runner" else faults.kill_workers
    _assert_ok(kill(cmd, long_reference, 20, rng), 20)


@pytest.mark.slow
def test_disk_full_five_times(tmp_path: Path, reference: pd.DataFrame) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    rng = np.random.default_rng(5)
    for i in range(5):
        cmd = faults.SweepCommand(tmp_path / f"out{i}", **{**QUICK, "workers": 2})
        try:
            with faults.small_tmpfs(cmd.out, 1024):
                outcome = faults.disk_full(cmd, reference, rng)
        except PermissionError as exc:
            pytest.skip(str(exc))
        _assert_ok(outcome, 1)


# ------------------------------------------------------------------ the runner's own rules
PLAN = ExperimentPlan(
    name="t-faults",
    description="test",
    scenarios=("sphere5",),
    algorithms=(Algorithm("pso", "pso"),),
    scales={"smoke": Scale(runs=40, iterations=5, pop_size=8),
            "paper": Scale(runs=40, iterations=5, pop_size=8)},
    kind="function",
)  # fmt: skip


def _lossy(losses: list[bool]) -> Any:
    """An executor that, call after call, yields one chunk then loses its workers (True), or
    loses them at once (False); then runs normally."""
    calls = iter(losses)

    def it(chunks: list[Any]) -> Iterator[list[dict[str, Any]]]:
        after_one = next(calls, None)
        for k, c in enumerate(chunks):
            if after_one is not None and k == int(after_one):
                raise runner._WorkerLost("a worker was killed")
            yield runner.execute_chunk(c, single_thread=False)

    return it


def test_the_incremental_folder_check_sees_every_fault(tmp_path: Path) -> None:
    """The harness's check reads only new or rewritten shards, and still sees a shard gone, a
    run stored twice, a row unlike the reference's, a rewritten shard and one that is cut."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    run_sweep(PLAN, tmp_path / "ref", executor="serial")
    reference = faults.stored_rows(tmp_path / "ref")
    out = tmp_path / "out"
    (out / "runs").mkdir(parents=True)
    shards = sorted((tmp_path / "ref" / "runs").glob("part-*.parquet"))
    assert len(shards) >= 3
    checker = faults.FolderCheck(out, reference)
    stored: set[str] = set()
    for s in shards[:2]:
        (out / "runs" / s.name).write_bytes(s.read_bytes())
        c = checker.check(stored)
        assert not c.problems and len(c.stored) > len(stored)
        stored = c.stored
    assert checker.equal
    first = out / "runs" / shards[0].name
    first.rename(first.with_name("gone.parquet"))  # a shard removed: its runs lost
    c = checker.check(stored)
    assert any("runs lost" in p for p in c.problems), c.problems
    first.with_name("gone.parquet").rename(first)
    assert not checker.check(stored).problems
    twice = out / "runs" / "part-twice.parquet"  # the same runs in a second shard
    twice.write_bytes(first.read_bytes())
    c = checker.check(stored)
    assert any("stored twice" in p for p in c.problems) and not checker.equal, c.problems
    twice.unlink()
    assert not checker.check(stored).problems and checker.equal
    table = pq.read_table(first)  # a shard rewritten with a wrong cost
    cost = table.column("best_cost").to_numpy().copy()
    cost[0] += 1e-12
    pq.write_table(table.set_column(table.schema.get_field_index("best_cost"), "best_cost",
                                    pa.array(cost)), first)  # fmt: skip
    c = checker.check(stored)
    assert any("best_cost" in p for p in c.problems) and not checker.equal, c.problems
    cut = out / "runs" / shards[2].name  # a new shard cut short
    cut.write_bytes(shards[2].read_bytes()[:-100])
    assert any("does not read" in p for p in checker.check(stored).problems)


def test_workers_lost_now_and_then_never_stop_the_sweep(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(runner, "_iter_serial", _lossy([True] * 10))
    s = run_sweep(PLAN, tmp_path, executor="serial", max_pool_restarts=1)
    assert s.executed == 40
    df = ResultStore(tmp_path).read()
    assert len(df) == 40 and df.run_id.is_unique


def test_workers_lost_in_a_row_stop_the_sweep_with_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(runner, "_iter_serial", _lossy([True, False, False, False]))
    with pytest.raises(SweepStopped, match=r"workers lost 3 times in a row .* are saved in"):
        run_sweep(PLAN, tmp_path, executor="serial", max_pool_restarts=2)
    saved = ResultStore(tmp_path).finished_ids()
    assert saved  # the chunk before the losses
    monkeypatch.undo()
    assert run_sweep(PLAN, tmp_path, executor="serial").skipped == len(saved)


def test_a_dask_cluster_without_workers_does_not_hang_the_sweep(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A local cluster whose nannies gave up restarting killed workers (seen in the fault
    campaign: the sweep waited for ever) or a remote one that lost every node: after
    NO_WORKER_TIMEOUT the workers count as lost; the sweep starts a new local cluster, or,
    lost again and again, stops with one line."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(runner, "NO_WORKER_TIMEOUT", 2.0)
    with (
        distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
        pytest.raises(SweepStopped, match=r"workers lost 2 times in a row .* no worker for 2 s"),
    ):
        run_sweep(PLAN, tmp_path, executor="dask", dask_client=client, max_pool_restarts=1)


def test_a_dead_worker_the_pool_does_not_notice_is_lost_all_the_same(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Once in the default test run a pool whose only worker was killed never failed its
    futures (Python 3.11; a worker killed while it sends its result does that, see the next
    test): the runner counts a worker seen dead with no chunk finishing for
    DEAD_WORKER_TIMEOUT as lost, and stops the pool's other workers."""
    monkeypatch.setattr(runner, "DEAD_WORKER_TIMEOUT", 2.0)
    monkeypatch.setattr(runner, "_dead_worker", lambda pool: True)  # as if the pool hung
    long = PLAN.runs("smoke", runs=1, iterations=10**7)  # a run that does not end by itself
    with pytest.raises(runner._WorkerLost, match="its pool hangs"):
        list(runner._iter_process([long], workers=1))


def test_a_worker_killed_while_it_sends_its_rows_does_not_hang_the_runner() -> None:
    """A worker killed half way through sending a chunk's rows leaves the pool's manager
    thread reading the rest for ever: the runner counts the worker lost after
    DEAD_WORKER_TIMEOUT and must end that thread, or the process never exits (the fault
    campaign saw a sweep stopped by a full disk print its one line and hang: its workers were
    terminated while one was sending). In a subprocess, so that a hang fails this test only."""
    script = textwrap.dedent(
        f"""
        import sys
        sys.path[:0] = {[str(Path(faults.__file__).parents[1])]!r}
        from bench import faults
        from uavplan.bench import runner
        runner.execute_chunk = faults.die_while_sending
        runner.DEAD_WORKER_TIMEOUT = 2.0
        try:
            list(runner._iter_process([[None]], workers=1))
        except runner._WorkerLost as exc:
            print("lost:", exc)
        """
    )
    res = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert "lost: a worker died" in res.stdout, res.stdout + res.stderr[-2000:]


def test_a_full_disk_stops_the_sweep_and_keeps_what_was_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import uavplan.bench.store as store

    real = store.write_bytes_atomic
    writes = []

    def full_after_two(path: Path, data: bytes) -> Path:
        writes.append(path)
        if len(writes) > 2:
            raise OSError(28, "No space left on device")
        return real(path, data)

    monkeypatch.setattr(store, "write_bytes_atomic", full_after_two)
    with pytest.raises(SweepStopped, match=r"No space left on device; \d+ runs of this sweep are "
                                           r"saved there, the \d+ finished since"):  # fmt: skip
        run_sweep(PLAN, tmp_path, executor="serial")
    saved = ResultStore(tmp_path).finished_ids()
    assert len(ResultStore(tmp_path).shards()) == 2 and saved
    monkeypatch.undo()
    rest = run_sweep(PLAN, tmp_path, executor="serial")
    assert rest.skipped == len(saved) and rest.skipped + rest.executed == 40


def test_one_sweep_at_a_time_per_folder(tmp_path: Path) -> None:
    lock = runner._lock_folder(tmp_path)
    try:
        with pytest.raises(SweepStopped, match=rf"{tmp_path} is in use by another sweep \(pid "):
            run_sweep(PLAN, tmp_path, executor="serial")
    finally:
        lock.close()
    assert run_sweep(PLAN, tmp_path, executor="serial").executed == 40


def test_a_killed_writers_temporary_file_is_removed_and_never_read(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / ".part-20260101T000000-dead-00001.parquet.k3j2.tmp").write_bytes(b"PAR1 half")
    (tmp_path / ".manifest.json.x8a1.tmp").write_text('{"plan": ')
    assert ResultStore(tmp_path).finished_ids() == set()
    run_sweep(PLAN, tmp_path, executor="serial")
    assert not list(runs.glob(".part-*")) and not list(tmp_path.glob(".*.tmp"))


def test_an_unreadable_shard_is_named(tmp_path: Path) -> None:
    run_sweep(PLAN, tmp_path, executor="serial", runs=2)
    bad = tmp_path / "runs" / "part-00000000T000000-junk-00001.parquet"
    bad.write_bytes(b"not parquet")
    with pytest.raises(SweepStopped, match=rf"{bad}: not a readable Parquet shard"):
        run_sweep(PLAN, tmp_path, executor="serial")


def test_cli_full_disk_exit_code_2_and_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from typer.testing import CliRunner

    import uavplan.bench.store as store
    from uavplan.cli import app

    def full(path: Path, data: bytes) -> Path:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(store, "write_bytes_atomic", full)
    res = CliRunner().invoke(app, ["bench", "run", "overhead", "--executor", "serial",
                                   "--out", str(tmp_path), "--no-report"])  # fmt: skip
    assert res.exit_code == 2, res.output
    assert f"bench run overhead: cannot write to {tmp_path / 'runs'}: No space left on device" in (
        res.output
    )
    assert "Traceback" not in res.output
    assert get_plan("overhead")  # the plan the message names
