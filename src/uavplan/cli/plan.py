"""``uavplan plan`` and ``uavplan demo``: plan every task of a scenario, write plan.json and
plan.png, print a summary."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from uavplan.cli._common import compile_notice, err, fail, out, parse_params, print_table

if TYPE_CHECKING:
    from uavplan.planners.fleet.fleet_plan import FleetPlan


def write_plan(plan: FleetPlan, out: str | Path, figure: bool = True) -> list[Path]:
    """Write ``out/plan.json`` (atomically), ``out/plan.png`` and ``out/plan.html`` (the
    viewer page); returns the paths."""
    from uavplan.io.atomic import write_text_atomic
    from uavplan.io.plan_file import parse_plan, plan_document, write_plan_file
    from uavplan.viz.viewer import viewer_html

    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    written = [write_plan_file(plan, d / "plan.json")]
    if figure:
        given = plan.scenario.metadata.get("given", plan.scenario)  # not the widened world
        page = viewer_html(parse_plan(plan_document(plan)), given)
        written.append(write_text_atomic(d / "plan.html", page))
        from uavplan.viz.figures import save_plan_figure

        title = f"{plan.scenario.name}: {plan.algorithm}, seed {plan.seed}"
        written.append(save_plan_figure(plan.scenario, plan.results, d / "plan.png", title))
    return written


def _run_plan(
    scenario_ref: str,
    algorithm: str | None,
    seed: int,
    out_dir: Path,
    iterations: int | None,
    pop_size: int | None,
    waypoints: int | None,
    cost: str | None,
    params: list[str],
    figure: bool = True,
    raw: bool = False,
    max_time: float | None = None,
    nominal: bool = False,
) -> Any:
    from uavplan.compile_clock import Stopwatch  # here: it imports Numba
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.io.scenario_file.schema import MAX_PATH_POINTS, MAX_WAYPOINTS
    from uavplan.optimizers.base import Budget, OptimizerError
    from uavplan.planners import PlannerError, get_planner
    from uavplan.scenarios import resolve

    for flag, value in (("--iterations", iterations), ("--pop-size", pop_size),
                        ("--waypoints", waypoints)):  # fmt: skip
        if value is not None and value < 1:
            raise fail(f"{flag} {value}: must be at least 1")
    if waypoints is not None and waypoints > MAX_WAYPOINTS:
        raise fail(f"--waypoints {waypoints}: at most {MAX_WAYPOINTS} free waypoints per path")
    if max_time is not None and not max_time > 0:
        raise fail(f"--time {max_time}: must be a positive number of seconds")
    compile_notice()
    try:
        given_world = resolve(scenario_ref)
    except ScenarioFileError as exc:
        raise fail(getattr(exc, "problems", None) or [str(exc)]) from None
    pw = planning_world(given_world, scenario_ref, nominal)
    scenario, given_world = pw.world, pw.given or given_world
    # the scenario's planning block gives what the command line does not (checked at load)
    block = (scenario.metadata.get("spec") or {}).get("planning") or {}
    from_file = algorithm is None and "planner" in block
    algorithm = algorithm or block.get("planner")
    iterations = iterations or block.get("iterations")
    pop_size = pop_size or block.get("pop_size")
    max_time = max_time or block.get("time")
    if cost is not None:
        from uavplan.problems import preset_problem

        why = preset_problem(cost, scenario.dim)
        if why is not None:
            raise fail(f"--cost {cost}: {why}")
    n_points = (waypoints or scenario.n_waypoints) + 2  # the free waypoints, start and goal
    if pop_size is not None and pop_size * n_points > MAX_PATH_POINTS:
        raise fail(
            f"--pop-size {pop_size}: a population of {pop_size} paths of {n_points} "
            f"points exceeds the {MAX_PATH_POINTS:,} path points a run may hold; use a smaller "
            "population"
        )
    given = parse_params(params)
    options: dict[str, Any] = {**(block.get("options") or {}), **given}
    if pop_size is not None:
        options["pop_size"] = pop_size
    if waypoints is not None:
        options["n_waypoints"] = waypoints
    if cost is not None:
        options["cost"] = cost
    from uavplan.strategy import chosen, execute, strategy_for

    if algorithm is None:
        strategy = strategy_for(scenario).with_options(options, repair=not raw)
        if params or pop_size or waypoints or block.get("options"):  # for the default
            strategy = strategy.plain()
        kind = strategy.kind.value if strategy.kind else ""
        out.print(f"planner: {strategy.planner} (the default for a {kind}: {strategy.why}"
                  f"{strategy.describe()}; docs/results.md; -a NAME for another)")  # fmt: skip
    else:
        if from_file:
            out.print(f"planner: {algorithm} (the scenario's planning block; -a NAME for "
                      "another)")  # fmt: skip
        strategy = chosen(algorithm, options, repair=not raw)
    try:
        planner = get_planner(strategy.planner, **options)
    except (PlannerError, OptimizerError, TypeError, ValueError) as exc:
        raise fail(_option_problem(strategy.planner, options, given, params, exc)) from None
    from uavplan.planners.memory import estimate_run, memory_problem

    why = memory_problem(estimate_run(scenario, planner, pop_size, waypoints))
    if why is not None:
        raise fail(f"{scenario_ref}: {why}")
    budget = (
        Budget(max_iterations=iterations, max_time=max_time) if iterations or max_time else None
    )
    n_iter = iterations or (None if max_time else planner.specs.default_iterations)

    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.fields[best]}"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
    ) as progress:

        def make_cb(uav: str, name: str) -> Any:
            tid = progress.add_task(f"{uav} {name}", total=n_iter, best="")

            def cb(it: int, best: float) -> bool:
                progress.update(tid, completed=it, best=f"best {best:.6g}")
                return False

            return cb

        clock = Stopwatch()
        try:
            outcome = execute(strategy, scenario, budget, seed, make_cb)
        except ValueError as exc:
            raise fail(f"{scenario_ref}: {exc}") from None
    _attempt_lines(outcome)
    plan, n_runs = outcome.plan, len(outcome.competing)
    planning = clock.elapsed  # the files and the figure are not the planner's time
    plan.scenario.metadata["given"] = given_world  # what the verifier checks against
    try:
        write_plan(plan, out_dir, figure=figure)
    except OSError as exc:
        raise fail(f"--out {out_dir}: cannot write: {exc}") from None
    return plan, (planning, clock.compile, n_runs)


def planning_world(scenario: Any, ref: str, nominal: bool, model: Any = None) -> Any:
    """The world a plan is made in (:func:`uavplan.strategy.planning_world`: a
    ``PlanningWorld``); says the model (and any turns, speeds or tasks changed) on the console;
    exit 2 when it cannot be made."""
    from uavplan.strategy import WorldProblem
    from uavplan.strategy import planning_world as make

    try:
        pw = make(scenario, ref, nominal, model)
    except WorldProblem as exc:
        raise fail(exc.problems) from None
    for line in (pw.turns_line(), pw.speeds_line(), pw.tasks_line()):
        if line:
            out.print(line, markup=False)
    hint = "" if nominal or pw.model.nominal else "; --nominal plans for an exact execution"
    out.print(f"execution model: {pw.model.describe()} ({pw.source}){hint}", markup=False)
    from uavplan.world.execution import UNCALIBRATED

    if UNCALIBRATED in pw.source:
        err.print("WARNING: this airframe's tracking error in uavplan's default model is not "
                  "calibrated: in simulation its flights leave it (docs/results.md), so the "
                  "plan's margins hold for flights it does not fly; state the model in the "
                  "scenario (execution:) or fly the plan with uavplan simulate",
                  markup=False)  # fmt: skip
    return pw


def _attempt_lines(outcome: Any) -> None:
    """What the strategy did, when it did more than one run: the runs and their costs, the
    kept one (and the command that plans it alone), the fallbacks tried and why."""
    best = outcome.attempts[outcome.best]
    if len(outcome.competing) > 1:
        costs = ", ".join(
            f"{a.planner} seed {a.seed}: {a.cost:.6g}" + ("" if a.flies else " (does not fly)")
            for a in outcome.competing
        )
        out.print(f"runs ({costs}); kept {best.planner} seed {best.seed}, which "
                  f"`-a {best.planner} --seed {best.seed}` plans alone")  # fmt: skip
    tried = best
    for fb in outcome.fallbacks:
        bad = next(r for r in tried.plan.results if not r.flown_feasible)
        why = _verdict(False, bad.flown_violations or bad.violations)[4:] or "a check"
        out.print(f"{tried.planner}'s plan does not fly ({bad.uav_id}: {why}); "
                  f"trying the fallback {fb.planner}")  # fmt: skip
        if fb.flies:
            out.print(f"{fb.planner}'s plan flies: it is the one written")
        tried = fb
    if outcome.fallbacks and not outcome.fallbacks[-1].flies:
        out.print(f"no fallback's plan flies either: {outcome.plan.algorithm}'s is written")


def _option_problem(
    algorithm: str,
    options: dict[str, Any],
    given: dict[str, Any],
    params: list[str],
    exc: Exception,
) -> str:
    """The line naming what the planner refused: the ``--param`` it came from if one did."""
    from uavplan.planners import get_planner

    text = " ".join(str(exc).split())
    for k in given:
        try:
            get_planner(algorithm, **{k: given[k]})
        except Exception:
            raw = next((p for p in params if p.split("=", 1)[0].strip() == k), k)
            return f"--param {raw}: {text}"
    return f"--algorithm {algorithm}: {text}"


def verified_by_the_verifier(plan: Any, out_dir: Path) -> bool:
    """The gate before a feasible plan leaves with exit 0: the independent verifier (which
    imports no planning code) reads the plan.json just written and checks every UAV's flown
    trajectory, kinematic limits included, against the scenario as given (not the widened
    world it was planned in) under the execution model the plan states, and writes the
    margins it measures into plan.json. Prints its findings; False (and loud lines on stderr
    naming the first violations and the UAVs) if it rejects a plan the planner called
    feasible, or the plan does not meet its model."""
    from uavplan.cli.verify import margin_lines, margins_record
    from uavplan.io.plan_file import read_plan_file, with_margins
    from uavplan.verify import verify_trajectories

    pf = read_plan_file(out_dir / "plan.json", plan.scenario.dim)
    world = plan.scenario.metadata.get("given", plan.scenario)
    report = verify_trajectories(pf.trajectories("flown"), world, pf.scenario, model=pf.execution)
    if report.model is not None:
        with_margins(out_dir / "plan.json", margins_record(report))
        for line in margin_lines(report, cruise=float(world.uav.speed)):
            out.print(line, markup=False)
    rejected = sorted({u for v in report.violations for u in v.uavs})
    if (out_dir / "plan.html").exists() and (report.model is not None or rejected):
        # the page shows the margins just measured, and what the verifier rejects in red
        from uavplan.io.atomic import write_text_atomic
        from uavplan.viz.viewer import viewer_html

        page = viewer_html(read_plan_file(out_dir / "plan.json", plan.scenario.dim), world,
                           rejected=rejected)  # fmt: skip
        write_text_atomic(out_dir / "plan.html", page)
    if report.ok:
        under = " under the execution model" if report.model is not None else ""
        out.print(f"independent verifier: every flown trajectory passes{under} "
                  f"({report.n_segments} segments, kinematic limits included)")  # fmt: skip
        return True
    uavs = rejected
    err.print(
        "[bold red]UNSAFE[/]: the planner called this plan feasible, and the independent "
        f"verifier rejects it ({len(report.violations)} violations, UAVs "
        f"{', '.join(uavs[:12])}{' ...' if len(uavs) > 12 else ''}); do not fly it; "
        f"`uavplan verify {out_dir / 'plan.json'}` lists them"
    )
    for v in report.violations[:5]:
        err.print(f"  {v.kind}: {v.message}", markup=False, highlight=False)
    return False


def _verdict(ok: bool, violations: Any) -> str:
    """A table cell: yes, or NO and the first failed check (+ how many more)."""
    if ok:
        return "yes"
    why = list(dict.fromkeys(str(v).split(":")[0] for v in violations))
    if not why:
        return "NO"
    return f"NO: {why[0]}" + (f" +{len(why) - 1}" if len(why) > 1 else "")


def _flown_cell(r: Any) -> str:
    """A UAV's flight verdict."""
    return _verdict(bool(r.flown_feasible), r.flown_violations or r.violations)


