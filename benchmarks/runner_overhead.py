"""Runner overhead for a sweep of many short runs, and the time to resume a finished sweep.

Run: ``python benchmarks/runner_overhead.py [--runs 10000] [--workers 2] [--out DIR]``

Runs the ``overhead`` plan (PSO, 40 particles x 200 iterations on the 10-D sphere: a few
milliseconds of compute each) with the local process executor and prints:

* the sum of the runs' own wall times (their compute), the sweep's wall time, and the
  overhead ``wall x workers / compute - 1`` (worker start-up, scheduling, transfer, storing);
* the time to run the same command again on the finished folder (it should do no work).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from uavplan.bench.catalog import get_plan
from uavplan.bench.runner import run_sweep


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="uavplan-overhead-"))
    plan = get_plan("overhead")
    s = run_sweep(
        plan, out, scale="paper", runs=args.runs, executor="process", workers=args.workers
    )
    per_run = s.run_time / max(1, s.executed)
    print(
        f"{s.executed} runs on {s.workers} workers: wall {s.wall_time:.1f} s, "
        f"runs' own compute {s.run_time:.1f} s ({1e3 * per_run:.1f} ms per run), "
        f"failed {s.failed}"
    )
    print(
        f"runner overhead: {100 * (s.overhead or 0):.2f} % of the runs' compute time "
        f"(wall x workers / compute - 1)"
    )
    t0 = time.perf_counter()
    again = run_sweep(
        plan, out, scale="paper", runs=args.runs, executor="process", workers=args.workers
    )
    print(
        f"resume of the finished sweep: {time.perf_counter() - t0:.2f} s, "
        f"{again.executed} runs executed, {again.skipped} skipped"
    )
    if args.out is None:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
