"""Run kinds: how one run of a plan is executed, by name (a plan's ``kind``).

Built in: ``planner`` (a single-UAV planner), ``function`` (an optimizer on a benchmark
function), ``fleet`` (a fleet planner, its plan checked by the independent verifier),
``simulate`` (a plan's missions flown in simulation, :mod:`uavplan.bench.simulation`). A paper
whose runs need something else registers its own kind with :func:`register_kind` in its module
under :mod:`uavplan.bench.papers`. A kind takes the :class:`~uavplan.bench.plans.RunSpec` and
returns the run's metrics (the columns of its row).

**The verifier as a gate.** Every kind that plans paths runs the independent verifier
(:mod:`uavplan.verify`, which imports no planning code) in the worker on every trajectory the
run calls feasible, and records the verdict with :func:`gate`: ``verifier_ok`` (True: all of
them pass; False: the verifier rejects one; None: the run calls nothing feasible),
``verifier_rejects`` (the first violations of a rejected one) and ``band_paper_criterion``
(polylines feasible under the papers' altitude criterion, the band at the waypoints, that the
verifier's band check along whole segments fails). ``tests/bench/test_plans.py`` asserts
``verifier_ok`` on every smoke run that calls a plan feasible; the report counts them.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from uavplan.bench.plans import PlanError, RunSpec

RunKind = Callable[[RunSpec], dict[str, Any]]
_KINDS: dict[str, RunKind] = {}


def register_kind(name: str) -> Callable[[RunKind], RunKind]:
    """Decorator: register a run kind under ``name``."""

    def add(fn: RunKind) -> RunKind:
        if name in _KINDS and _KINDS[name] is not fn:
            raise PlanError(f"run kind {name!r} is already registered")
        _KINDS[name] = fn
        return fn

    return add


def run_kind(name: str) -> RunKind:
    """The run kind registered under ``name`` (the paper modules' kinds too: a worker process
    imports them here, on its first run of a kind it does not know)."""
    if name not in _KINDS:
        # the papers' kinds, and "simulate"
        import uavplan.bench.papers
        import uavplan.bench.simulation  # noqa: F401
    try:
        return _KINDS[name]
    except KeyError:
        raise PlanError(f"unknown run kind {name!r}; registered: {sorted(_KINDS)}") from None


def kinds() -> list[str]:
    return sorted(_KINDS)


@functools.lru_cache(maxsize=16)
def _scenario(ref: str) -> Any:
    from uavplan.scenarios import resolve

    return resolve(ref)


def _budget(params: Any) -> Any:
    from uavplan.optimizers import Budget

    if params.get("evaluations"):
        return Budget(max_evaluations=int(params["evaluations"]))
    return Budget(max_iterations=int(params["iterations"]))


@register_kind("planner")
def run_planner(spec: RunSpec) -> dict[str, Any]:
    """A single-UAV planner on the scenario's first task (feasibility tracked)."""
    scenario = _scenario(spec.scenario)
    return planner_row(plan_run(spec), scenario)


def plan_run(spec: RunSpec) -> Any:
    """The :class:`~uavplan.planners.PlanResult` of a planner run (feasibility tracked)."""
    from uavplan.planners import get_planner

    p = spec.params
    planner = get_planner(p["planner"], **dict(p["options"]))
    if "track_feasibility" in planner.option_names():
        planner = get_planner(p["planner"], track_feasibility=True, **dict(p["options"]))
    return planner.plan(_scenario(spec.scenario), None, _budget(p), spec.seed)


#: A claim the verifier judged: (what, its report, whether it was called feasible under the
#: papers' altitude criterion: a polyline whose band a planner checks at its waypoints only).
Claim = tuple[str, Any, bool]


