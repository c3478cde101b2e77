"""PPSwarm (Meng, Chen & Qu 2024, *Drones* 8, 192): its experiments (Sect. 5, the plans
``ppswarm-table3/4/5`` and ``ppswarm-params``, run kind ``fleet``) and its report sections (the
plans' report hook :func:`sections`): our Tables 3-5 beside the paper's, the independent
verifier's verdicts, and the restart curves of Sect. 5.3.3.

Costs are the fleet's total F (Eq. 13, the sum over UAVs); a fleet with an infeasible UAV costs
inf. Best / worst / mean / std are over the runs whose fleet is feasible, and ``feasible`` is the
share of such runs, so that one failed run does not hide the others (the paper reports finite
numbers only). Our scenarios are ours (the paper's Fig. 4 is not reproducible from its text), so
absolute costs compare only in order of magnitude; the orderings are what can be compared.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from uavplan._lazy import lazy_module
from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, register_plan

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")

ALGS = ("pso", "de", "abc", "gwo", "spso", "ppswarm")

#: Table 3: per scenario, per algorithm (ALGS order): best, worst, mean, std cost, runtime (s).
PAPER_TABLE3: dict[int, dict[str, list[float]]] = {
    1: {
        "best": [195927, 332830, 251589, 254721, 258545, 159023],
        "worst": [488132, 458830, 506118, 288642, 274688, 164938],
        "mean": [275781, 373006, 311405, 270288, 264363, 161649],
        "std": [889871, 35699, 58226, 9868, 3212, 1681],
        "runtime": [337.6, 330.3, 261.8, 325.6, 1405.4, 149.9],
    },
    2: {
        "best": [229738, 176380, 181202, 200904, 220546, 147572],
        "worst": [295353, 194223, 408479, 306069, 2361814, 159212],
        "mean": [272361, 182666, 228962, 212742, 229682, 153744],
        "std": [16250, 4576, 67392, 22216, 5329, 3171],
        "runtime": [348.2, 412.4, 280.8, 325.6, 2425.2, 111.7],
    },
    3: {
        "best": [189039, 192234, 204343, 203650, 229676, 152923],
        "worst": [409891, 211615, 220851, 230760, 246710, 168341],
        "mean": [244827, 200284, 211773, 215424, 229676, 157357],
        "std": [59342, 5104, 3719, 7815, 235959, 4023],
        "runtime": [208.5, 327.7, 218.4, 385.9, 1811.6, 111.8],
    },
    4: {
        "best": [206189, 185995, 209277, 185229, 229093, 160720],
        "worst": [314960, 209045, 222588, 209501, 236863, 171798],
        "mean": [228587, 195390, 214462, 200212, 232768, 165053],
        "std": [34610, 5742, 3392, 6577, 1736, 3123],
        "runtime": [217.5, 194.9, 238.7, 189.7, 1875.4, 110.5],
    },
}

#: Table 4: UAVs -> (best cost, time s) for N_restart = 1 and 5.
PAPER_TABLE4: dict[int, dict[str, tuple[float, float]]] = {
    40: {"ppswarm-r1": (189604, 81.2), "ppswarm-r5": (161649, 149.9)},
    100: {"ppswarm-r1": (727884, 419.6), "ppswarm-r5": (597725, 778.3)},
    200: {"ppswarm-r1": (1341113, 1468.6), "ppswarm-r5": (1228034, 3070.4)},
    300: {"ppswarm-r1": (2069532, 2458.2), "ppswarm-r5": (1840845, 5744.7)},
    400: {"ppswarm-r1": (2807932, 3981.7), "ppswarm-r5": (2479620, 13898.4)},
    500: {"ppswarm-r1": (3715660, 5847.5), "ppswarm-r5": (3275223, 21636.0)},
}

#: Table 5 as printed: scenario -> UAVs -> (cost LH, SH, RND "x 10^4", time LH, SH, RND s).
#: The printed costs are not on one scale (10 and 20 UAVs read ~40-90, 30 and 40 UAVs ~1-8).
PAPER_TABLE5: dict[int, dict[int, tuple[float, ...]]] = {
    1: {
        10: (41.97, 46.01, 43.60, 7.171, 6.806, 6.888),
        20: (88.01, 87.64, 88.80, 17.90, 19.31, 17.79),
        30: (1.286, 1.291, 1.305, 34.20, 44.33, 45.79),
        40: (7.556, 8.317, 7.565, 45.82, 44.33, 45.79),
    },
    2: {
        10: (42.15, 42.81, 45.87, 11.72, 18.25, 17.70),
        20: (85.33, 85.98, 87.91, 20.26, 44.72, 47.76),
        30: (1.285, 1.295, 1.295, 36.17, 35.53, 35.23),
        40: (1.969, 3.023, 3.005, 56.45, 61.59, 56.70),
    },
    3: {
        10: (48.15, 48.43, 47.21, 7.099, 7.221, 7.168),
        20: (89.88, 90.70, 91.73, 18.96, 23.90, 19.92),
        30: (1.380, 1.412, 1.364, 38.60, 41.80, 34.74),
        40: (2.919, 3.022, 3.654, 56.21, 57.93, 66.96),
    },
    4: {
        10: (45.37, 46.01, 45.47, 6.992, 7.452, 7.858),
        20: (87.25, 87.31, 87.89, 21.93, 20.31, 27.40),
        30: (1.374, 1.394, 1.377, 70.19, 68.232, 79.83),
        40: (3.421, 4.133, 3.669, 135.8, 141.5, 75.20),
    },
}


def _scenario_number(name: str) -> int | None:
    base = name.partition("@")[0]
    tail = base.removeprefix("ppswarm")
    return int(tail) if tail.isdigit() else None


def _uavs(name: str, default: int = 40) -> int:
    _, _, n = name.partition("@")
    return int(n) if n else default


def cost_table(df: pd.DataFrame) -> pd.DataFrame:
    """Best / worst / mean / std of the feasible runs' fleet cost, feasible share, runtime."""
    ok = df[df["status"] == "ok"].copy()
    rows = []
    for (sc, alg), g in ok.groupby(["scenario", "algorithm"]):
        c = np.asarray(g["best_cost"], dtype=np.float64)
        feas = g["feasible"].astype(bool).to_numpy() & np.isfinite(c)
        f = c[feas]
        rows.append(
            {
                "scenario": sc,
                "algorithm": alg,
                "runs": len(g),
                "feasible": float(feas.mean()),
                "best": float(f.min()) if f.size else np.inf,
                "worst": float(f.max()) if f.size else np.inf,
                "mean": float(f.mean()) if f.size else np.inf,
                "std": float(f.std(ddof=1)) if f.size > 1 else np.nan,
                "runtime_s": float(g["wall_time"].mean()),
                "infeasible_uavs": (
                    float(g["n_infeasible"].mean()) if "n_infeasible" in g else np.nan
                ),
            }
        )
    out = pd.DataFrame(rows)
    out["_n"] = [_uavs(str(s)) for s in out["scenario"]]
    out = out.sort_values(["_n", "scenario", "algorithm"], kind="stable").drop(columns="_n")
    return out.set_index(["scenario", "algorithm"])


