"""PPSwarm fleet planning time against the number of UAVs, one process per run, in our default mode
(``flight=in-loop``: each UAV's Dubins-smoothed, timed flight checked while planning, reserved
and declared; blocked UAVs wait) and in the paper's (``flight=after``, ``max_delays=0``:
polylines reserved and declared, smoothing after as information), beside the paper's times
(Table 4) and, with ``--reference``, beside the previous implementation measured in the same
run.

    python benchmarks/ppswarm_fleet.py                           # the default pairs (below)
    python benchmarks/ppswarm_fleet.py --runs 40:5 500:5         # chosen (UAVs:N_restart) pairs
    python benchmarks/ppswarm_fleet.py --runs 40:5 --reference main --repeat 3
    python benchmarks/ppswarm_fleet.py --runs 40:5 --modes after --kernel-share
    python benchmarks/ppswarm_fleet.py --runs 500:1 1000:1 --modes in-loop --model default

Default pairs: 40 UAVs with N_restart 5 (Table 1), 100-500 with 1, 500 with 5, 1,000 with 1
(1,000 UAVs sit in stacked start layers, see ``uavplan.world.fleet_tasks``).

``--reference COMMIT`` extracts that commit's ``src/`` (``git archive``) into a cache folder and
runs every (pair, mode) with it and with this tree (or ``--current COMMIT``'s, so that the tree
may change while it runs), alternately, each run in a fresh process with ``NUMBA_NUM_THREADS``
as given (``--threads``, default 1) and the kernels compiled (or loaded) before the clock
starts; ``--repeat`` runs each that many times and keeps the run of least CPU time. Per run it
prints the planner's wall time (compilation left out), the process's CPU time while planning (on
a machine shared with other work, the figure the ratios are least disturbed in; compilation of a
kernel first called there included), time per UAV and restart, RRT* time, UAVs whose declared
flight fails (the plan says so), UAVs delayed, the independent verifier's verdict on the
declared trajectories (kinematic limits included), the fleet cost, the paper's time and the
speed-up against it; with a reference, the speed-up against the reference and whether both gave
the same fleet (cost equal to 1e-9, the same failed UAVs).

``--model default`` plans each fleet as ``uavplan plan`` does without ``--nominal`` (in the
world widened by uavplan's default execution model for the fleet, with the airframe's flyable
turns and speeds; the planner alone, no repair after planning) and verifies it in the given
world under that model; the default is the nominal fleets of the paper.

``--kernel-share`` also times every call from Python into a Numba kernel, by module, and prints
the share of the run spent outside them (issue 18's target: at most 20 % outside the cost and
validity kernels, those of ``uavplan.problems`` and ``uavplan.world``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: PPSwarm's Table 4 times, seconds, by (UAVs, N_restart).
PAPER = {(40, 5): 149.9, (40, 1): 81.2, (100, 1): 419.6, (100, 5): 778.3, (200, 1): 1468.6,
         (200, 5): 3070.4, (300, 1): 2458.2, (300, 5): 5744.7, (400, 1): 3981.7,
         (400, 5): 13898.4, (500, 1): 5847.5, (500, 5): 21636.0}  # fmt: skip
DEFAULT_RUNS = ("40:5", "100:1", "200:1", "500:1", "500:5", "1000:1")
#: the modules whose kernels count as the cost and validity kernels (issue 18, item 3)
KERNEL_PACKAGES = ("uavplan.problems", "uavplan.world", "uavplan.planners.fleet.fleet_objective")


# ---------------------------------------------------------------------------- child
def _time_kernels() -> dict[str, float]:
    """Time every call from Python into a Numba dispatcher, by the kernel's module and name."""
    from numba import _dispatcher
    from numba.core.registry import CPUDispatcher

    spent: dict[str, float] = {}
    base = _dispatcher.Dispatcher.__call__
    depth = [0]

    def timed(self: Any, *args: Any, **kw: Any) -> Any:
        if depth[0]:
            return base(self, *args, **kw)
        depth[0] += 1
        t0 = time.perf_counter()
        try:
            return base(self, *args, **kw)
        finally:
            depth[0] -= 1
            key = f"{self.py_func.__module__}.{self.py_func.__name__}"
            spent[key] = spent.get(key, 0.0) + time.perf_counter() - t0

    CPUDispatcher.__call__ = timed  # type: ignore[method-assign]
    return spent


