"""RSCDWOA (Zhang et al.): the benchmark functions f1-f9 of its Table 4 (30-D, 30 agents, the
evaluations of 100 iterations, 30 runs) against WOA, PSO, GA, DE, GWO and ABC, with Wilcoxon
rank-sum tests (its Table 5) in the generic report; and its multi-UAV application with the
artificial potential field (Sects. 5.3-5.4, Figs. 12-16, Table 3):

* ``rscdwoa-static`` (Fig. 12): APF, WOA-APF, RSCDWOA-APF, PSO-APF and GA-APF fly the four UAVs
  of Table 1 through ``rscdwoa-static``; the pass-through rate (UAVs that reach the target, over
  runs x UAVs) with Wilson 95 % intervals; the paper: 100 % for RSCDWOA-APF, less for WOA-APF,
  the APF caught.
* ``rscdwoa-dynamic`` (Figs. 13-15): the same on ``rscdwoa-mixed`` (three moving obstacles), with
  the least clearance to each moving obstacle over continuous time (flown trajectories), arrival
  times, the least separation between UAVs, curvature before and after the optimizer (the APF's
  flight is "before"), the fitness convergence (Fig. 16); our SPSO and PSO in the prioritized
  frame and PPSwarm as extra rows (RRT* and RGG-PSO+ refuse moving obstacles: their graphs have
  no time).
* ``rscdwoa-table3``: MAE and RMSE per UAV (the paper does not define them; ours: of the
  horizontal distance, in km, from every 1 s sample of the flown trajectory to the shortest
  horizontal path around the static obstacles, a visibility graph on their footprints).

Every run's plan goes through the independent verifier (:mod:`uavplan.verify`) on the flown
trajectories; ``feasible_but_failed`` counts plans called feasible that it rejects (must be 0).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from uavplan._lazy import lazy_module
from uavplan.bench.kinds import gate, register_kind
from uavplan.bench.plans import Algorithm, ExperimentPlan, RunSpec, Scale, register_plan
from uavplan.bench.stats import stack_histories

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")

#: RSCDWOA's Table 5 rivals; the WOA family's schedules (a: 2 -> 0) span 100 iterations
FUNCTION_ALGORITHMS = (
    Algorithm("rscdwoa", "rscdwoa", {"max_iterations": 100}),
    Algorithm("rscdwoa-logistic", "rscdwoa", {"max_iterations": 100, "chaos": "logistic"}),
    Algorithm("woa", "woa", {"max_iterations": 100}),
    Algorithm("pso", "pso"),
    Algorithm("ga", "ga"),
    Algorithm("de", "de"),
    Algorithm("gwo", "gwo", {"max_iterations": 100}),
    Algorithm("abc", "abc"),
)


def _functions_plan(name: str, description: str, smoke: Scale, paper: Scale) -> None:
    register_plan(
        ExperimentPlan(
            name=name,
            description=description,
            scenarios=tuple(f"f{i}" for i in range(1, 10)),
            algorithms=FUNCTION_ALGORITHMS,
            scales={"smoke": smoke, "paper": paper},
            kind="function",
            reference="rscdwoa",
        )
    )


_functions_plan(
    "functions",
    "RSCDWOA (tent map; and the logistic map) vs WOA, PSO, GA, DE, GWO, ABC on f1-f9 of RSCDWOA "
    "Table 4, 30-D, 30 agents, the evaluations of 100 iterations",
    Scale(runs=2, iterations=10, pop_size=30, evaluations=330),
    Scale(runs=30, iterations=100, pop_size=30, evaluations=3030),
)
_functions_plan(
    "functions-iterations",
    "f1-f9 as `functions`, under the RSCDWOA paper's own protocol: 100 iterations of 30 agents "
    "for every algorithm, whatever the evaluations they take",
    Scale(runs=2, iterations=10, pop_size=30),
    Scale(runs=30, iterations=100, pop_size=30),
)


#: RSCDWOA's decisions where the paper is silent or inconsistent, each changed alone
#: (``functions-variants``): the lifespan S (no value in Alg. 1; ours 10), l's range ((0, 1) as
#: Eq. 15 writes w(t); (-1, 1) as Sect. 2.2's WOA), the chaotic draws against plain uniform
#: ones, and WOA beside them; on f1-f9 and on the same functions with the optimum moved off
#: the box's centre (``f1s``-``f9s``), where the reverse search's pull towards the centre
#: gains nothing.
VARIANT_ALGORITHMS = (
    Algorithm("rscdwoa", "rscdwoa", {"max_iterations": 100}),
    Algorithm("rscdwoa-S0", "rscdwoa", {"max_iterations": 100, "S": 0}),
    Algorithm("rscdwoa-S1", "rscdwoa", {"max_iterations": 100, "S": 1}),
    Algorithm("rscdwoa-S3", "rscdwoa", {"max_iterations": 100, "S": 3}),
    Algorithm("rscdwoa-l-symmetric", "rscdwoa", {"max_iterations": 100, "l_range": "symmetric"}),
    Algorithm("rscdwoa-uniform", "rscdwoa", {"max_iterations": 100, "chaos": "uniform"}),
    Algorithm("woa", "woa", {"max_iterations": 100}),
)
for _name, _which, _scenarios in (
    ("functions-variants", "on f1-f9", tuple(f"f{i}" for i in range(1, 10))),
    (
        "functions-shifted",
        "on f1s-f9s (f1-f9 with the optimum moved off the box's centre)",
        tuple(f"f{i}s" for i in range(1, 10)),
    ),
):
    register_plan(
        ExperimentPlan(
            name=_name,
            description="RSCDWOA's undecided choices as variants (lifespan S 0/1/3/10, l in "
            f"(0, 1) or (-1, 1), chaotic or uniform draws) and WOA {_which}, 30-D, 30 agents, "
            "the evaluations of 100 iterations",
            scenarios=_scenarios,
            algorithms=VARIANT_ALGORITHMS,
            scales={"smoke": Scale(runs=2, iterations=10, pop_size=30, evaluations=330),
                    "paper": Scale(runs=30, iterations=100, pop_size=30, evaluations=3030)},
            kind="function",
            reference="rscdwoa",
        )
    )  # fmt: skip


# ---------------------------------------------------------------------- the APF application
APF_FAMILY = ("apf", "woa-apf", "rscdwoa-apf", "pso-apf", "ga-apf")


def reference_path(scenario: Any, task: Any) -> np.ndarray:
    """The shortest horizontal path of ``task`` around the footprints of the static obstacles
    (cylinders as circles; :func:`uavplan.world.visibility.shortest_path`), (k, 2)."""
    from uavplan.world import Bounds, Circle, Scenario, Task
    from uavplan.world.visibility import shortest_path

    flat = Scenario(
        "footprints",
        Bounds(tuple(scenario.bounds.lo[:2]), tuple(scenario.bounds.hi[:2])),
        (Task(task.id, tuple(task.start[:2]), tuple(task.goal[:2])),),
        circles=tuple(Circle(tuple(c.center), c.effective_radius) for c in scenario.cylinders),
        cost="length2d",
    )
    _, path = shortest_path(flat)
    return np.asarray(path, dtype=np.float64)


def deviation(points: np.ndarray, times: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Horizontal distance (m) from the trajectory, sampled every second, to polyline ``ref``."""
    t = np.arange(float(times[0]), float(times[-1]), 1.0)
    xy = np.column_stack([np.interp(t, times, points[:, k]) for k in range(2)])
    a, b = ref[:-1], ref[1:]
    ab = b - a
    L = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    u = np.clip(np.einsum("pkd,kd->pk", xy[:, None, :] - a[None], ab) / L, 0.0, 1.0)
    near = a[None] + u[..., None] * ab[None]
    return np.asarray(np.linalg.norm(xy[:, None, :] - near, axis=2).min(axis=1))


