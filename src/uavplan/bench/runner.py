"""Run a plan's runs on local worker processes, in this process, or on a Dask cluster.

* **Resumable.** Finished runs are read from the store and skipped; results are written as they
  arrive, in atomic shards. Ctrl-C, a kill -9 of the runner or of a worker, a lost node or a
  full disk costs at most the runs that were in flight: run the same command again and the
  sweep goes on where it was. A killed worker is replaced while the sweep goes on; the workers
  of a killed runner die with it (they compute nothing nobody will store). One sweep at a time
  writes to a folder (a lock), so no run is stored twice.
* **Same results anywhere.** Seeds come from the run's identity (:func:`derive_seed`), and each
  worker uses one thread for Numba and BLAS.
* **Errors recorded.** A run that raises becomes a row with ``status="error"``; the sweep goes on.
"""

from __future__ import annotations

import contextlib
import math
import os
import platform
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
from uavplan.bench.store import ResultStore, StoreError
from uavplan.io.atomic import write_json_atomic

EXECUTORS = ("process", "serial", "dask")


class SweepInterrupted(RuntimeError):
    """Ctrl-C during a sweep; everything finished so far is saved."""


class SweepStopped(RuntimeError):
    """The sweep cannot go on: its results cannot be written (a full disk), the folder is in
    use by another sweep, a shard cannot be read, or workers keep dying on the same runs. The
    message is one line that says what happened and what is saved; everything stored before is
    intact, and the same command resumes once the cause is gone."""


class _WorkerLost(Exception):
    """A worker process died (killed, out of memory): the runs it had are to be run again."""


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


def die_with_parent(parent: int) -> None:
    """Worker initializer: end this process when the runner ``parent`` ends, however it ends
    (a kill -9 included), so that no orphaned worker goes on computing runs nobody will store.
    Linux: the kernel sends SIGKILL when the parent dies (``PR_SET_PDEATHSIG``); elsewhere a
    thread checks the parent once a second."""
    import signal
    import sys
    import threading

    armed = False
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - a libc without prctl
            armed = False
    if os.getppid() != parent:  # the runner died before the signal was armed
        os._exit(1)
    if not armed:  # pragma: no cover - not Linux

        def watch() -> None:
            while True:
                time.sleep(1.0)
                if os.getppid() != parent:
                    os._exit(1)

        threading.Thread(target=watch, name="die-with-parent", daemon=True).start()


def _iter_process(chunks: list[list[RunSpec]], workers: int) -> Iterator[list[dict[str, Any]]]:
    import multiprocessing as mp

    saved = _single_thread_env()
    try:
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=mp.get_context("spawn"),
            initializer=die_with_parent,
            initargs=(os.getpid(),),
        )
    finally:
        _restore_env(saved)
    pending: set[Future[list[dict[str, Any]]]] = set()
    queue = list(reversed(chunks))
    complete = False
    dead_for = 0.0  # seconds since a dead worker was seen with no chunk finishing
    try:
        while queue or pending:
            while queue and len(pending) < 2 * workers:
                try:
                    pending.add(pool.submit(execute_chunk, queue.pop()))
                except BrokenProcessPool as exc:  # a worker died since the last wait
                    raise _WorkerLost(str(exc)) from exc
            done, pending = wait(pending, timeout=2.0, return_when=FIRST_COMPLETED)
            if not done:  # a dead worker the pool has not noticed is lost (_end_manager_thread)
                dead_for = dead_for + 2.0 if _dead_worker(pool) else 0.0
                if dead_for >= DEAD_WORKER_TIMEOUT:
                    raise _WorkerLost(f"a worker died {dead_for:.0f} s ago, its pool hangs")
                continue
            dead_for = 0.0
            lost: BaseException | None = None
            for fut in done:  # the chunks that finished are stored before the loss is handled
                try:
                    rows = fut.result()
                except BrokenProcessPool as exc:
                    lost = exc
                    continue
                yield rows
            if lost is not None:
                raise _WorkerLost(str(lost)) from lost
        complete = True
    finally:
        for fut in pending:
            fut.cancel()
        # what shutdown() forgets: the workers, the pool's manager thread and its result pipe
        procs = list((getattr(pool, "_processes", None) or {}).values())
        manager = getattr(pool, "_executor_manager_thread", None)
        results = getattr(pool, "_result_queue", None)
        if not complete:  # the sweep stops: the runs in flight would be stored by nobody
            _terminate_workers(pool)
        pool.shutdown(wait=False, cancel_futures=True)
        if not complete:
            _end_manager_thread(procs, manager, results)


