"""A simulated execution's errors against its plan: the Numba kernels against the NumPy
references, on the tracks of one execution.

Run: ``python benchmarks/sim_errors.py PLAN SCENARIO [--seed 1] [--repeats 3]``, or without
PLAN and SCENARIO on a small fleet planned here (``ppswarm1@40``, 8 iterations).

Per track, :func:`uavplan.sim.runs.errors_against` (the nearest point of the plan within the
time window) and :func:`uavplan.sim.runs.conformance` (the schedule lag and the excess over
the execution model) are timed against their references (``errors_against_reference``,
``conformance_reference``) in this one run (best of ``--repeats``; the machine is shared),
with whether the answers agree. It prints the seconds per execution of each and the ratio.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from _timing import best_time
from uavplan.io.plan_file import read_plan_file
from uavplan.scenarios import resolve
from uavplan.sim.runs import (
    conformance,
    conformance_reference,
    errors_against,
    errors_against_reference,
    simulate_once,
)
from uavplan.world.execution import ExecutionModel


def small_plan(folder: Path) -> tuple[Path, str]:
    from typer.testing import CliRunner

    from uavplan.cli import app

    r = CliRunner().invoke(app, ["plan", "ppswarm1@40", "-a", "ppswarm", "--param", "n_restart=1",
                                 "--iterations", "8", "--out", str(folder)])  # fmt: skip
    if r.exit_code != 0:
        raise SystemExit(r.output)
    return folder / "plan.json", "ppswarm1@40"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plan", nargs="?")
    ap.add_argument("scenario", nargs="?")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path, ref = (Path(a.plan), a.scenario) if a.plan else small_plan(Path(tmp))
        plan = read_plan_file(path)
        sc = resolve(ref)
        model = ExecutionModel.from_record(plan.execution) if plan.execution else None
        d0, rho = model.timing(float(sc.uav.speed)) if model else (0.0, 0.0)
        eh, ev = (model.track_h, model.track_v) if model else (1.0, 1.0)
        ex = simulate_once(plan, sc, a.seed)
        pairs = list(zip(ex.tracks, plan.trajectories("flown"), strict=True))

        def run(err, conf):  # type: ignore[no-untyped-def]
            return lambda: [(err(tr, pl), conf(tr, pl, d0, rho, eh, ev)) for tr, pl in pairs]

        fast = run(errors_against, conformance)
        ref_ = run(errors_against_reference, conformance_reference)
        agree = True
        for (e1, c1), (e2, c2) in zip(fast(), ref_(), strict=True):
            agree &= all(np.allclose(x, y, rtol=0, atol=1e-9) for x, y in zip(e1, e2, strict=True))
            agree &= bool(np.array_equal(c1[0], c2[0]))
        t_fast = best_time(fast, a.repeats)
        t_ref = best_time(ref_, a.repeats)
    samples = sum(len(tr.times) for tr, _ in pairs)
    print(f"{ref}: {len(pairs)} tracks, {samples} samples, seed {a.seed}")
    print(f"  NumPy references: {t_ref:.3f} s per execution")
    print(f"  Numba kernels:    {t_fast:.3f} s per execution")
    print(f"  ratio: {t_ref / t_fast:.1f}x; answers agree: {'yes' if agree else 'NO'}")


if __name__ == "__main__":
    main()