def table3(df: pd.DataFrame) -> pd.DataFrame:
    """Our Table 3 with the paper's values beside (``paper_*`` columns)."""
    t = cost_table(df)
    for col in ("best", "worst", "mean", "std", "runtime"):
        vals = []
        for sc, alg in t.index:
            k = _scenario_number(str(sc))
            paper = PAPER_TABLE3.get(k or 0, {})
            vals.append(paper[col][ALGS.index(alg)] if paper and alg in ALGS else np.nan)
        t[f"paper_{col}"] = vals
    return t


def table4(df: pd.DataFrame) -> pd.DataFrame:
    t = cost_table(df)[["runs", "feasible", "infeasible_uavs", "best", "runtime_s"]].copy()
    pb, pt = [], []
    for sc, alg in t.index:
        p = PAPER_TABLE4.get(_uavs(str(sc)), {}).get(str(alg))
        pb.append(p[0] if p else np.nan)
        pt.append(p[1] if p else np.nan)
    t["paper_best"] = pb
    t["paper_time_s"] = pt
    return t


def table5(df: pd.DataFrame) -> pd.DataFrame:
    t = cost_table(df)[["runs", "feasible", "infeasible_uavs", "mean", "runtime_s"]].copy()
    pc, pt = [], []
    for sc, alg in t.index:
        k = _scenario_number(str(sc))
        row = PAPER_TABLE5.get(k or 0, {}).get(_uavs(str(sc)))
        order = str(alg).rpartition("-")[2]
        i = ("lh", "sh", "rnd").index(order) if order in ("lh", "sh", "rnd") else None
        pc.append(row[i] if row and i is not None else np.nan)
        pt.append(row[3 + i] if row and i is not None else np.nan)
    t["paper_cost_x1e4"] = pc
    t["paper_time_s"] = pt
    return t


