"""PSO, DE, GA and SPSO at SPSO's budget on the SPSO benchmark scenario, over 10 seeds.

Run: ``python benchmarks/spso_budget.py [--seeds 10] [--algorithms pso de ga]``

Budget as in Phung & Ha 2021: 500 individuals x 200 iterations, 10 free waypoints (Cartesian
encoding), SPSO's published cost (5 J1 + J2 + 10 J3 + J4). Prints, per algorithm: how many runs
ended with a finite cost, how many with a feasible path (decided on continuous segments, which
SPSO's cost does not check between waypoints), mean / best / worst cost over the finite runs, and
the mean wall time per run.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

from uavplan.planners import get_planner
from uavplan.scenarios import load_builtin


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--algorithms", nargs="+", default=["pso", "de", "ga", "spso"])
    ap.add_argument("--pop-size", type=int, default=500)
    ap.add_argument("--iterations", type=int, default=200)
    args = ap.parse_args()
    sc = load_builtin("spso")
    print(
        f"SPSO scenario, {args.pop_size} x {args.iterations}, {args.seeds} seeds, "
        f"{os.cpu_count()} cores"
    )
    print(
        f"{'algorithm':>9} {'finite':>6} {'feasible':>8} {'mean':>10} {'best':>10} {'worst':>10}"
        f" {'s/run':>7}"
    )
    for alg in args.algorithms:
        planner = get_planner(alg, pop_size=args.pop_size)
        planner.plan(sc, budget=2, seed=0)  # JIT warm-up, not timed
        costs, feas, times = [], [], []
        for seed in range(args.seeds):
            r = planner.plan(sc, budget=args.iterations, seed=seed)
            costs.append(r.cost)
            feas.append(r.feasible)
            times.append(r.wall_time)
        c = np.array(costs)
        fin = c[np.isfinite(c)]
        stats = (
            f"{fin.mean():10.1f} {fin.min():10.1f} {fin.max():10.1f}"
            if len(fin)
            else f"{'-':>10} {'-':>10} {'-':>10}"
        )
        print(f"{alg:>9} {len(fin):>6} {sum(feas):>8} {stats} {np.mean(times):7.2f}")


if __name__ == "__main__":
    main()
