"""Record real calls of every population kernel and compare its serial and parallel builds on
them, bit for bit (``uavplan.kernel_builds``).

    NUMBA_NUM_THREADS=2 python tests/kernel_agreement.py

runs a small workload (``uavplan plan`` on built-in scenarios covering 2-D scenes, terrain,
cylinders, fleets and moving obstacles; 200-obstacle worlds for the indexed passes; the reference
kernels called directly), keeps each kernel's first calls for each set of argument types (a
kernel called with other types is another build), runs both builds on copies of their
arguments and prints one JSON line: the kernels compared, those never called, those whose
parallel build Numba cannot build for a real call's types (a run then falls back to the
serial build and loses the parallel speed) and those whose builds differ.
``tests/test_kernel_builds.py`` runs it (a slow test: it compiles every parallel build).
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from typing import Any

import numba
import numpy as np

from uavplan import kernel_builds
from uavplan.kernel_builds import ALL, PopulationKernel

#: calls kept per kernel and argument types (a kernel called with other types is another
#: build: each is compared)
KEEP = 2
#: (scenario, planner, extra CLI options) of the workload
PLANS = [
    ("simple2d", "spso", []),
    ("simple2d", "rrt-star", []),
    ("spso", "spso", []),
    ("hrmaga-jacksboro", "hr-maga", []),
    ("ppswarm1", "ppswarm", []),
    ("rscdwoa-mixed", "rscdwoa-apf", []),
    ("dense", "prioritized", []),
]


def _copy(a: Any) -> Any:
    return a.copy() if isinstance(a, np.ndarray) else a


def _same(x: Any, y: Any) -> bool:
    if isinstance(x, tuple):
        return isinstance(y, tuple) and len(x) == len(y) and all(map(_same, x, y))
    if isinstance(x, np.ndarray):
        return bool(x.shape == y.shape and x.dtype == y.dtype
                    and np.array_equal(x, y, equal_nan=x.dtype.kind == "f"))  # fmt: skip
    return bool(x == y or (x != x and y != y))


def record() -> dict[str, list[tuple[Any, ...]]]:
    """Run the workload with every kernel serial, keeping the first calls' arguments."""
    calls: dict[str, list[tuple[Any, ...]]] = {}
    original = PopulationKernel.__call__

    seen: dict[tuple[str, str], int] = {}

    def keep(self: PopulationKernel, *args: Any) -> Any:
        types = str(tuple(numba.typeof(a) for a in args))
        n = seen.get((self.__qualname__, types), 0)
        if n < KEEP:
            seen[(self.__qualname__, types)] = n + 1
            calls.setdefault(self.__qualname__, []).append(tuple(_copy(a) for a in args))
        return original(self, *args)

    from uavplan.cli import app

    kernel_builds.set_mode("never")
    PopulationKernel.__call__ = keep  # type: ignore[method-assign]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for scenario, planner, extra in PLANS:
                argv = ["plan", scenario, "-a", planner, "--iterations", "4", "-o", tmp, *extra]
                with contextlib.ExitStack() as quiet:
                    quiet.enter_context(contextlib.redirect_stdout(io.StringIO()))
                    quiet.enter_context(contextlib.redirect_stderr(io.StringIO()))
                    quiet.enter_context(contextlib.suppress(SystemExit))
                    app(argv, standalone_mode=False)
        _direct_calls()
    finally:
        PopulationKernel.__call__ = original  # type: ignore[method-assign]
    return calls


def _direct_calls() -> None:
    """The kernels the plans above do not reach: the indexed cylinder pass (64 or more
    cylinders), the indexed danger-area and 2-D scene passes (64 or more obstacles), the
    per-pair distances and the reference kernels (those of the fused costs among them)."""
    from uavplan.problems import costs
    from uavplan.world import geometry
    from uavplan.world._terrain_kernels import (
        mean_height_batch,
        mean_height_batch_reference,
        mean_height_lower_batch,
    )

    rng = np.random.default_rng(0)
    paths = rng.uniform(0, 1000, (40, 12, 3))
    centers = rng.uniform(0, 1000, (200, 2))
    radii = rng.uniform(5, 30, 200)
    z_lo, z_hi = np.zeros(200), rng.uniform(100, 900, 200)
    geometry.cylinder_hits(paths, centers, z_lo, z_hi, radii)
    # the fused costs' references: SPSO's smoothness and the threat pass over every pair
    costs.smoothness_cost_spso(paths)
    r10 = radii[:10]
    geometry.cylinder_threat(paths, centers[:10], z_lo[:10], z_hi[:10], r10, r10 + 5.0, False)
    geometry.cylinder_distances(paths, centers, z_lo, z_hi)
    geometry.segment_circle_inside_fraction(paths[..., :2], centers[:20], radii[:20])
    geometry.circle_inside_length(paths, centers, radii)  # 64 or more: the indexed pass
    square = np.array([[0.0, 0.0], [200.0, 0.0], [200.0, 200.0], [0.0, 200.0]])
    verts, starts = geometry.pack_polygons([square + 300.0, square[::-1] * 0.5 + 600.0])
    flat = np.ascontiguousarray(paths[..., :2])
    geometry.segment_polygon_distance(flat, verts, starts)
    geometry.segment_polygon_inside_fraction(flat, verts, starts)
    margins = np.zeros(2)
    box = (np.zeros(2), np.full(2, 1000.0))  # 200 circles and 2 polygons: the indexed scene pass
    geometry.scene2d_batch(flat, centers, radii, verts, starts, margins, *box)  # the grid kernel
    H = rng.uniform(0, 100, (50, 60))
    u, v = rng.uniform(0, 59, (40, 12)), rng.uniform(0, 49, (40, 12))
    mean_height_batch(H, u, v)
    mean_height_batch_reference(H, u, v)
    # HR-MAGA's lower bound of the terrain term over 8 x 8 blocks (reached on larger maps)
    Hb = np.ascontiguousarray(rng.uniform(0, 100, (7, 8)))
    mean_height_lower_batch(Hb, 8.0, 1e-9, u, v)


def compare(calls: dict[str, list[tuple[Any, ...]]]) -> dict[str, Any]:
    differ, cannot_build = [], []
    for qualname, kept in sorted(calls.items()):
        k = next(k for k in ALL if k.__qualname__ == qualname)
        for args in kept:
            a = k.serial(*(_copy(x) for x in args))
            try:
                b = k.parallel(*(_copy(x) for x in args))
            except Exception as exc:  # Numba cannot build it for these argument types
                cannot_build.append(f"{qualname}: {type(exc).__name__}: {str(exc)[:300]}")
                break
            if not _same(a, b):
                differ.append(qualname)
                break
    names = {k.__module__ + "." + k.__qualname__ for k in ALL}
    seen = {k.__module__ + "." + k.__qualname__ for k in ALL if k.__qualname__ in calls}
    return {"compared": sorted(seen), "not_called": sorted(names - seen), "differ": differ,
            "cannot_build": cannot_build, "registered": sorted(names),
            "calls": sum(map(len, calls.values()))}  # fmt: skip


if __name__ == "__main__":
    report = compare(record())
    report["threads"] = numba.get_num_threads()
    print(json.dumps(report))
    sys.exit(1 if report["differ"] or report["not_called"] or report["cannot_build"] else 0)
