"""Determinism (issue 19 item 5): the same plan and seeds give bit-identical results on every
executor: this process (serial), local worker processes (1 and 2), a Dask cluster (1 and 2
workers), a rerun, and two Numba threads with the parallel kernel builds. Every registered
planner (fleet planners and named configurations included) and every registered optimizer
(as a planner, and on a benchmark function) is covered by iterating the registries, so a new
one is covered without a word here. Compared: every column of the stored rows except the
measured ones (:data:`uavplan.bench.store.MEASURED_COLUMNS`: times, memory, host); costs,
waypoints, histories, feasibility and the verifier's verdicts among them.

The default run compares the serial executor with a pool of two worker processes on every
planner (one tiny 3-D scenario, a budget of 3 iterations); ``-m slow`` runs the whole matrix
(``test_every_executor_gives_the_same_bits``) and prints it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from bench.compare import differing_cells, result_frame
from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale
from uavplan.bench.runner import run_sweep
from uavplan.bench.store import ResultStore
from uavplan.optimizers.base import available as available_optimizers
from uavplan.planners import available_planners, get_planner, planner_entry

#: tiny worlds: a 3-D one with terrain (every planner plans in 3-D), a 2-D one, a fleet of 3
SCENARIO_3D, SCENARIO_2D, FLEET, FUNCTION = "hrmaga-virtual", "simple2d", "ppswarm1@3", "sphere5"


def _options(name: str) -> dict[str, Any]:
    """A small population and, for the fleet engine, one restart and a short RRT*."""
    names = get_planner(name).option_names()
    small = {"pop_size": 12, "n_restart": 1, "rrt_iterations": 800}
    return {k: v for k, v in small.items() if k in names}


def _scales(runs: int, iterations: int) -> dict[str, Scale]:
    s = Scale(runs=runs, iterations=iterations)
    return {"smoke": s, "paper": s}


def planner_plan(scenario: str, runs: int = 1, iterations: int = 3) -> ExperimentPlan:
    """Every registered planner that plans in the scenario's dimension, one UAV (a fleet
    planner plans a fleet of one)."""
    from uavplan.scenarios import resolve

    dim = resolve(scenario).dim
    names = [n for n in available_planners() if dim in get_planner(n).specs.dims]
    return ExperimentPlan(
        f"det-planners-{dim}d", "determinism", (scenario,),
        tuple(Algorithm(n, n, _options(n)) for n in names), _scales(runs, iterations),
    )  # fmt: skip


def fleet_plan(runs: int = 1, iterations: int = 2) -> ExperimentPlan:
    """Every registered fleet planner on a fleet of three (run kind ``fleet``: the verifier's
    verdicts on the plan are compared too)."""
    names = [n for n in available_planners() if planner_entry(n).fleet]
    return ExperimentPlan(
        "det-fleet", "determinism", (FLEET,), tuple(Algorithm(n, n, _options(n)) for n in names),
        _scales(runs, iterations), kind="fleet",
    )  # fmt: skip


def function_plan(runs: int = 2, iterations: int = 5) -> ExperimentPlan:
    """Every registered optimizer on a benchmark function."""
    return ExperimentPlan(
        "det-functions", "determinism", (FUNCTION,),
        tuple(Algorithm(n, n, {"pop_size": 12}) for n in available_optimizers()),
        _scales(runs, iterations), kind="function",
    )  # fmt: skip


#: An executor: a name and how to run a plan into a folder with it.
Executor = tuple[str, Callable[[ExperimentPlan, Path], Any]]


def serial(plan: ExperimentPlan, out: Path) -> Any:
    return run_sweep(plan, out, executor="serial")


def pool(workers: int) -> Executor:
    def run(plan: ExperimentPlan, out: Path) -> Any:
        return run_sweep(plan, out, executor="process", workers=workers)

    return (f"process x{workers}", run)


def _results(out: Path) -> pd.DataFrame:
    return result_frame(ResultStore(out).read())


def _compare(name: str, got: pd.DataFrame, want: pd.DataFrame) -> list[str]:
    """Every difference (the matrix needs all of them, the message the first few)."""
    if list(got.index) != list(want.index):
        return [f"{name}: runs {sorted(set(got.index) ^ set(want.index))[:5]} differ"]
    return [f"{name}: {d}" for d in differing_cells(got, want, limit=10**9)]


def run_matrix(
    plans: list[ExperimentPlan], executors: list[Executor], root: Path
) -> tuple[dict[tuple[str, str], str], list[str], dict[str, float]]:
    """Run every plan with every executor; compare each with the serial run. The matrix
    (algorithm, executor) -> "same" or "DIFFERS", the differences, seconds per executor."""
    matrix: dict[tuple[str, str], str] = {}
    problems: list[str] = []
    seconds: dict[str, float] = {}
    for plan in plans:
        serial_out = root / "serial" / plan.name
        t = time.monotonic()
        run_sweep(plan, serial_out, executor="serial")
        seconds["serial"] = seconds.get("serial", 0.0) + time.monotonic() - t
        want = _results(serial_out)
        assert (want["status"] == "ok").all(), want[want["status"] != "ok"]["error"].tolist()
        for label, run in executors:
            out = root / label.replace(" ", "_") / plan.name
            t = time.monotonic()
            run(plan, out)
            seconds[label] = seconds.get(label, 0.0) + time.monotonic() - t
            got = _results(out)
            diffs = _compare(f"{plan.name} {label}", got, want)
            problems += diffs
            for alg in {a.label for a in plan.algorithms}:
                bad = any(f"/{alg}/" in d for d in diffs) or len(got) != len(want)
                matrix[(f"{plan.kind}: {alg}", label)] = "DIFFERS" if bad else "same"
    return matrix, problems, seconds


def _covered(plans: list[ExperimentPlan]) -> None:
    """The plans cover every registered planner and optimizer (none left out silently)."""
    planned = {a.planner for p in plans if p.kind in ("planner", "fleet") for a in p.algorithms}
    assert planned == set(available_planners())
    assert set(available_optimizers()) <= planned  # every optimizer as a planner
    functions = {a.planner for p in plans if p.kind == "function" for a in p.algorithms}
    assert functions in (set(), set(available_optimizers()))


def test_every_planner_gives_the_same_bits_in_a_worker_pool(tmp_path: Path) -> None:
    plans = [planner_plan(SCENARIO_3D)]
    _covered(plans)
    _, problems, _ = run_matrix(plans, [pool(2)], tmp_path)
    assert not problems, "\n".join(problems)


def _serial_threads(plan: ExperimentPlan, out: Path) -> Any:
    """The serial executor in a fresh process with two Numba threads and the parallel kernel
    builds always on (a thread count cannot change inside a process): one process runs every
    plan of :data:`PLANS` (the parallel builds compile once) into ``out``'s folder; the calls
    for the other plans find their runs there."""
    if (out / "runs").is_dir():
        return None
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]);"
        "from pathlib import Path;"
        "from bench.test_determinism import PLANS;"
        "from uavplan.bench.runner import run_sweep;"
        "[run_sweep(make(), Path(sys.argv[2]) / name, executor='serial')"
        " for name, make in PLANS.items()]"
    )
    env = {**os.environ, "NUMBA_NUM_THREADS": "2", "UAVPLAN_PARALLEL_KERNELS": "always"}
    tests = str(Path(__file__).resolve().parents[1])
    res = subprocess.run([sys.executable, "-c", code, tests, str(out.parent)], env=env,
                         capture_output=True, text=True)  # fmt: skip
    assert res.returncode == 0, res.stderr[-2000:]
    return None


def _dask(workers: int) -> Executor:
    def run(plan: ExperimentPlan, out: Path) -> Any:
        distributed = pytest.importorskip("distributed")
        with (
            distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,  # fmt: skip
            distributed.Client(cluster) as client,
        ):
            return run_sweep(plan, out, executor="dask", dask_client=client)

    return (f"dask x{workers}", run)


#: the slow matrix's plans by name (the subprocess of ``_serial_threads`` rebuilds them)
PLANS: dict[str, Callable[[], ExperimentPlan]] = {
    "det-planners-3d": lambda: planner_plan(SCENARIO_3D, runs=2),
    "det-planners-2d": lambda: planner_plan(SCENARIO_2D, runs=2),
    "det-fleet": fleet_plan,
    "det-functions": function_plan,
}


@pytest.mark.slow  # 4 plans x 7 executors: several minutes on 2 cores
def test_every_executor_gives_the_same_bits(tmp_path: Path) -> None:
    plans = [make() for make in PLANS.values()]
    _covered(plans)
    executors: list[Executor] = [
        ("serial rerun", serial),
        pool(1),
        pool(2),
        _dask(1),
        _dask(2),
        ("serial, 2 threads, parallel kernels", _serial_threads),
    ]
    t0 = time.monotonic()
    matrix, problems, seconds = run_matrix(plans, executors, tmp_path)
    labels = ["serial rerun"] + [e[0] for e in executors[1:]]
    rows = sorted({k[0] for k in matrix})
    lines = [" | ".join(["planner / optimizer", *labels])]
    lines += [" | ".join([r, *(matrix.get((r, c), "-") for c in labels)]) for r in rows]
    report = {"rows": len(rows), "executors": len(labels), "seconds": round(time.monotonic() - t0),
              "per_executor_s": {k: round(v) for k, v in seconds.items()}}  # fmt: skip
    print("\n".join(lines), json.dumps(report), sep="\n")
    assert not problems, "\n".join(problems[:40])
