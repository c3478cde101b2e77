"""Run a plan's runs on local worker processes, in this process, or on a Dask cluster.

* **Resumable.** Finished runs are read from the store and skipped; results are written as they
  arrive, in atomic shards. Ctrl-C, a killed worker or a lost node costs at most the runs that
  were in flight: run the same command again and the sweep goes on where it was.
* **Same results anywhere.** Seeds come from the run's identity (:func:`derive_seed`), and each
  worker uses one thread for Numba and BLAS.
* **Errors recorded.** A run that raises becomes a row with ``status="error"``; the sweep goes on.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uavplan import __version__
from uavplan.bench.execute import execute_chunk
from uavplan.bench.plans import ExperimentPlan, RunSpec
from uavplan.bench.store import ResultStore
from uavplan.io.atomic import write_json_atomic

EXECUTORS = ("process", "serial", "dask")


class SweepInterrupted(RuntimeError):
    """Ctrl-C during a sweep; everything finished so far is saved."""


@dataclass
class Progress:
    """What a progress display needs after every finished chunk."""

    total: int
    skipped: int
    done: int = 0
    failed: int = 0
    started: float = field(default_factory=time.monotonic)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    @property
    def remaining(self) -> int:
        return self.total - self.skipped - self.done

    @property
    def eta(self) -> float | None:
        if self.done == 0:
            return None
        return self.elapsed / self.done * self.remaining


@dataclass(frozen=True)
class SweepSummary:
    plan: str
    scale: str
    out: Path
    total: int
    skipped: int
    executed: int
    failed: int
    wall_time: float
    run_time: float  # sum of the runs' own wall times executed in this sweep
    failures: tuple[str, ...] = ()
    executor: str = "process"
    workers: int = 1

    @property
    def overhead(self) -> float | None:
        """(wall time x workers) / (sum of run times) - 1: the runner's share on top of the runs."""
        if self.run_time <= 0:
            return None
        return self.wall_time * self.workers / self.run_time - 1.0


def _chunks(specs: Sequence[RunSpec], size: int) -> list[list[RunSpec]]:
    return [list(specs[i : i + size]) for i in range(0, len(specs), size)]


def chunk_size(n: int, workers: int) -> int:
    """Enough chunks to balance load (about 16 per worker), at most 64 runs each."""
    return max(1, min(64, math.ceil(n / max(1, workers * 16))))


def _single_thread_env() -> dict[str, str | None]:
    """Set thread limits in this process's environment (inherited by worker processes)."""
    saved = {}
    for var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        saved[var] = os.environ.get(var)
        os.environ[var] = "1"
    return saved


def _restore_env(saved: dict[str, str | None]) -> None:
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def _iter_serial(chunks: list[list[RunSpec]]) -> Iterator[list[dict[str, Any]]]:
    for c in chunks:
        yield execute_chunk(c, single_thread=False)


def _iter_process(chunks: list[list[RunSpec]], workers: int) -> Iterator[list[dict[str, Any]]]:
    import multiprocessing as mp

    saved = _single_thread_env()
    try:
        pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"))
    finally:
        _restore_env(saved)
    pending: set[Future[list[dict[str, Any]]]] = set()
    queue = list(reversed(chunks))
    try:
        while queue or pending:
            while queue and len(pending) < 2 * workers:
                pending.add(pool.submit(execute_chunk, queue.pop()))
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                yield fut.result()
    finally:
        for fut in pending:
            fut.cancel()
        pool.shutdown(wait=False, cancel_futures=True)