def verification_table(df: pd.DataFrame) -> pd.DataFrame:
    """The independent verifier's verdicts per scenario and configuration."""
    ok = df[df["status"] == "ok"].copy()
    ok["feasible_b"] = ok["feasible"].astype(bool)
    ok["verified_b"] = ok["verified"].astype("boolean")  # None: polylines not planned apart
    ok["feasible_not_verified"] = (ok["feasible_b"] & ~ok["verified_b"]).fillna(False)
    agg: dict[str, Any] = {
        "runs": ("run_id", "size"),
        "feasible": ("feasible_b", "mean"),
        "verified": ("verified_b", "mean"),
        "feasible_but_failed": ("feasible_not_verified", "sum"),
        "min_separation_m": ("min_separation", "min"),
    }
    if "flown_verified" in ok:  # rows run before flights were declared have none
        ok["flown_ok_b"] = ok["flown_verified"].astype("boolean")
        ok["flown_feasible_b"] = ok["flown_feasible"].astype("boolean")
        ok["flown_not_verified"] = (ok["flown_feasible_b"] & ~ok["flown_ok_b"]).fillna(False)
        agg["flown_runs"] = ("flown_ok_b", "count")
        agg["flown_feasible"] = ("flown_feasible_b", "mean")
        agg["flown_verified"] = ("flown_ok_b", "mean")
        agg["flown_feasible_but_failed"] = ("flown_not_verified", "sum")
        agg["flown_smoothed_uavs"] = ("flown_smoothed", "mean")
    if "smoothed_verified" in ok:
        ok["smoothed_ok_b"] = ok["smoothed_verified"].astype("boolean").fillna(False)
        agg["smoothed_verified"] = ("smoothed_ok_b", "mean")
        agg["smoothed_not_clear_uavs"] = ("smoothed_not_clear", "mean")
    return ok.groupby(["scenario", "algorithm"]).agg(**agg)


def restart_curves_figure(df: pd.DataFrame) -> Any:
    """Mean fleet cost after each restart per configuration (Figs. 9-10), feasible runs."""
    import matplotlib.pyplot as plt

    ok = df[(df["status"] == "ok") & df["restart_costs"].notna()]
    if ok.empty:
        return None
    fig, ax = plt.subplots(figsize=(8, 5))
    for alg, g in ok.groupby("algorithm"):
        curves = [
            np.minimum.accumulate(np.asarray(c, dtype=np.float64)) for c in g["restart_costs"]
        ]
        n = max(len(c) for c in curves)
        m = np.array([np.pad(c, (0, n - len(c)), mode="edge") for c in curves])
        m = np.where(np.isfinite(m), m, np.nan)
        ax.plot(np.arange(1, n + 1), np.nanmean(m, axis=0), label=str(alg))
    ax.set_xlabel("restart")
    ax.set_ylabel("best fleet cost so far (mean over runs)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def sections(
    df: pd.DataFrame, plan: str
) -> tuple[list[tuple[str, str, Any]], list[tuple[str, str, Any]]]:
    """(sections, figures) for a ``ppswarm-*`` plan."""
    out: list[tuple[str, str, Any]] = []
    figs: list[tuple[str, str, Any]] = []
    note_cost = (
        "fleet cost F (Eq. 13), sum over UAVs; best/worst/mean/std over the feasible runs, "
        "feasible = share of runs whose whole fleet is feasible (separation included); "
        "infeasible_uavs = mean number of UAVs per run left without a feasible path; "
        "runtime = mean wall time per run in seconds on this machine (1 thread)"
    )
    if plan == "ppswarm-table3":
        out.append(("PPSwarm Table 3, ours beside the paper's", note_cost, table3(df)))
    elif plan == "ppswarm-table4":
        out.append(
            ("PPSwarm Table 4 (scalability), ours beside the paper's", note_cost, table4(df))
        )
    elif plan in ("ppswarm-table5", "ppswarm-table5-r1"):
        out.append(
            (
                "PPSwarm Table 5 (priority orders), ours beside the paper's",
                note_cost + "; the paper's costs are printed 'x 10^4' but not on one scale",
                table5(df),
            )
        )
    else:
        out.append(("Fleet cost", note_cost, cost_table(df)))
        fig = restart_curves_figure(df)
        if fig is not None:
            figs.append(("restart_curves", "Best fleet cost per restart (Figs. 9-10)", fig))
    out.append(
        (
            "Independent verification (uavplan verify)",
            "every fleet plan is checked by uavplan.verify, written apart from the "
            "planner: continuous-time separation >= S2 for every pair, obstacles, terrain and "
            "the altitude band along every segment; feasible_but_failed must be 0; "
            "feasible and verified judge the planned polylines as geometric paths (the "
            "paper's criterion); flown_* judge the trajectories the plan declares to be flown, "
            "with the UAV's kinematic limits (speed range, climb angle, turn radius): what the "
            "plan guarantees, flown_feasible_but_failed must be 0 too; flown_smoothed_uavs = "
            "UAVs per run whose flight is Dubins-smoothed (the others fly their polyline); "
            "smoothed = the informative Dubins-smoothed paths of the paper's mode",
            verification_table(df),
        )
    )
    return out, figs


