"""PPSwarm fleet planning time against the number of UAVs (issue figures: 40 UAVs on scenario 1
with Table 1 parameters; 500 UAVs with N_restart = 1), one process, one Numba thread.

    python benchmarks/ppswarm_fleet.py                 # 40 (N_restart 5) and 40..500 (N_restart 1)
    python benchmarks/ppswarm_fleet.py --sizes 40 100  # fewer sizes

Prints per fleet: wall time, time per UAV and restart, RRT* time, whether the fleet is feasible
(and how many UAVs are not), and the independent verifier's verdict. The paper (MATLAB, Table 4):
40 UAVs 149.9 s with N_restart = 5; 500 UAVs 5,847.5 s with N_restart = 1.
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
from uavplan.world.fleet_tasks import with_fleet

PAPER = {(40, 5): 149.9, (40, 1): 81.2, (100, 1): 419.6, (200, 1): 1468.6, (300, 1): 2458.2,
         (400, 1): 3981.7, (500, 1): 5847.5}  # fmt: skip


def one(n: int, restarts: int, seed: int, **opts: object) -> None:
    sc = with_fleet(resolve("ppswarm1"), n)
    planner = get_planner("ppswarm", n_restart=restarts, **opts)
    t0 = time.perf_counter()
    fr = planner.plan_fleet(sc, None, seed)
    wall = time.perf_counter() - t0
    rep = verify_plan(plan_document(FleetPlan(sc, planner.name, {}, seed, fr.results, fr)), sc)
    bad = sum(not r.feasible for r in fr.results)
    paper = PAPER.get((n, restarts))
    print(
        f"{n:>5} {restarts:>8} {wall:>9.1f} {wall / n / restarts * 1000:>12.0f} "
        f"{fr.info['rrt_time']:>7.1f} {('yes' if fr.feasible else f'no ({bad})'):>10} "
        f"{('ok' if rep.ok else f'{len(rep.violations)} viol.'):>9} "
        f"{(f'{paper:,.0f}' if paper else '-'):>9} {(f'{paper / wall:.0f}x' if paper else ''):>6}"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="*", default=[40, 100, 200, 300, 400, 500])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-delays", type=int, default=0)
    a = ap.parse_args()
    opts = {"max_delays": a.max_delays} if a.max_delays else {}
    get_planner("ppswarm", n_restart=1, pop_size=10, n_iter=2).plan_fleet(
        with_fleet(resolve("ppswarm1"), 2), None, 0
    )  # compile
    print(f"{'UAVs':>5} {'restarts':>8} {'wall s':>9} {'ms/UAV/rst':>12} {'RRT* s':>7} "
          f"{'feasible':>10} {'verifier':>9} {'paper s':>9} {'faster':>6}")  # fmt: skip
    one(40, 5, a.seed, **opts)
    for n in a.sizes:
        one(n, 1, a.seed, **opts)


if __name__ == "__main__":
    main()