#: seconds a worker may be seen dead, with no chunk finishing, before the runner counts it lost
#: itself (the pool normally notices at once and fails its futures)
DEAD_WORKER_TIMEOUT = 20.0


def _dead_worker(pool: ProcessPoolExecutor) -> bool:
    """Whether one of the pool's worker processes has ended (private attribute, as above)."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    return any(p.exitcode is not None for p in procs)


def _terminate_workers(pool: ProcessPoolExecutor) -> None:
    """SIGTERM the pool's workers (Python 3.14 has ``terminate_workers``; before, the
    processes are only in a private attribute)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()


def _end_manager_thread(procs: list[Any], manager: Any, results: Any) -> None:
    """Make sure a pool whose workers were lost or stopped ends its manager thread. A worker
    killed while it sends a result (a kill -9, the OOM killer, or :func:`_terminate_workers`)
    leaves that thread reading the rest of the message for ever: the pool never fails its
    futures (the dead worker that :data:`DEAD_WORKER_TIMEOUT` catches) and the interpreter,
    which joins the thread at exit, never exits (seen: a sweep stopped by a full disk printed
    its one line and hung). Once the workers are gone, this process holds the last write end
    of the result pipe: closing it ends the read (EOF), and the thread marks the pool broken
    and ends as it does when a worker dies between two results."""
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.join(timeout=5.0)
            if proc.is_alive():
                proc.kill()
                proc.join(timeout=5.0)
    if manager is None or results is None:
        return
    manager.join(timeout=0.5)
    if manager.is_alive():
        with contextlib.suppress(Exception):
            results._writer.close()
        manager.join(timeout=5.0)


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
        max_pool_restarts: how many times in a row workers may die (the pool is restarted, or
            Dask gives up on a chunk) without a chunk finishing in between, before the sweep
            stops; a worker killed now and then never stops it.
        dask_client: an existing ``distributed.Client`` to use (tests).
        only: run only these configurations (algorithm labels) of the plan; the others' runs
            are left as they are (the manifest still describes the whole plan).
    Raises:
        SweepInterrupted: on Ctrl-C, after saving every finished run.
        SweepStopped: the results cannot be written (e.g. no space left), ``out`` is in use by
            another sweep, a shard cannot be read, or workers die more than
            ``max_pool_restarts`` times in a row; every run stored before is intact.
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
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = _lock_folder(out)
    except OSError as exc:
        raise SweepStopped(f"cannot write to {out}: {exc.strerror or exc}") from None
    try:
        return _sweep(
            plan, out, scale, runs, iterations, root_seed, specs, executor, workers, scheduler,
            progress, retry_failed, max_pool_restarts, dask_client, only,
        )  # fmt: skip
    finally:
        lock.close()


def _lock_folder(out: Path) -> Any:
    """Hold ``out/.lock`` for this sweep (an advisory lock the kernel drops when the process
    ends, a kill -9 included): two sweeps writing one folder would both run its open runs."""
    f = open(out / ".lock", "a+")  # noqa: SIM115 - held until the sweep ends
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock
        return f
    try:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        f.seek(0)
        who = f.read().strip() or "another process"
        f.close()
        raise SweepStopped(
            f"{out} is in use by another sweep ({who}); wait for it to end, or give another --out"
        ) from None
    f.seek(0)
    f.truncate()
    f.write(f"pid {os.getpid()} on {platform.node()}\n")
    f.flush()
    return f


