"""APF steps per second per UAV (issue 15's figure: at least 10,000), against the same field
and motion stepped in NumPy (``force_reference``) measured in the same run.

Per layout (``rscdwoa-static``, ``rscdwoa-mixed``): the Numba loop's steps per second over one
UAV's whole flight, and the NumPy reference's over its first ``--ref-steps`` steps; the ratio.
Also the fused planner's flights per second (a flight plus its exact check).
Run: ``python benchmarks/apf_speed.py [--ref-steps 300]``; ``NUMBA_NUM_THREADS=1`` on a shared
machine.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from uavplan.planners import get_planner
from uavplan.planners.potential.apf import field_params, fly_field, force_reference
from uavplan.scenarios import resolve


def reference_steps(sc, prm, start, goal, n):  # type: ignore[no-untyped-def]
    """``n`` steps of the motion of :func:`fly_field` with the NumPy force (no stall/arrival)."""
    p = np.array(start, dtype=float)
    psi = math.atan2(goal[1] - p[1], goal[0] - p[0])
    gam, t = 0.0, 0.0
    step = prm.v * prm.dt
    for _ in range(n):
        vel = prm.v * np.array([math.cos(gam) * math.cos(psi), math.cos(gam) * math.sin(psi),
                                math.sin(gam)])  # fmt: skip
        F = force_reference(sc, prm, p, vel, t, goal)
        gam_new = min(max(math.atan2(F[2], math.hypot(F[0], F[1])), -prm.descent), prm.climb)
        dpsi = prm.turn_k * step * min(math.cos(gam), math.cos(gam_new))
        turn = (math.atan2(F[1], F[0]) - psi + math.pi) % (2 * math.pi) - math.pi
        psi += min(max(turn, -dpsi), dpsi)
        gam = gam_new
        p = p + step * np.array([math.cos(gam) * math.cos(psi), math.cos(gam) * math.sin(psi),
                                 math.sin(gam)])  # fmt: skip
        t += prm.dt
    return p


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref-steps", type=int, default=300)
    args = ap.parse_args()
    head = ("layout", "numba steps/s", "numpy steps/s", "ratio", "flights/s")
    print(f"{head[0]:16} {head[1]:>14} {head[2]:>14} {head[3]:>7} {head[4]:>10}")
    for name in ("rscdwoa-static", "rscdwoa-mixed"):
        sc = resolve(name)
        task = sc.tasks[0]
        s, g = np.asarray(task.start, float), np.asarray(task.goal, float)
        prm = field_params(get_planner("apf").config, sc, float(np.linalg.norm(g - s)))
        fly_field(sc, s, g, prm, 10)  # compile
        t0 = time.perf_counter()
        reps = 0
        steps = 0
        while time.perf_counter() - t0 < 1.0:
            steps += fly_field(sc, s, g, prm, 20_000).steps
            reps += 1
        fast = steps / (time.perf_counter() - t0)
        t0 = time.perf_counter()
        reference_steps(sc, prm, s, g, args.ref_steps)
        slow = args.ref_steps / (time.perf_counter() - t0)
        fused = get_planner("rscdwoa-apf", pop_size=10)
        fused.plan(sc, task, budget=1, seed=0)  # compile
        t0 = time.perf_counter()
        r = fused.plan(sc, task, budget=3, seed=0)
        fps = r.evaluations / (time.perf_counter() - t0)
        print(f"{name:16} {fast:14,.0f} {slow:14,.0f} {fast / slow:7.0f} {fps:10.1f}")


if __name__ == "__main__":
    main()
