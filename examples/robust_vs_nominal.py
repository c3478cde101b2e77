"""What planning for the execution error costs: the same six-UAV fleet planned nominally and
under uavplan's default model, each then flown 20 times in simulation (take-off errors, wind,
turbulence); the figure shows both fleets, the title their simulated violations.
Run: ``python examples/robust_vs_nominal.py [OUT.png]``."""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib.pyplot as plt

from uavplan.bench.simulation import NOT_SAFETY
from uavplan.io.plan_file import parse_plan, plan_document
from uavplan.planners.fleet.fleet_plan import FleetPlan
from uavplan.scenarios import resolve
from uavplan.sim.runs import Conditions, simulate_once
from uavplan.strategy import execute, planning_world, strategy_for
from uavplan.verify import verify_trajectories
from uavplan.world.scenario import Scenario


def violated(plan: FleetPlan, given: Scenario, runs: int = 20) -> int:
    pf = parse_plan(plan_document(plan), 3)
    bad = 0
    for seed in range(runs):
        ex = simulate_once(pf, given, seed, Conditions(takeoff_s=2.0))
        rep = verify_trajectories(ex.tracks, given, kinematics=False)
        bad += any(v.kind not in NOT_SAFETY for v in rep.violations)  # a track's ground
        # speed in wind is not the airspeed the speed limits are about: not a safety check
    return bad


def main(out: Path) -> None:
    given = resolve("ppswarm1@6")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, nominal in zip(axes, (True, False), strict=True):
        world = planning_world(given, "ppswarm1@6", nominal=nominal).world
        plan = execute(strategy_for(world).with_options({"n_restart": 1}), world, 10, 0).plan
        n = violated(plan, given)
        for r in plan.results:
            P, _ = r.flown_trajectory()
            ax.plot(P[:, 0], P[:, 1], lw=1)
        for c in given.cylinders:
            ax.add_patch(plt.Circle(c.center[:2], c.radius, color="0.6", alpha=0.5))
        ax.set_aspect("equal")
        ax.set_title(f"{'nominal' if nominal else 'default model'}: {n} of 20 runs violate")
        print(ax.get_title())
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "robust_vs_nominal.png"))
