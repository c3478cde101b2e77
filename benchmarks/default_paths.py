"""What a user gets without ``-a`` (issue 17's figure): ``uavplan plan NAME --seed S`` on built-in
scenarios, seeds 0-9, through the CLI itself (default planner, budget and polish pass).

Per scenario: the default planner, feasible runs out of the seeds (the plan's own verdict, which
is the flown trajectories'), runs whose horizontal track crosses itself (a loop), and the
default's path length against two references, both taken over the feasible runs here: the
default's own seeds and, for a single UAV, the rival planners of ``--rivals`` (default: SPSO,
RGG-PSO+, HR-MAGA, RRT*; those that plan the scenario), seeds ``0..--rival-seeds - 1``, each
also through the CLI with its defaults (polished, as a user gets them):

* ``len/shortest``: median and worst length over the shortest feasible path any run reached,
  whatever it cost under the scenario's objective;
* ``cost/best`` and ``len/best``: the median and worst cost over the best (lowest) cost any run
  reached under the scenario's own cost preset (every plan is scored by it: the plan's
  ``cost``), and the median and worst length over that best result's length. Where the
  objective is length alone the two references are the same path; where it weighs more than
  length (threats, danger areas, terrain height) the shortest path can be a worse result (it
  crosses a danger area).

Fleets: the length and cost are the fleet's totals.

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
    cost = sum(u["cost"] for u in uavs) if all(u["cost"] is not None for u in uavs) else None
    return {
        "algorithm": doc["algorithm"],
        "feasible": bool(doc["feasible"]),
        "loops": sum(track_crosses_itself(np.asarray(u["waypoints"])) for u in uavs),
        "length": float(sum(u["length"] for u in uavs)),
        "cost": float("inf") if cost is None else float(cost),
    }


def pair(x: np.ndarray) -> str:
    """Median and worst of a ratio."""
    return f"{np.median(x):.3f} {x.max():.3f}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenarios", default=None, help="comma-separated (default: every built-in)")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--rivals", default="spso,rgg-pso+,hr-maga,rrt-star")
    ap.add_argument("--rival-seeds", type=int, default=3)
    ap.add_argument("--single-only", action="store_true", help="single-UAV scenarios only")
    ap.add_argument("--jsonl", default=None, help="also write every run as a JSON line here")
    a = ap.parse_args()
    names = a.scenarios.split(",") if a.scenarios else builtin_names()
    bad = 0
    head = ["scenario".ljust(18), "planner".ljust(8), "feasible", "loops"]
    head += ["len/shortest", "cost/best".rjust(13), "len/best".rjust(13)]
    head += [" shortest from; best from"]
    print(" ".join(head))
    for name in names:
        fleet = len(load_builtin(name).tasks) > 1
        if fleet and a.single_only:
            continue
        own = [run(name, s, None) for s in range(a.seeds)]
        rows = [r for r in own if r is not None]
        rival = []
        if not fleet:
            for alg in a.rivals.split(","):
                if alg == rows[0]["algorithm"]:
                    continue  # the default's own seeds are already in
                rival += [
                    r for r in (run(name, s, alg) for s in range(a.rival_seeds)) if r is not None
                ]
        if a.jsonl:
            with open(a.jsonl, "a") as f:
                for i, r in enumerate(rows):
                    f.write(json.dumps({"scenario": name, "default": True, "seed": i, **r}) + "\n")
                for r in rival:
                    f.write(json.dumps({"scenario": name, "default": False, **r}) + "\n")
        ok = [r for r in rows + rival if r["feasible"]]
        mine = [r for r in rows if r["feasible"]]
        n_ok = len(mine)
        loops = sum(r["loops"] > 0 for r in rows)
        bad += (len(rows) - n_ok) + loops
        if not ok or not mine:
            print(f"{name:18} {rows[0]['algorithm']:8} {n_ok:>4}/{len(rows):<3} {loops:>5}")
            continue
        short = min(ok, key=lambda r: r["length"])
        best = min(ok, key=lambda r: r["cost"])
        to_short = np.array([r["length"] / short["length"] for r in mine])
        to_best = np.array([r["length"] / best["length"] for r in mine])
        cost = np.array([r["cost"] / best["cost"] for r in mine])

        print(f"{name:18} {rows[0]['algorithm']:8} {n_ok:>4}/{len(rows):<3} {loops:>5} "
              f"{pair(to_short):>13} {pair(cost):>13} {pair(to_best):>13}  "
              f"{short['algorithm']} ({short['length']:,.0f} m); "
              f"{best['algorithm']} ({best['length']:,.0f} m, cost {best['cost']:,.1f})",
              flush=True)  # fmt: skip
    print("every default run feasible and loop-free" if not bad else f"{bad} runs failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
