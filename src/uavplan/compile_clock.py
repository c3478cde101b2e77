"""Seconds spent compiling (or loading from the cache) Numba kernels in this process, so that
reported planning times leave them out.

A kernel compiles on its first call with a new signature (about 10-30 s for those of a plan
the first time on a machine, a fraction of a second to load them from the cache later); that is not
the planner's time. Numba announces every compilation as a ``numba:compile`` event
(:mod:`numba.core.event`); one listener, registered on import, adds up their durations (nested
compilations, a kernel compiling the kernels it calls, count once). A timed section takes the
difference of :func:`compile_seconds` around it::

    t0, c0 = time.perf_counter(), compile_seconds()
    ...
    wall = time.perf_counter() - t0 - (compile_seconds() - c0)
"""

from __future__ import annotations

import threading
import time

from numba.core import event

_lock = threading.Lock()


class _CompileClock(event.Listener):
    """Total seconds between the outermost start and end of ``numba:compile`` events."""

    def __init__(self) -> None:
        self.depth = 0
        self.total = 0.0
        self.started = 0.0

    def on_start(self, event: event.Event) -> None:
        with _lock:
            if self.depth == 0:
                self.started = time.perf_counter()
            self.depth += 1

    def on_end(self, event: event.Event) -> None:
        with _lock:
            self.depth -= 1
            if self.depth == 0:
                self.total += time.perf_counter() - self.started


_clock = _CompileClock()
event.register("numba:compile", _clock)


def compile_seconds() -> float:
    """Seconds of kernel compilation so far in this process, a compilation under way included."""
    with _lock:
        running = time.perf_counter() - _clock.started if _clock.depth else 0.0
        return _clock.total + running


class Stopwatch:
    """Wall time since creation less the kernel compilation in it (:func:`compile_seconds`)."""

    def __init__(self) -> None:
        self.t0 = time.perf_counter()
        self.c0 = compile_seconds()

    @property
    def compile(self) -> float:
        """Seconds of compilation since the start."""
        return compile_seconds() - self.c0

    @property
    def elapsed(self) -> float:
        """Wall seconds since the start, compilation excluded."""
        return time.perf_counter() - self.t0 - self.compile


__all__ = ["Stopwatch", "compile_seconds"]