# ------------------------------------------------------------------------------ the plans
#: The paper's mode: the polylines are planned and guaranteed, Dubins smoothing comes after as
#: information (Sect. 4.4), no take-off delays. The ``*-flown`` configurations run our default
#: instead (each UAV's smoothed, timed flight is checked while planning and is what the plan
#: guarantees; blocked UAVs may wait up to 12 x 5 s).
PAPER: dict[str, Any] = {"flight": "after", "max_delays": 0}


def plans() -> list[ExperimentPlan]:
    """PPSwarm (Meng, Chen & Qu 2024) Sect. 5 on our four scenarios (``ppswarm1``-``4``, 40 UAVs;
    ``NAME@N`` is the same world with a generated fleet of N UAVs). Each configuration runs with
    its own ``N_iter`` (a scale's ``iterations = 0``); the smoke scale runs 4 UAVs with a tiny
    budget. Every fleet plan is checked by the independent verifier."""
    table2 = {  # Table 2: the baselines under LH prioritized planning, N_pop 300, N_iter 100
        "pso": {"optimizer": "pso", "w": 0.8, "c1": 1.45, "c2": 1.5},
        "de": {"optimizer": "de", "F": 0.8, "CR": 0.9},
        # ABC: one of our iterations is one phase, so 100 cycles are 201 iterations
        "abc": {"optimizer": "abc", "n_iter": 201},
        "gwo": {"optimizer": "gwo", "max_iterations": 100},
        "spso": {"optimizer": "spso", "w": 1.0, "c1": 1.5, "c2": 1.5},
    }
    scen4 = tuple(f"ppswarm{i}" for i in range(1, 5))
    smoke = Scale(
        runs=1,
        iterations=3,
        pop_size=12,
        scenarios=("ppswarm1@4",),
        options={"pop_size": 12, "rrt_iterations": 1500},
    )
    smoke_params = Scale(
        runs=1,
        iterations=2,
        scenarios=("ppswarm1@3",),
        options={"pop_size": 8, "n_restart": 2, "rrt_iterations": 1500},
    )
    plans = [
        ExperimentPlan(
            name="ppswarm-table3",
            description=(
                "PPSwarm vs PSO, DE, ABC, GWO, SPSO (LH prioritized planning), 40 UAVs, four "
                "scenarios, 20 runs: best/worst/mean/std cost and runtime (Table 3), "
                "convergence (Fig. 5), box plots (Fig. 6)"
            ),
            scenarios=scen4,
            # graded infeasibility for every method: with the literal infinite costs of Sect. 2
            # the uniformly seeded baselines end with most UAVs infeasible (see
            # uavplan.planners.fleet.prioritized); feasible paths still cost exactly F
            algorithms=(
                Algorithm("ppswarm", "ppswarm", {**PAPER, "constraints": "feasibility-first"}),
                *(
                    Algorithm(k, "prioritized", {**v, **PAPER, "constraints": "feasibility-first"})
                    for k, v in table2.items()
                ),
                # ours: the default mode, flights checked while planning
                Algorithm("ppswarm-flown", "ppswarm", {"constraints": "feasibility-first"}),
            ),
            scales={"smoke": smoke, "paper": Scale(runs=20, iterations=0, pop_size=300)},
            kind="fleet",
            report=sections,
            reference="ppswarm",
        ),
        ExperimentPlan(
            name="ppswarm-table4",
            description=(
                "PPSwarm scalability on scenario 1: 40-500 UAVs with N_restart = 1 and 5 "
                "(Table 4, Fig. 7)"
            ),
            scenarios=tuple(f"ppswarm1@{n}" for n in (40, 100, 200, 300, 400, 500)),
            algorithms=(
                Algorithm("ppswarm-r1", "ppswarm", {**PAPER, "n_restart": 1}),
                Algorithm("ppswarm-r5", "ppswarm", {**PAPER, "n_restart": 5}),
                # ours, not the paper's: UAVs blocked at take-off may wait up to 12 x 5 s
                Algorithm(
                    "ppswarm-r1-wait", "ppswarm", {**PAPER, "n_restart": 1, "max_delays": 12}
                ),
                Algorithm("ppswarm-r5-flown", "ppswarm", {"n_restart": 5}),  # ours: default mode
            ),
            scales={"smoke": smoke, "paper": Scale(runs=1, iterations=0, pop_size=300)},
            kind="fleet",
            report=sections,
            reference="ppswarm-r5",
        ),
        ExperimentPlan(
            name="ppswarm-table5",
            description=(
                "Priority orders LH vs SH vs RND with 10, 20, 30, 40 UAVs on the four "
                "scenarios, 20 runs (Table 5)"
            ),
            scenarios=tuple(f"{s}@{n}" for s in scen4 for n in (10, 20, 30, 40)),
            algorithms=(
                *(
                    Algorithm(f"ppswarm-{o}", "ppswarm", {**PAPER, "order": o})
                    for o in ("lh", "sh", "rnd")
                ),
                Algorithm("ppswarm-lh-flown", "ppswarm", {"order": "lh"}),  # ours: default mode
            ),
            scales={"smoke": smoke, "paper": Scale(runs=20, iterations=0, pop_size=300)},
            kind="fleet",
            report=sections,
            reference="ppswarm-lh",
        ),
        ExperimentPlan(
            name="ppswarm-table5-r1",
            description=(
                "Table 5's priority orders with one restart: with five, the priorities are "
                "reshuffled after each restart and the best kept, so the order decides only the "
                "first; one restart isolates it (ours, not the paper's protocol)"
            ),
            scenarios=tuple(f"{s}@{n}" for s in scen4 for n in (10, 20, 30, 40)),
            algorithms=tuple(
                Algorithm(f"ppswarm-{o}", "ppswarm", {**PAPER, "order": o, "n_restart": 1})
                for o in ("lh", "sh", "rnd")
            ),
            scales={"smoke": smoke, "paper": Scale(runs=20, iterations=0, pop_size=300)},
            kind="fleet",
            report=sections,
            reference="ppswarm-lh",
        ),
        ExperimentPlan(
            name="ppswarm-params",
            description=(
                "Sect. 5.3.3 parameter analysis on scenario 1 (10 UAVs), 30 restarts: N_iter "
                "20/40/60 with N_pop 100 and 300 and rho 0 (Fig. 9); rho 0-60 % (Fig. 10)"
            ),
            scenarios=("ppswarm1@10",),
            algorithms=(
                *(
                    Algorithm(
                        f"pop{p}-iter{it}-rho0",
                        "ppswarm",
                        {**PAPER, "pop_size": p, "n_iter": it, "rho": 0.0, "n_restart": 30},
                    )
                    for p in (100, 300)
                    for it in (20, 40, 60)
                ),
                *(
                    Algorithm(
                        f"pop{p}-iter{it}-rho{int(r * 100)}",
                        "ppswarm",
                        {**PAPER, "pop_size": p, "n_iter": it, "rho": r, "n_restart": 30},
                    )
                    for p, it in ((100, 20), (300, 20), (300, 40), (300, 60))
                    for r in (0.2, 0.4, 0.6)
                ),
                # ours: the reference configuration in the default mode
                Algorithm("pop300-iter20-rho20-flown", "ppswarm", {"n_restart": 30}),
            ),
            scales={"smoke": smoke_params, "paper": Scale(runs=20, iterations=0)},
            kind="fleet",
            report=sections,
            reference="pop300-iter20-rho20",
        ),
    ]
    return plans


for _plan in plans():
    register_plan(_plan)
