"""The results store: finished runs as Parquet shards under ``DIR/runs/``.

Each shard is written atomically (a fsynced temporary file, then ``os.replace``, then a fsync of
the folder), so a reader (pandas, DuckDB, pyarrow) never sees a half-written record, and a sweep
killed at any instant, or stopped by a full disk, leaves only whole shards behind (and at most a
hidden ``.part-*.tmp`` file, which the next sweep removes). A run is *finished* once its row is
in a shard; starting the same sweep again skips finished runs. Rows are tidy: one per run,
metrics and run metadata as columns, the convergence history as a compact ``list<float32>``
column.

Read everything with ``pandas.read_parquet(DIR / "runs")`` or, in DuckDB,
``SELECT * FROM read_parquet('DIR/runs/*.parquet')``.
"""

from __future__ import annotations

import contextlib
import os
import time
import uuid
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from uavplan.io.atomic import write_bytes_atomic

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

#: Columns that measure the machine and the moment rather than the run: times, memory, the
#: host and the code's version. Every other column is a function of the run's identity (plan,
#: scale, scenario, configuration, run index, root seed) alone: the same bits on any executor,
#: with any number of workers, on a rerun (``tests/bench/test_determinism.py`` compares them).
#: A run kind that records a new measurement adds its column here.
MEASURED_COLUMNS = frozenset(
    {
        # every row (bench/execute.py)
        "wall_time",
        "compile_time",
        "start_time",
        "end_time",
        "peak_rss_mb",
        "rss_before_mb",
        "version",
        "git_commit",
        "host",
        "cpu",
        "python",
        # the fleet kind: the planner's own clocks
        "planner_wall_time",
        "rrt_time",
        # the rscdwoa kind: planning time per UAV
        "uav_plan_s",
        # the mission kind: the repair's compute time and whether it met its deadline
        "repair_ms",
        "deadline_missed",
    }
)


class StoreError(OSError):
    """The store cannot be written (a full disk, a read-only folder) or read (a shard that is
    not Parquet); the message (``str``) names the folder or file; ``errno`` is the cause's."""

    def __init__(self, message: str, errno: int | None = None):
        super().__init__(message)
        self.errno = errno


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
        # column types of the shards on disk: known (non-null) types, and the shards where a
        # column is all null (scanned once, then kept up to date with this store's writes)
        self._known: dict[str, pa.DataType] | None = None
        self._nulls: dict[Path, list[str]] = {}
        #: rows written to shards by this store object
        self.written = 0

    # ------------------------------------------------------------------ writing
    def add(self, row: Mapping[str, Any]) -> None:
        self._buffer.append(dict(row))
        if (
            len(self._buffer) >= self.flush_rows
            or time.monotonic() - self._last_flush >= self.flush_seconds
        ):
            self.flush()

    def flush(self) -> Path | None:
        """Write the buffered rows as one shard, atomically. Returns its path (or None).

        Raises:
            StoreError: the shard could not be written (e.g. no space left); the rows stay
                buffered, every shard already written is intact and no temporary file is left.
        """
        self._last_flush = time.monotonic()
        if not self._buffer:
            return None
        try:
            table = self._harmonize(rows_to_table(self._buffer))
            self._seq += 1
            name = f"part-{time.strftime('%Y%m%dT%H%M%S')}-{self._session}-{self._seq:05d}.parquet"
            final = self.dir / name
            _write_shard(table, final)
        except OSError as exc:
            raise StoreError(f"cannot write to {self.dir}: {_reason(exc)}", exc.errno) from exc
        self._note_schema(final, table.schema)
        self.written += len(self._buffer)
        self._buffer.clear()
        return final

    @property
    def buffered(self) -> int:
        """Rows added and not yet written."""
        return len(self._buffer)

    def remove_stale_temporaries(self) -> int:
        """Remove the temporary files of writes that never finished (a writer killed mid-write:
        shards, the sweep's manifest and timing). Only while no other process writes to this
        store (the runner holds the folder's lock). Returns how many were removed."""
        n = 0
        stale = [*self.dir.glob(".part-*.tmp")]
        for name in ("manifest.json", "last_sweep.json"):
            stale += self.root.glob(f".{name}.*.tmp")
        for tmp in stale:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
                n += 1
        return n

    def _scan_schemas(self) -> dict[str, pa.DataType]:
        if self._known is None:
            self._known = {}
            for shard in self.shards():
                self._note_schema(shard, _read_schema(shard))
        return self._known

    def _note_schema(self, shard: Path, schema: pa.Schema) -> None:
        known = self._known if self._known is not None else self._scan_schemas()
        nulls = []
        for f in schema:
            if _nullish(f.type):
                nulls.append(f.name)
            else:
                known.setdefault(f.name, f.type)
        if nulls:
            self._nulls[shard] = nulls
        else:
            self._nulls.pop(shard, None)

    def _harmonize(self, table: pa.Table) -> pa.Table:
        """One type per column across the store's shards. A kind's own metric that is null in
        every row of a chunk has Arrow's null type; pandas and pyarrow read a folder with the
        first shard's schema and cannot cast numbers to null. So a null column takes the type
        the other shards give it, and earlier shards where it was null are rewritten with the
        type this one brings (each atomically, as written)."""
        known = self._scan_schemas()
        for i, f in enumerate(table.schema):
            if _nullish(f.type) and f.name in known:
                table = table.set_column(i, f.name, table.column(i).cast(known[f.name]))
        mine = {f.name: f.type for f in table.schema if not _nullish(f.type)}
        for shard, cols in list(self._nulls.items()):
            fix = [c for c in cols if c in mine and c not in known]
            if fix:
                old = _read_table(shard)
                for c in fix:
                    i = old.schema.get_field_index(c)
                    old = old.set_column(i, c, old.column(i).cast(mine[c]))
                _write_shard(old, shard)
                self._note_schema(shard, old.schema)
        return table

    def compact(self, rows_per_shard: int = 20_000) -> tuple[int, int]:
        """Rewrite the shards as few large ones of at most ``rows_per_shard`` rows (a sweep of
        tens of thousands of small runs leaves hundreds of shards of a few dozen rows each,
        most of whose bytes are per-file metadata): the same rows, a run written twice kept
        once (the last written, as :meth:`read`). The new shards are written (each
        atomically) before the old ones are removed, so a kill in between leaves every row on
        disk, some twice, which reading and resuming already handle. Returns the shards
        before and after."""
        self.flush()
        old = self.shards()
        if len(old) <= 1:
            return len(old), len(old)
        table = pa.concat_tables([_read_table(s) for s in old], promote_options="default")
        ids = table.column("run_id").to_pylist()
        last = {r: i for i, r in enumerate(ids)}
        if len(last) < len(ids):
            table = table.take(pa.array(sorted(last.values()), type=pa.int64()))
        new: list[Path] = []
        try:
            for start in range(0, table.num_rows, rows_per_shard):
                self._seq += 1
                name = (f"part-{time.strftime('%Y%m%dT%H%M%S')}-{self._session}-"
                        f"{self._seq:05d}.parquet")  # fmt: skip
                _write_shard(table.slice(start, rows_per_shard), self.dir / name)
                new.append(self.dir / name)
        except OSError as exc:
            for f in new:
                with contextlib.suppress(OSError):
                    f.unlink()
            raise StoreError(f"cannot write to {self.dir}: {_reason(exc)}", exc.errno) from exc
        for f in old:
            f.unlink()
        self._known, self._nulls = None, {}
        return len(old), len(new)

    # ------------------------------------------------------------------ reading
    def shards(self) -> list[Path]:
        return sorted(self.dir.glob("part-*.parquet"))

    def finished_ids(self, include_errors: bool = True) -> set[str]:
        """Ids of the runs already in the store (by default errored runs count as finished)."""
        ids: set[str] = set()
        for shard in self.shards():
            t = _read_table(shard, columns=["run_id", "status"])
            run_ids = t.column("run_id").to_pylist()
            if include_errors:
                ids.update(run_ids)
            else:
                status = t.column("status").to_pylist()
                ids.update(r for r, s in zip(run_ids, status, strict=True) if s == "ok")
        return ids

    def read(
        self, columns: list[str] | None = None, lists: bool | Collection[str] = True
    ) -> pd.DataFrame:
        """All rows as a DataFrame; if a run appears twice (an errored run retried), the last
        written row wins. ``lists`` (without ``columns``): the per-run list columns
        (histories, waypoints) to read besides the others, True for all of them: they hold
        most of a sweep's bytes, and a reader that needs none of them reads a shard several
        times faster."""
        shards = self.shards()
        if not shards:
            return pd.DataFrame(columns=list(columns or BASE_COLUMNS))
        tables = [_read_table(s, columns=columns, lists=lists) for s in shards]
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