#: samples of the curvature profile along the normalized horizontal arc length (Fig. 14)
PROFILE = 200


def curvature_profile(points: np.ndarray, n: int = PROFILE) -> tuple[list[float], list[float]]:
    """Curvature (1/km) and its derivative along the track (1/km^2) at ``n`` points of the
    normalized horizontal arc length (the largest value in each of ``n`` equal bins, so that a
    sharp turn is not averaged away; 0 where a bin holds no interior point)."""
    from uavplan.planners.potential.apf_fused import curvature

    p = np.asarray(points, dtype=np.float64)[:, :2]
    k = curvature(p) * 1000.0
    if k.size < 2:
        return [0.0] * n, [0.0] * n
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)]) / 1000.0  # km
    si = s[1:-1]
    dk = np.abs(np.gradient(k, si)) if np.all(np.diff(si) > 0) else np.zeros_like(k)
    bins = np.minimum((si / max(s[-1], 1e-12) * n).astype(int), n - 1)
    kp = np.zeros(n)
    dp = np.zeros(n)
    np.maximum.at(kp, bins, k)
    np.maximum.at(dp, bins, dk)
    return kp.tolist(), dp.tolist()


def _curv_stats(points: np.ndarray) -> tuple[float, float]:
    from uavplan.planners.potential.apf_fused import curvature

    k = curvature(points)
    return (
        float(k.max()) * 1000 if k.size else 0.0,
        float(np.abs(np.diff(k)).max()) * 1e6 if k.size > 1 else 0.0,
    )


