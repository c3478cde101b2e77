"""RSCDWOA (Zhang et al.): the benchmark functions f1-f9 of its Table 4 (30-D, 30 agents, the
evaluations of 100 iterations, 30 runs) against WOA, PSO, GA, DE, GWO and ABC, with Wilcoxon
rank-sum tests (its Table 5) in the generic report. The multi-UAV application with the
artificial potential field is not yet here (a later issue).
"""

from __future__ import annotations

from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, register_plan

register_plan(
    ExperimentPlan(
        name="functions",
        description=(
            "RSCDWOA (tent map; and the logistic map) vs WOA, PSO, GA, DE, GWO, ABC on f1-f9 "
            "of RSCDWOA Table 4, 30-D, 30 agents, the evaluations of 100 iterations"
        ),
        scenarios=tuple(f"f{i}" for i in range(1, 10)),
        algorithms=(
            Algorithm("rscdwoa", "rscdwoa", {"max_iterations": 100}),
            Algorithm("rscdwoa-logistic", "rscdwoa", {"max_iterations": 100, "chaos": "logistic"}),
            Algorithm("woa", "woa", {"max_iterations": 100}),
            Algorithm("pso", "pso"),
            Algorithm("ga", "ga"),
            Algorithm("de", "de"),
            Algorithm("gwo", "gwo", {"max_iterations": 100}),
            Algorithm("abc", "abc"),
        ),
        scales={
            "smoke": Scale(runs=2, iterations=10, pop_size=30, evaluations=330),
            "paper": Scale(runs=30, iterations=100, pop_size=30, evaluations=3030),
        },
        kind="function",
        reference="rscdwoa",
    )
)
