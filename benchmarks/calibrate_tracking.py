"""Where the default execution model's tracking error comes from: each UAV class's exported
missions flown many times by the batched flight model (:mod:`uavplan.sim`) under the
calibration conditions (Dryden turbulence ``--turbulence``, a steady wind up to ``--wind``
m/s, navigation error on), and the distribution of each UAV flight's largest horizontal and
vertical distance from the trajectory the plan verified.

    python benchmarks/calibrate_tracking.py --runs 50

The classes' plans are the default plans of a built-in scenario of that class, made with the
nominal model (``uavplan plan --nominal``: the tracking error comes from the missions and the
flight, not from the margins a robust plan adds; ``--plans default`` flies the default plans
instead, on which the small fixed wing and the quadrotor are calibrated). The figure per class
is the 99th percentile of a flight's largest error, rounded up to the next half metre (the
error stated for a fleet of up to ten), and the exponential tail fitted above the 95th
percentile (``tail_fit``), from which larger fleets' errors are read
(:func:`uavplan.world.airframes.fleet_tracking`); the airframes
(:mod:`uavplan.world.airframes`) carry the figures, and ``docs/results.md`` the runs.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

CLASSES = {"small-fixed-wing": "ppswarm1", "fast-fixed-wing": "rscdwoa-static",
           "quadrotor": "quadrotors"}  # fmt: skip


def tail_fit(a: np.ndarray) -> tuple[float, float]:
    """The per-flight maxima's 95th percentile ``u`` and the scale of an exponential tail
    above it (the mean excess over ``u``, its maximum-likelihood estimate): the quantile of
    exceedance probability ``p < 0.05`` is then ``u + scale * ln(0.05 / p)``, what the default
    model's fleet-size rule reads (:func:`uavplan.world.airframes.fleet_tracking`)."""
    u = float(np.quantile(a, 0.95))
    return u, float(np.mean(a[a > u] - u))


def main() -> None:
    from typer.testing import CliRunner

    from uavplan.cli import app
    from uavplan.io.plan_file import read_plan_file
    from uavplan.scenarios import resolve
    from uavplan.sim.runs import Conditions, simulate_once
    from uavplan.world.airframes import AIRFRAMES

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--classes", nargs="+", default=list(CLASSES))
    ap.add_argument(
        "--scenario",
        default=None,
        help="fly this scenario's plan instead of the class's built-in (one class; e.g. "
        "ppswarm1@500: a large fleet's flights, where the tail is used)",
    )
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--wind", type=float, default=3.0)
    ap.add_argument("--turbulence", default="light")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--plans",
        choices=["nominal", "default"],
        default="nominal",
        help="fly the nominal plans (the calibration) or the default plans made "
        "under the calibrated model (its check)",
    )
    ap.add_argument(
        "--save",
        type=Path,
        default=None,
        help="write each class's per-flight maxima here (.npz, h_<class>, v_<class>)",
    )
    args = ap.parse_args()
    saved: dict[str, np.ndarray] = {}
    cond = Conditions(args.wind, args.turbulence)
    print(
        "class | scenario | flights | per-flight h p50/p90/p99/max | per-flight v p50/p90/p99/max"
        " | samples h p99.9, v p99.9 | tail h, v (p95 + scale) | stated e_h/e_v"
        " | flights beyond e_h / e_v | s per run"
    )
    for name in args.classes:
        ref = args.scenario or CLASSES[name]
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp)
            cmd = ["plan", ref, "--seed", str(args.seed), "--out", str(out)]
            if "@" in ref:  # a generated fleet: PPSwarm with one restart, as the fleets are made
                cmd += ["-a", "ppswarm", "--param", "n_restart=1"]
            r = CliRunner().invoke(app, cmd + (["--nominal"] if args.plans == "nominal" else []))
            if r.exit_code not in (0, 1):
                raise SystemExit(f"uavplan plan {ref} failed: {r.output}")
            pf = read_plan_file(out / "plan.json")
        scenario = resolve(ref)
        af = AIRFRAMES[name]
        hm: list[float] = []
        vm: list[float] = []
        sh, sv = [], []
        t = time.perf_counter()
        for run in range(args.runs):
            ex = simulate_once(pf, scenario, 1000 * args.seed + run, cond, af)
            hm += [x for x in ex.track_h.values() if math.isfinite(x)]
            vm += [x for x in ex.track_v.values() if math.isfinite(x)]
            sh.append(ex.samples_h)
            sv.append(np.abs(ex.samples_v))
        per_run = (time.perf_counter() - t) / args.runs
        H, V = np.asarray(hm), np.asarray(vm)

        def fmt(a: np.ndarray) -> str:
            q = np.quantile(a, (0.5, 0.9, 0.99, 0.999))
            return "/".join(f"{x:.2f}" for x in (*q, a.max()))

        def tail(a: np.ndarray) -> str:
            u, beta = tail_fit(a)
            return f"{u:.2f} + {beta:.2f}"

        saved[f"h_{name}"], saved[f"v_{name}"] = H, V

        print(f"{name} | {ref} | {len(H)} | {fmt(H)} | {fmt(V)} | "
              f"{np.quantile(np.concatenate(sh), 0.999):.2f}, "
              f"{np.quantile(np.concatenate(sv), 0.999):.2f} | {tail(H)}, {tail(V)} | "
              f"{af.track_h}/{af.track_v} | {int((af.track_h < H).sum())} / "
              f"{int((af.track_v < V).sum())} | {per_run:.2f}", flush=True)  # fmt: skip
    if args.save is not None:
        np.savez(args.save, **saved)


if __name__ == "__main__":
    main()
