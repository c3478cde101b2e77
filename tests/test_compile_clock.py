"""Kernel compilation is measured apart and left out of reported times."""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from uavplan.compile_clock import Stopwatch, compile_seconds


def _fresh_kernel():  # type: ignore[no-untyped-def]
    """A kernel never compiled before in this process (no cache), calling another one."""

    @njit(cache=False)
    def inner(x):  # pragma: no cover - numba
        return x * 2.0

    @njit(cache=False)
    def outer(a):  # pragma: no cover - numba
        s = 0.0
        for v in a:
            s += inner(v)
        return s

    return outer


def test_compilation_is_counted_once_and_left_out() -> None:
    f = _fresh_kernel()
    t0 = time.perf_counter()
    clock = Stopwatch()
    assert f(np.arange(4.0)) == 12.0  # compiles outer and, nested, inner
    compiling, elapsed = clock.compile, clock.elapsed
    total = time.perf_counter() - t0
    assert compiling > 0.0
    assert elapsed + compiling <= total + 1e-6  # nested compilations counted once, not twice
    before = compile_seconds()
    f(np.arange(4.0))  # compiled already: no more compile time
    assert compile_seconds() == before


def test_a_planner_reports_its_time_without_compilation() -> None:
    from uavplan.planners import get_planner
    from uavplan.scenarios import resolve

    planner = get_planner("pso", pop_size=8)
    sc = resolve("simple2d")
    f = _fresh_kernel()
    original = planner._plan

    def compiling(run):  # type: ignore[no-untyped-def]
        f(np.arange(3.0))  # a first-use compilation inside the planner's time
        return original(run)

    planner._plan = compiling  # type: ignore[method-assign]
    t0 = time.perf_counter()
    c0 = compile_seconds()
    r = planner.plan(sc, budget=2, seed=0)
    total, spent = time.perf_counter() - t0, compile_seconds() - c0
    assert spent > 0.0
    assert r.wall_time <= total - spent + 1e-6


def _cached_twice(x):  # pragma: no cover - numba
    return x + 1.0


def test_loading_from_the_cache_is_left_out_but_is_not_compilation() -> None:
    from uavplan.compile_clock import kernel_seconds

    njit(cache=True)(_cached_twice)(1.0)  # compiled here or loaded: either way on disk now
    clock = Stopwatch()
    k0, c0 = kernel_seconds(), compile_seconds()
    again = njit(cache=True)(_cached_twice)  # a new dispatcher: its first call loads the file
    assert again(2.0) == 3.0
    assert again.stats.cache_hits  # loaded, not compiled
    assert compile_seconds() == c0
    assert kernel_seconds() > k0
    assert clock.kernels > 0.0 and clock.compile == 0.0
