"""Simulated executions of a plan as a sweep: the run kind ``simulate`` (one execution of the
plan's exported missions through the batched flight model, :mod:`uavplan.sim.runs`, its tracks
checked by the independent verifier), the plan of such runs that ``uavplan simulate`` hands to
the experiment runner (local processes or Dask, resumable), and the summary of the rows: the
probability of a violation with its Wilson 95 % interval, the tracking and timing errors, the
worst pair.

Safety is what the verifier says of the flown tracks: separation, obstacles, terrain, the
altitude band, the bounds and moving obstacles. The speed range is not among them: a track's
ground speed in wind is not the airspeed the UAV's limits are about (the model keeps its
airspeed within them).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from uavplan.bench.kinds import register_kind
from uavplan.bench.plans import Algorithm, ExperimentPlan, RunSpec, Scale

#: What the verifier checks that is not safety of the flown tracks (see the module docstring).
NOT_SAFETY = frozenset({"speed", "climb", "turn"})


@functools.lru_cache(maxsize=4)
def _plan_file(path: str) -> Any:
    from uavplan.io.plan_file import read_plan_file

    return read_plan_file(path)


@functools.lru_cache(maxsize=4)
def _scenario(ref: str) -> Any:
    from uavplan.scenarios import resolve

    return resolve(ref)


def conditions_of(params: Mapping[str, Any]) -> Any:
    from uavplan.sim.runs import Conditions

    return Conditions(
        wind_max=float(params.get("wind_max", 3.0)),
        turbulence=str(params.get("turbulence", "light")),
        takeoff_s=None if params.get("takeoff_s") is None else float(params["takeoff_s"]),
        nav=bool(params.get("nav", True)),
    )


def _q(a: np.ndarray, q: float) -> float:
    return float(np.percentile(a, q)) if a.size else math.nan


@register_kind("simulate")
def run_simulation(spec: RunSpec) -> dict[str, Any]:
    """One simulated execution (``spec.params["options"]``: ``plan_file``, the conditions,
    ``airframe``, ``max_items``); its row: the verdict, the worst pair, the errors."""
    from uavplan.sim.runs import simulate_once
    from uavplan.verify import verify_trajectories
    from uavplan.world.airframes import AIRFRAMES

    opts = dict(spec.params.get("options", {}))
    plan = _plan_file(str(opts["plan_file"]))
    scenario = _scenario(spec.scenario)
    airframe = AIRFRAMES[opts["airframe"]] if opts.get("airframe") else None
    ex = simulate_once(plan, scenario, spec.seed, conditions_of(opts), airframe,
                       int(opts.get("max_items", 500)))  # fmt: skip
    rep = verify_trajectories(ex.tracks, scenario, kinematics=False)
    bad = [v for v in rep.violations if v.kind not in NOT_SAFETY]
    first = bad[0] if bad else None
    pairs = sorted({v.uavs for v in bad if v.kind == "separation"})
    te = ex.samples_t
    return {
        "violated": bool(bad),
        "n_violations": len(bad),
        "kinds": ",".join(sorted({v.kind for v in bad})),
        "uavs_violating": len({u for v in bad for u in v.uavs}),
        "pairs_violating": len(pairs),
        "first_violation": first.message if first else None,
        "violation_x": float(first.where[0][0]) if first and first.where else None,
        "violation_y": float(first.where[0][1]) if first and first.where else None,
        "violation_t": float(first.time) if first and first.time is not None else None,
        "min_separation": float(rep.min_separation),
        "min_separation_pair": "/".join(rep.min_separation_pair or ()) or None,
        "min_separation_time": rep.min_separation_time,
        "wind": float(np.linalg.norm(ex.wind)),
        "uavs": len(ex.tracks),
        "finished": ex.finished,
        "track_h_p50": _q(ex.samples_h, 50),
        "track_h_p95": _q(ex.samples_h, 95),
        "track_h_p99": _q(ex.samples_h, 99),
        "track_h_max": float(ex.samples_h.max()) if ex.samples_h.size else math.nan,
        "track_v_p95": _q(np.abs(ex.samples_v), 95),
        "track_v_p99": _q(np.abs(ex.samples_v), 99),
        "track_v_max": float(np.abs(ex.samples_v).max()) if ex.samples_v.size else math.nan,
        "timing_min": float(te.min()) if te.size else math.nan,
        "timing_p01": _q(te, 1),
        "timing_p99": _q(te, 99),
        "timing_max": float(te.max()) if te.size else math.nan,
        "lag_min": min((lo for lo, _ in ex.lag.values()), default=math.nan),
        "lag_max": max((hi for _, hi in ex.lag.values()), default=math.nan),
        "nonconformant": sum(1 for e in ex.excess.values() if e > 0),
        "excess_max": max(ex.excess.values(), default=math.nan),
        "mission_items_max": max(ex.items.values(), default=0),
    }


def simulation_plan(
    plan_file: str,
    scenario: str,
    runs: int,
    options: Mapping[str, Any],
    name: str = "simulate",
) -> ExperimentPlan:
    """The sweep of ``runs`` simulated executions of ``plan_file`` in ``scenario``."""
    opts = {**options, "plan_file": str(plan_file)}
    scale = Scale(runs=runs, iterations=0)
    return ExperimentPlan(
        name=name,
        description=f"{runs} simulated executions of {plan_file}",
        scenarios=(scenario,),
        algorithms=(Algorithm("sim", "-", opts),),
        scales={"smoke": scale, "paper": scale},
        kind="simulate",
        metric="violated",
    )


def wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``k / n`` (95 % by default)."""
    if n <= 0:
        return 0.0, 1.0
    p = k / n
    d = 1.0 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    # the bounds are exactly 0 (1) when k = 0 (n); c - h leaves round-off there
    return (0.0 if k == 0 else max(0.0, c - h)), (1.0 if k == n else min(1.0, c + h))


