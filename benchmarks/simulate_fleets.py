"""Fleets flown in simulation: for each scenario, the default planner's plan made nominally
and under the default execution model (as ``uavplan plan`` and ``uavplan plan --nominal``
make them), each flown ``--runs`` times through the batched flight model
(:mod:`uavplan.sim`: take-off errors of the plan's model (the robust one's for both, so the
nominal plan meets the same conditions), a steady wind up to ``--wind``, Dryden turbulence,
navigation error), every run checked by the independent verifier: runs with a violation,
P(violation) with its Wilson 95 % interval, the tracking and timing errors, and the time one
simulated execution of the fleet takes.

    python benchmarks/simulate_fleets.py --scenarios ppswarm1 quadrotors --runs 1000

Runs go through the experiment runner (``--workers``), results under ``--out``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any


def plan(ref: str, model: str, out: Path, restarts: int | None) -> Path:
    from typer.testing import CliRunner

    from uavplan.cli import app

    args = ["plan", ref, "--out", str(out)]
    if model == "nominal":
        args.append("--nominal")
    if restarts is not None and "@" in ref:
        args += ["--param", f"n_restart={restarts}"]
    r = CliRunner().invoke(app, args)
    if r.exit_code not in (0, 1):
        raise SystemExit(f"uavplan plan {ref} failed: {r.output}")
    return out / "plan.json"


def main() -> None:
    from uavplan.bench.runner import run_sweep
    from uavplan.bench.simulation import simulation_plan, summarize
    from uavplan.bench.store import ResultStore
    from uavplan.io.plan_file import read_plan_file
    from uavplan.scenarios import resolve
    from uavplan.sim.runs import Conditions, simulate_once

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", default=["ppswarm1", "ppswarm2", "ppswarm3",
                                                       "ppswarm4", "rscdwoa-mixed",
                                                       "quadrotors"])  # fmt: skip
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--wind", type=float, default=3.0)
    ap.add_argument("--turbulence", default="light")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--restarts", type=int, default=None, help="n_restart for NAME@N fleets")
    ap.add_argument("--out", type=Path, default=Path("results/simulate-fleets"))
    args = ap.parse_args()
    head = ("scenario", "plan", "UAVs", "flown", "runs", "violated", "P", "Wilson 95 %",
            "track h p95/p99/max", "track v p99/max", "timing s", "one execution s")  # fmt: skip
    print(" | ".join(head), flush=True)
    rows_out: list[dict[str, Any]] = []
    for ref in args.scenarios:
        robust_model: dict[str, Any] | None = None
        for model in ("default", "nominal"):
            folder = args.out / ref / model
            pf_path = plan(ref, model, folder, args.restarts)
            pf = read_plan_file(pf_path)
            if model == "default":
                robust_model = dict(pf.execution or {})
            d0 = float((robust_model or {}).get("takeoff_s", 2.0))
            opts = {"wind_max": args.wind, "turbulence": args.turbulence, "takeoff_s": d0}
            sc = resolve(ref)
            t0 = time.perf_counter()
            simulate_once(pf, sc, 12345, Conditions(args.wind, args.turbulence, d0))
            one = time.perf_counter() - t0  # kernels compiled by then? the first may compile
            t0 = time.perf_counter()
            simulate_once(pf, sc, 12346, Conditions(args.wind, args.turbulence, d0))
            one = min(one, time.perf_counter() - t0)
            sweep = simulation_plan(str(pf_path.resolve()), ref, args.runs, opts,
                                    name=f"simfleets-{ref}-{model}")  # fmt: skip
            run_sweep(sweep, folder / "runs", "smoke", None, None, 0, "process", args.workers)
            s = summarize(ResultStore(folder / "runs").read().to_dict("records"))
            flown = sum(bool(t.feasible) for t in pf.trajectories("flown"))
            lo, hi = s["wilson95"]
            line = (ref, model, len(pf.uavs), flown, s["runs"], s["violated"],
                    f"{s['p_violation']:.4f}", f"[{lo:.4f}, {hi:.4f}]",
                    f"{s['track_h_p95_median_run']:.2f}/{s['track_h_p99_worst_run']:.2f}/"
                    f"{s['track_h_max']:.2f}",
                    f"{s['track_v_p99_worst_run']:.2f}/{s['track_v_max']:.2f}",
                    f"{s['timing_min']:+.1f}..{s['timing_max']:+.1f}", f"{one:.2f}")  # fmt: skip
            print(" | ".join(str(x) for x in line), flush=True)
            rows_out.append({"scenario": ref, "plan": model, "summary": s, "one_execution_s": one,
                             "execution": pf.execution})  # fmt: skip
            (args.out / "summary.json").write_text(json.dumps(rows_out, indent=1, default=str))


if __name__ == "__main__":
    main()