#: How the summary table names the kinds of flight.
_AS = {"smoothed": "dubins", "polyline": "line"}


def _summary(plan: Any, times: tuple[float, float, int], out_dir: Path) -> None:
    """The table and lines after a plan; ``times``: planning and kernel-compilation seconds,
    and the number of runs they cover (the best of several is written)."""
    elapsed, compiled, n_runs = times
    import numpy as np
    from rich import box

    table = Table(
        title=f"{plan.scenario.name} / {plan.algorithm} / seed {plan.seed}",
        box=box.SIMPLE_HEAD,
    )
    for col in ("UAV", "planned", "flown", "as", "cost", "m", "flight s", "cpu s"):
        table.add_column(col, justify="right", no_wrap=True)
    shown = plan.results if len(plan.results) <= 25 else plan.results[:20]
    for r in shown:
        _, ft = r.flown_trajectory()
        table.add_row(
            r.uav_id,
            _verdict(bool(r.feasible), r.violations),
            _flown_cell(r),
            _AS.get(r.flown_kind, r.flown_kind),
            f"{r.cost:.6g}",
            f"{r.length:.1f}",
            f"{ft[-1] - ft[0]:.1f}",
            f"{r.wall_time:.2f}",
        )
    print_table(table)
    if len(shown) < len(plan.results):
        out.print(f"... and {len(plan.results) - len(shown)} more UAVs in plan.json")
    n = len(plan.results)
    fleet = getattr(plan, "fleet", None)
    if fleet is not None:
        n_bad = sum(not r.feasible for r in plan.results)
        verdict = (
            "polylines feasible (UAV separation included)"
            if fleet.planned_feasible
            else f"{n_bad} UAV polyline(s) infeasible"
        )
        restarts = ", ".join(f"{float(c):.1f}" if np.isfinite(c) else "inf"
                             for c in fleet.restart_costs)  # fmt: skip
        extra = (
            " (each UAV planned against the flights before it, longest first)"
            if fleet.info.get("frame") == "sequential"
            else f", restarts ({restarts}), best restart {fleet.info.get('best_restart')}"
        )
        delayed = fleet.info.get("delayed") or {}
        if delayed:
            extra += f"; {len(delayed)} UAV(s) take off later (up to {max(delayed.values()):g} s)"
        out.print(f"fleet of {n}: cost {fleet.cost:.6g}, {verdict}{extra}", markup=False)
        repair = fleet.info.get("repair") or {}
        if repair:
            out.print(
                f"repaired after planning (--raw skips this): {len(repair)} UAV(s) re-flown "
                "against all the others' flights: "
                + "; ".join(f"{u} ({how})" for u, how in repair.items()),
                markup=False,
            )
        sm = fleet.info.get("smoothing", {})
        if sm:
            out.print(
                f"Dubins-smoothed paths (information only): {len(sm.get('not_clear', []))} of "
                f"{sm.get('checked')} not clear {sm.get('not_clear', [])[:10]}"
            )
    n_ok = sum(bool(r.flown_feasible) for r in plan.results)
    kinds = {k: sum(r.flown_kind == k for r in plan.results) for k in ("smoothed", "polyline")}
    flown = sum(float(np.linalg.norm(np.diff(r.flown_trajectory()[0], axis=0), axis=1).sum())
                for r in plan.results)  # fmt: skip
    planned = sum(r.length for r in plan.results)
    out.print(
        f"flights: {n_ok} of {n} pass every check as flown (Dubins-smoothed {kinds['smoothed']}, "
        f"polylines {kinds['polyline']}); flown length {flown:.1f} m, "
        f"{flown / planned if planned > 0 else 1.0:.3f} x planned"
    )
    terrain = plan.scenario.terrain
    if terrain is not None and terrain.georef.get("voids_filled"):
        from uavplan.world.raster import length_over_voids

        for r in plan.results:
            metres = length_over_voids(terrain, r.flown_trajectory()[0])
            if metres > 0:
                err.print(f"WARNING: {r.uav_id} flies about {metres:,.0f} m over voids (no data) "
                          f"of {terrain.name}; there the ground is unknown and the plan holds "
                          "its band above the highest height on each void's rim, a guess, not "
                          "a measurement", markup=False)  # fmt: skip
    w = plan.work
    did = f"{w['cost_paths']:,} paths costed, {w['checked_segments']:,} segments checked"
    out.print(
        f"wrote {out_dir / 'plan.json'}, {out_dir / 'plan.png'} and {out_dir / 'plan.html'} "
        + (
            f"({did} in {elapsed:.1f} s of planning"
            if n_runs == 1
            else f"(the kept run: {did}; {elapsed:.1f} s of planning for all {n_runs} runs"
        )
        + (f", and {compiled:.1f} s compiling kernels once)" if compiled >= 0.5 else ")")
    )
    if not plan.feasible:
        bad = [r.uav_id for r in plan.results if not r.flown_feasible]
        err.print(
            f"[bold red]NOT FLYABLE[/]: {len(bad)} of {n} UAVs' flown trajectories fail a check "
            f"({', '.join(bad[:10])}{' ...' if len(bad) > 10 else ''}); plan.json says "
            "feasible: false; do not fly this plan"
        )
        err.print(f"why, UAV by UAV: uavplan explain {out_dir}; the planners' searches are "
                  "random, so another --seed is another plan", markup=False)  # fmt: skip
        if plan.planned_feasible and kinds["polyline"] and plan.scenario.uav.turn_radius > 0:
            err.print(
                "the plan declares its planned polylines as the flights (flight=after or none), "
                f"and a UAV with a {plan.scenario.uav.turn_radius:g} m turn radius cannot fly "
                "their corners; the default flight=in-loop plans flights that it can"
            )


