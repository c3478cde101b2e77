"""Compacting a sweep's shards (``ResultStore.compact``, ``uavplan bench compact``): the same
runs, read and resumed the same, in fewer shards."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from typer.testing import CliRunner

from uavplan.bench.store import ResultStore
from uavplan.cli import app


def _row(i: int, status: str = "ok", error: str | None = None) -> dict:
    return {"run_id": f"r{i}", "plan": "p", "scenario": "s", "algorithm": "a", "run_index": i,
            "status": status, "error": error, "best_cost": float(i), "feasible": i % 2 == 0,
            "history": [float(i), float(i) / 2]}  # fmt: skip


def _store(root: Path) -> ResultStore:
    s = ResultStore(root, flush_rows=3, flush_seconds=1e9)
    for i in range(20):
        s.add(_row(i))
    s.add(_row(5, "error", "boom"))  # a run written twice: the last row counts
    s.flush()
    return s


def test_compact_keeps_every_run_in_fewer_shards(tmp_path: Path) -> None:
    s = _store(tmp_path)
    before = s.read().sort_values("run_id").reset_index(drop=True)
    ids = s.finished_ids()
    n = len(s.shards())
    assert n == 7
    assert s.compact(rows_per_shard=8) == (7, 3)
    after = ResultStore(tmp_path).read().sort_values("run_id").reset_index(drop=True)
    pd.testing.assert_frame_equal(after, before)
    assert after.set_index("run_id").loc["r5", "status"] == "error"
    assert ResultStore(tmp_path).finished_ids() == ids
    s.add(_row(99))  # the store goes on as before
    s.flush()
    assert len(ResultStore(tmp_path).read()) == 21


def test_the_command_says_what_it_did_and_refuses_a_folder_without_runs(tmp_path: Path) -> None:
    _store(tmp_path / "sweep")
    r = CliRunner().invoke(app, ["bench", "compact", str(tmp_path / "sweep")])
    assert r.exit_code == 0, r.output
    assert "7 shards" in r.output and "-> 1 " in r.output
    r = CliRunner().invoke(app, ["bench", "compact", str(tmp_path / "nothing")])
    assert r.exit_code == 2
    assert "no runs/ folder" in r.output and "Traceback" not in r.output


def test_columns_read_from_every_shard_and_a_missing_one_names_the_shard(tmp_path: Path) -> None:
    """Reading some columns reads them from every shard (the last row of a run wins); a
    column a shard lacks is an error that names the shard, as an unreadable shard is."""
    import pytest

    from uavplan.bench.store import StoreError

    s = _store(tmp_path)
    df = s.read(columns=["run_id", "status"])
    assert list(df.columns) == ["run_id", "status"] and len(df) == 20
    assert df.set_index("run_id").loc["r5", "status"] == "error"
    with pytest.raises(StoreError, match=r"part-.*\.parquet: not a readable Parquet shard.*nope"):
        s.read(columns=["run_id", "nope"])


def test_list_columns_are_read_only_when_asked(tmp_path: Path) -> None:
    """``lists``: the per-run list columns (here ``history``) are left unread unless named
    (or True, the default: all); the other columns and rows are the same; columns asked for
    by name are read whatever ``lists`` says."""
    s = _store(tmp_path)
    full = s.read()
    light = s.read(lists=())
    assert "history" in full and "history" not in light
    assert list(light.columns) == [c for c in full.columns if c != "history"]
    pd.testing.assert_frame_equal(light, full.drop(columns="history"))
    assert "history" in s.read(lists=("history",))
    assert list(s.read(columns=["run_id", "history"], lists=()).columns) == ["run_id", "history"]
