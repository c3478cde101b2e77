"""Execute one run (in whatever process or machine) and return its tidy row.

A run that raises is recorded with ``status="error"`` and the exception's text, so that the sweep
goes on. Everything a worker needs is rebuilt from the :class:`RunSpec`; scenarios are cached per
process.
"""

from __future__ import annotations

import functools
import os
import platform
import subprocess
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np

from uavplan import __version__
from uavplan.bench.kinds import run_kind
from uavplan.bench.plans import RunSpec
from uavplan.compile_clock import Stopwatch

_single_thread_done = False


def limit_threads() -> None:
    """One thread per worker for Numba and BLAS, so two cores run two runs, not four halves."""
    global _single_thread_done
    if _single_thread_done:
        return
    _single_thread_done = True
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    try:
        import numba

        numba.set_num_threads(1)
    except Exception:  # pragma: no cover - numba is a dependency; be defensive
        pass
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    except Exception:
        pass


@functools.cache
def host_info() -> dict[str, str]:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"host": platform.node(), "cpu": cpu, "python": platform.python_version()}


def _rev_parse(folder: Path) -> str | None:
    if not (folder / ".git").exists():
        return None
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=folder, capture_output=True, text=True, timeout=5
        )
        return out.stdout.strip() or None
    except Exception:
        return None


@functools.cache
def git_commit() -> str | None:
    """The commit of the uavplan source: the checkout this module runs from; else, for a
    package installed by pip, the commit its install record names (PEP 610
    ``direct_url.json``: ``vcs_info.commit_id`` for ``pip install git+URL``, or the HEAD of the
    local checkout it was installed from, if that is still there: the install's own commit
    unless the checkout has moved since); None when nothing says."""
    here = _rev_parse(Path(__file__).resolve().parents[3])
    if here is not None:
        return here
    try:
        import json
        from importlib.metadata import distribution
        from urllib.parse import unquote, urlparse

        text = distribution("uavplan").read_text("direct_url.json")
        if not text:
            return None
        info = json.loads(text)
        commit = (info.get("vcs_info") or {}).get("commit_id")
        if commit:
            return str(commit)
        url = urlparse(str(info.get("url", "")))
        if url.scheme == "file":
            return _rev_parse(Path(unquote(url.path)))
    except Exception:
        return None
    return None


def _status_mb(field: str) -> float | None:
    """A ``/proc/self/status`` memory field (``VmRSS``, ``VmHWM``) in MiB; None off Linux."""
    from uavplan.planners.memory import proc_field_kib

    kib = proc_field_kib("/proc/self/status", field)
    return None if kib is None else kib / 1024.0


def _reset_peak_rss() -> bool:
    """Reset this process's peak resident set size (Linux >= 4.0: ``clear_refs`` 5)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def execute_run(spec: RunSpec) -> dict[str, Any]:
    """Run ``spec`` and return its row (never raises for errors inside the run). The row's
    ``peak_rss_mb`` is the worker process's peak resident memory during the run (the
    interpreter and libraries included; ``rss_before_mb`` is what it held at the start), None
    where the operating system cannot say."""
    peak_ok = _reset_peak_rss()
    rss0 = _status_mb("VmRSS")
    start = time.time()
    clock = Stopwatch()
    row: dict[str, Any] = {
        "run_id": spec.run_id,
        "plan": spec.plan,
        "scenario": spec.scenario,
        "algorithm": spec.algorithm,
        "run_index": spec.run_index,
        "seed": str(spec.seed),
        "root_seed": spec.root_seed,
        "scale": spec.scale,
    }
    try:
        metrics = run_kind(spec.kind)(spec)
        row.update(status="ok", error=None)
        row.update(metrics)
    except Exception as exc:  # recorded, the sweep goes on
        tb = traceback.format_exception_only(type(exc), exc)[-1].strip()
        row.update(
            status="error",
            error=tb,
            best_cost=None,
            path_length=None,
            feasible=None,
            first_feasible_iteration=None,
            evaluations=None,
            iterations=None,
            history=None,
        )
    # kernel compilation (a worker's first runs) is not the run's time; it is recorded apart
    row["wall_time"] = clock.elapsed
    row["compile_time"] = clock.compile
    row["peak_rss_mb"] = _status_mb("VmHWM") if peak_ok else None
    row["rss_before_mb"] = rss0
    row["start_time"] = start
    row["end_time"] = time.time()
    row.update(version=__version__, git_commit=git_commit(), **host_info())
    return row


_warm = False


def warm_up() -> None:
    """Compile (or load from Numba's cache) every batched kernel once per process, so that the
    first run a worker executes is not charged for it."""
    global _warm
    if _warm:
        return
    _warm = True
    from uavplan.problems.path_problem import PRESETS, PathProblem
    from uavplan.world import (
        AltitudeBand,
        Bounds,
        Circle,
        Cylinder,
        DangerArea,
        MovingObstacle,
        Polygon,
        Scenario,
        Task,
        Terrain,
    )

    terrain = Terrain(np.arange(16.0).reshape(4, 4), 0.0, 0.0, 10.0, 10.0)
    sc3 = Scenario(
        "warm3",
        Bounds((0, 0, 0), (30, 30, 100)),
        (Task("a", (1, 1, 50), (29, 29, 50)),),
        terrain=terrain,
        cylinders=(Cylinder((15, 15), 2.0),),
        danger_areas=(DangerArea((5, 5), 2),),
        moving_obstacles=(MovingObstacle(1.0, np.array([0.0, 5.0]), np.zeros((2, 3))),),
        altitude=AltitudeBand(10, 90, "ground"),
    )
    sc2 = Scenario(
        "warm2",
        Bounds((0, 0), (30, 30)),
        (Task("a", (1, 1), (29, 29)),),
        circles=(Circle((15, 15), 2.0),),
        polygons=(Polygon(((5, 20), (8, 20), (8, 25))),),
    )
    rng = np.random.default_rng(0)
    for sc in (sc3, sc2):
        paths = rng.uniform(1, 29, (2, 4, sc.dim))
        paths[:, 0], paths[:, -1] = sc.tasks[0].start, sc.tasks[0].goal
        for preset in PRESETS:
            if sc.dim == 2 and preset != "length2d":
                continue
            PathProblem(sc, cost=preset).evaluate(paths)
    terrain.min_clearance(np.full((1, 2, 3), 5.0))
    terrain.max_clearance(np.full((1, 2, 3), 5.0))
    terrain.stays_within(np.full((1, 2, 3), 5.0), 10.0)
    from uavplan.world.reservations import ReservationTable

    table = ReservationTable(np.zeros(3), np.full(3, 30.0), 1.0)
    table.add("a", np.array([[1.0, 1, 5], [29, 29, 5]]), np.array([0.0, 3.0]))
    table.conflicts(np.array([[[29.0, 1, 5], [1, 29, 5]]]), np.array([[0.0, 3.0]]))


def execute_chunk(specs: list[RunSpec], single_thread: bool = True) -> list[dict[str, Any]]:
    """Run several specs in this process (the unit of work sent to a worker)."""
    if single_thread:
        limit_threads()
    warm_up()
    return [execute_run(s) for s in specs]
