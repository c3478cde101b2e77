"""Not a paper: the experiment runner's own overhead, measured on many short PSO runs on the 10-D
sphere function (``benchmarks/runner_overhead.py`` reports it)."""

from __future__ import annotations

from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, register_plan

register_plan(
    ExperimentPlan(
        name="overhead",
        description=(
            "Runner overhead benchmark: many short PSO runs on the 10-D sphere function "
            "(paper scale: 10,000 runs)"
        ),
        scenarios=("sphere10",),
        algorithms=(Algorithm("pso", "pso"),),
        scales={
            "smoke": Scale(runs=40, iterations=20, pop_size=20),
            "paper": Scale(runs=10_000, iterations=200, pop_size=40),
        },
        kind="function",
        reference="pso",
    )
)