def child(a: argparse.Namespace) -> None:
    """One run; prints one JSON line."""
    spent = _time_kernels() if a.kernel_share else None
    from uavplan.io.plan_file import plan_document
    from uavplan.planners import get_planner
    from uavplan.planners.fleet.fleet_plan import FleetPlan
    from uavplan.scenarios import resolve
    from uavplan.verify import verify_plan

    warm = get_planner("ppswarm", n_restart=2, pop_size=10, n_iter=2, flight=a.mode)
    warm.plan_fleet(resolve(f"{a.scenario}@4"), None, 0)  # compile or load every kernel
    sc = given = resolve(f"{a.scenario}@{a.uavs}")
    if a.model == "default":  # uavplan's default: the execution model, flyable turns and speeds
        from uavplan.strategy.world import planning_world

        pw = planning_world(given, f"{a.scenario}@{a.uavs}")
        sc, given = pw.world, pw.given or given  # planned in the widened world, checked in its own
    # the paper's mode is the paper's: no take-off delays (docs/results.md, PPSwarm)
    delays = {"max_delays": 0} if a.mode == "after" else {}
    planner = get_planner("ppswarm", n_restart=a.restarts, flight=a.mode, **delays)
    if spent is not None:
        spent.clear()
    t0, c0 = time.perf_counter(), time.process_time()
    fr = planner.plan_fleet(sc, None, a.seed)
    outer, cpu = time.perf_counter() - t0, time.process_time() - c0
    kernels = dict(spent) if spent is not None else None
    doc = plan_document(FleetPlan(sc, planner.name, {}, a.seed, fr.results, fr))
    rep = verify_plan(doc, given)
    out = {
        "wall": fr.wall_time,
        "outer": outer,
        "cpu": cpu,
        "rrt": fr.info["rrt_time"],
        "failed": sorted(r.uav_id for r in fr.results if not r.flown_feasible),
        "delayed": len(fr.info.get("delayed") or {}),
        "verified": bool(rep.ok),
        "violations": len(rep.violations),
        "cost": fr.cost if math.isfinite(fr.cost) else None,
        "total": float(sum(r.cost for r in fr.results)),
        "kernels": kernels,
    }
    print("RESULT " + json.dumps(out), flush=True)


# ---------------------------------------------------------------------------- parent
def reference_src(commit: str) -> Path:
    """``src/`` of ``commit``, extracted once into ``.bench-cache/`` (its own Numba cache)."""
    sha = subprocess.run(["git", "rev-parse", commit], cwd=ROOT, check=True, capture_output=True,
                         text=True).stdout.strip()  # fmt: skip
    dest = ROOT / ".bench-cache" / f"src-{sha[:12]}"
    if not (dest / "src" / "uavplan").is_dir():
        dest.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "archive", sha, "src"], cwd=ROOT, check=True,
                                 capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return dest / "src"


def run_one(src: Path, a: argparse.Namespace, n: int, r: int, mode: str) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS=str(a.threads))
    cmd = [sys.executable, __file__, "--child", "--uavs", str(n), "--restarts", str(r),
           "--mode", mode, "--scenario", a.scenario, "--seed", str(a.seed),
           "--model", a.model]  # fmt: skip
    if a.kernel_share:
        cmd.append("--kernel-share")
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    for line in proc.stdout.splitlines():
        if line.startswith("RESULT "):
            return dict(json.loads(line[7:]))
    raise SystemExit(f"run failed ({src}): {proc.stderr[-2000:]}")


def same_fleet(x: dict[str, Any], y: dict[str, Any]) -> bool:
    return x["failed"] == y["failed"] and math.isclose(x["total"], y["total"], rel_tol=1e-9)


