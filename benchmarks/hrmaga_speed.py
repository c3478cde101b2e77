"""HR-MAGA's planning time per map and its repair latency, against references run here.

Per map (the four ``hrmaga-*`` scenarios): the median wall time (and CPU time of this thread:
on a shared machine the wall time also counts the waits for a core) of one ``hr-maga`` plan at
the given iteration budget over ``--seeds`` seeds, with the level's P-MAGAs batched (the
default) and with one MAGA object per sub-problem (``lockstep="reference"``, the previous
implementation, which gives the same plan: the script checks it), and their ratio; then
``p-maga`` on the whole path given the same number of evaluations (what the hierarchy costs or
saves per evaluation).

Then the repair: an area unknown to the planner is placed on each plan (a tenth of the map's
side, at half its flight time) and revealed in flight; HR-MAGA's local repair (batched, and
with the reference lockstep) is timed against planning the rest from scratch with HR-MAGA
itself (``Planner.repair``, the baseline), with p50/p95/max and the misses of a 100 ms deadline.

Then, with ``--budgets 30,60,120,300``, what a smaller budget buys: per map and budget the median
plan time, the share of flown-feasible plans and the median loss (Eq. 4) of the feasible ones.
Run: ``python benchmarks/hrmaga_speed.py [--iterations 300] [--seeds 5] [--budgets ...]
[--no-pmaga] [--maps a,b]``. Set ``NUMBA_NUM_THREADS=1`` on a shared machine: small batches
lose more to a busy thread pool than they gain.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from typing import Any

import numpy as np

from uavplan.optimizers import Budget
from uavplan.planners import Planner, get_planner
from uavplan.planners.replanning import fly_mission, position_at
from uavplan.scenarios import resolve
from uavplan.world.obstacles import UncertainArea

MAPS = ("hrmaga-spso", "hrmaga-jacksboro", "hrmaga-topobathy", "hrmaga-virtual")


def timed(f: Any, *args: Any, **kwargs: Any) -> tuple[Any, float, float]:
    """``f(*args, **kwargs)``, its wall time and this thread's CPU time (s)."""
    w, c = time.perf_counter(), time.thread_time()
    out = f(*args, **kwargs)
    return out, time.perf_counter() - w, time.thread_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--iterations", type=int, default=300)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--budgets", default="", help="comma-separated iteration budgets")
    ap.add_argument("--no-pmaga", action="store_true", help="leave out p-maga (slow)")
    ap.add_argument("--maps", default=",".join(MAPS), help="comma-separated scenario names")
    args = ap.parse_args()
    if args.budgets:
        budgets(args.seeds, [int(b) for b in args.budgets.split(",")])
        return
    print(
        f"{'map':18} {'batched s':>9} {'(cpu)':>6} {'reference s':>11} {'(cpu)':>6} "
        f"{'ref/batched':>11} {'same':>5} {'p-maga s':>9} {'feasible':>9}"
    )
    lat: dict[str, list[float]] = {"local": [], "local reference": [], "scratch": []}
    cpu: dict[str, list[float]] = {k: [] for k in lat}
    hows: list[str] = []
    for name in args.maps.split(","):
        sc = resolve(name)
        hr = get_planner("hr-maga")
        ref = get_planner("hr-maga", lockstep="reference")
        for p in (hr, ref):
            p.plan(sc, budget=10, seed=0)  # compile the kernels outside the timing
        t_hr, t_ref, t_pm, feas, same = [], [], [], 0, 0
        for seed in range(args.seeds):
            r, w, c = timed(hr.plan, sc, budget=args.iterations, seed=seed)
            t_hr.append((w, c))
            r0, w, c = timed(ref.plan, sc, budget=args.iterations, seed=seed)
            t_ref.append((w, c))
            same += bool(np.array_equal(r.waypoints, r0.waypoints) and r.cost == r0.cost)
            feas += bool(r.flown_feasible)
            if not args.no_pmaga:
                _, w, _ = timed(
                    get_planner("p-maga").plan,
                    sc,
                    budget=Budget(max_evaluations=r.evaluations),
                    seed=seed,
                )
                t_pm.append(w)
            # the repair: an unknown area on this plan, revealed in flight
            c = position_at(r.waypoints, r.times, 0.5 * float(r.times[-1]))
            side = 0.1 * float(min(np.subtract(sc.bounds.hi, sc.bounds.lo)[:2]))
            area = UncertainArea(c[0] - side / 2, c[1] - side / 2, side, side, revealed=False)
            hidden = dataclasses.replace(sc, uncertain_areas=(*sc.uncertain_areas, area))
            for key, planner in (
                ("local", _Timed(hr)),
                ("local reference", _Timed(ref)),
                ("scratch", _Timed(hr, args.iterations)),
            ):
                m = fly_mission(planner, hidden, initial=r, seed=seed)  # type: ignore[arg-type]
                lat[key] += [e.compute_time for e in m.events if e.action == "repair"]
                cpu[key] += planner.cpu
                if key == "local":
                    hows += [str(e.info.get("how")) for e in m.events if e.action == "repair"]
        (a, ac), (b, bc) = np.median(t_hr, axis=0), np.median(t_ref, axis=0)
        pm = f"{np.median(t_pm):9.3f}" if t_pm else f"{'-':>9}"
        print(
            f"{name:18} {a:9.3f} {ac:6.2f} {b:11.3f} {bc:6.2f} {b / a:11.2f} "
            f"{same:>2}/{args.seeds:<2} {pm} {feas:>4}/{args.seeds}"
        )
    print()
    print(
        f"{'repair':26} {'n':>3} {'p50 ms':>8} {'p95 ms':>8} {'max ms':>8} {'> 100 ms':>9} "
        f"{'cpu p50':>8} {'cpu p95':>8}"
    )
    for k, v in lat.items():
        ms, cms = 1000 * np.asarray(v), 1000 * np.asarray(cpu[k])
        if ms.size:
            print(
                f"{'HR-MAGA ' + k:26} {ms.size:3d} {np.median(ms):8.1f} "
                f"{np.percentile(ms, 95):8.1f} {ms.max():8.1f} {int((ms > 100).sum()):9d} "
                f"{np.median(cms):8.1f} {np.percentile(cms, 95):8.1f}"
            )
    loc, scr = np.median(lat["local"] or [np.nan]), np.median(lat["scratch"] or [np.nan])
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


class _Timed:
    """A planner's repair, its CPU time recorded; with ``iterations``, the default repair
    (plan the rest from scratch with that budget)."""

    def __init__(self, inner: Planner, iterations: int | None = None) -> None:
        self.inner = inner
        self.iterations = iterations
        self.cpu: list[float] = []

    def repair(self, scenario, task, path, times, area, budget=None, seed=None):  # type: ignore[no-untyped-def]
        c = time.thread_time()
        if self.iterations is None:
            out = self.inner.repair(scenario, task, path, times, area, budget, seed)
        else:
            out = Planner.repair(
                self.inner, scenario, task, path, times, area, self.iterations, seed
            )
        self.cpu.append(time.thread_time() - c)
        return out


if __name__ == "__main__":
    main()
