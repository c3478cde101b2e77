"""What a user gets without ``-a`` (issue 17's figure): ``uavplan plan NAME --seed S`` on built-in
scenarios, seeds 0-9, through the CLI itself (default planner, budget and polish pass).

Per scenario: the default planner, feasible runs out of the seeds (the plan's own verdict, which
is the flown trajectories'), runs whose horizontal track crosses itself (a loop), and the
median and worst path length relative to the best feasible length that any of the runs here
reached on that scenario: the default's own seeds and, for a single UAV, the rival planners of
``--rivals`` (default: RGG-PSO+ on 2-D scenes, HR-MAGA on terrain, RRT*), seeds 0-2, each also
through the CLI with its defaults. Fleets: the length is the fleet's total.

Run: ``python benchmarks/default_paths.py [--scenarios a,b] [--seeds 10] [--single-only]``
(``NUMBA_NUM_THREADS=1`` on a shared machine). Prints one row per scenario and the totals; exit 1
if a default run is infeasible or loops.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.scenarios import builtin_names, load_builtin
from uavplan.world.geometry import track_crosses_itself


def run(name: str, seed: int, algorithm: str | None) -> dict | None:  # type: ignore[type-arg]
    """One ``uavplan plan`` run; None when the planner refuses the scenario (exit 2)."""
    with tempfile.TemporaryDirectory() as out:
        args = ["plan", name, "--seed", str(seed), "--out", out]
        if algorithm:
            args += ["-a", algorithm]
        r = CliRunner().invoke(app, args)
        if r.exit_code == 2:
            return None
        doc = json.loads((Path(out) / "plan.json").read_text())
    uavs = doc["uavs"]
    return {
        "algorithm": doc["algorithm"],
        "feasible": bool(doc["feasible"]),
        "loops": sum(track_crosses_itself(np.asarray(u["waypoints"])) for u in uavs),
        "length": float(sum(u["length"] for u in uavs)),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenarios", default=None, help="comma-separated (default: every built-in)")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--rivals", default="rgg-pso+,hr-maga,rrt-star")
    ap.add_argument("--rival-seeds", type=int, default=3)
    ap.add_argument("--single-only", action="store_true", help="single-UAV scenarios only")
    a = ap.parse_args()
    names = a.scenarios.split(",") if a.scenarios else builtin_names()
    bad = 0
    print(f"{'scenario':18} {'planner':8} {'feasible':>8} {'loops':>5} {'median':>7} "
          f"{'worst':>7}  best from")  # fmt: skip
    for name in names:
        fleet = len(load_builtin(name).tasks) > 1
        if fleet and a.single_only:
            continue
        own = [run(name, s, None) for s in range(a.seeds)]
        rows = [r for r in own if r is not None]
        rival = []
        if not fleet:
            for alg in a.rivals.split(","):
                rival += [
                    r for r in (run(name, s, alg) for s in range(a.rival_seeds)) if r is not None
                ]
        lengths = [(r["length"], r["algorithm"]) for r in rows + rival if r["feasible"]]
        best, who = min(lengths) if lengths else (float("nan"), "-")
        ratio = np.array([r["length"] / best for r in rows if r["feasible"]])
        n_ok = sum(r["feasible"] for r in rows)
        loops = sum(r["loops"] > 0 for r in rows)
        bad += (len(rows) - n_ok) + loops
        med = f"{np.median(ratio):.3f}" if ratio.size else "-"
        worst = f"{ratio.max():.3f}" if ratio.size else "-"
        print(f"{name:18} {rows[0]['algorithm']:8} {n_ok:>4}/{len(rows):<3} {loops:>5} {med:>7} "
              f"{worst:>7}  {who} ({best:,.0f} m)", flush=True)  # fmt: skip
    print("every default run feasible and loop-free" if not bad else f"{bad} runs failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
