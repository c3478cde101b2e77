"""PPSwarm fleet planning time against the number of UAVs, one process, one Numba thread, in our
default mode (``flight=in-loop``: each UAV's Dubins-smoothed, timed flight checked while
planning, reserved and declared) and in the paper's (``flight=after``: polylines reserved and
declared, smoothing after as information), measured in the same run.

    python benchmarks/ppswarm_fleet.py                       # the issue-13 figures (see below)
    python benchmarks/ppswarm_fleet.py --runs 40:5 500:1     # chosen (UAVs:N_restart) pairs
    python benchmarks/ppswarm_fleet.py --modes in-loop       # one mode only

Default pairs: 40 UAVs with N_restart 5 (Table 1), 100-500 with 1, 500 with 5, 1,000 with 1
(1,000 UAVs sit in stacked start layers, see ``uavplan.world.fleet_tasks``). Prints per run:
wall time, time per UAV and restart, RRT* time, how many UAVs' flights fail (the plan says so),
how many were delayed, the verifier's verdict on the flown trajectories (kinematic limits
included), and the paper's time (MATLAB, Table 4) with its ratio to ours; for each pair run in
both modes, the in-loop / paper-mode time ratio (what the flown guarantee costs).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from uavplan.io.plan_file import plan_document
from uavplan.planners import get_planner
from uavplan.planners.fleet_plan import FleetPlan
from uavplan.scenarios import resolve
from uavplan.verify import verify_plan

#: PPSwarm's Table 4 times, seconds, by (UAVs, N_restart).
PAPER = {(40, 5): 149.9, (40, 1): 81.2, (100, 1): 419.6, (100, 5): 778.3, (200, 1): 1468.6,
         (200, 5): 3070.4, (300, 1): 2458.2, (300, 5): 5744.7, (400, 1): 3981.7,
         (400, 5): 13898.4, (500, 1): 5847.5, (500, 5): 21636.0}  # fmt: skip
DEFAULT_RUNS = ("40:5", "100:1", "200:1", "500:1", "500:5", "1000:1")


def one(scenario: str, n: int, restarts: int, mode: str, seed: int) -> float:
    sc = resolve(f"{scenario}@{n}")
    planner = get_planner("ppswarm", n_restart=restarts, flight=mode)
    t0 = time.perf_counter()
    fr = planner.plan_fleet(sc, None, seed)
    wall = time.perf_counter() - t0
    rep = verify_plan(plan_document(FleetPlan(sc, planner.name, {}, seed, fr.results, fr)), sc)
    failed = sum(not r.flown_feasible for r in fr.results)
    delayed = len(fr.info.get("delayed") or {})
    paper = PAPER.get((n, restarts)) if scenario == "ppswarm1" else None
    print(
        f"{n:>5} {restarts:>3} {mode:>8} {wall:>8.1f} {wall / n / restarts * 1000:>10.0f} "
        f"{fr.info['rrt_time']:>6.1f} {failed:>7} {delayed:>7} "
        f"{('ok' if rep.ok else f'{len(rep.violations)} viol.'):>12} "
        f"{(f'{paper:,.0f}' if paper else '-'):>8} {(f'{paper / wall:.0f}x' if paper else ''):>6}",
        flush=True,
    )
    return wall


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", nargs="*", default=list(DEFAULT_RUNS), help="UAVs:N_restart pairs")
    ap.add_argument("--modes", nargs="*", default=["in-loop", "after"])
    ap.add_argument("--scenario", default="ppswarm1")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    pairs = [tuple(int(x) for x in r.split(":")) for r in a.runs]
    get_planner("ppswarm", n_restart=1, pop_size=10, n_iter=2).plan_fleet(
        resolve(f"{a.scenario}@2"), None, 0
    )  # compile
    print(f"{a.scenario}, seed {a.seed}; verifier: flown trajectories with kinematic limits")
    head = (
        ("UAVs", 5),
        ("rst", 3),
        ("mode", 8),
        ("wall s", 8),
        ("ms/UAV/rst", 10),
    )
    head += ("RRT* s", 6), ("failed", 7), ("delayed", 7), ("verifier", 12), ("paper s", 8)
    print(" ".join(f"{h:>{w}}" for h, w in (*head, ("faster", 6))))
    for n, r in pairs:
        walls = {m: one(a.scenario, n, r, m, a.seed) for m in a.modes}
        if len(walls) == 2 and "after" in walls and "in-loop" in walls:
            print(f"      in-loop / paper mode time: {walls['in-loop'] / walls['after']:.2f}")


if __name__ == "__main__":
    main()
