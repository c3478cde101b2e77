"""SPSO (Phung & Ha, "Safety-enhanced UAV path planning with spherical vector-based particle swarm
optimization", Applied Soft Computing 107, 2021): its benchmark scenario (the ChrismasTerrain DEM,
six threats, SPSO's cost) and budget (500 particles x 200 iterations), 20 runs, with the
optimizers of this package as rivals.
"""

from __future__ import annotations

from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, register_plan

register_plan(
    ExperimentPlan(
        name="spso-small",
        description=(
            "PSO, DE and GA on the SPSO benchmark scenario with SPSO's cost; paper scale uses "
            "SPSO's budget (500 x 200) and 20 runs"
        ),
        scenarios=("spso",),
        algorithms=(
            Algorithm("pso", "pso"),
            Algorithm("de", "de"),
            Algorithm("ga", "ga"),
        ),
        scales={
            "smoke": Scale(runs=3, iterations=15, pop_size=40),
            "paper": Scale(runs=20, iterations=200, pop_size=500),
        },
        reference="pso",
    )
)

register_plan(
    ExperimentPlan(
        name="spso-scenario",
        description=(
            "PSO, SPSO (synchronous and, as the authors' code, asynchronous), GA, DE, ABC, GWO, "
            "WOA, RSCDWOA and MAGA on the SPSO benchmark with SPSO's cost and budget (500 x 200 "
            "evaluations' worth), 20 runs"
        ),
        scenarios=("spso",),
        algorithms=(
            Algorithm("spso", "spso"),
            # the global best replaced particle by particle, as SPSO_MAIN.m does
            Algorithm("spso-async", "spso", {"update": "async"}),
            Algorithm("pso", "pso"),
            Algorithm("ga", "ga"),
            Algorithm("de", "de"),
            Algorithm("abc", "abc"),
            Algorithm("gwo", "gwo", {"max_iterations": 200}),
            Algorithm("woa", "woa", {"max_iterations": 200}),
            Algorithm("rscdwoa", "rscdwoa", {"max_iterations": 200}),
            Algorithm("maga", "maga", {"pop_size": 49}),  # its 7 x 7 lattice (Table I)
        ),
        scales={
            "smoke": Scale(runs=2, iterations=10, pop_size=50, evaluations=550),
            "paper": Scale(runs=20, iterations=200, pop_size=500, evaluations=100_500),
        },
        reference="spso",
    )
)
