"""``uavplan simulate PLAN [SCENARIO] --runs N``: the plan's exported missions flown many times
through the batched flight model in sampled wind, turbulence and navigation error, every run's
tracks checked by the independent verifier (:mod:`uavplan.bench.simulation`, on the
experiment runner: local processes or Dask, resumable)."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Annotated, Any

import typer

from uavplan.cli._common import err, fail, load_world, out


def _identity(plan_file: Path, options: dict[str, Any]) -> str:
    """A short hash of the plan's bytes and the options: runs of another plan or other
    conditions never resume into these."""
    h = hashlib.sha256(plan_file.read_bytes())
    h.update(json.dumps(options, sort_keys=True).encode())
    return h.hexdigest()[:10]


def simulate(
    plan_file: Annotated[Path, typer.Argument(help="A plan.json (or its folder).")],
    scenario: Annotated[
        str | None, typer.Argument(help="The scenario it flies in [the plan's own].")
    ] = None,
    runs: Annotated[int, typer.Option(help="Simulated executions.")] = 100,
    wind: Annotated[
        float, typer.Option(help="Steady wind, m/s: each run's is uniform up to it.")
    ] = 3.0,
    turbulence: Annotated[
        str, typer.Option(help="Dryden turbulence: none, light, moderate or severe.")
    ] = "light",
    takeoff: Annotated[
        float | None,
        typer.Option(help="Take-off error, s (uniform within ±it) [the plan's execution model]."),
    ] = None,
    airframe: Annotated[
        str | None,
        typer.Option(help="Airframe [the scenario UAV's: uav.airframe, else by its limits]."),
    ] = None,
    max_items: Annotated[int, typer.Option(help="Most items per mission (as export).")] = 500,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Results folder [PLANDIR/simulate-HASH].")
    ] = None,
    workers: Annotated[int | None, typer.Option(help="Worker processes [all cores].")] = None,
    executor: Annotated[str, typer.Option(help="process, serial or dask.")] = "process",
    scheduler: Annotated[str | None, typer.Option(help="A Dask scheduler's address.")] = None,
    seed: Annotated[int, typer.Option(help="Root seed of the runs' conditions.")] = 0,
) -> None:
    """Fly PLAN's exported missions RUNS times in simulation (take-off errors, a steady wind,
    Dryden turbulence, navigation error drawn per run; an autopilot's guidance through a
    point-mass airframe) and check every run's tracks with the independent verifier. Prints the
    probability of a violation with its Wilson 95 % interval, the tracking and timing errors
    and the worst pair; writes the runs (Parquet), simulate.json and simulate.png into the
    results folder. Runs already in the folder are kept (the same command resumes). Exit 0: no
    run violated; 1: some did (UNSAFE as flown); 2: bad input."""
    from uavplan.bench.runner import SweepInterrupted, SweepStopped, run_sweep
    from uavplan.bench.simulation import simulation_plan, summarize
    from uavplan.io.plan_file import PlanFormatError, plan_path, read_plan_file
    from uavplan.scenarios import builtin_names
    from uavplan.sim.turbulence import INTENSITIES
    from uavplan.world.airframes import AIRFRAMES, airframe_of

    if runs < 1:
        raise fail(f"--runs {runs}: at least 1")
    if turbulence not in INTENSITIES:
        raise fail(f"--turbulence {turbulence!r}: choose from {', '.join(INTENSITIES)}")
    if not (math.isfinite(wind) and 0 <= wind <= 50):
        raise fail(f"--wind {wind}: from 0 to 50 m/s")
    if takeoff is not None and not (math.isfinite(takeoff) and 0 <= takeoff <= 600):
        raise fail(f"--takeoff {takeoff}: from 0 to 600 s")
    if airframe is not None and airframe not in AIRFRAMES:
        raise fail(f"--airframe {airframe!r}: choose from {', '.join(sorted(AIRFRAMES))}")
    if not 3 <= max_items <= 100_000:
        raise fail(f"--max-items {max_items}: from 3 to 100,000")
    try:
        shown = plan_path(plan_file)
        plan = read_plan_file(plan_file)
    except PlanFormatError as exc:
        raise fail(exc.problems[0]) from None
    ref = scenario or plan.scenario
    if not ref:
        raise fail(f"{shown}: the plan names no scenario; give one: uavplan simulate "
                   f"{plan_file} SCENARIO")  # fmt: skip
    world = load_world(ref)
    assert world is not None
    if world.dim != 3 or plan.dim != 3:
        raise fail(f"{shown}: simulation flies 3-D plans (this one is {plan.dim}-D)")
    if Path(ref).is_file() and ref not in builtin_names():  # as resolve() reads it
        ref = str(Path(ref).resolve())
    af = AIRFRAMES[airframe] if airframe else airframe_of(world.uav)
    options = {"wind_max": wind, "turbulence": turbulence, "takeoff_s": takeoff,
               "airframe": af.name, "max_items": max_items}  # fmt: skip
    ident = _identity(shown, {**options, "scenario": ref, "seed": seed})
    folder = out_dir or shown.parent / f"simulate-{ident}"
    sweep = simulation_plan(str(shown.resolve()), ref, runs, options, name=f"simulate-{ident}")
    model = dict(plan.execution or {})
    d0 = takeoff if takeoff is not None else float(model.get("takeoff_s", 0.0))
    refused = [u.id for u in plan.uavs
               if (u.flown_feasible if u.flown is not None else u.feasible) is False]  # fmt: skip
    if refused or plan.feasible is False:
        listed = ", ".join(refused[:5]) + (", ..." if len(refused) > 5 else "")
        err.print(f"NOT FLYABLE as planned: {shown} says {len(refused)} of {len(plan.uavs)} "
                  f"UAVs' flights fail a check ({listed or 'the plan is infeasible'}); "
                  "simulated all the same, to see how it would fly (exit 1 whatever the runs "
                  "show)", markup=False)  # fmt: skip
    out.print(f"{shown}: {len(plan.uavs)} UAV(s), airframe {af.name} ({af.kind}); "
              f"{runs} run(s): take-off ±{d0:g} s, "
              f"wind up to {wind:g} m/s, {turbulence} turbulence, navigation error "
              f"{af.nav_h:g} m / {af.nav_v:g} m", markup=False)  # fmt: skip
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[bold]simulate[/bold]"), BarColumn(), MofNCompleteColumn(),
                  TextColumn("{task.fields[info]}"), TimeElapsedColumn(), console=err,
                  transient=False) as bar:  # fmt: skip
        tid = bar.add_task("runs", total=runs, info="")

        def on_progress(pr: Any) -> None:
            eta = f"{pr.eta:,.0f} s left" if pr.eta is not None else ""
            bar.update(tid, total=pr.total, completed=pr.skipped + pr.done,
                       info=f"{pr.failed} failed  {eta}")  # fmt: skip

        try:
            summary = run_sweep(sweep, folder, "smoke", None, None, seed, executor, workers,
                                scheduler, on_progress)  # fmt: skip
        except SweepInterrupted as exc:
            raise fail(str(exc), 130) from None
        except SweepStopped as exc:
            raise fail(f"simulate {shown}: {exc}") from None
        except (OSError, RuntimeError, ValueError) as exc:
            raise fail(f"simulate {shown}: {exc}", 1) from None
    from uavplan.bench.store import ResultStore

    rows: list[dict[str, Any]] = [
        {str(k): v for k, v in r.items()} for r in ResultStore(folder).read().to_dict("records")
    ]
    s = summarize(rows)
    from uavplan.io.atomic import strict_json, write_json_atomic

    doc = {"format": "uavplan.simulate/1", "plan": str(shown), "scenario": ref,
           "airframe": af.record(), "conditions": options, "seed": seed,
           "execution": plan.execution, "summary": s}  # fmt: skip
    write_json_atomic(folder / "simulate.json", strict_json(doc))
    figure = _figure(folder, plan, world, rows, seed, options, af)
    lo, hi = s["wilson95"]
    out.print(f"{s['runs']} run(s) in {summary.wall_time:.1f} s: {s['violated']} with a "
              f"violation; P(violation) = {s['p_violation']:.4g}, Wilson 95 % interval "
              f"[{lo:.4g}, {hi:.4g}]", markup=False)  # fmt: skip
    out.print(f"tracking error: horizontal p95 {s['track_h_p95_median_run']:.2f} m (median run), "
              f"p99 {s['track_h_p99_worst_run']:.2f} m, max {s['track_h_max']:.2f} m (worst run); "
              f"vertical p99 {s['track_v_p99_worst_run']:.2f} m, max {s['track_v_max']:.2f} m; "
              f"timing {s['timing_min']:+.2f} to {s['timing_max']:+.2f} s "
              f"(the plan tolerates {model.get('track_h', 0.0):g} m / "
              f"{model.get('track_v', 0.0):g} m)", markup=False)  # fmt: skip
    if not _nominal(model):
        out.print(f"schedule lag {s['lag_min']:+.2f} to {s['lag_max']:+.2f} s; runs with a UAV "
                  f"outside the plan's execution model: {s['nonconformant_runs']} of "
                  f"{s['runs']}", markup=False)  # fmt: skip
        from uavplan.world.airframes import FLEET_ALPHA

        if s["runs"] and s["nonconformant_runs"] > FLEET_ALPHA * s["runs"]:
            # the default model is fitted so that at most FLEET_ALPHA flights an execution
            # leave it: more runs than that outside it and the model does not describe them
            err.print(f"WARNING: in {s['nonconformant_runs']} of {s['runs']} executions a UAV "
                      "flew outside the plan's execution model (more than the "
                      f"{100 * FLEET_ALPHA:g} % it is stated for): the plan's margins were "
                      "verified for flights these are not; no violation here is what these "
                      "runs found, not what the model guarantees", markup=False)  # fmt: skip
    if s["worst_pair"]:
        out.print(f"closest pair: {s['worst_pair']}, {s['min_separation']:.2f} m apart at "
                  f"t={s['worst_pair_time']:.1f} s (S2 {world.uav.separation_radius:g} m)",
                  markup=False)  # fmt: skip
    out.print(f"wrote {folder / 'simulate.json'} and {figure}", markup=False)
    if s["errors"]:
        err.print(f"{s['errors']} run(s) failed to run (recorded in {folder})")
    if s["violated"]:
        err.print(f"UNSAFE as flown: {s['violated']} of {s['runs']} simulated executions "
                  f"violate ({', '.join(f'{k}: {v}' for k, v in s['violations_by_kind'].items())})",
                  markup=False)  # fmt: skip
        for m in s["first_violations"]:
            err.print(f"  {m}", markup=False, highlight=False)
        if s["violated_conformant"]:
            err.print(f"{s['violated_conformant']} violating run(s) had every UAV inside the "
                      "plan's execution model: the plan's guarantee does not hold as stated",
                      markup=False)  # fmt: skip
        raise typer.Exit(1)
    if s["errors"]:
        raise typer.Exit(1)
    if refused or plan.feasible is False:
        err.print(f"NOT FLYABLE as planned ({listed or 'the plan is infeasible'}): no run "
                  "violated, but the plan's own checks fail", markup=False)  # fmt: skip
        raise typer.Exit(1)


def _nominal(model: dict[str, Any]) -> bool:
    return not any(float(model.get(k) or 0.0)
                   for k in ("takeoff_s", "speed", "track_h", "track_v", "wind"))  # fmt: skip


def _figure(folder: Path, plan: Any, world: Any, rows: list[dict[str, Any]], seed: int,
            options: dict[str, Any], af: Any) -> Path:  # fmt: skip
    """simulate.png: one run's tracking error over time (each UAV's, and their envelope), and
    the first violation of every run that had one, on the map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from uavplan.bench.simulation import conditions_of
    from uavplan.sim.runs import error_window, errors_against, plan_slack, simulate_once

    ex = simulate_once(plan, world, seed, conditions_of(options), af,
                       int(options.get("max_items", 500)))  # fmt: skip
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5))
    planned = plan.trajectories("flown")
    for tr, pl in zip(ex.tracks, planned, strict=True):
        window = error_window(pl, abs(ex.takeoff_errors[tr.id]), float(np.linalg.norm(ex.wind)),
                              float(world.uav.speed))  # fmt: skip
        h, _, _ = errors_against(tr, pl, window, plan_slack(pl, world, plan.execution))
        a1.plot(tr.times, h, lw=0.6, alpha=0.6)
    rec = dict(plan.execution or {})
    if rec.get("track_h"):
        a1.axhline(float(rec["track_h"]), color="k", ls="--", lw=1,
                   label=f"the plan's horizontal tracking error, {rec['track_h']:g} m")  # fmt: skip
        a1.legend(loc="upper right")
    a1.set_xlabel("t (s)")
    a1.set_ylabel("horizontal distance from the verified path (m)")
    a1.set_title("one simulated execution: tracking error of each UAV")
    lo, hi = world.bounds.lower, world.bounds.upper
    for tr in planned:
        a2.plot(tr.points[:, 0], tr.points[:, 1], color="0.75", lw=0.5)
    for c in world.cylinders:
        a2.add_patch(plt.Circle(c.center, c.radius, color="tab:red", alpha=0.3))
    pts = np.array([(r["violation_x"], r["violation_y"]) for r in rows
                    if r.get("violated") and r.get("violation_x") is not None])  # fmt: skip
    if len(pts):
        a2.scatter(pts[:, 0], pts[:, 1], s=12, color="tab:red", marker="x",
                   label=f"first violation of a run ({len(pts)})")  # fmt: skip
        a2.legend(loc="upper right")
    a2.set_xlim(lo[0], hi[0])
    a2.set_ylim(lo[1], hi[1])
    a2.set_aspect("equal")
    where = "where they violated" if len(pts) else "none violated"
    a2.set_title(f"{len(rows)} runs: {where} (planned paths in grey)")
    fig.tight_layout()
    path = folder / "simulate.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