def gate(claims: list[Claim]) -> dict[str, Any]:
    """The gate's columns from the verifier's reports on what a run calls feasible:

    * ``verifier_ok``: True when every claim passes the verifier, False when it rejects one,
      None when the run calls nothing feasible;
    * ``verifier_rejects``: the first violations of the rejected claims;
    * ``band_paper_criterion``: how many polylines called feasible under the papers' altitude
      criterion (the band checked at the waypoints, heights read as the paper reads them:
      PPSwarm Eq. 7, SPSO's nearest DEM cell; ``docs/decisions.md``) the verifier's band check
      fails (along whole segments on the bilinear DEM). Such a polyline is counted, not
      rejected, for the band alone: it is the criterion the papers' results are compared under;
      every other check of it is gated, and the trajectory that is flown is gated on all of
      them, the band along whole segments included.
    """
    notes: list[str] = []
    rejected = band = 0
    for what, rep, paper_band in claims:
        hard = [v for v in rep.violations if not (paper_band and v.kind == "altitude")]
        band += len(hard) < len(rep.violations)
        rejected += bool(hard)
        notes += [f"{what}: {v.kind}: {v.message}" for v in hard]
    return {
        "verifier_ok": None if not claims else not rejected,
        "verifier_rejects": "; ".join(notes[:3]),
        "band_paper_criterion": band,
    }


def result_claims(
    r: Any, scenario: Any, prefix: str = "", flown: bool = True, paper_band: bool = True
) -> list[Claim]:
    """The verifier on what a single-UAV :class:`~uavplan.planners.PlanResult` calls feasible:
    its planned polyline (a geometric path: clearances, bounds, maximum speed; its band judged
    by the papers' criterion unless ``paper_band`` is False, see :func:`gate`) and the
    trajectory it is to fly (kinematic limits too, the band along whole segments, as ``uavplan
    plan`` checks before it exits 0; unless ``flown`` is False), each if the result claims it."""
    from uavplan.verify import Trajectory, verify_trajectories

    claims: list[Claim] = []
    if r.feasible:
        line = Trajectory(r.uav_id, np.asarray(r.waypoints), np.asarray(r.times), True)
        rep = verify_trajectories([line], scenario, kinematics=False)
        claims.append((f"{prefix}planned", rep, paper_band))
    if flown and r.flown_feasible:
        pts, ts = r.flown_trajectory()
        fly = Trajectory(r.uav_id, np.asarray(pts), np.asarray(ts), True)
        claims.append((f"{prefix}flown", verify_trajectories([fly], scenario), False))
    return claims


def planner_row(r: Any, scenario: Any) -> dict[str, Any]:
    """The row of a single-UAV planner run, the verifier's verdict on it included."""
    return {
        "best_cost": r.cost,
        "path_length": r.length,
        "feasible": r.feasible,
        "first_feasible_iteration": r.first_feasible_iteration,
        "evaluations": r.evaluations,
        "iterations": r.iterations,
        "history": np.asarray(r.history),
        "evaluations_history": np.asarray(r.evaluations_history, dtype=np.float64),
        "feasible_history": np.asarray(r.feasible_history),
        "violations": ",".join(r.violations),
        "waypoints": np.asarray(r.waypoints).ravel().tolist(),
        "reference_length": scenario.metadata.get("reference_length"),
        "n_dim": int(np.asarray(r.waypoints).shape[1]),
        **gate(result_claims(r, scenario)),
    }


@register_kind("function")
def run_function(spec: RunSpec) -> dict[str, Any]:
    """An optimizer on a benchmark function (:mod:`uavplan.optimizers.functions`)."""
    from uavplan.optimizers import minimize
    from uavplan.optimizers.functions import function_problem

    p = spec.params
    problem = function_problem(spec.scenario, noise_seed=spec.seed)
    r = minimize(problem, p["planner"], _budget(p), spec.seed, **dict(p["options"]))
    return {
        "best_cost": r.f,
        "path_length": None,
        "feasible": True,
        "first_feasible_iteration": 1,
        "evaluations": r.evaluations,
        "iterations": r.iterations,
        "history": np.asarray(r.history),
        "evaluations_history": np.asarray(r.evaluations_history, dtype=np.float64),
    }


def fleet_scenario(ref: str) -> Any:
    """A fleet scenario reference: a built-in name or file, optionally ``@N`` for the same world
    with a generated fleet of N UAVs (:func:`uavplan.scenarios.resolve`)."""
    return _scenario(ref)


