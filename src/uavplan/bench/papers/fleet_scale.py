"""Not a paper's: how far the flown-fleet guarantee scales. PPSwarm's engine in our
default mode (each UAV's Dubins-smoothed, timed flight checked while planning, reserved and
declared; the rescues of :mod:`uavplan.planners.fleet.prioritized`) with ``N_restart = 1`` on 40 to
1,000 UAVs: the four PPSwarm maps, the flat open map (``open``, the crowd alone) and the dense
field (``dense``, >= 40 cylinders with narrow passages). Every plan is checked by the
independent verifier as flown (kinematic limits included).

Sizes that a map cannot hold (``with_fleet`` cannot place them 3 S2 apart) are recorded as
failed runs with the placement's message, not left out. The report: per map and size, the share
of runs whose whole flown fleet is feasible and verified (``flown_feasible_but_failed`` must be
0), UAVs left failed, delayed and rescued per kind, planning time, time per UAV, peak memory,
and the flown length against the planned polylines'; a figure of time per UAV against fleet
size.
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

MAPS = ("ppswarm1", "ppswarm2", "ppswarm3", "ppswarm4", "open", "dense")
SIZES = (40, 100, 200, 500, 1000)
RESCUES = ("first", "candidate", "slower", "wait", "delay")


def _map(ref: str) -> str:
    return ref.partition("@")[0]


def _n(ref: str) -> int:
    tail = ref.partition("@")[2]
    return int(tail) if tail else 0


def scale_table(df: pd.DataFrame) -> pd.DataFrame:
    """Per map and fleet size: runs, placed, flown feasible and verified shares, failed and
    delayed UAVs, rescues, times and memory (means over the runs that placed)."""
    rows = []
    for (sc, alg), g in df.groupby(["scenario", "algorithm"]):
        ok = g[g["status"] == "ok"]
        row: dict[str, Any] = {"map": _map(str(sc)), "uavs": _n(str(sc)), "algorithm": alg,
                               "runs": len(g), "ok_runs": len(ok)}  # fmt: skip
        if len(ok):
            ff = ok["flown_feasible"].astype(bool)
            fv = ok["flown_verified"].astype(bool)
            t = ok["planner_wall_time"].astype(float)
            row.update(
                flown_feasible=float(ff.mean()),
                flown_verified=float(fv.mean()),
                flown_feasible_but_failed=int((ff & ~fv).sum()),
                failed_uavs=float(ok["flown_not_ok"].mean()),
                delayed_uavs=float(ok["n_delayed"].mean()) if "n_delayed" in ok else np.nan,
                **{
                    f"rescued_{k}": float(ok[f"rescue_{k}"].mean())
                    for k in RESCUES
                    if f"rescue_{k}" in ok
                },
                plan_s=float(t.mean()),
                s_per_uav=float((t / ok["n_uavs"].astype(float)).mean()),
                peak_rss_mb=float(ok["peak_rss_mb"].max()) if "peak_rss_mb" in ok else np.nan,
                flown_over_planned=float(
                    (ok["flown_length"].astype(float) / ok["path_length"].astype(float)).mean()
                ),
            )
        else:
            row["error"] = str(g["error"].iloc[0])[:160]
        rows.append(row)
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    return out.sort_values(["map", "uavs", "algorithm"]).set_index(["map", "uavs", "algorithm"])


def time_per_uav_figure(df: pd.DataFrame) -> Any:
    """Planning time per UAV against fleet size, one line per map (log x)."""
    import matplotlib.pyplot as plt

    ok = df[df["status"] == "ok"].copy()
    if ok.empty:
        return None
    ok["map"] = ok["scenario"].map(_map)
    ok["uavs"] = ok["scenario"].map(_n)
    ok["s_per_uav"] = ok["planner_wall_time"].astype(float) / ok["n_uavs"].astype(float)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for m, g in ok.groupby("map"):
        mean = g.groupby("uavs")["s_per_uav"].mean()
        ax.plot(mean.index.to_numpy(), mean.to_numpy(), marker="o", label=str(m))
    ax.set_xscale("log")
    ax.set_xlabel("UAVs in the fleet")
    ax.set_ylabel("planning time per UAV (s)")
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def sections(
    df: pd.DataFrame, plan: str
) -> tuple[list[tuple[str, str, Any]], list[tuple[str, str, Any]]]:
    """(sections, figures) of the ``fleet-scale`` plan."""
    note = (
        "flown_* = the trajectories the plans declare, checked by uavplan.verify with the "
        "kinematic limits (turn radius, climb angle, speed range) and S2 between every pair "
        "over continuous time; flown_feasible_but_failed must be 0; failed_uavs = UAVs per "
        "run whose flight fails a check (the fleet then says so); rescued_* = UAVs per run "
        "whose flight came from the best candidate (first), a later candidate, a slower "
        "speed, the same candidates taking off later (wait) or a re-plan from a later "
        "take-off (delay); plan_s = planner wall time (1 thread); peak_rss_mb = the "
        "worker's peak resident memory (interpreter included); runs that could not place the "
        "fleet show the placement's error"
    )
    figs = []
    fig = time_per_uav_figure(df)
    if fig is not None:
        figs.append(("time_per_uav", "Planning time per UAV against fleet size", fig))
    return [("Flown fleets at scale", note, scale_table(df))], figs


register_plan(
    ExperimentPlan(
        name="fleet-scale",
        description=(
            "Flown-fleet guarantee at scale: PPSwarm's engine in the default mode (flights "
            "checked while planning), N_restart 1, 40-1,000 UAVs on ppswarm1-4, open and dense, "
            "3 runs: verified flown fleets, failed/delayed/rescued UAVs, time per UAV, memory"
        ),
        scenarios=tuple(f"{m}@{n}" for m in MAPS for n in SIZES),
        algorithms=(Algorithm("ppswarm-r1", "ppswarm", {"n_restart": 1}),),
        scales={
            "smoke": Scale(
                runs=1,
                iterations=3,
                scenarios=("ppswarm1@4", "open@4", "dense@4"),
                options={"pop_size": 12, "rrt_iterations": 1500},
            ),
            "paper": Scale(runs=3, iterations=0),
        },
        kind="fleet",
        report=sections,
        reference="ppswarm-r1",
    )
)
