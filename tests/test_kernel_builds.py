"""The serial and parallel builds of the population kernels (``uavplan.kernel_builds``): which
one runs, that they never share cache entries, and (slow) that they return the same bits on
real calls of every kernel."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import prange

from uavplan import kernel_builds
from uavplan.kernel_builds import ALL, PopulationKernel, population_kernel

HERE = Path(__file__).resolve().parent
KERNEL_MODULES = ("uavplan.world.geometry", "uavplan.world._terrain_kernels",
                  "uavplan.world.reservations", "uavplan.problems.costs",
                  "uavplan.problems._validity_kernels",
                  "uavplan.planners.fleet.fleet_objective")  # fmt: skip


def _row_sums(x):  # pragma: no cover - numba
    out = np.empty(x.shape[0])
    for i in prange(x.shape[0]):
        s = 0.0
        for j in range(x.shape[1]):
            s += x[i, j] * x[i, j]
        out[i] = s
    return out


def _fresh() -> PopulationKernel:
    return population_kernel()(_row_sums)


def test_one_thread_runs_the_serial_build_only() -> None:
    k = _fresh()
    x = np.arange(12.0).reshape(3, 4)
    with_one = numba.get_num_threads() == 1
    if not with_one:
        pytest.skip("the suite runs Numba with one thread (tests/conftest.py)")
    for _ in range(5):
        np.testing.assert_array_equal(k(x), (x * x).sum(axis=1))
    assert k.serial.signatures and not k.parallel.signatures
    assert k.serial_calls == 0  # with one thread nothing is timed: there is nothing to switch to


def test_more_threads_switch_to_the_parallel_build_after_the_serial_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    k = _fresh()
    x = np.ones((4, 3))
    monkeypatch.setattr(numba, "get_num_threads", lambda: 2)
    monkeypatch.setattr(kernel_builds, "PARALLEL_AFTER", 1e9)
    k(x)  # compiles (or loads) the serial build: not counted
    k(x)
    k(x)
    assert not k.switched and k.serial_calls == 2 and not k.parallel.signatures
    monkeypatch.setattr(kernel_builds, "PARALLEL_AFTER", 0.0)
    monkeypatch.setattr(kernel_builds, "PARALLEL_MIN_CALL", 1e9)  # calls too small to gain
    k(x)
    assert not k.switched
    monkeypatch.setattr(kernel_builds, "PARALLEL_MIN_CALL", 0.0)
    k(x)
    assert k.switched and k.use_parallel()
    np.testing.assert_array_equal(k(x), np.full(4, 3.0))
    assert k.parallel.signatures


def test_a_parallel_build_that_cannot_be_built_falls_back_to_the_serial_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A parallel build that fails before it has ever run (as Numba's parfor lowering of some
    tuple arguments does) is not used again: the serial build answers, with the same bits; once
    the parallel build has run, its errors are the run's and propagate."""
    k = _fresh()
    x = np.ones((4, 3))
    monkeypatch.setattr(numba, "get_num_threads", lambda: 2)
    k.switched = True

    def cannot_build(*args: object) -> None:
        raise TypeError("scalar type Tuple(...) given for non scalar argument #29")

    monkeypatch.setattr(k, "parallel", cannot_build)
    np.testing.assert_array_equal(k(x), np.full(4, 3.0))
    assert k.parallel_error is not None and "argument #29" in k.parallel_error
    np.testing.assert_array_equal(k(x), np.full(4, 3.0))  # the serial build from then on
    k2 = _fresh()
    k2.switched = True
    np.testing.assert_array_equal(k2(x), np.full(4, 3.0))  # the parallel build runs
    assert k2.parallel_ran and k2.parallel_error is None
    monkeypatch.setattr(k2, "parallel", cannot_build)
    with pytest.raises(TypeError, match="argument #29"):
        k2(x)


def test_modes_override_the_rule_and_reject_unknown_names() -> None:
    k = _fresh()
    previous = kernel_builds.set_mode("always")
    try:
        assert k.use_parallel()
        kernel_builds.set_mode("never")
        assert not k.use_parallel()
        with pytest.raises(ValueError, match="one of auto, always, never"):
            kernel_builds.set_mode("fast")
    finally:
        kernel_builds.set_mode(previous)


def test_the_builds_have_their_own_cache_names() -> None:
    from uavplan.world.geometry import scene2d_kernel

    assert isinstance(scene2d_kernel, PopulationKernel) and scene2d_kernel in ALL
    for k in ALL:
        assert k.serial.py_func.__qualname__ != k.parallel.py_func.__qualname__
        assert k.parallel.py_func.__code__ is k.serial.py_func.__code__  # one source


@pytest.mark.slow
def test_parallel_builds_give_the_bits_of_the_serial_ones_on_real_calls(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_NUM_THREADS": "2", "PYTHONPATH": str(HERE)}
    proc = subprocess.run([sys.executable, str(HERE / "kernel_agreement.py")], env=env,
                          capture_output=True, text=True, timeout=1800)  # fmt: skip
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["threads"] == 2
    assert not report["not_called"], report
    assert not report["differ"], report
    assert not report["cannot_build"], report
    assert report["compared"] == report["registered"]
    # every kernel this process knows of was registered there too (ALL fills on import)
    for module in KERNEL_MODULES:
        importlib.import_module(module)
    assert {k.__module__ + "." + k.__qualname__ for k in ALL} <= set(report["registered"])
    assert len(report["registered"]) >= 16


def test_an_unknown_mode_in_the_environment_warns_and_falls_back_to_auto() -> None:
    env = {**os.environ, "UAVPLAN_PARALLEL_KERNELS": "fast"}
    code = "import uavplan.kernel_builds as k; print(k._mode)"
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert proc.stdout.strip() == "auto"
    assert "UAVPLAN_PARALLEL_KERNELS='fast' is not one of auto, always, never" in proc.stderr
