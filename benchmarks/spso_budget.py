"""PSO, DE, GA and SPSO at SPSO's budget on the SPSO benchmark scenario, over 10 seeds, and where
their time goes.

Run: ``NUMBA_NUM_THREADS=1 python benchmarks/spso_budget.py [--seeds 10] [--algorithms pso de]``

Budget as in Phung & Ha 2021: 500 individuals x 200 iterations, 10 free waypoints (SPSO on its
spherical encoding, the others on the Cartesian one), SPSO's published cost (5 J1 + J2 + 10 J3 +
J4), feasibility tracked as the experiments track it. Prints, per algorithm: how many runs ended
with a finite cost, how many with a feasible path (decided on continuous segments, which SPSO's
cost does not check between waypoints), mean / best / worst cost over the finite runs, the mean
wall time per run and the mean CPU time of this thread per run (the wall time of a shared
machine includes the other processes' turns), and the share of that CPU time spent:

* ``kernels``: in the cost and validity kernels (the population kernels of
  :mod:`uavplan.kernel_builds`) and the encoding's decoding kernel, i.e. evaluating;
* ``outside``: everything else (the optimizer's own work, its move kernel included, and the
  Python around it): what the issue's "at most 20 % of a run outside the kernels" measures.

With more than one Numba thread the CPU time is this thread's only (the kernels' worker threads
are not counted): read the wall time then.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

import uavplan.problems.encoding as encoding
from uavplan.kernel_builds import PopulationKernel
from uavplan.planners import get_planner
from uavplan.scenarios import load_builtin


class KernelClock:
    """Adds up the thread CPU time spent in the population kernels and the decoding kernel."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.depth = 0

    def timed(self, f: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any) -> Any:
            if self.depth:  # a kernel called from a timed kernel's wrapper: counted already
                return f(*args)
            self.depth += 1
            t0 = time.thread_time()
            try:
                return f(*args)
            finally:
                self.seconds += time.thread_time() - t0
                self.depth -= 1

        return call

    def install(self) -> None:
        original = PopulationKernel.__call__
        PopulationKernel.__call__ = self.timed(original)  # type: ignore[method-assign]
        # the decoding kernel (clipped_cumsum where an older tree has no decode_kernel)
        name = "decode_kernel" if hasattr(encoding, "decode_kernel") else "clipped_cumsum"
        setattr(encoding, name, self.timed(getattr(encoding, name)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--algorithms", nargs="+", default=["pso", "de", "ga", "spso"])
    ap.add_argument("--pop-size", type=int, default=500)
    ap.add_argument("--iterations", type=int, default=200)
    args = ap.parse_args()
    clock = KernelClock()
    clock.install()
    sc = load_builtin("spso")
    print(
        f"SPSO scenario, {args.pop_size} x {args.iterations}, {args.seeds} seeds, "
        f"{os.cpu_count()} cores, {numba.get_num_threads()} Numba threads"
    )
    print(
        f"{'algorithm':>9} {'finite':>6} {'feasible':>8} {'mean':>10} {'best':>10} {'worst':>10}"
        f" {'s/run':>7} {'cpu s':>7} {'kernels':>8} {'outside':>8}"
    )
    for alg in args.algorithms:
        planner = get_planner(alg, pop_size=args.pop_size)
        planner.plan(sc, budget=2, seed=0)  # JIT warm-up, not timed
        costs, feas, times = [], [], []
        clock.seconds = 0.0
        cpu0 = time.thread_time()
        for seed in range(args.seeds):
            r = planner.plan(sc, budget=args.iterations, seed=seed)
            costs.append(r.cost)
            feas.append(r.feasible)
            times.append(r.wall_time)
        cpu = time.thread_time() - cpu0
        c = np.array(costs)
        fin = c[np.isfinite(c)]
        stats = (
            f"{fin.mean():10.1f} {fin.min():10.1f} {fin.max():10.1f}"
            if len(fin)
            else f"{'-':>10} {'-':>10} {'-':>10}"
        )
        inside = clock.seconds / cpu
        print(
            f"{alg:>9} {len(fin):>6} {sum(feas):>8} {stats} {np.mean(times):7.3f}"
            f" {cpu / args.seeds:7.3f} {inside:8.1%} {1 - inside:8.1%}"
        )


if __name__ == "__main__":
    main()