def _iter_dask(
    chunks: list[list[RunSpec]], scheduler: str | None, workers: int
) -> Iterator[list[dict[str, Any]]]:
    try:
        from distributed import Client
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise RuntimeError(
            "the Dask executor needs dask.distributed: pip install 'uavplan[cluster]'"
        ) from exc
    client = (
        Client(scheduler)
        if scheduler
        else Client(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    )
    try:
        yield from _iter_dask_client(chunks, client)
    finally:
        client.close()


def run_sweep(
    plan: ExperimentPlan,
    out: str | Path,
    scale: str = "smoke",
    runs: int | None = None,
    iterations: int | None = None,
    root_seed: int = 0,
    executor: str = "process",
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[Progress], None] | None = None,
    retry_failed: bool = False,
    max_pool_restarts: int = 3,
    dask_client: Any = None,
    only: Sequence[str] | None = None,
) -> SweepSummary:
    """Run every not-yet-finished run of ``plan`` and store the results under ``out``.

    Args:
        executor: ``process`` (local worker processes, default), ``serial`` (this process) or
            ``dask`` (``scheduler`` address, or a throw-away local cluster).
        workers: worker processes (default: all cores).
        retry_failed: run again the runs that ended with an error.
        dask_client: an existing ``distributed.Client`` to use (tests).
        only: run only these configurations (algorithm labels) of the plan; the others' runs
            are left as they are (the manifest still describes the whole plan).
    Raises:
        SweepInterrupted: on Ctrl-C, after saving every finished run.
    """
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; choose from {EXECUTORS}")
    specs = plan.runs(scale, runs, root_seed, iterations)
    labels = [a.label for a in plan.algorithms]
    if only is not None:
        unknown = [o for o in only if o not in labels]
        if unknown or not only:
            raise ValueError(
                f"plan {plan.name!r} has no configuration {', '.join(map(repr, unknown))}; "
                f"choose from {', '.join(labels)}"
            )
    out = Path(out)
    store = ResultStore(out)
    write_json_atomic(
        out / "manifest.json",
        {
            "plan": plan.name,
            "scale": scale,
            "runs": runs,
            "iterations": iterations,
            "root_seed": root_seed,
            "total_runs": len(specs),
            "version": __version__,
            "scenarios": list(plan.scenarios),
            "algorithms": [a.label for a in plan.algorithms],
            "reference": plan.reference,
            "metric": plan.metric,
        },
    )
    finished = store.finished_ids(include_errors=not retry_failed)
    selected = [s for s in specs if only is None or s.algorithm in only]
    todo = [s for s in selected if s.run_id not in finished]
    n_workers = 1 if executor == "serial" else (workers or os.cpu_count() or 1)
    prog = Progress(total=len(selected), skipped=len(selected) - len(todo))
    failures: list[str] = []
    run_time = 0.0
    t0 = time.perf_counter()
    remaining = {s.run_id: s for s in todo}
    restarts = 0
    try:
        while remaining:
            chunks = _chunks(list(remaining.values()), chunk_size(len(remaining), n_workers))
            if executor == "serial":
                it = _iter_serial(chunks)
            elif executor == "process":
                it = _iter_process(chunks, n_workers)
            else:
                it = (
                    _iter_dask_client(chunks, dask_client)
                    if dask_client is not None
                    else _iter_dask(chunks, scheduler, n_workers)
                )
            try:
                for rows in it:
                    for row in rows:
                        store.add(row)
                        remaining.pop(row["run_id"], None)
                        prog.done += 1
                        run_time += float(row.get("wall_time") or 0.0)
                        if row.get("status") != "ok":
                            prog.failed += 1
                            failures.append(f"{row['run_id']}: {row.get('error')}")
                    # a finished chunk is on disk before anything else happens: a kill now
                    # loses nothing (the store's own timer would keep all but its first row)
                    store.flush()
                    if progress:
                        progress(prog)
            except BrokenProcessPool:
                store.flush()
                restarts += 1
                if restarts > max_pool_restarts:
                    raise
                continue
    except KeyboardInterrupt:
        store.flush()
        raise SweepInterrupted(
            f"interrupted: {prog.done} runs finished and saved in {out}; "
            "run the same command again to resume"
        ) from None
    finally:
        store.flush()
    summary = SweepSummary(
        plan=plan.name,
        scale=scale,
        out=out,
        total=len(specs),
        skipped=prog.skipped,
        executed=prog.done,
        failed=prog.failed,
        wall_time=time.perf_counter() - t0,
        run_time=run_time,
        failures=tuple(failures),
        executor=executor,
        workers=n_workers,
    )
    write_json_atomic(
        out / "last_sweep.json",
        {
            "executed": summary.executed,
            "skipped": summary.skipped,
            "failed": summary.failed,
            "wall_time": summary.wall_time,
            "run_time": summary.run_time,
            "executor": executor,
            "workers": n_workers,
            "overhead": summary.overhead,
        },
    )
    return summary


def _iter_dask_client(chunks: list[list[RunSpec]], client: Any) -> Iterator[list[dict[str, Any]]]:
    from distributed import as_completed

    futures = client.map(execute_chunk, chunks, pure=False)
    try:
        for fut in as_completed(futures):
            yield fut.result()
    finally:
        client.cancel(futures)
