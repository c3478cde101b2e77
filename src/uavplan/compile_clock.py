"""Seconds spent compiling Numba kernels, and loading them from the cache, in this process, so
that reported planning times leave them out.

A kernel compiles on its first call with a new signature (about 10-20 s for those of a plan
the first time on a machine); later processes load it from the cache, a tenth of a second or so
per kernel and more for the first (Numba sets up its target then). Neither is the planner's time.
Numba announces every compilation as a ``numba:compile`` event and every entry to its compiler
lock, which a cache load holds too, as ``numba:compiler_lock`` (:mod:`numba.core.event`); two
listeners, registered on import, add up the outermost intervals of each (nested ones, a kernel
compiling the kernels it calls, count once). :func:`compile_seconds` is the compilation alone
(what the CLI's "compiling kernels once" line reports), :func:`kernel_seconds` compilation and
loading together (what :class:`Stopwatch` leaves out). A timed section takes the difference
around it::

    t0, k0 = time.perf_counter(), kernel_seconds()
    ...
    wall = time.perf_counter() - t0 - (kernel_seconds() - k0)
"""

from __future__ import annotations

import threading
import time

from numba.core import event

_lock = threading.Lock()


class _CompileClock(event.Listener):
    """Total seconds between the outermost start and end of one kind of event."""

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
_locked = _CompileClock()
event.register("numba:compiler_lock", _locked)


def _seconds(clock: _CompileClock) -> float:
    with _lock:
        running = time.perf_counter() - clock.started if clock.depth else 0.0
        return clock.total + running


def compile_seconds() -> float:
    """Seconds of kernel compilation so far in this process, a compilation under way included."""
    return _seconds(_clock)


def kernel_seconds() -> float:
    """Seconds so far in this process under Numba's compiler lock: compiling kernels and loading
    them from the cache (at least :func:`compile_seconds`)."""
    return max(_seconds(_locked), _seconds(_clock))


class Stopwatch:
    """Wall time since creation less the kernels' compilation and cache loading in it
    (:func:`kernel_seconds`)."""

    def __init__(self) -> None:
        self.t0 = time.perf_counter()
        self.c0 = compile_seconds()
        self.k0 = kernel_seconds()

    @property
    def compile(self) -> float:
        """Seconds of compilation since the start."""
        return compile_seconds() - self.c0

    @property
    def kernels(self) -> float:
        """Seconds of compilation and cache loading since the start."""
        return kernel_seconds() - self.k0

    @property
    def elapsed(self) -> float:
        """Wall seconds since the start, compilation and cache loading excluded."""
        return time.perf_counter() - self.t0 - self.kernels


__all__ = ["Stopwatch", "compile_seconds", "kernel_seconds"]
