"""Population kernels built twice, serial and parallel, and the parallel build used only where it
pays for its compilation.

A kernel written with ``prange`` over the paths of a population compiles about four times
longer with ``parallel=True`` than without (13.8 s against 3.3 s for the 2-D scene kernel,
measured with an empty cache), and with one Numba thread, as the tests and every experiment
worker run, the parallel build only costs that compilation. :func:`population_kernel` therefore
makes two builds of the same Python function (``prange`` is ``range`` in the serial one) and
picks one per call:

* ``serial`` when Numba runs one thread (``numba.get_num_threads() == 1``);
* otherwise the serial build until this process has spent :data:`PARALLEL_AFTER` seconds in the
  kernel's serial calls (leaving out the calls that compiled or loaded a build from the cache)
  at :data:`PARALLEL_MIN_CALL` or more per call on average, then the parallel build from
  there on: a first ``uavplan plan`` compiles only what a short run needs, and a long run
  switches within a second or two.

``UAVPLAN_PARALLEL_KERNELS`` overrides the choice: ``always``, ``never`` or ``auto`` (the
default); :func:`set_mode` does the same from Python (benchmarks measure the parallel builds).
Both builds compute every path of the population independently, with the same operations in the
same order, so they return the same bits (``tests/test_kernel_builds.py`` checks the builds'
agreement kernel by kernel); which build ran never changes a result.

Numba names a kernel's cache files after the function's qualified name, so the parallel build
compiles a copy of the function named ``<name>__parallel``: the two builds never read each
other's cache entries.
"""

from __future__ import annotations

import os
import time
import types
import warnings
from collections.abc import Callable
from typing import Any

import numba
from numba import njit

#: seconds of serial calls (those that compiled or loaded a build left out) after which a
#: kernel switches to its parallel build when Numba runs more than one thread
PARALLEL_AFTER = 1.0
#: the mean seconds per serial call below which a kernel stays serial (a thread pool's wake-up
#: costs tens of microseconds, more than a small call gains)
PARALLEL_MIN_CALL = 100e-6

_MODES = ("auto", "always", "never")
_mode = os.environ.get("UAVPLAN_PARALLEL_KERNELS", "auto")
if _mode not in _MODES:
    warnings.warn(f"UAVPLAN_PARALLEL_KERNELS={_mode!r} is not one of {', '.join(_MODES)}: "
                  "using auto", stacklevel=1)  # fmt: skip
    _mode = "auto"


def set_mode(mode: str) -> str:
    """Set how every population kernel picks its build (``auto``, ``always``, ``never``);
    returns the previous mode."""
    global _mode
    if mode not in _MODES:
        raise ValueError(f"kernel build mode {mode!r}: one of {', '.join(_MODES)}")
    previous, _mode = _mode, mode
    return previous


def _renamed(f: Callable[..., Any], suffix: str) -> Callable[..., Any]:
    g = types.FunctionType(f.__code__, f.__globals__, f.__name__ + suffix, f.__defaults__,
                           f.__closure__)  # fmt: skip
    g.__qualname__ = f.__qualname__ + suffix
    g.__module__ = f.__module__
    g.__doc__ = f.__doc__
    g.__kwdefaults__ = f.__kwdefaults__
    return g


#: every population kernel, in the order their modules defined them
ALL: list[PopulationKernel] = []


class PopulationKernel:
    """A kernel's ``serial`` and ``parallel`` Numba builds behind one call (see the module)."""

    def __init__(self, f: Callable[..., Any], options: dict[str, Any]) -> None:
        self.py_func = f
        self.__name__ = f.__name__
        self.__qualname__ = f.__qualname__
        self.__doc__ = f.__doc__
        self.__module__ = f.__module__
        self.serial = njit(cache=True, parallel=False, **options)(f)
        self.parallel = njit(cache=True, parallel=True, **options)(_renamed(f, "__parallel"))
        self.serial_seconds = 0.0
        self.serial_calls = 0
        self.switched = False
        #: the parallel build has run once (so an error from it is the run's, not its build's)
        self.parallel_ran = False
        #: why the parallel build could not be used (it failed to compile), else None
        self.parallel_error: str | None = None
        ALL.append(self)

    def _parallel_or_serial(self, *args: Any) -> Any:
        """The parallel build; where it fails before it has ever run (Numba cannot build it
        for these arguments: some parfor lowerings of tuple arguments fail), the serial build
        from then on, which gives the same bits (the module docstring). ``always`` mode never
        falls back: benchmarks of the parallel builds must see the failure."""
        if self.parallel_error is None:
            try:
                out = self.parallel(*args)
            except Exception as exc:  # any failure to build it
                if self.parallel_ran:
                    raise
                self.parallel_error = f"{type(exc).__name__}: {exc}"
            else:
                self.parallel_ran = True
                return out
        return self.serial(*args)

    def use_parallel(self) -> bool:
        """Whether the next call runs the parallel build."""
        if _mode != "auto":
            return _mode == "always"
        return self.switched and numba.get_num_threads() > 1

    def __call__(self, *args: Any) -> Any:
        if _mode != "auto":
            return (self.parallel if _mode == "always" else self.serial)(*args)
        threads = numba.get_num_threads()
        if threads == 1 or self.switched:
            return self._parallel_or_serial(*args) if threads > 1 else self.serial(*args)
        n0, t0 = len(self.serial.overloads), time.perf_counter()
        result = self.serial(*args)
        if len(self.serial.overloads) != n0:
            return result  # it compiled or loaded a build from the cache: not run time
        self.serial_seconds += time.perf_counter() - t0
        self.serial_calls += 1
        if (self.serial_seconds >= PARALLEL_AFTER
                and self.serial_seconds >= PARALLEL_MIN_CALL * self.serial_calls):  # fmt: skip
            self.switched = True
        return result


def population_kernel(**options: Any) -> Callable[[Callable[..., Any]], PopulationKernel]:
    """Decorator: ``njit(cache=True, **options)`` built serial and parallel, one picked per call
    (the module's rule)."""

    def wrap(f: Callable[..., Any]) -> PopulationKernel:
        return PopulationKernel(f, options)

    return wrap
