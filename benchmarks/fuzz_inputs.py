"""Fuzz the inputs users give uavplan: scenario files, plan files, DEMs (``tests/io/fuzzing.py``).

Run: ``NUMBA_NUM_THREADS=1 nice -n 10 python benchmarks/fuzz_inputs.py [--cases 10000]
[--seed 0] [--workers 2] [--timeout 60] [--wall-timeout 600] [--memory-gib 6]``; one case again:
``python benchmarks/fuzz_inputs.py --seed S --case I --keep DIR`` (its files are left in DIR).

Case ``i`` of seed ``S`` is drawn from ``numpy.random.default_rng([S, i])``, so a case is the same
on any run and any worker. Each worker process runs cases in-process through the real CLI
(``typer.testing.CliRunner``) under an address-space limit (``RLIMIT_AS``, ``--memory-gib``); the
parent kills a worker whose case takes more than ``--timeout`` CPU seconds or
``--wall-timeout`` wall seconds (a hang) and counts a
worker that dies (memory, a signal) as a crash. It prints the count of each outcome class (clean
error exit 2 / valid / uncaught error / hang / non-finite output / verifier disagreement /
unclear error message / crash) and every failure with its reproducer.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import resource
import shutil
import sys
import tempfile
import time
from collections import Counter
from multiprocessing.connection import Connection
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "io"))

import fuzzing


def one_case(seed: int, index: int, root: Path, cache: Path) -> fuzzing.Result:
    folder = root / f"case-{index}"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    t0 = time.monotonic()
    case = fuzzing.make_case(fuzzing.RngDraw([seed, index]), folder, cache)
    result = fuzzing.run_case(case)
    result.detail = f"[{case.kind}: {case.note}, {time.monotonic() - t0:.1f} s] {result.detail}"
    return result


def _worker(conn: Connection, seed: int, root: str, memory_gib: float, keep: bool) -> None:
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    if memory_gib > 0:
        limit = int(memory_gib * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    base = Path(root)
    cache = base / f"cache-{os.getpid()}"
    cache.mkdir(parents=True, exist_ok=True)
    while True:
        index = conn.recv()
        if index is None:
            return
        try:
            r = one_case(seed, index, base, cache)
        except MemoryError as exc:
            r = fuzzing.Result(fuzzing.UNCAUGHT, f"MemoryError: {exc}")
        except Exception as exc:  # the case generator itself failed: a failure to look at
            r = fuzzing.Result(fuzzing.UNCAUGHT, f"generator: {type(exc).__name__}: {exc}")
        if not keep or r.outcome not in fuzzing.FAILURES:
            shutil.rmtree(base / f"case-{index}", ignore_errors=True)
        conn.send((index, r.outcome, r.detail, r.command))


class Worker:
    def __init__(self, args: argparse.Namespace, root: Path) -> None:
        ctx = mp.get_context("fork")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(
            target=_worker,
            args=(child, args.seed, str(root), args.memory_gib, args.keep_failures),
            daemon=True,
        )
        self.proc.start()
        self.index: int | None = None
        self.started = self.cpu0 = 0.0

    def give(self, index: int) -> None:
        self.index, self.started = index, time.monotonic()
        self.cpu0 = self.cpu()
        self.conn.send(index)

    def cpu(self) -> float:
        """The worker's CPU seconds so far (``/proc``; 0 where it cannot be read)."""
        try:
            with open(f"/proc/{self.proc.pid}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        except (OSError, ValueError, IndexError):
            return 0.0

    def overdue(self, args: argparse.Namespace) -> str | None:
        """Why the running case counts as a hang: more CPU time than ``--timeout`` (the machine
        is shared: wall time says little), or more wall time than ``--wall-timeout`` (a case
        that waits, e.g. on a FIFO, uses no CPU)."""
        cpu = self.cpu() - self.cpu0
        wall = time.monotonic() - self.started
        if cpu > args.timeout:
            return f"over {args.timeout:g} s of CPU time ({wall:.0f} s wall)"
        if wall > args.wall_timeout:
            return f"over {args.wall_timeout:g} s of wall time ({cpu:.1f} s CPU)"
        return None

    def stop(self) -> None:
        if self.proc.is_alive():
            self.proc.kill()  # this worker, by its own handle
        self.proc.join(5)


def run(args: argparse.Namespace) -> int:
    root = Path(args.keep or tempfile.mkdtemp(prefix="uavplan-fuzz-"))
    root.mkdir(parents=True, exist_ok=True)
    counts: Counter[str] = Counter()
    failures: list[tuple[int, str, str, list[str]]] = []
    pending = list(range(args.first, args.first + args.cases))[::-1]
    workers = [Worker(args, root) for _ in range(max(1, args.workers))]
    t0 = time.monotonic()
    done = 0

    def record(index: int, outcome: str, detail: str, command: list[str]) -> None:
        nonlocal done
        done += 1
        counts[outcome] += 1
        if outcome in fuzzing.FAILURES:
            failures.append((index, outcome, detail, command))
            print(f"FAIL case {index}: {outcome}: {detail.splitlines()[0][:300]}", flush=True)
        if done % args.report_every == 0:
            rate = done / (time.monotonic() - t0)
            print(f"{done}/{args.cases} cases, {rate:.1f}/s: {dict(counts)}", flush=True)

    try:
        while pending or any(w.index is not None for w in workers):
            for w in workers:
                if w.index is None and pending:
                    w.give(pending.pop())
            busy = [w for w in workers if w.index is not None]
            ready = mp.connection.wait(
                [w.conn for w in busy] + [w.proc.sentinel for w in busy], timeout=1.0
            )
            for k, w in enumerate(workers):
                if w.index is None:
                    continue
                if w.conn in ready and w.conn.poll():
                    index, outcome, detail, command = w.conn.recv()
                    record(index, outcome, detail, command)
                    w.index = None
                elif w.proc.sentinel in ready or not w.proc.is_alive():
                    record(w.index, fuzzing.CRASH, f"exit code {w.proc.exitcode}", [])
                    w.stop()
                    workers[k] = Worker(args, root)
                elif (why := w.overdue(args)) is not None:
                    record(w.index, fuzzing.HANG, why, [])
                    w.stop()
                    workers[k] = Worker(args, root)
    finally:
        for w in workers:
            if w.proc.is_alive():
                w.conn.send(None)
            w.proc.join(5)
            w.stop()
    elapsed = time.monotonic() - t0
    print(
        f"\n{done} cases (seed {args.seed}, from {args.first}) in {elapsed:.0f} s, "
        f"{args.workers} workers, RLIMIT_AS {args.memory_gib:g} GiB, timeout {args.timeout:g} s "
        f"CPU / {args.wall_timeout:g} s wall"
    )
    for name in fuzzing.OUTCOMES:
        print(f"  {name:<36} {counts.get(name, 0):>6}")
    for index, outcome, detail, command in failures:
        print(
            f"\ncase {index}: {outcome}\n  reproduce: python benchmarks/fuzz_inputs.py "
            f"--seed {args.seed} --case {index} --keep /tmp/fuzz-{index}\n"
            f"  command: uavplan {' '.join(command)}\n  {detail[:1500]}"
        )
    if not args.keep:
        shutil.rmtree(root, ignore_errors=True)
    return 1 if failures else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--first", type=int, default=0, help="index of the first case")
    ap.add_argument("--case", type=int, default=None, help="run this one case, in-process")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=60.0, help="CPU seconds per case")
    ap.add_argument("--wall-timeout", type=float, default=600.0, help="wall seconds per case")
    ap.add_argument("--memory-gib", type=float, default=6.0, help="RLIMIT_AS per worker")
    ap.add_argument("--keep", default=None, help="folder for the cases (kept)")
    ap.add_argument("--keep-failures", action="store_true", help="keep failing cases' files")
    ap.add_argument("--report-every", type=int, default=250)
    args = ap.parse_args()
    if args.case is not None:
        root = Path(args.keep or tempfile.mkdtemp(prefix="uavplan-fuzz-"))
        cache = root / "cache"
        cache.mkdir(parents=True, exist_ok=True)
        r = one_case(args.seed, args.case, root, cache)
        print(
            f"case {args.case}: {r.outcome}\n  command: uavplan {' '.join(r.command)}\n"
            f"  {r.detail}\n  files: {root / f'case-{args.case}'}"
        )
        return 1 if r.outcome in fuzzing.FAILURES else 0
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
