"""The benchmarks' timer (imported by the scripts beside it: run them as
``python benchmarks/NAME.py``, which puts this folder on the import path)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable


def best_time(fn: Callable[[], object], repeats: int) -> float:
    """The least wall time of ``repeats`` calls after one warm-up call (JIT compiles, caches):
    on a shared machine the least is the least noisy."""
    fn()
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
