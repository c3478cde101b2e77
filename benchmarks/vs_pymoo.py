"""Framework overhead against pymoo: its vectorized PSO, DE and GA and ours on one batched problem.

Run: ``pip install -e ".[peers]"`` (pymoo), then
``NUMBA_NUM_THREADS=1 python benchmarks/vs_pymoo.py [--seeds 5] [--pop 100] [--evaluations 20000]
[--encoding spherical|cartesian] [--rule cost|inf|feasibility-first]``

The problem is the SPSO benchmark scenario's path problem (10 free waypoints, SPSO's cost) on
SPSO's spherical genes under the ``cost`` rule by default (SPSO's problem as its paper poses
it: the cost, infinite on a collision), or on Cartesian genes, or under another constraint rule
(:mod:`uavplan.optimizers.constraints`; ``feasibility-first``: the cost where a path passes
every check, ``1e7 + violation`` elsewhere, a finite number for every path, whose exact checks
make the evaluation itself about ten times dearer): **one object** whose ``evaluate(X (pop,
dim))`` both libraries call with whole populations (pymoo through a ``Problem`` with
``elementwise=False``). A timer
around that call measures the time spent in the shared evaluation; the rest of a run is the
framework's own work. For each algorithm, library and seed, at the same budget of evaluations and
population size, it prints:

* the CPU time of this thread per evaluation, total and without the shared evaluation (the
  framework's overhead; CPU time, because other processes share this machine's cores);
* the best value found; then per algorithm the medians over the seeds, pymoo's time per
  evaluation over ours (total and overhead alone) and the two-sided Wilcoxon rank-sum p-value
  of the final values (with few seeds only a large difference can show).

Settings: pymoo's PSO as it comes (adaptive inertia, its velocity rules; ours: SPSO's/RGG-PSO+'s
``w = 1`` damped by 0.98, ``c1 = c2 = 1.5``); pymoo's DE as ``DE/rand/1/bin`` with ``F = 0.8``,
``CR = 0.9`` and no dither (ours); pymoo's GA with its SBX crossover and polynomial mutation and
without duplicate elimination (ours has none; it would only add to pymoo's time). The
algorithms differ in their operators, so the final values compare the libraries' algorithms as
they are, at one budget.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from uavplan.optimizers import Budget, minimize
from uavplan.optimizers.constraints import RULES, Constrained
from uavplan.problems import PathProblem
from uavplan.problems.encoding import ENCODINGS
from uavplan.scenarios import load_builtin


class Timed:
    """The shared problem: counts evaluations and the CPU time spent evaluating."""

    def __init__(self, objective: Constrained) -> None:
        self.objective = objective
        self.dim, self.lower, self.upper = objective.dim, objective.lower, objective.upper
        self.block = objective.block
        self.seconds = 0.0
        self.evaluations = 0

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        t0 = time.thread_time()
        f = self.objective.evaluate(np.asarray(X, dtype=np.float64))
        self.seconds += time.thread_time() - t0
        self.evaluations += len(X)
        return f


def pymoo_run(name: str, problem: Timed, pop: int, evaluations: int, seed: int) -> float:
    from pymoo.algorithms.soo.nonconvex.de import DE
    from pymoo.algorithms.soo.nonconvex.ga import GA
    from pymoo.algorithms.soo.nonconvex.pso import PSO
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize as pymoo_minimize

    class Shared(Problem):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__(n_var=problem.dim, n_obj=1, xl=problem.lower, xu=problem.upper,
                             elementwise=False)  # fmt: skip

        def _evaluate(self, X: np.ndarray, out: dict[str, Any], *args: Any, **kw: Any) -> None:
            out["F"] = problem.evaluate(X)

    algorithm = {
        "pso": lambda: PSO(pop_size=pop),
        "de": lambda: DE(pop_size=pop, variant="DE/rand/1/bin", F=0.8, CR=0.9, dither="no"),
        "ga": lambda: GA(pop_size=pop, eliminate_duplicates=False),
    }[name]()
    res = pymoo_minimize(Shared(), algorithm, ("n_evals", evaluations), seed=seed, verbose=False)
    return float(np.min(res.F))


def ours_run(name: str, problem: Timed, pop: int, evaluations: int, seed: int) -> float:
    res = minimize(problem, name, Budget(max_evaluations=evaluations), seed=seed, pop_size=pop)
    return float(res.f)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--pop", type=int, default=100)
    ap.add_argument("--evaluations", type=int, default=20_000)
    ap.add_argument("--algorithms", nargs="+", default=["pso", "de", "ga"])
    ap.add_argument("--rule", default="cost", choices=RULES)
    ap.add_argument("--encoding", default="spherical", choices=sorted(ENCODINGS))
    args = ap.parse_args()
    from scipy.stats import ranksums

    enc = ENCODINGS[args.encoding](PathProblem(load_builtin("spso")))
    objective = Constrained(enc, args.rule)
    Timed(objective).evaluate(enc.lower[None] + 0.5 * (enc.upper - enc.lower))  # compile
    print(f"SPSO scenario, {args.encoding} genes ({enc.dim}), rule {args.rule}, population "
          f"{args.pop}, {args.evaluations:,} evaluations, seeds 0..{args.seeds - 1}; "
          "CPU microseconds per evaluation")  # fmt: skip
    print(f"{'algorithm':>9} {'library':>7} {'seed':>4} {'total':>8} {'overhead':>9} {'best':>12}")
    runs = {"ours": ours_run, "pymoo": pymoo_run}
    summary = []
    for alg in args.algorithms:
        got: dict[str, dict[str, list[float]]] = {}
        for lib, run in runs.items():
            run(alg, Timed(objective), args.pop, 2 * args.pop, 0)  # warm-up
            rec = got.setdefault(lib, {"total": [], "overhead": [], "best": []})
            for seed in range(args.seeds):
                p = Timed(objective)
                t0 = time.thread_time()
                best = run(alg, p, args.pop, args.evaluations, seed)
                cpu = time.thread_time() - t0
                total, over = cpu / p.evaluations * 1e6, (cpu - p.seconds) / p.evaluations * 1e6
                rec["total"].append(total)
                rec["overhead"].append(over)
                rec["best"].append(best)
                print(f"{alg:>9} {lib:>7} {seed:>4} {total:8.2f} {over:9.2f} {best:12.1f}")
        med = {lib: {k: float(np.median(v)) for k, v in r.items()} for lib, r in got.items()}
        p = float(ranksums(got["ours"]["best"], got["pymoo"]["best"]).pvalue)
        summary.append((alg, med, p))
    print("\nmedians over the seeds; ratio = pymoo / ours")
    head = ("algorithm", "total ours", "pymoo", "ratio", "overhead ours", "pymoo", "ratio",
            "best ours", "pymoo", "rank-sum p")  # fmt: skip
    widths = (9, 10, 8, 6, 13, 8, 7, 11, 11, 10)
    print(" ".join(f"{h:>{w}}" for h, w in zip(head, widths, strict=True)))
    for alg, m, p in summary:
        o, q = m["ours"], m["pymoo"]
        print(f"{alg:>9} {o['total']:10.2f} {q['total']:8.2f} {q['total'] / o['total']:6.1f}"
              f" {o['overhead']:13.2f} {q['overhead']:8.2f} {q['overhead'] / o['overhead']:7.1f}"
              f" {o['best']:11.1f} {q['best']:11.1f} {p:10.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