def plan(
    scenario: Annotated[
        str,
        typer.Argument(
            help="A scenario file (.yaml/.json) or built-in name; NAME@N: the same world with "
            "a generated fleet of N UAVs."
        ),
    ],
    algorithm: Annotated[
        str | None,
        typer.Option(
            "--algorithm",
            "-a",
            help="Planner name (default: the best for the scenario's kind by our results: "
            "spso for one UAV, 2-D or 3-D; hr-maga with danger or uncertain areas; ppswarm "
            "for a fleet; rscdwoa-apf for a fleet of constant-speed UAVs; for one UAV, when "
            "that plan does not fly, rrt-star and then rgg-pso+ are tried).",
        ),
    ] = None,
    seed: Annotated[int, typer.Option(help="Root random seed.")] = 0,
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")] = Path("out"),
    iterations: Annotated[
        int | None,
        typer.Option(
            help="Iteration budget (default: the planner's own: 200 generations for the "
            "optimizers; RRT*'s is its max_iterations option, `uavplan planners rrt-star`)."
        ),
    ] = None,
    max_time: Annotated[
        float | None,
        typer.Option(
            "--time",
            help="Wall-time budget per UAV's search, seconds (with --iterations: whichever "
            "ends first; alone: no iteration limit, for anytime planners such as rrt-star).",
        ),
    ] = None,
    pop_size: Annotated[int | None, typer.Option(help="Population size.")] = None,
    waypoints: Annotated[int | None, typer.Option(help="Free waypoints per path.")] = None,
    cost: Annotated[str | None, typer.Option(help="Cost preset (default: the scenario's).")] = None,
    param: Annotated[list[str] | None, typer.Option(help="Planner parameter NAME=VALUE.")] = None,
    raw: Annotated[
        bool,
        typer.Option(
            help="Keep the planner's paths as found (no terrain following, no "
            "line-of-sight shortcut, no repair of a fleet's looping or failing UAVs)."
        ),
    ] = False,
    nominal: Annotated[
        bool,
        typer.Option(
            help="Plan for an exact execution (no take-off, speed or tracking error) instead "
            "of the scenario's execution model or uavplan's default (take-off ±2 s, speed "
            "±3 %, tracking 3 m horizontal and 2 m vertical, or the tracking error calibrated "
            "for the UAV's named airframe and the fleet's size when larger)."
        ),
    ] = False,
) -> None:
    """Plan every task of SCENARIO; write OUT/plan.json, OUT/plan.png and OUT/plan.html. A
    single UAV's path is polished unless --raw (the experiments use the raw paths): where its
    flight leaves the altitude band, points are moved or added vertically (terrain following),
    then it is shortened by line of sight; kept when it stays feasible and costs no more, or
    flies where the raw path did not. A fleet's UAVs whose tracks loop or whose flights fail
    are repaired one by one against all the others' flights (loop cut, else RRT* and a later
    take-off), unless --raw."""
    result, times = _run_plan(
        scenario, algorithm, seed, out_dir, iterations, pop_size, waypoints, cost, param or [],
        raw=raw, max_time=max_time, nominal=nominal,
    )  # fmt: skip
    _summary(result, times, out_dir)
    if not result.feasible or not verified_by_the_verifier(result, out_dir):
        raise typer.Exit(1)
    import json

    from uavplan.world.execution import UNCALIBRATED

    stated = json.loads((out_dir / "plan.json").read_text()).get("execution") or {}
    if UNCALIBRATED in str(stated.get("source", "")):
        err.print(
            "NOT GUARANTEED as flown: verified under a tracking error this airframe's "
            "simulated flights leave (the WARNING above); exit 1",
            markup=False,
        )
        raise typer.Exit(1)


def demo(
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")] = Path(
        "uavplan-demo"
    ),
    seed: Annotated[int, typer.Option(help="Root random seed.")] = 0,
    nominal: Annotated[
        bool, typer.Option(help="Plan for an exact execution (see `uavplan plan --help`).")
    ] = False,
) -> None:
    """Plan the built-in SPSO benchmark with the default planner for it (SPSO) at SPSO's budget
    (500 x 200); write OUT/plan.json,
    OUT/plan.png (the figure) and OUT/plan.html (open it in a browser), and print a summary."""
    result, times = _run_plan("spso", None, seed, out_dir, 200, 500, None, None, [],
                              nominal=nominal)  # fmt: skip
    _summary(result, times, out_dir)
    if not result.feasible or not verified_by_the_verifier(result, out_dir):
        raise typer.Exit(1)
