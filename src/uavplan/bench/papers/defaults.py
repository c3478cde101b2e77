"""Not a paper's: what a user gets from ``uavplan plan NAME`` without ``-a``, as experiments.
The run kind ``strategy`` does what the command does (:mod:`uavplan.strategy`: the world under
uavplan's default execution model, the strategy for the scenario's kind with its runs, other
planners, repair and fallbacks) and then what the command's gate does: the independent
verifier on the flown trajectories, against the scenario as given, under the plan's model.
A planner named instead of ``default`` runs alone, as ``-a NAME`` does.

* ``default-paths``: the default on every built-in scenario: feasible and verified as flown,
  tracks crossing themselves, fallbacks and the planner kept.
* ``default-rivals``: on the 3-D single-UAV built-ins, the default beside the planners a user
  could name (SPSO, RGG-PSO+, HR-MAGA, RRT*, each with the command's defaults): the default's
  length over the shortest flying path any run reached, and its cost over the best.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from uavplan._lazy import lazy_module
from uavplan.bench.kinds import register_kind
from uavplan.bench.plans import (
    Algorithm,
    ExperimentPlan,
    ReportSections,
    RunSpec,
    Scale,
    register_plan,
)

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")

#: The built-in scenarios with one UAV (``default-rivals``).
SINGLE = ("simple2d", "spso", "jacksboro", "luxembourg", "topobathy", "hrmaga-jacksboro",
          "hrmaga-popup", "hrmaga-spso", "hrmaga-topobathy", "hrmaga-virtual")  # fmt: skip
#: The built-in fleets (``default-paths`` runs these too).
FLEETS = ("ppswarm1", "ppswarm2", "ppswarm3", "ppswarm4", "ppswarm1-traffic", "dense", "open",
          "quadrotors", "rscdwoa-static", "rscdwoa-mixed")  # fmt: skip
RIVALS = ("spso", "rgg-pso+", "hr-maga", "rrt-star")


@register_kind("strategy")
def run_strategy(spec: RunSpec) -> dict[str, Any]:
    """``uavplan plan`` as a run: the default strategy (planner ``default``) or the named
    planner alone, in the world under uavplan's default execution model, then the verifier on
    the flown trajectories (the scenario as given, the plan's model)."""
    from uavplan.io.plan_file import plan_document
    from uavplan.scenarios import resolve
    from uavplan.strategy import chosen, execute, planning_world, strategy_for
    from uavplan.verify import verify_plan
    from uavplan.world.geometry import track_crosses_itself

    p = spec.params
    given = resolve(spec.scenario)
    pw = planning_world(given, spec.scenario)
    given = pw.given or given  # a generated fleet placed again in the widened world
    options = dict(p["options"])
    if p["planner"] == "default":
        strategy = strategy_for(pw.world).with_options(options)
        if options:
            strategy = strategy.plain()
    else:
        strategy = chosen(p["planner"], options)
    budget = int(p["iterations"]) if p.get("iterations") else None
    t0 = time.perf_counter()
    outcome = execute(strategy, pw.world, budget, spec.seed)
    wall = time.perf_counter() - t0
    plan = outcome.plan
    rep = verify_plan(plan_document(plan), given)  # under the model the plan states
    flown = [r.flown_trajectory()[0] for r in plan.results]
    cost = float(sum(r.cost for r in plan.results))
    return {
        "best_cost": cost,
        "path_length": float(sum(r.length for r in plan.results)),
        "flown_length": float(sum(np.linalg.norm(np.diff(P, axis=0), axis=1).sum() for P in flown)),
        "feasible": bool(plan.planned_feasible),
        "first_feasible_iteration": None,
        "evaluations": int(sum(int(r.evaluations) for r in plan.results)),
        "flown_feasible": bool(plan.feasible),
        "flown_verified": bool(rep.ok),
        "flown_violations": len(rep.violations),
        "n_uavs": len(plan.results),
        "loops": int(sum(track_crosses_itself(np.asarray(r.waypoints)) for r in plan.results)),
        "kept": plan.algorithm,
        "attempts": len(outcome.attempts),
        "fallback": outcome.attempts[outcome.kept].role == "fallback",
        "planner_wall_time": wall,
        "verifier_ok": bool(rep.ok) if plan.feasible else None,
        "verifier_rejects": "; ".join(f"{v.kind}: {v.message}" for v in rep.violations[:3])
        if plan.feasible
        else "",
    }


def paths_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per scenario and planner: runs, flown feasible and verified, flown feasible but rejected
    (must be 0), runs with a track crossing itself, fallbacks, the planners kept, the median
    planning time."""
    rows = []
    for (sc, alg), g in df.groupby(["scenario", "algorithm"]):
        ok = g[g["status"] == "ok"]
        row: dict[str, Any] = {"scenario": sc, "planner": alg, "runs": len(g),
                               "ok_runs": len(ok)}  # fmt: skip
        if len(ok):
            ff = ok["flown_feasible"].astype(bool)
            fv = ok["flown_verified"].astype(bool)
            row.update(
                flown_feasible=int(ff.sum()),
                verified=int(fv.sum()),
                feasible_but_rejected=int((ff & ~fv).sum()),
                loops=int((ok["loops"].astype(int) > 0).sum()),
                fallbacks=int(ok["fallback"].astype(bool).sum()),
                kept=", ".join(sorted(set(ok["kept"].astype(str)))),
                plan_s=float(ok["planner_wall_time"].astype(float).median()),
            )
        else:
            row["error"] = str(g["error"].iloc[0])[:160]
        rows.append(row)
    out = pd.DataFrame(rows)
    return out if out.empty else out.set_index(["scenario", "planner"])


def rivals_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per scenario: the default's flying runs, the median and worst of its length over the
    shortest flying path any run reached and of its cost over the best cost any run reached,
    and which planner reached each."""
    rows = []
    ok = df[(df["status"] == "ok") & df["flown_feasible"].astype(bool)]
    for sc, g in ok.groupby("scenario"):
        mine = g[g["algorithm"] == "default"]
        n = int((df[(df["scenario"] == sc) & (df["algorithm"] == "default")]).shape[0])
        row: dict[str, Any] = {"scenario": sc, "default_flies": f"{len(mine)}/{n}"}
        if len(mine):
            short = g.iloc[int(np.argmin(g["path_length"].astype(float).to_numpy()))]
            best = g.iloc[int(np.argmin(g["best_cost"].astype(float).to_numpy()))]
            to_short = mine["path_length"].astype(float) / float(short["path_length"])
            to_best = mine["best_cost"].astype(float) / float(best["best_cost"])
            row.update(
                len_over_shortest_median=float(to_short.median()),
                len_over_shortest_worst=float(to_short.max()),
                cost_over_best_median=float(to_best.median()),
                cost_over_best_worst=float(to_best.max()),
                shortest_by=str(short["algorithm"]),
                best_by=str(best["algorithm"]),
            )
        rows.append(row)
    out = pd.DataFrame(rows)
    return out if out.empty else out.set_index("scenario")


def sections(df: pd.DataFrame, plan: str) -> ReportSections:
    """(sections, figures) of ``default-paths`` and ``default-rivals``."""
    note = (
        "what `uavplan plan NAME` gives (default: the strategy for the scenario's kind; a "
        "planner's name: that planner alone, as -a NAME), under uavplan's default execution "
        "model; verified = the independent verifier passes every flown trajectory against the "
        "scenario as given under the plan's model; feasible_but_rejected must be 0; loops = "
        "runs with a UAV whose horizontal track crosses itself; fallbacks = runs whose kept "
        "plan came from a fallback planner"
    )
    out = [("What a user gets", note, paths_table(df))]
    if plan == "default-rivals":
        out.append(("The default beside the planners a user could name",
                    "lengths and costs of flying runs only; the references are the shortest "
                    "and the cheapest flying plan any run of any planner reached",
                    rivals_table(df)))  # fmt: skip
    return out, []


register_plan(
    ExperimentPlan(
        name="default-paths",
        description=(
            "What `uavplan plan NAME` gives on every built-in scenario (the default strategy "
            "under the default execution model): flown feasible and verified, loops, fallbacks"
        ),
        scenarios=SINGLE + FLEETS,
        algorithms=(Algorithm("default", "default"),),
        scales={
            "smoke": Scale(runs=1, iterations=10, scenarios=("simple2d", "ppswarm1@3")),
            "paper": Scale(runs=10, iterations=0),
        },
        kind="strategy",
        report=sections,
        reference="default",
    )
)

register_plan(
    ExperimentPlan(
        name="default-rivals",
        description=(
            "The default beside SPSO, RGG-PSO+, HR-MAGA and RRT* as `-a NAME` runs them, on the "
            "single-UAV built-ins: length over the shortest and cost over the best flying plan"
        ),
        scenarios=tuple(n for n in SINGLE if n != "simple2d"),  # HR-MAGA plans 3-D only
        algorithms=(Algorithm("default", "default"), *(Algorithm(n, n) for n in RIVALS)),
        scales={
            "smoke": Scale(runs=1, iterations=10, scenarios=("spso",)),
            "paper": Scale(runs=3, iterations=0),
        },
        kind="strategy",
        report=sections,
        reference="default",
    )
)