def _nullish(t: pa.DataType) -> bool:
    """Arrow's null type, or a list of it: what a column of Nones (or of lists of Nones) gets."""
    return bool(pa.types.is_null(t) or (pa.types.is_list(t) and pa.types.is_null(t.value_type)))


def _write_shard(table: pa.Table, path: Path) -> None:
    """Write ``table`` to ``path`` atomically: a fsynced temporary file (removed if the write
    fails), a rename, then a fsync of the folder, so that the rename outlives a crash of the
    machine too."""
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink, compression="zstd")
    write_bytes_atomic(path, sink.getvalue().to_pybytes())
    with contextlib.suppress(OSError):  # not every platform opens folders
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def _unreadable(shard: Path, exc: Exception) -> StoreError:
    return StoreError(
        f"{shard}: not a readable Parquet shard ({exc}); move it out of {shard.parent} "
        "and its runs are run again by the next sweep",
    )


def _read_table(
    shard: Path, columns: list[str] | None = None, lists: bool | Collection[str] = True
) -> pa.Table:
    """One shard (``columns`` of it: each must be there; else every column but the list
    columns not in ``lists``, all with True), read as one file on this thread:
    ``pq.read_table`` goes through the dataset layer and a thread pool, twice the time of a
    small shard's read (a claims ledger reads over a thousand)."""
    try:
        with pq.ParquetFile(shard) as f:
            schema = f.schema_arrow
            if columns is not None and (missing := set(columns) - set(schema.names)):
                raise pa.ArrowInvalid(f"no column {sorted(missing)[0]!r}")
            if columns is None and lists is not True:
                keep = set(lists or ())
                columns = [n for n in schema.names
                           if n in keep or not pa.types.is_list(schema.field(n).type)]  # fmt: skip
            return f.read(columns=columns, use_threads=False)
    except (pa.ArrowException, OSError) as exc:
        raise _unreadable(shard, exc) from exc


def _read_schema(shard: Path) -> pa.Schema:
    try:
        return pq.read_schema(shard)
    except (pa.ArrowException, OSError) as exc:
        raise _unreadable(shard, exc) from exc


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
            arrays[k] = pa.array(values, from_pandas=True)
    return pa.table(arrays)
