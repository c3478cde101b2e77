"""Twelve small fixed wings on PPSwarm's scenario 1 map, planned together as `uavplan plan`
plans a fleet (PPSwarm, every UAV's flight checked while planning) under uavplan's default
execution model, and drawn; the console says which UAVs take off later.
Run: ``python examples/fleet.py [OUT.png]``."""

from __future__ import annotations

import sys
from pathlib import Path

from uavplan.scenarios import resolve
from uavplan.strategy import execute, planning_world, strategy_for
from uavplan.viz.figures import save_plan_figure


def main(out: Path) -> None:
    world = planning_world(resolve("ppswarm1@12"), "ppswarm1@12").world
    strategy = strategy_for(world).with_options({"n_restart": 1})
    plan = execute(strategy, world, 10, seed=0).plan
    late = (plan.fleet.info.get("delayed") or {}) if plan.fleet is not None else {}
    title = f"ppswarm1, 12 UAVs: flies {plan.feasible}, {len(late)} taking off later"
    save_plan_figure(world, plan.results, out, title)
    print(title)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "fleet.png"))