def summarize(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """What the runs say together: runs, violations, P with its Wilson interval, the error
    quantiles (over the runs' own quantiles: the median run's and the worst run's), the worst
    pair (closest approach over all runs)."""
    ok = [r for r in rows if r.get("status", "ok") == "ok"]
    n = len(ok)
    k = sum(bool(r["violated"]) for r in ok)
    lo, hi = wilson(k, n)
    worst = min(ok, key=lambda r: r["min_separation"], default=None)

    def col(name: str) -> np.ndarray:
        return np.asarray([r[name] for r in ok if r.get(name) is not None], dtype=np.float64)

    kinds: dict[str, int] = {}
    for r in ok:
        for kk in filter(None, str(r.get("kinds") or "").split(",")):
            kinds[kk] = kinds.get(kk, 0) + 1
    return {
        "runs": n,
        "errors": len(rows) - n,
        "violated": k,
        "p_violation": k / n if n else math.nan,
        "wilson95": [lo, hi],
        "violations_by_kind": kinds,
        "track_h_p95_median_run": _q(col("track_h_p95"), 50),
        "track_h_p99_worst_run": float(col("track_h_p99").max()) if n else math.nan,
        "track_h_max": float(col("track_h_max").max()) if n else math.nan,
        "track_v_p99_worst_run": float(col("track_v_p99").max()) if n else math.nan,
        "track_v_max": float(col("track_v_max").max()) if n else math.nan,
        "timing_min": float(col("timing_min").min()) if n else math.nan,
        "timing_max": float(col("timing_max").max()) if n else math.nan,
        "lag_min": float(col("lag_min").min()) if col("lag_min").size else math.nan,
        "lag_max": float(col("lag_max").max()) if col("lag_max").size else math.nan,
        "nonconformant_runs": sum(1 for r in ok if (r.get("nonconformant") or 0) > 0),
        "violated_conformant": sum(1 for r in ok if r["violated"] and r.get("nonconformant") == 0),
        "min_separation": float(worst["min_separation"]) if worst else math.nan,
        "worst_pair": worst["min_separation_pair"] if worst else None,
        "worst_pair_time": worst["min_separation_time"] if worst else None,
        "first_violations": [r["first_violation"] for r in ok if r["violated"]][:5],
    }