@register_kind("rscdwoa")
def run_rscdwoa(spec: RunSpec) -> dict[str, Any]:
    """Four UAVs by one planner (the prioritized frame for single-UAV planners, the fleet
    planner's own otherwise), verified as flown; per-UAV figures as lists."""
    from uavplan.io.plan_file import plan_document
    from uavplan.planners import get_planner
    from uavplan.planners.fleet.fleet_plan import plan_all
    from uavplan.scenarios import resolve
    from uavplan.verify import verify_plan

    p = spec.params
    sc = resolve(spec.scenario)
    planner = get_planner(p["planner"], **dict(p["options"]))
    budget = int(p["iterations"]) if p.get("iterations") else None
    plan = plan_all(sc, planner, budget, spec.seed)
    rep = verify_plan(plan_document(plan), sc, trajectory="flown")
    per: dict[str, list[Any]] = {
        k: []
        for k in (
            "uav",
            "arrived",
            "flown_ok",
            "arrival_s",
            "max_curv_km",
            "max_dcurv_km2",
            "mae_km",
            "rmse_km",
            "min_clear_m",
            "curv_profile",
            "dcurv_profile",
            "plan_s",
            "fitness_history",
            "arrived_history",
        )
    }
    for task, r in zip(plan.scenario.tasks, plan.results, strict=True):
        pts, ts = r.flown_trajectory()
        status = r.info.get("status")
        arrived = bool(np.allclose(pts[-1], task.goal)) and status in (None, "arrived")
        dev = deviation(pts, ts, reference_path(sc, task))
        kmax, dkmax = _curv_stats(pts)
        clear = [
            float(o.min_distance(pts[None], ts[None]).min() - o.radius) for o in sc.moving_obstacles
        ]
        per["uav"].append(task.id)
        per["arrived"].append(arrived)
        per["flown_ok"].append(bool(r.flown_feasible))
        per["arrival_s"].append(float(ts[-1] - ts[0]) if arrived else math.nan)
        per["max_curv_km"].append(kmax)
        per["max_dcurv_km2"].append(dkmax)
        per["mae_km"].append(float(np.mean(dev)) / 1000)
        per["rmse_km"].append(float(np.sqrt(np.mean(dev**2))) / 1000)
        per["min_clear_m"].append(min(clear) if clear else math.nan)
        per["plan_s"].append(float(r.wall_time))
        kp, dp = curvature_profile(pts)
        per["curv_profile"].append(kp)
        per["dcurv_profile"].append(dp)
        per["fitness_history"].append(list(r.info.get("fitness_history") or []))
        per["arrived_history"].append(list(r.info.get("arrived_history") or []))
    feasible = bool(plan.feasible)
    return {
        "best_cost": float(sum(r.cost for r in plan.results)),
        "path_length": float(sum(r.length for r in plan.results)),
        "feasible": feasible,
        "first_feasible_iteration": None,
        "evaluations": int(sum(r.evaluations for r in plan.results)),
        "iterations": int(max(r.iterations for r in plan.results)),
        "n_uavs": len(plan.results),
        "n_arrived": int(sum(per["arrived"])),
        "flown_verified": bool(rep.ok),
        "feasible_but_failed": int(feasible and not rep.ok),
        **gate([("flown", rep, False)] if feasible else []),
        "min_separation": float(rep.min_separation),
        **{f"uav_{k}": v for k, v in per.items() if not k.endswith("_history")},
        # per iteration, over the run's UAVs, the share of candidates whose flight arrives
        "arrived_history": [
            float(np.mean(col)) for col in zip(*per["arrived_history"], strict=False)
        ]
        if all(per["arrived_history"])
        else [],
        "fitness_history": [
            float(np.mean(col)) for col in zip(*per["fitness_history"], strict=False)
        ]
        if all(per["fitness_history"])
        else [],
    }


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score interval of ``k`` successes in ``n`` (95 % by default)."""
    if n == 0:
        return (math.nan, math.nan)
    ph = k / n
    den = 1 + z * z / n
    mid = (ph + z * z / (2 * n)) / den
    half = z * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / den
    return (mid - half, mid + half)


def _uav_frame(df: pd.DataFrame) -> pd.DataFrame:
    """One row per UAV of every finished run; a per-UAV column that a run does not have (runs
    made before the column existed) is NaN for its UAVs."""
    ok = df[df["status"] == "ok"]
    rows = []
    for _, r in ok.iterrows():
        cols = {k[4:]: r[k] for k in r.index if k.startswith("uav_") and k != "uav_uav"}
        for i, u in enumerate(r["uav_uav"]):
            per_uav = {k: (v[i] if hasattr(v, "__len__") else np.nan) for k, v in cols.items()}
            rows.append({"algorithm": r["algorithm"], "run": r["run_index"], "uav": u, **per_uav})
    return pd.DataFrame(rows)


def apf_sections(df: pd.DataFrame, plan: str) -> Any:
    import matplotlib.pyplot as plt

    ok = df[df["status"] == "ok"]
    u = _uav_frame(df)
    rows = []
    for alg, g in u.groupby("algorithm", sort=False):
        safe = g["arrived"].astype(bool) & g["flown_ok"].astype(bool)
        k, n = int(safe.sum()), len(g)
        lo, hi = wilson(k, n)
        runs = ok[ok["algorithm"] == alg]
        rows.append(
            {
                "method": alg,
                "runs": len(runs),
                "uav_flights": n,
                "pass_through": k / n if n else math.nan,
                "wilson_lo": lo,
                "wilson_hi": hi,
                "arrived": float(g["arrived"].astype(bool).mean()),
                "all_four_arrived": float((runs["n_arrived"] == runs["n_uavs"]).mean()),
                "flown_verified": float(runs["flown_verified"].mean()),
                "feasible_but_failed": int(runs["feasible_but_failed"].sum()),
                "median_arrival_s": float(np.nanmedian(g["arrival_s"]))
                if g["arrival_s"].notna().any()
                else math.nan,
                "min_clear_moving_m": float(np.nanmin(g["min_clear_m"]))
                if g["min_clear_m"].notna().any()
                else math.nan,
                "min_separation_m": float(runs["min_separation"].min()),
                "max_curv_per_km": float(g["max_curv_km"].max()),
                "median_max_curv_per_km": float(g["max_curv_km"].median()),
                "median_plan_s_per_uav": float(g["plan_s"].median())
                if "plan_s" in g and g["plan_s"].notna().any()
                else math.nan,
            }
        )
    table = pd.DataFrame(rows)
    figs = []
    hist = ok[ok["fitness_history"].map(len) > 0]
    if not hist.empty:
        fig, ax = plt.subplots(figsize=(6.0, 3.6))
        for alg, g in hist.groupby("algorithm", sort=False):
            M = stack_histories(list(g["fitness_history"]))
            ax.plot(np.arange(1, M.shape[1] + 1), np.nanmean(M, axis=0) / 1000, label=str(alg))
        ax.set_xlabel("iteration")
        ax.set_ylabel("best fitness, km (mean over runs and UAVs)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        figs.append(("fitness", "Fig. 16: the smoothing fitness over iterations", fig))
    if "curv_profile" in u.columns and not u.empty:
        fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.4))
        x = (np.arange(PROFILE) + 0.5) / PROFILE
        for alg, g in u[u["algorithm"].isin(APF_FAMILY)].groupby("algorithm", sort=False):
            for ax, col in zip(axes, ("curv_profile", "dcurv_profile"), strict=True):
                M = np.asarray([np.asarray(v, dtype=float) for v in g[col]])
                ax.plot(x, np.median(M, axis=0), lw=1, label=f"{alg} (median of {len(M)} UAVs)")
        axes[0].axhline(0.5, color="k", ls=":", lw=0.8, label="1 / turn radius (2 km)")
        axes[0].set_ylabel("curvature, 1/km (largest per bin)")
        axes[1].set_ylabel("|d curvature / ds|, 1/km^2")
        for ax in axes:
            ax.set_xlabel("horizontal arc length / total")
            ax.grid(True, alpha=0.3)
        axes[0].legend(fontsize=6)
        fig.tight_layout()
        figs.append(
            (
                "curvature",
                "Fig. 14: curvature and its derivative along the track, before (apf) and after "
                "smoothing (the fused planners); the APF family only (the Dubins arcs of the "
                "prioritized rows jump between 0 and 1/R)",
                fig,
            )
        )
    note = (
        "pass_through = UAV flights that reach the target and pass every check as flown / all "
        "UAV flights, with the Wilson 95 % interval; arrived = share that reach it; "
        "all_four_arrived = share of runs where every UAV arrives; flown_verified = "
        "share of runs whose flown trajectories the independent verifier accepts (it checks "
        "safety, not arrival; feasible_but_failed, plans called feasible that it rejects, must "
        "be 0); curvature of the horizontal track (1/km, the flight "
        "check's estimate; the turn radius of 2 km allows 0.5); median_plan_s_per_uav: the "
        "planner's wall time per UAV on this shared machine; the paper: RSCDWOA-APF passes "
        "100 %, WOA-APF less, the APF is caught (Fig. 12); curvature below 2 after smoothing "
        "(Fig. 14, no unit given)"
    )
    return [("Pass-through, safety and smoothness", note, table)], figs


def table3_sections(df: pd.DataFrame, plan: str) -> Any:
    u = _uav_frame(df)
    if u.empty:
        return [], []
    t = u.groupby(["uav", "algorithm"], sort=False)[["mae_km", "rmse_km"]].median().reset_index()
    paper = {
        ("uav1", "pso-apf"): (0.1983, 0.4724),
        ("uav1", "ga-apf"): (0.1771, 0.4449),
        ("uav1", "woa-apf"): (0.1139, 0.3293),
        ("uav1", "rscdwoa-apf"): (0.0538, 0.1762),
        ("uav2", "pso-apf"): (0.1952, 0.4625),
        ("uav2", "ga-apf"): (0.1734, 0.4435),
        ("uav2", "woa-apf"): (0.1176, 0.3391),
        ("uav2", "rscdwoa-apf"): (0.0493, 0.1724),
        ("uav3", "pso-apf"): (0.1986, 0.4765),
        ("uav3", "ga-apf"): (0.1752, 0.4438),
        ("uav3", "woa-apf"): (0.1093, 0.3258),
        ("uav3", "rscdwoa-apf"): (0.0576, 0.1864),
        ("uav4", "pso-apf"): (0.2027, 0.4812),
        ("uav4", "ga-apf"): (0.1725, 0.4436),
        ("uav4", "woa-apf"): (0.1124, 0.3279),
        ("uav4", "rscdwoa-apf"): (0.0513, 0.1742),
    }
    t["paper_mae"] = [
        paper.get((a, b), (math.nan,) * 2)[0] for a, b in zip(t["uav"], t["algorithm"], strict=True)
    ]
    t["paper_rmse"] = [
        paper.get((a, b), (math.nan,) * 2)[1] for a, b in zip(t["uav"], t["algorithm"], strict=True)
    ]
    note = (
        "ours: median over runs of the MAE and RMSE (km) of the horizontal distance from each 1 s "
        "sample of the flown trajectory to the shortest horizontal path around the static "
        "obstacles' footprints (the paper defines neither its MAE nor its RMSE nor their unit)"
    )
    return [("Table 3: MAE and RMSE per UAV", note, t)], []


def dynamic_sections(df: pd.DataFrame, plan: str) -> Any:
    """``rscdwoa-dynamic``'s report: pass-through and safety, and Table 3 from the same runs
    (the same layout and fused planners as ``rscdwoa-table3``)."""
    sections, figs = apf_sections(df, plan)
    t3, _ = table3_sections(df[df["algorithm"].isin(APF_FAMILY[1:])], plan)
    return sections + t3, figs


#: the classical APF's iteration is 50 steps; 500 per iteration lets it fly 20,000 steps (400 km)
#: in the 40 iterations the optimizers get
_APF = {"steps_per_iteration": 500}


def _apf_plan(name: str, description: str, scenario: str, algorithms: tuple[Algorithm, ...],
              runs: int, report: Any) -> None:  # fmt: skip
    """One of the APF application's plans: smoke 1 run of 1 iteration, paper ``runs`` of 40."""
    register_plan(
        ExperimentPlan(
            name=name,
            description=description,
            scenarios=(scenario,),
            algorithms=algorithms,
            scales={
                "smoke": Scale(runs=1, iterations=1),
                "paper": Scale(runs=runs, iterations=40),
            },
            kind="rscdwoa",
            report=report,
        )
    )