def print_kernels(label: str, res: dict[str, Any]) -> None:
    k = res["kernels"]
    wall = res["outer"]
    ours = sum(v for m, v in k.items() if m.startswith(KERNEL_PACKAGES))
    other = sum(k.values()) - ours
    print(f"      {label}: {100 * ours / wall:.0f} % of {wall:.1f} s in cost/validity kernels, "
          f"{100 * other / wall:.0f} % in other kernels, "
          f"{100 * (wall - ours - other) / wall:.0f} % outside kernels")  # fmt: skip
    for name, v in sorted(k.items(), key=lambda kv: -kv[1])[:6]:
        print(f"        {100 * v / wall:5.1f} %  {name}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", nargs="*", default=list(DEFAULT_RUNS), help="UAVs:N_restart pairs")
    ap.add_argument("--modes", nargs="*", default=["in-loop", "after"])
    ap.add_argument("--scenario", default="ppswarm1")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--reference", help="a commit to measure beside this tree (e.g. main)")
    ap.add_argument("--current", help="measure this commit instead of the working tree")
    ap.add_argument("--repeat", type=int, default=1, help="runs per cell; the least time kept")
    ap.add_argument("--threads", type=int, default=1, help="NUMBA_NUM_THREADS of each run")
    ap.add_argument("--kernel-share", action="store_true", help="time the Numba kernels")
    ap.add_argument(
        "--model",
        choices=["nominal", "default"],
        default="nominal",
        help="plan nominally (the paper's fleets) or under uavplan's default "
        "execution model for the fleet, its turns and speeds (as `uavplan plan`)",
    )
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--uavs", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--restarts", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--mode", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a)
        return
    impls = [("this tree", ROOT / "src")]
    if a.current:
        impls = [(a.current, reference_src(a.current))]
    if a.reference:
        impls.insert(0, (f"ref {a.reference}", reference_src(a.reference)))
    print(f"{a.scenario}, seed {a.seed}, {a.threads} Numba thread(s), least of {a.repeat}; "
          "verifier: declared trajectories with kinematic limits")  # fmt: skip
    head = (("UAVs", 5), ("rst", 3), ("mode", 8), ("impl", 14), ("wall s", 8),
            ("cpu s", 8), ("ms/UAV/rst", 10), ("RRT* s", 6), ("failed", 6), ("delayed", 7),
            ("verifier", 12), ("paper s", 8), ("vs paper", 8))  # fmt: skip
    print(" ".join(f"{h:>{w}}" for h, w in head) + "  vs ref (wall, cpu)  same")
    pairs = [tuple(int(x) for x in r.split(":")) for r in a.runs]
    for n, r in pairs:
        walls: dict[str, float] = {}
        for mode in a.modes:
            best: dict[str, dict[str, Any]] = {}
            for _ in range(a.repeat):
                for label, src in impls:
                    res = run_one(src, a, n, r, mode)
                    if label not in best or res["cpu"] < best[label]["cpu"]:
                        best[label] = res
            ref = best[impls[0][0]] if a.reference else None
            for label, _src in impls:
                res = best[label]
                wall = res["wall"]
                paper = PAPER.get((n, r)) if a.scenario == "ppswarm1" else None
                verdict = "ok" if res["verified"] else f"{res['violations']} viol."
                line = (f"{n:>5} {r:>3} {mode:>8} {label:>14} {wall:>8.2f} {res['cpu']:>8.2f} "
                        f"{wall / n / r * 1000:>10.1f} {res['rrt']:>6.2f} "
                        f"{len(res['failed']):>6} {res['delayed']:>7} {verdict:>12} "
                        f"{(f'{paper:,.0f}' if paper else '-'):>8} "
                        f"{(f'{paper / wall:.0f}x' if paper else ''):>8}")  # fmt: skip
                if ref is not None and res is not ref:
                    same = "yes" if same_fleet(ref, res) else "NO"
                    line += f"  {ref['wall'] / wall:5.2f}x {ref['cpu'] / res['cpu']:5.2f}x  {same}"
                print(line, flush=True)
                if res["kernels"] is not None:
                    print_kernels(label, res)
            walls[mode] = best[impls[-1][0]]["wall"]
        if "after" in walls and "in-loop" in walls:
            print(f"      in-loop / paper mode time (this tree): "
                  f"{walls['in-loop'] / walls['after']:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
