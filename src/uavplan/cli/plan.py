"""``uavplan plan`` and ``uavplan demo``: plan every task of a scenario, write plan.json and
plan.png, print a summary."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from uavplan.cli._common import err, fail, out, parse_params

if TYPE_CHECKING:
    from uavplan.planners.fleet_plan import FleetPlan


def write_plan(plan: FleetPlan, out: str | Path, figure: bool = True) -> list[Path]:
    """Write ``out/plan.json`` (atomically) and ``out/plan.png``; returns the paths."""
    from uavplan.io.plan_file import write_plan_file

    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    written = [write_plan_file(plan, d / "plan.json")]
    if figure:
        from uavplan.viz.figures import save_plan_figure

        title = f"{plan.scenario.name}: {plan.algorithm}, seed {plan.seed}"
        written.append(save_plan_figure(plan.scenario, plan.results, d / "plan.png", title))
    return written


def _run_plan(
    scenario_ref: str,
    algorithm: str,
    seed: int,
    out_dir: Path,
    iterations: int | None,
    pop_size: int | None,
    waypoints: int | None,
    cost: str | None,
    params: list[str],
    figure: bool = True,
) -> Any:
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.optimizers.base import Budget, OptimizerError
    from uavplan.planners import PlannerError, get_planner
    from uavplan.planners.fleet_plan import plan_all
    from uavplan.scenarios import resolve

    try:
        scenario = resolve(scenario_ref)
    except ScenarioFileError as exc:
        raise fail(getattr(exc, "problems", None) or [str(exc)]) from None
    options: dict[str, Any] = parse_params(params)
    if pop_size is not None:
        options["pop_size"] = pop_size
    if waypoints is not None:
        options["n_waypoints"] = waypoints
    if cost is not None:
        options["cost"] = cost
    try:
        planner = get_planner(algorithm, **options)
    except (PlannerError, OptimizerError, TypeError, ValueError) as exc:
        raise fail(f"--algorithm {algorithm}: {exc}") from None
    budget = Budget(max_iterations=iterations) if iterations else None
    n_iter = iterations or 200

    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.fields[best]}"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
    ) as progress:

        def make_cb(uav: str) -> Any:
            tid = progress.add_task(f"{uav} {algorithm}", total=n_iter, best="")

            def cb(it: int, best: float) -> bool:
                progress.update(tid, completed=it, best=f"best {best:.6g}")
                return False

            return cb

        t0 = time.perf_counter()
        try:
            plan = plan_all(scenario, planner, budget, seed, make_cb)
        except ValueError as exc:
            raise fail(f"{scenario_ref}: {exc}") from None
        elapsed = time.perf_counter() - t0
    try:
        write_plan(plan, out_dir, figure=figure)
    except OSError as exc:
        raise fail(f"--out {out_dir}: cannot write: {exc}") from None
    return plan, elapsed


def _summary(plan: Any, elapsed: float, out_dir: Path) -> None:
    table = Table(title=f"{plan.scenario.name} / {plan.algorithm} / seed {plan.seed}")
    for col in (
        "UAV",
        "feasible",
        "cost",
        "length (m)",
        "flight time (s)",
        "evaluations",
        "time (s)",
    ):
        table.add_column(col, justify="right")
    shown = plan.results if len(plan.results) <= 25 else plan.results[:20]
    for r in shown:
        table.add_row(
            r.uav_id,
            "yes" if r.feasible else "NO: " + ",".join(r.violations),
            f"{r.cost:.6g}",
            f"{r.length:.1f}",
            f"{r.times[-1] - r.times[0]:.1f}",
            str(r.evaluations),
            f"{r.wall_time:.2f}",
        )
    out.print(table)
    if len(shown) < len(plan.results):
        out.print(f"... and {len(plan.results) - len(shown)} more UAVs in plan.json")
    fleet = getattr(plan, "fleet", None)
    if fleet is not None:
        n_bad = sum(not r.feasible for r in plan.results)
        sm = fleet.info.get("smoothing", {})
        verdict = (
            "feasible (separation S2 included)" if fleet.feasible else f"{n_bad} UAV(s) infeasible"
        )
        restarts = [round(float(c), 1) for c in fleet.restart_costs]
        out.print(
            f"fleet of {len(plan.results)}: cost {fleet.cost:.6g}, {verdict}, "
            f"restarts {restarts}, best restart {fleet.info.get('best_restart')}"
        )
        if sm:
            out.print(
                f"Dubins-smoothed paths: {len(sm.get('not_clear', []))} of {sm.get('checked')} "
                f"not clear {sm.get('not_clear', [])[:10]}"
            )
    out.print(f"wrote {out_dir / 'plan.json'} and {out_dir / 'plan.png'} ({elapsed:.1f} s)")


def plan(
    scenario: Annotated[
        str, typer.Argument(help="A scenario file (.yaml/.json) or built-in name.")
    ],
    algorithm: Annotated[str, typer.Option("--algorithm", "-a", help="Planner name.")] = "pso",
    seed: Annotated[int, typer.Option(help="Root random seed.")] = 0,
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")] = Path("out"),
    iterations: Annotated[int | None, typer.Option(help="Iteration budget (default 200).")] = None,
    pop_size: Annotated[int | None, typer.Option(help="Population size.")] = None,
    waypoints: Annotated[int | None, typer.Option(help="Free waypoints per path.")] = None,
    cost: Annotated[str | None, typer.Option(help="Cost preset (default: the scenario's).")] = None,
    param: Annotated[list[str] | None, typer.Option(help="Planner parameter NAME=VALUE.")] = None,
) -> None:
    """Plan every task of SCENARIO; write OUT/plan.json and OUT/plan.png."""
    result, elapsed = _run_plan(
        scenario, algorithm, seed, out_dir, iterations, pop_size, waypoints, cost, param or []
    )
    _summary(result, elapsed, out_dir)
    if not result.feasible:
        raise typer.Exit(1)


def demo(
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")] = Path(
        "uavplan-demo"
    ),
    seed: Annotated[int, typer.Option(help="Root random seed.")] = 0,
) -> None:
    """Plan the built-in SPSO benchmark with PSO at SPSO's budget (500 x 200) and show it."""
    result, elapsed = _run_plan("spso", "pso", seed, out_dir, 200, 500, None, None, [])
    _summary(result, elapsed, out_dir)
