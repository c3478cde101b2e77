"""How many Dubins-smoothed PPSwarm paths keep their clearances (PPSwarm Sect. 4.4), by the
smoothing's timing and the planner's separation margin (our options; the paper has neither).

    python benchmarks/smoothing_clearance.py                  # scenarios 1-4, 40 UAVs, 3 seeds
    python benchmarks/smoothing_clearance.py --scenarios ppswarm1 --seeds 5 --margins 0 1 2

Each fleet is planned once per margin (Table 1 parameters, smoothing off), then smoothed with
each timing ("constant": the paper's constant speed along the curve; "planned": every pose
at its planned time, never faster than the UAV's speed) and checked by the independent
verifier (``verify_plan(..., smoothed=True)``). Prints per configuration: the planned fleet
cost, the mean number of UAVs whose smoothed path is not clear (by kind of violation), the
largest lateness behind the plan, the smallest separation between smoothed flights and
whether the planner's own judgement agreed with the verifier's on every fleet.
"""

from __future__ import annotations

import argparse
import os
from collections import Counter
from dataclasses import replace

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np

from uavplan.io.plan_file import plan_document
from uavplan.planners import get_planner
from uavplan.planners.fleet.fleet_plan import FleetPlan
from uavplan.planners.fleet.prioritized import smooth_fleet
from uavplan.scenarios import resolve
from uavplan.verify import verify_plan
from uavplan.world.fleet_tasks import with_fleet


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenarios", nargs="+", default=[f"ppswarm{i}" for i in range(1, 5)])
    ap.add_argument("--uavs", type=int, default=40)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--margins", nargs="+", type=float, default=[0.0, 1.0])
    args = ap.parse_args()

    print(
        f"{'scenario':>9} {'margin':>6} {'timing':>8} {'fleets':>6} {'cost':>9} "
        f"{'not clear':>9}  {'kinds (total)':<34} {'late s':>6} {'min sep':>7} {'agree':>5}"
    )
    for name in args.scenarios:
        sc = with_fleet(resolve(name), args.uavs)
        for margin in args.margins:
            planner = get_planner("ppswarm", separation_margin=margin, smooth=False)
            fleets = [planner.plan_fleet(sc, None, seed) for seed in range(args.seeds)]
            feasible = [f for f in fleets if f.flown_feasible]
            for timing in ("constant", "planned"):
                cfg = replace(planner.config, smooth_timing=timing)  # type: ignore[attr-defined]
                counts, kinds, late, seps, agree = [], Counter(), [], [], 0
                for f in feasible:
                    res, rep = smooth_fleet(sc, f.results, list(f.priority), cfg)
                    counts.append(len(rep["not_clear"]))
                    kinds.update(k for r in res for k in r.smoothed_violations)
                    late.append(rep["max_late"])
                    plan = FleetPlan(sc, "ppswarm", {}, 0, res, replace(f, results=res))
                    v = verify_plan(plan_document(plan), sc, smoothed=True)
                    seps.append(v.min_separation)
                    agree += v.ok == all(r.smoothed_ok for r in res)
                cost = np.mean([f.cost for f in feasible]) if feasible else float("nan")
                kind_s = ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())) or "-"
                print(
                    f"{name:>9} {margin:>6g} {timing:>8} {len(feasible):>3}/{len(fleets):<2} "
                    f"{cost:>9,.0f} {np.mean(counts) if counts else float('nan'):>9.1f}  "
                    f"{kind_s:<34} {max(late, default=0.0):>6.1f} "
                    f"{min(seps, default=float('inf')):>7.2f} {agree:>2}/{len(feasible):<2}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