_apf_plan(
    "rscdwoa-static",
    "RSCDWOA Fig. 12: APF and its fused versions in the static layout with a trap",
    "rscdwoa-static",
    (Algorithm("apf", "apf", _APF), *(Algorithm(a, a) for a in APF_FAMILY[1:])),
    100,
    apf_sections,
)
_apf_plan(
    "rscdwoa-static-corridor",
    "Fig. 12's trap with the fused planners' sub-goals within 10 % of the start-goal distance "
    "of the straight line (ours): can leading out tell the optimizers apart",
    "rscdwoa-static",
    tuple(Algorithm(a, a, {"subgoal_corridor": 0.1}) for a in APF_FAMILY[1:]),
    20,
    apf_sections,
)
_apf_plan(
    "rscdwoa-dynamic",
    "RSCDWOA Figs. 13-16: the APF family among three moving obstacles; SPSO, PSO",
    "rscdwoa-mixed",
    (
        Algorithm("apf", "apf", _APF),
        *(Algorithm(a, a) for a in APF_FAMILY[1:]),
        Algorithm("spso", "spso", {"constraints": "feasibility-first"}),
        Algorithm("pso", "pso", {"constraints": "feasibility-first"}),
        Algorithm("ppswarm", "ppswarm"),
    ),
    20,
    dynamic_sections,
)
_apf_plan(
    "rscdwoa-table3",
    "RSCDWOA Table 3: MAE and RMSE per UAV of PSO-, GA-, WOA- and RSCDWOA-APF",
    "rscdwoa-mixed",
    tuple(Algorithm(a, a) for a in ("pso-apf", "ga-apf", "woa-apf", "rscdwoa-apf")),
    20,
    table3_sections,
)
