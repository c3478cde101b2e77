"""One UAV over the SPSO benchmark terrain, as `uavplan plan spso` plans it: the default
strategy under uavplan's default execution model, the plan checked by the independent verifier
and drawn. Run: ``python examples/single_uav.py [OUT.png]``."""

from __future__ import annotations

import sys
from pathlib import Path

from uavplan.io.plan_file import plan_document
from uavplan.scenarios import resolve
from uavplan.strategy import execute, planning_world, strategy_for
from uavplan.verify import verify_plan
from uavplan.viz.figures import save_plan_figure


def main(out: Path) -> None:
    given = resolve("spso")
    world = planning_world(given, "spso").world
    plan = execute(strategy_for(world), world, None, seed=0).plan
    report = verify_plan(plan_document(plan), given)  # under the model the plan states
    r = plan.results[0]
    title = f"spso: {plan.algorithm}, {r.length:.0f} m, verified: {report.ok}"
    save_plan_figure(world, plan.results, out, title)
    print(title)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "single_uav.png"))
