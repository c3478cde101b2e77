"""Cross-check against an independent implementation: mealpy's PSO, DE, ABC, GWO and WOA vs ours.

Run: ``pip install mealpy`` (a development-only dependency), then
``python benchmarks/vs_mealpy.py [--runs 10] [--functions f1 ... f9] [--pop 100] [--epochs 100]``

For every function (30-D f1-f9 of RSCDWOA Table 4, the same Python function objects for both
libraries) and every shared algorithm, both implementations get the same hyperparameters where
they map onto each other and the same number of function evaluations (mealpy's ``nfe_counter``
after ``--epochs`` epochs; ours runs with that evaluation budget), over ``--runs`` seeds. Printed:

* final best values (median over runs) side by side, the two-sided Wilcoxon rank-sum p-value
  (Benjamini-Hochberg adjusted over the whole table), Cliff's delta (negative: ours lower) and
  the outcome from our side: ``+`` ours significantly better, ``~`` no significant difference,
  ``-`` ours significantly worse;
* the wall time per function evaluation of each library and the ratio, measured in this run.

mealpy evaluates one solution per call of the objective; ours evaluates a whole population per
call: the time ratio measures exactly that difference in design, on the same work.
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from uavplan.bench import stats
from uavplan.optimizers import Budget, minimize
from uavplan.optimizers.functions import function_problem

# (our name, our overrides, mealpy module attr, mealpy class, mealpy kwargs): same settings
PAIRS: list[tuple[str, dict[str, Any], str, str, dict[str, Any]]] = [
    # mealpy OriginalPSO: w fixed (0.4 default), c1 = c2 = 2.05; ours with the same, no damping
    (
        "pso",
        {"w": 0.4, "w_damp": 1.0, "c1": 2.05, "c2": 2.05},
        "PSO",
        "OriginalPSO",
        {"w": 0.4, "c1": 2.05, "c2": 2.05},
    ),
    # DE/rand/1/bin with F = 0.8, CR = 0.9 in both (mealpy strategy 0)
    ("de", {"F": 0.8, "CR": 0.9}, "DE", "OriginalDE", {"wf": 0.8, "cr": 0.9, "strategy": 0}),
    # ABC: mealpy's pop_size is the number of food sources (ours: pop_size / 2), limit 25 in
    # both. Note mealpy's OriginalABC moves every dimension of a source (phi is a vector), where
    # Karaboga's ABC (ours) moves one random dimension.
    ("abc", {"limit": 25}, "ABC", "OriginalABC", {"n_limits": 25}),
    ("gwo", {}, "GWO", "OriginalGWO", {}),
    ("woa", {}, "WOA", "OriginalWOA", {}),
]


def run_mealpy(
    module: str,
    cls: str,
    kwargs: dict[str, Any],
    f: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    pop: int,
    epochs: int,
    seed: int,
) -> tuple[float, int, float]:
    import mealpy

    opt = getattr(getattr(mealpy, module), cls)(epoch=epochs, pop_size=pop, **kwargs)
    problem = {
        "obj_func": lambda x: float(f(np.asarray(x)[None])[0]),
        "bounds": mealpy.FloatVar(lb=lo.tolist(), ub=hi.tolist()),
        "minmax": "min",
        "log_to": None,
    }
    t0 = time.perf_counter()
    best = opt.solve(problem, seed=seed)
    dt = time.perf_counter() - t0
    return float(best.target.fitness), int(opt.nfe_counter), dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--functions", nargs="+", default=[f"f{i}" for i in range(1, 10)])
    ap.add_argument("--algorithms", nargs="+", default=[p[0] for p in PAIRS])
    ap.add_argument("--pop", type=int, default=100)
    ap.add_argument("--epochs", type=int, default=100)
    args = ap.parse_args()
    warnings.filterwarnings("ignore")
    rows = []
    timing: dict[str, list[float]] = {}
    for fname in args.functions:
        for ours, over, mod, cls, kw in PAIRS:
            if ours not in args.algorithms:
                continue
            for seed in range(args.runs):
                problem = function_problem(fname, noise_seed=seed)
                f_m, nfe, t_m = run_mealpy(
                    mod,
                    cls,
                    kw,
                    problem.f,
                    problem.lower,
                    problem.upper,
                    args.pop,
                    args.epochs,
                    seed,
                )
                overrides = dict(over)
                if ours in ("gwo", "woa"):
                    overrides["max_iterations"] = max(1, nfe // args.pop - 1)
                problem = function_problem(fname, noise_seed=seed)
                t0 = time.perf_counter()
                r = minimize(
                    problem,
                    ours,
                    Budget(max_evaluations=nfe),
                    seed=seed,
                    pop_size=args.pop,
                    **overrides,
                )
                t_o = time.perf_counter() - t0
                rows.append(
                    {
                        "scenario": fname,
                        "algorithm": f"mealpy-{ours}",
                        "pair": ours,
                        "run_index": seed,
                        "status": "ok",
                        "best_cost": f_m,
                    }
                )
                rows.append(
                    {
                        "scenario": fname,
                        "algorithm": ours,
                        "pair": ours,
                        "run_index": seed,
                        "status": "ok",
                        "best_cost": r.f,
                    }
                )
                timing.setdefault(f"mealpy-{ours}", []).append(t_m / nfe)
                timing.setdefault(ours, []).append(t_o / r.evaluations)
    df = pd.DataFrame(rows)
    out = []
    for ours in dict.fromkeys(df["pair"]):
        sub = df[df["pair"] == ours]
        cmp = stats.compare_to_reference(
            sub, ours, "best_cost", by="scenario", test="ranksum", correction="none"
        )
        out.append(cmp)
    table = pd.concat(out, ignore_index=True)
    table["p_adjusted"] = stats.bh_adjust(table["p"].to_numpy())
    sig = table["p_adjusted"] < 0.05
    table["outcome"] = np.where(
        sig & (table["effect_size"] < 0), "+", np.where(sig & (table["effect_size"] > 0), "-", "~")
    )
    pd.set_option("display.width", 200)
    show = table[
        [
            "scenario",
            "reference",
            "median_reference",
            "median_algorithm",
            "p_adjusted",
            "effect_size",
            "outcome",
        ]
    ].rename(
        columns={
            "reference": "ours",
            "median_reference": "median ours",
            "median_algorithm": "median mealpy",
        }
    )
    print(
        f"{args.runs} runs, pop {args.pop}, {args.epochs} mealpy epochs, same evaluations; "
        "outcome from our side (+ ours better, ~ same, - ours worse)"
    )
    print(show.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    print("\n+/~/- per algorithm (ours vs mealpy):")
    for ours, g in table.groupby("reference", sort=False):
        c = g["outcome"].value_counts()
        print(f"  {ours:>4}: {c.get('+', 0)}/{c.get('~', 0)}/{c.get('-', 0)}")
    print("\ntime per evaluation (mean over runs):")
    for ours in dict.fromkeys(df["pair"]):
        a = float(np.mean(timing[ours]))
        b = float(np.mean(timing[f"mealpy-{ours}"]))
        print(f"  {ours:>4}: ours {a * 1e6:8.2f} us, mealpy {b * 1e6:8.2f} us -> ours x{b / a:.1f}")


if __name__ == "__main__":
    main()
