"""Where the default execution model's tracking error comes from: each UAV class's exported
missions flown many times by the batched flight model (:mod:`uavplan.sim`) under the
calibration conditions (Dryden turbulence ``--turbulence``, a steady wind up to ``--wind``
m/s, navigation error on), and the distribution of each UAV flight's largest horizontal and
vertical distance from the trajectory the plan verified.

    python benchmarks/calibrate_tracking.py --runs 50

The classes' plans are the default plans of built-in scenarios of that class, made with the
nominal model (``uavplan plan --nominal``: the tracking error comes from the missions and the
flight, not from the margins a robust plan adds; ``--plans default`` flies the default plans
instead, on which every class is calibrated). A built-in that states its own execution model
(the fast fixed wing's RSCDWOA layouts: nominal, their goals on the band's floor) is flown with
``--plans default`` as its variant under uavplan's default model: the scenario without its
``execution`` line, every goal less than :data:`LIFT` above the band's floor lifted to it (a
goal on the floor leaves no room for any vertical tracking error). The flights of a class's
scenarios are pooled. The figure per class is the 99th percentile of a flight's largest
error, rounded up to the next half metre (the error stated for a fleet of up to ten), and the
exponential tail fitted above the 95th percentile (``tail_fit``), from which larger fleets'
errors are read (:func:`uavplan.world.airframes.fleet_tracking`); the airframes
(:mod:`uavplan.world.airframes`) carry the figures, and ``docs/results.md`` the runs. A fixed
wing's vertical error is measured beyond the height lag its plan is verified with
(:func:`uavplan.sim.runs.plan_slack`).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

CLASSES = {"small-fixed-wing": ("ppswarm1",), "fast-fixed-wing": ("rscdwoa-static",
           "rscdwoa-mixed"), "quadrotor": ("quadrotors",)}  # fmt: skip

#: How far above the band's floor a goal of a default-model variant is put, m (at least).
LIFT = 30.0


def default_variant(ref: str, folder: Path) -> str:
    """``ref`` as a file planned under uavplan's default model: a built-in that states its
    execution model without that line, its goals lifted to :data:`LIFT` above the band's
    floor (the band's reference absolute); other references as they are."""
    import yaml

    from uavplan.scenarios import builtin_path, resolve

    try:
        path = builtin_path(ref)
    except (KeyError, ValueError, FileNotFoundError):
        return ref
    doc = yaml.safe_load(path.read_text())
    if "execution" not in doc:
        return ref
    del doc["execution"]
    floor = resolve(ref).altitude
    for task in doc.get("tasks", []):
        if floor is not None and floor.reference == "absolute":
            task["goal"][2] = max(float(task["goal"][2]), floor.min + LIFT)
    out = folder / f"{ref}-default.yaml"
    out.write_text(yaml.safe_dump(doc, sort_keys=False))
    return str(out)


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
        nargs="+",
        default=None,
        help="fly these scenarios' plans instead of the class's built-ins (one class; e.g. "
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

    def fmt(a: np.ndarray) -> str:
        q = np.quantile(a, (0.5, 0.9, 0.99, 0.999))
        return "/".join(f"{x:.2f}" for x in (*q, a.max()))

    def tail(a: np.ndarray) -> str:
        u, beta = tail_fit(a)
        return f"{u:.2f} + {beta:.2f}"

    def row(name: str, label: str, H: np.ndarray, V: np.ndarray, sh: list[np.ndarray],
            sv: list[np.ndarray], per_run: float) -> None:  # fmt: skip
        af = AIRFRAMES[name]
        print(f"{name} | {label} | {len(H)} | {fmt(H)} | {fmt(V)} | "
              f"{np.quantile(np.concatenate(sh), 0.999):.2f}, "
              f"{np.quantile(np.concatenate(sv), 0.999):.2f} | {tail(H)}, {tail(V)} | "
              f"{af.track_h}/{af.track_v} | {int((af.track_h < H).sum())} / "
              f"{int((af.track_v < V).sum())} | {per_run:.2f}", flush=True)  # fmt: skip

    for name in args.classes:
        hm: list[float] = []
        vm: list[float] = []
        sh: list[np.ndarray] = []
        sv: list[np.ndarray] = []
        refs = tuple(args.scenario or CLASSES[name])
        for ref in refs:
            with tempfile.TemporaryDirectory() as tmp:
                out = Path(tmp)
                flown = default_variant(ref, out) if args.plans == "default" else ref
                cmd = ["plan", flown, "--seed", str(args.seed), "--out", str(out / "plan")]
                if "@" in ref:  # a generated fleet: PPSwarm with one restart, as they are made
                    cmd += ["-a", "ppswarm", "--param", "n_restart=1"]
                r = CliRunner().invoke(app, cmd + (["--nominal"] if args.plans == "nominal"
                                                   else []))  # fmt: skip
                if r.exit_code not in (0, 1):
                    raise SystemExit(f"uavplan plan {flown} failed: {r.output}")
                pf = read_plan_file(out / "plan" / "plan.json")
                scenario = resolve(flown)
            af = AIRFRAMES[name]
            h1: list[float] = []
            v1: list[float] = []
            s1h: list[np.ndarray] = []
            s1v: list[np.ndarray] = []
            t = time.perf_counter()
            for run in range(args.runs):
                ex = simulate_once(pf, scenario, 1000 * args.seed + run, cond, af)
                h1 += [x for x in ex.track_h.values() if math.isfinite(x)]
                v1 += [x for x in ex.track_v.values() if math.isfinite(x)]
                s1h.append(ex.samples_h)
                s1v.append(np.abs(ex.samples_v))
            per_run = (time.perf_counter() - t) / args.runs
            label = ref if flown == ref else f"{ref} (default model)"
            row(name, label, np.asarray(h1), np.asarray(v1), s1h, s1v, per_run)
            hm += h1
            vm += v1
            sh += s1h
            sv += s1v
        H, V = np.asarray(hm), np.asarray(vm)
        if len(refs) > 1:
            row(name, "all, pooled", H, V, sh, sv, math.nan)
        saved[f"h_{name}"], saved[f"v_{name}"] = H, V
    if args.save is not None:
        np.savez(args.save, **saved)


if __name__ == "__main__":
    main()