@register_kind("fleet")
def run_fleet(spec: RunSpec) -> dict[str, Any]:
    """A fleet planner run, its plan checked by the independent verifier
    (:mod:`uavplan.verify`): the planned polylines as geometric paths where they were planned
    apart (PPSwarm's criterion and mode: ``feasible``, ``verified``; None in-loop), the flown
    trajectories with the kinematic limits (the plan's guarantee: ``flown_feasible``,
    ``flown_verified``) and informative smoothed paths if any."""
    from uavplan.io.plan_file import plan_document
    from uavplan.planners import get_planner
    from uavplan.planners.fleet.fleet_plan import FleetPlan
    from uavplan.verify import verify_plan

    p = spec.params
    scenario = fleet_scenario(spec.scenario)
    planner = get_planner(p["planner"], **dict(p["options"]))
    budget = int(p["iterations"]) if p.get("iterations") else None
    fr = planner.plan_fleet(scenario, budget, spec.seed)  # type: ignore[attr-defined]
    plan = FleetPlan(scenario, planner.name, planner.describe(), spec.seed, fr.results, fr)
    d = plan_document(plan)
    # the polylines are checked against each other only where they were planned apart (the
    # paper's mode); in-loop each UAV was kept apart from the others' flights, not polylines
    polylines = fr.info.get("separated", "polylines") == "polylines"
    rep = verify_plan(d, scenario, trajectory="planned") if polylines else None
    rep_f = verify_plan(d, scenario, trajectory="flown")
    smoothed = all(r.smoothed is not None for r in fr.results)
    rep_s = verify_plan(d, scenario, smoothed=True) if smoothed else None
    # the claims: the polylines (together where they were planned apart; else each alone,
    # kept apart only from the others' flights), and the flown fleet it guarantees
    claims: list[Claim] = []
    if fr.planned_feasible:
        if rep is not None:
            claims.append(("planned", rep, False))  # the engine checks the band along segments
        else:
            for r in fr.results:
                # the engine checks the band along whole segments (strict_altitude)
                claims += result_claims(r, scenario, f"{r.uav_id} ", flown=False, paper_band=False)
    claims += [("flown", rep_f, False)] if fr.flown_feasible else []
    flown_length = 0.0
    for r in fr.results:
        pts, _ = r.flown_trajectory()
        flown_length += float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    return {
        "best_cost": fr.cost,
        "path_length": float(sum(r.length for r in fr.results)),
        "feasible": fr.planned_feasible,
        "first_feasible_iteration": None,
        "evaluations": int(fr.info.get("evaluations", 0)),
        "iterations": len(fr.history),
        "history": np.asarray(fr.history),
        "restart_costs": np.asarray(fr.restart_costs),
        "n_uavs": len(fr.results),
        "n_infeasible": int(sum(not r.feasible for r in fr.results)),
        "verified": None if rep is None else bool(rep.ok),
        "verify_violations": None if rep is None else len(rep.violations),
        "min_separation": None if rep is None else float(rep.min_separation),
        "flown_feasible": bool(fr.flown_feasible),
        "flown_verified": bool(rep_f.ok),
        "flown_violations": len(rep_f.violations),
        "flown_not_ok": int(sum(not r.flown_feasible for r in fr.results)),
        "flown_smoothed": int(sum(r.flown_kind == "smoothed" for r in fr.results)),
        "flown_length": flown_length,
        "flown_min_separation": float(rep_f.min_separation),
        "n_delayed": len(fr.info.get("delayed") or {}),
        **{f"rescue_{k}": int(v) for k, v in fr.info.get("flights", {}).get("rescue", {}).items()},
        "smoothed_verified": None if rep_s is None else bool(rep_s.ok),
        "smoothed_violations": None if rep_s is None else len(rep_s.violations),
        "smoothed_not_clear": int(sum(r.smoothed_ok is False for r in fr.results)),
        "rrt_time": float(fr.info.get("rrt_time", 0.0)),
        "planner_wall_time": float(fr.wall_time),
        **gate(claims),
    }
