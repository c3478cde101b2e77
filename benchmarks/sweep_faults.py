"""Sweeps under faults (issue 19 item 4): kill -9 the runner, then a pool worker, then a Dask
worker at random moments, N times each, and fill the disk during a shard write; after every
fault the results folder must have lost nothing, stored nothing twice and hold only whole
shards whose rows equal an uninterrupted sweep's (the harness: ``tests/bench/faults.py``).

    NUMBA_NUM_THREADS=1 nice -n 5 python benchmarks/sweep_faults.py             # 20 of each
    python benchmarks/sweep_faults.py --kills 3 --only runner,disk

The disk-full case mounts a small tmpfs: it needs root (it is skipped, and says so, without).
Prints one line per kill and a summary line per kind of fault; exit code 1 if any failed.
"""

from __future__ import annotations

import argparse
import signal
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from bench import faults


def main() -> int:
    # a SIGTERM ends the campaign like Ctrl-C: the sweep running is killed, the folder removed
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kills", type=int, default=20, help="faults of each kind [20]")
    ap.add_argument("--runs", type=int, default=3000, help="runs of the sweep [3000]")
    ap.add_argument("--iterations", type=int, default=60, help="PSO iterations per run [60]")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0, help="seed of the random kill moments")
    ap.add_argument(
        "--only",
        default="runner,workers,dask,disk",
        help="comma-separated: runner, workers, dask, disk",
    )
    args = ap.parse_args()
    only = set(args.only.split(","))
    rng = np.random.default_rng(args.seed)
    outcomes = []
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        cmd = faults.SweepCommand(
            root / "sweep", args.runs, args.iterations, "process", args.workers
        )
        t = time.monotonic()
        reference = cmd.reference(root / "reference")
        print(
            f"uninterrupted sweep (serial, in process): {len(reference)} runs in "
            f"{time.monotonic() - t:.0f} s"
        )
        cases = [
            ("runner", lambda c: faults.kill_runner(c, reference, args.kills, rng), "process"),
            ("workers", lambda c: faults.kill_workers(c, reference, args.kills, rng), "process"),
            ("dask", lambda c: faults.kill_workers(c, reference, args.kills, rng), "dask"),
        ]
        for name, run, executor in cases:
            if name not in only:
                continue
            c = faults.SweepCommand(
                faults.fresh(root / name), args.runs, args.iterations, executor, args.workers
            )
            print(f"{name}:")
            outcomes.append(run(c))
            print(outcomes[-1].line(), *outcomes[-1].problems[:10], sep="\n  ")
        if "disk" in only:
            print("disk:")
            for i in range(args.kills):
                c = faults.SweepCommand(
                    root / f"disk{i}", min(args.runs, 600), args.iterations, "process", args.workers
                )
                try:
                    with faults.small_tmpfs(c.out, 1024):
                        outcomes.append(faults.disk_full(c, reference, rng))
                except PermissionError as exc:
                    print(f"disk full: skipped ({exc})")
                    break
                print(outcomes[-1].line(), *outcomes[-1].problems[:10], sep="\n  ")
    print(f"\nsummary ({time.monotonic() - t0:.0f} s, {args.workers} workers, seed {args.seed}):")
    for o in outcomes:
        print(" ", o.line())
    return 0 if all(o.ok for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
