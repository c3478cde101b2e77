"""HR-MAGA's planning time per map and its repair latency, against references run here.

Per map (the four ``hrmaga-*`` scenarios): the median wall time of one ``hr-maga`` plan at the
given iteration budget over ``--seeds`` seeds, and of ``p-maga`` on the whole path given the same
number of evaluations (the ratio shows what the hierarchy costs or saves per evaluation).
Then the repair: an area unknown to the planner is placed on each plan (a tenth of the map's
side, at half its flight time) and revealed in flight; HR-MAGA's local repair is timed against
planning the rest from scratch with HR-MAGA itself (``Planner.repair``, the baseline), with
p50/p95/max and the misses of a 100 ms deadline.

Then, with ``--budgets 30,60,120,300``, what a smaller budget buys: per map and budget the median
plan time, the share of flown-feasible plans and the median loss (Eq. 4) of the feasible ones.
Run: ``python benchmarks/hrmaga_speed.py [--iterations 300] [--seeds 5] [--budgets ...]``. Set
``NUMBA_NUM_THREADS=1`` on a shared machine: small batches lose more to a busy thread pool than
they gain.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from uavplan.optimizers import Budget
from uavplan.planners import Planner, get_planner
from uavplan.planners.replanning import fly_mission, position_at
from uavplan.scenarios import resolve
from uavplan.world.obstacles import UncertainArea

MAPS = ("hrmaga-spso", "hrmaga-jacksboro", "hrmaga-topobathy", "hrmaga-virtual")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--iterations", type=int, default=300)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--budgets", default="", help="comma-separated iteration budgets")
    args = ap.parse_args()
    if args.budgets:
        budgets(args.seeds, [int(b) for b in args.budgets.split(",")])
        return
    print(f"{'map':18} {'hr-maga s':>10} {'p-maga s':>9} {'ratio':>6} {'feasible':>9}")
    repairs: dict[str, list[float]] = {"local": [], "scratch": []}
    hows: list[str] = []
    for name in MAPS:
        sc = resolve(name)
        hr = get_planner("hr-maga")
        hr.plan(sc, budget=10, seed=0)  # compile the kernels outside the timing
        t_hr, t_pm, feas = [], [], 0
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            r = hr.plan(sc, budget=args.iterations, seed=seed)
            t_hr.append(time.perf_counter() - t0)
            feas += bool(r.flown_feasible)
            pm = get_planner("p-maga")
            t0 = time.perf_counter()
            pm.plan(sc, budget=Budget(max_evaluations=r.evaluations), seed=seed)
            t_pm.append(time.perf_counter() - t0)
            # the repair: an unknown area on this plan, revealed in flight
            c = position_at(r.waypoints, r.times, 0.5 * float(r.times[-1]))
            side = 0.1 * float(min(np.subtract(sc.bounds.hi, sc.bounds.lo)[:2]))
            area = UncertainArea(c[0] - side / 2, c[1] - side / 2, side, side, revealed=False)
            hidden = dataclasses.replace(sc, uncertain_areas=(*sc.uncertain_areas, area))
            m = fly_mission(hr, hidden, initial=r, seed=seed)
            repairs["local"] += [e.compute_time for e in m.events if e.action == "repair"]
            hows += [str(e.info.get("how")) for e in m.events if e.action == "repair"]
            scratch = _Scratch(hr, args.iterations)
            m2 = fly_mission(scratch, hidden, initial=r, seed=seed)
            repairs["scratch"] += [e.compute_time for e in m2.events if e.action == "repair"]
        a, b = float(np.median(t_hr)), float(np.median(t_pm))
        print(f"{name:18} {a:10.3f} {b:9.3f} {a / b:6.2f} {feas:>4}/{args.seeds}")
    print()
    print(f"{'repair':22} {'n':>3} {'p50 ms':>8} {'p95 ms':>8} {'max ms':>8} {'> 100 ms':>9}")
    for k, v in repairs.items():
        ms = 1000 * np.asarray(v)
        if ms.size:
            print(
                f"{'HR-MAGA ' + k:22} {ms.size:3d} {np.median(ms):8.1f} "
                f"{np.percentile(ms, 95):8.1f} {ms.max():8.1f} {int((ms > 100).sum()):9d}"
            )
    loc, scr = np.median(repairs["local"] or [np.nan]), np.median(repairs["scratch"] or [np.nan])
    print(f"local repair / from scratch (median): {loc / scr:.3f}")
    print("HR-MAGA repairs by kind:", {h: hows.count(h) for h in sorted(set(hows))})


def budgets(seeds: int, iterations: list[int]) -> None:
    """Plan time, feasibility and loss of hr-maga against its iteration budget."""
    print(f"{'map':18} {'iterations':>10} {'median s':>9} {'feasible':>9} {'median loss':>12}")
    for name in MAPS:
        sc = resolve(name)
        hr = get_planner("hr-maga")
        hr.plan(sc, budget=10, seed=0)  # compile outside the timing
        for it in iterations:
            ts, losses, feas = [], [], 0
            for seed in range(seeds):
                t0 = time.perf_counter()
                r = hr.plan(sc, budget=it, seed=seed)
                ts.append(time.perf_counter() - t0)
                if r.flown_feasible:
                    feas += 1
                    losses.append(r.cost)
            loss = f"{np.median(losses):12,.0f}" if losses else f"{'-':>12}"
            print(f"{name:18} {it:10d} {np.median(ts):9.3f} {feas:>4}/{seeds:<4} {loss}")


class _Scratch:
    """HR-MAGA whose repair is the default one: plan the rest from scratch."""

    def __init__(self, inner: Planner, iterations: int) -> None:
        self.inner = inner
        self.iterations = iterations

    def repair(self, scenario, task, path, times, area, budget=None, seed=None):  # type: ignore[no-untyped-def]
        return Planner.repair(self.inner, scenario, task, path, times, area, self.iterations, seed)


if __name__ == "__main__":
    main()