def _sweep(
    plan: ExperimentPlan,
    out: Path,
    scale: str,
    runs: int | None,
    iterations: int | None,
    root_seed: int,
    specs: list[RunSpec],
    executor: str,
    workers: int | None,
    scheduler: str | None,
    progress: Callable[[Progress], None] | None,
    retry_failed: bool,
    max_pool_restarts: int,
    dask_client: Any,
    only: Sequence[str] | None,
) -> SweepSummary:
    # a shard per finished chunk, written when it ends (no timer: it would write a chunk's
    # first row alone)
    store = ResultStore(out, flush_seconds=math.inf)
    try:
        store.remove_stale_temporaries()
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
    except StoreError as exc:
        raise SweepStopped(str(exc)) from None
    except OSError as exc:
        raise SweepStopped(f"cannot write to {out}: {exc.strerror or exc}") from None
    selected = [s for s in specs if only is None or s.algorithm in only]
    todo = [s for s in selected if s.run_id not in finished]
    n_workers = 1 if executor == "serial" else (workers or os.cpu_count() or 1)
    prog = Progress(total=len(selected), skipped=len(selected) - len(todo))
    failures: list[str] = []
    run_time = 0.0
    t0 = time.perf_counter()
    remaining = {s.run_id: s for s in todo}
    losses = 0  # workers lost in a row, without a chunk finishing in between
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
                    losses = 0
                    for row in rows:
                        store.add(row)
                        remaining.pop(row["run_id"], None)
                        prog.done += 1
                        run_time += float(row.get("wall_time") or 0.0)
                        if row.get("status") != "ok":
                            prog.failed += 1
                            failures.append(f"{row['run_id']}: {row.get('error')}")
                    # a finished chunk is on disk before anything else happens: a kill now
                    # loses nothing
                    store.flush()
                    if progress:
                        progress(prog)
            except _WorkerLost as exc:
                losses += 1
                if losses > max_pool_restarts:
                    raise SweepStopped(
                        f"workers lost {losses} times in a row with no chunk finishing in "
                        f"between (last: {exc}); {store.written} runs of this sweep are saved in "
                        f"{out}; if a run kills its worker (memory?), run fewer at once "
                        "(--workers) and run the same command again to resume"
                    ) from None
                continue
    except KeyboardInterrupt:
        _flush_quietly(store)
        raise SweepInterrupted(
            f"interrupted: {store.written} runs finished and saved in {out}; "
            "run the same command again to resume"
        ) from None
    except StoreError as exc:
        lost = store.buffered
        raise SweepStopped(
            f"{exc}; {store.written} runs of this sweep are saved there, the {lost} "
            "finished since the last write are not; free space and run the same command "
            "again to resume"
        ) from None
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
    try:
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
    except OSError as exc:
        raise SweepStopped(
            f"cannot write to {out}: {exc.strerror or exc}; every run is saved, only the "
            "sweep's timing (last_sweep.json) is not"
        ) from None
    return summary


def _flush_quietly(store: ResultStore) -> None:
    """Write what is buffered if possible (on Ctrl-C: the error that matters is the interrupt)."""
    with contextlib.suppress(StoreError):
        store.flush()


#: seconds a Dask cluster may have no worker while runs wait before the runner counts its
#: workers lost (a local cluster's nannies can give up restarting killed workers; a remote
#: cluster can lose every node): the sweep then goes on with a new local cluster, or stops
#: with one line after ``max_pool_restarts`` such losses in a row
NO_WORKER_TIMEOUT = 60.0


def _iter_dask_client(chunks: list[list[RunSpec]], client: Any) -> Iterator[list[dict[str, Any]]]:
    from distributed import wait as dask_wait
    from distributed.scheduler import KilledWorker

    futures = client.map(execute_chunk, chunks, pure=False)
    pending = set(futures)
    without = 0.0  # seconds since the cluster was last seen with a worker
    try:
        while pending:
            try:
                done, pending = dask_wait(pending, timeout=2.0, return_when="FIRST_COMPLETED")
            except TimeoutError:
                without = 0.0 if client.nthreads() else without + 2.0
                if without >= NO_WORKER_TIMEOUT:
                    raise _WorkerLost(
                        f"the Dask cluster has had no worker for {without:.0f} s"
                    ) from None
                continue
            for fut in done:
                try:
                    rows = fut.result()
                except KilledWorker as exc:  # Dask gave up on a chunk whose workers kept dying
                    raise _WorkerLost(str(exc)) from exc
                yield rows
    finally:
        client.cancel(futures)
