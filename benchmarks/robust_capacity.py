"""What planning against an execution model costs: the default fleet planner (PPSwarm, as
``uavplan plan`` runs it: flights in the loop, the repair after planning) on the built-in
fleet maps, nominal beside uavplan's default model (take-off ±2 s, speed ±3 %, tracking 3 m /
2 m), in the same run: UAVs flown, take-off delays, the fleet's cost and flown length,
planning time (kernel compilation left out) and its ratio to the nominal, whether the
verifier accepts the plan under the model it was made for, the fleet's margins, and random
executions drawn from the default model (Monte Carlo: take-off errors, speed factors and
tracking offsets) checked as plans: how many break separation, an obstacle, the terrain or the
band.

    python benchmarks/robust_capacity.py --maps ppswarm1 dense open --sizes 40 100 \\
        --executions 1000 --json results.json

A nominal plan is executed under the default model too: what planning against the model buys.
``--models calibrated`` plans as ``uavplan plan`` does by default (the model with the named
airframe's calibrated tracking error, its flyable turn radius and slowest speed, a generated
fleet placed again where the tracking error needs it) and draws the executions from that model.
"feasible" says whether the planner calls the fleet flyable (an unresolved UAV: the CLI exits 1
and says so); the executions of such a plan break where that UAV is.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np


def _margins(report: Any) -> dict[str, float]:
    ms = report.uav_margins
    out = {}
    for key in ("takeoff_s", "speed", "track_h", "track_v"):
        v = min((getattr(m, key) for m in ms), default=math.inf)
        out[key] = v
    return out


def run(
    name: str, model_name: str, seed: int, executions: int, restarts: int | None = None
) -> dict[str, Any]:
    from uavplan.compile_clock import Stopwatch
    from uavplan.io.plan_file import parse_plan, plan_document
    from uavplan.planners import get_planner
    from uavplan.planners.fleet.fleet_plan import plan_all
    from uavplan.scenarios import resolve
    from uavplan.strategy.world import planning_world
    from uavplan.verify import verify_trajectories
    from uavplan.verify.executions import sample_fleet
    from uavplan.verify.robust import Timing
    from uavplan.world.execution import DEFAULT, NOMINAL, default_for, widened

    given = resolve(name)
    calibrated = default_for(given.uav)
    model = {"default": DEFAULT, "nominal": NOMINAL, "calibrated": calibrated}[model_name]
    # the model the margins are checked against and the executions drawn from: the calibrated
    # one for its plans, else uavplan's least default (a nominal plan is executed under it)
    against = calibrated if model_name == "calibrated" else DEFAULT
    if model_name == "calibrated":  # the world ``uavplan plan`` plans in by default: the
        # airframe's flyable turns and slowest speed, a generated fleet placed again if needed
        pw = planning_world(given, name)
        world, given = pw.world, pw.given
    else:
        world = widened(given, model)
    clock = Stopwatch()
    opts = {} if restarts is None else {"n_restart": restarts}
    plan = plan_all(world, get_planner("ppswarm", **opts), None, seed, None, polish=True)
    planning = clock.elapsed
    pf = parse_plan(plan_document(plan), world.dim)
    trajs = pf.trajectories("flown")
    t0 = time.perf_counter()
    report = verify_trajectories(trajs, given, pf.scenario, model=against)
    verify_s = time.perf_counter() - t0
    fleet = plan.fleet
    delays = (fleet.info.get("delayed") or {}) if fleet is not None else {}
    flown = sum(float(np.sum(np.linalg.norm(np.diff(r.flown_trajectory()[0], axis=0), axis=1)))
                for r in plan.results)  # fmt: skip
    timing = Timing(against.takeoff_s, against.speed, against.track_h, against.track_v)
    rng = np.random.default_rng(seed)
    broken = 0
    by_kind: dict[str, int] = {}
    t_exec = time.perf_counter()
    for k in range(executions):
        if k and k % 100 == 0:
            took = time.perf_counter() - t_exec
            print(f"  {name} {model_name}: {k}/{executions} executions, {broken} broken, "
                  f"{took:.0f} s", file=sys.stderr, flush=True)  # fmt: skip
        executed = sample_fleet(trajs, timing, rng, extremes=k % 3 == 0)
        r = verify_trajectories(executed, given, kinematics=False, speed=False)
        kinds = {v.kind for v in r.violations}
        broken += bool(kinds)
        for kind in kinds:
            by_kind[kind] = by_kind.get(kind, 0) + 1
    return {
        "map": name, "model": model_name, "seed": seed, "uavs": len(plan.results),
        "flown_ok": sum(bool(r.flown_feasible) for r in plan.results),
        "feasible": bool(plan.feasible), "delayed": len(delays),
        "max_delay_s": max(delays.values(), default=0.0),
        "cost": float(fleet.cost) if fleet is not None else float("nan"),
        "flown_m": flown, "planning_s": planning, "verify_s": verify_s,
        "meets_default_model": bool(report.ok), "margins": _margins(report),
        "executions": executions, "executions_broken": broken, "broken_by_kind": by_kind,
        "restarts": restarts,
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", nargs="+", default=["ppswarm1", "ppswarm2", "ppswarm3",
                                                  "ppswarm4", "dense", "open"])  # fmt: skip
    ap.add_argument("--sizes", nargs="+", type=int, default=[40])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--executions", type=int, default=200)
    ap.add_argument("--nominal-executions", type=int, default=None,
                    help="executions of the nominal plans [--executions]; every nominal plan "
                    "breaks under the model, so a few show it")  # fmt: skip
    ap.add_argument("--restarts", type=int, default=None,
                    help="PPSwarm's N_restart [its default, 5]; 1 for 500-1,000 UAVs")  # fmt: skip
    ap.add_argument(
        "--models",
        nargs="+",
        default=["nominal", "default"],
        choices=["nominal", "default", "calibrated"],
    )
    ap.add_argument("--json", type=Path, default=None, help="append each row to this file")
    args = ap.parse_args()
    head = ("map", "model", "flown", "feasible", "delayed", "cost", "flown km", "plan s",
            "x nominal", "meets", "take-off", "speed", "track h/v", "broken execs")  # fmt: skip
    print(" | ".join(head))
    for size in args.sizes:
        for name in args.maps:
            ref = f"{name}@{size}" if size != 40 else name
            nominal_s = None
            for model_name in args.models:
                n_exec = args.executions
                if model_name == "nominal" and args.nominal_executions is not None:
                    n_exec = args.nominal_executions
                row = run(ref, model_name, args.seed, n_exec, args.restarts)
                if model_name == "nominal":
                    nominal_s = row["planning_s"]
                m = row["margins"]
                ratio = row["planning_s"] / nominal_s if nominal_s else float("nan")
                print(" | ".join(str(x) for x in (
                    ref, model_name, f"{row['flown_ok']}/{row['uavs']}", row["feasible"],
                    row["delayed"],
                    f"{row['cost']:.0f}", f"{row['flown_m'] / 1000:.1f}",
                    f"{row['planning_s']:.1f}", f"{ratio:.2f}", row["meets_default_model"],
                    f"{m['takeoff_s']:.3g} s", f"{100 * m['speed']:.3g} %",
                    f"{m['track_h']:.3g}/{m['track_v']:.3g} m",
                    f"{row['executions_broken']}/{row['executions']} {row['broken_by_kind']}",
                )), flush=True)  # fmt: skip
                if args.json is not None:
                    with args.json.open("a", encoding="utf-8") as f:
                        f.write(json.dumps({**row, "ratio": ratio}, default=float) + "\n")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
