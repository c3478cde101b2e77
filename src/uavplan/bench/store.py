"""The results store: finished runs as Parquet shards under ``DIR/runs/``.

Each shard is written atomically (a temporary file, then ``os.replace``), so a reader (pandas,
DuckDB, pyarrow) never sees a half-written record, and a sweep killed at any instant leaves only
whole shards behind. A run is *finished* once its row is in a shard; starting the same sweep
again skips finished runs. Rows are tidy: one per run, metrics and run metadata as columns,
the convergence history as a compact ``list<float32>`` column.

Read everything with ``pandas.read_parquet(DIR / "runs")`` or, in DuckDB,
``SELECT * FROM read_parquet('DIR/runs/*.parquet')``.
"""

from __future__ import annotations

import os
import time
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

#: Columns every row has (others, plan-specific, may be added).
BASE_COLUMNS = (
    "run_id",
    "plan",
    "scenario",
    "algorithm",
    "run_index",
    "seed",
    "root_seed",
    "scale",
    "status",
    "error",
    "best_cost",
    "path_length",
    "feasible",
    "first_feasible_iteration",
    "evaluations",
    "iterations",
    "wall_time",
    "start_time",
    "end_time",
    "version",
    "git_commit",
    "host",
    "cpu",
    "python",
    "history",
)


class ResultStore:
    """Append-only store of run rows in ``root/runs/*.parquet``.

    Args:
        root: the sweep's output folder.
        flush_rows / flush_seconds: write a shard when this many rows are buffered or this long
            has passed since the last write, whichever comes first.
    """

    def __init__(self, root: str | Path, flush_rows: int = 256, flush_seconds: float = 2.0):
        self.root = Path(root)
        self.dir = self.root / "runs"
        self.dir.mkdir(parents=True, exist_ok=True)
        self.flush_rows = flush_rows
        self.flush_seconds = flush_seconds
        self._buffer: list[dict[str, Any]] = []
        self._last_flush = time.monotonic()
        self._session = uuid.uuid4().hex[:8]
        self._seq = 0

    # ------------------------------------------------------------------ writing
    def add(self, row: Mapping[str, Any]) -> None:
        self._buffer.append(dict(row))
        if (
            len(self._buffer) >= self.flush_rows
            or time.monotonic() - self._last_flush >= self.flush_seconds
        ):
            self.flush()

    def flush(self) -> Path | None:
        """Write the buffered rows as one shard, atomically. Returns its path (or None)."""
        self._last_flush = time.monotonic()
        if not self._buffer:
            return None
        table = rows_to_table(self._buffer)
        self._seq += 1
        name = f"part-{time.strftime('%Y%m%dT%H%M%S')}-{self._session}-{self._seq:05d}.parquet"
        final = self.dir / name
        tmp = self.dir / f".{name}.tmp"
        pq.write_table(table, tmp, compression="zstd")
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, final)
        self._buffer.clear()
        return final

    # ------------------------------------------------------------------ reading
    def shards(self) -> list[Path]:
        return sorted(self.dir.glob("part-*.parquet"))

    def finished_ids(self, include_errors: bool = True) -> set[str]:
        """Ids of the runs already in the store (by default errored runs count as finished)."""
        ids: set[str] = set()
        for shard in self.shards():
            t = pq.read_table(shard, columns=["run_id", "status"])
            run_ids = t.column("run_id").to_pylist()
            if include_errors:
                ids.update(run_ids)
            else:
                status = t.column("status").to_pylist()
                ids.update(r for r, s in zip(run_ids, status, strict=True) if s == "ok")
        return ids

    def read(self, columns: list[str] | None = None) -> pd.DataFrame:
        """All rows as a DataFrame; if a run appears twice (an errored run retried), the last
        written row wins."""
        shards = self.shards()
        if not shards:
            return pd.DataFrame(columns=list(columns or BASE_COLUMNS))
        tables = [pq.read_table(s, columns=columns) for s in shards]
        df = pa.concat_tables(tables, promote_options="default").to_pandas()
        if "run_id" in df.columns:
            df = df.drop_duplicates("run_id", keep="last").reset_index(drop=True)
        return df


#: Arrow types of the known columns, so that every shard has the same schema (a column that is
#: all null in one shard must not become the null type there) and the folder reads as one
#: dataset in pandas, pyarrow and DuckDB.
TYPES: dict[str, pa.DataType] = {
    **{
        c: pa.string()
        for c in (
            "run_id",
            "plan",
            "scenario",
            "algorithm",
            "seed",
            "scale",
            "status",
            "error",
            "version",
            "git_commit",
            "host",
            "cpu",
            "python",
            "violations",
        )
    },
    **{
        c: pa.int64()
        for c in (
            "run_index",
            "root_seed",
            "first_feasible_iteration",
            "evaluations",
            "iterations",
            "n_dim",
        )
    },
    **{
        c: pa.float64() for c in ("best_cost", "path_length", "wall_time", "start_time", "end_time")
    },
    "feasible": pa.bool_(),
    "waypoints": pa.list_(pa.float64()),
}


def rows_to_table(rows: list[dict[str, Any]]) -> pa.Table:
    """Build an Arrow table from run rows; ``history``-like columns become list<float32>, known
    columns get their :data:`TYPES`."""
    cols: dict[str, list[Any]] = {}
    keys: list[str] = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols[k] = []
                keys.append(k)
    for r in rows:
        for k in keys:
            cols[k].append(r.get(k))
    arrays = {}
    for k in keys:
        values = cols[k]
        if k.endswith("history"):
            arrays[k] = pa.array(
                [None if v is None else np.asarray(v, dtype=np.float32) for v in values],
                type=pa.list_(pa.float32()),
            )
        elif k in TYPES:
            arrays[k] = pa.array(values, type=TYPES[k], from_pandas=True)
        else:
            arrays[k] = _no_null_type(pa.array(values, from_pandas=True))
    return pa.table(arrays)


def _no_null_type(arr: pa.Array) -> pa.Array:
    """A column of a kind's own metrics that is all null in this shard (a metric no run of the
    chunk had, such as a clearance with no moving obstacle) would get Arrow's null type, and
    pandas and pyarrow, reading the folder as one dataset with the first shard's schema, could
    not cast another shard's numbers to it: such metrics are numbers, so null becomes float64
    (and a list of nulls a list of float64)."""
    t = arr.type
    if pa.types.is_null(t):
        return arr.cast(pa.float64())
    if pa.types.is_list(t) and pa.types.is_null(t.value_type):
        return arr.cast(pa.list_(pa.float64()))
    return arr
