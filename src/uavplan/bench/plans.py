"""Experiment plans as code: a plan yields runs (scenario x algorithm configuration x run index).

Seeds derive from ``numpy.random.SeedSequence`` keyed on (root seed; plan, scenario, algorithm,
run index), so a run's result is the same whichever executor runs it and in whatever order.
A :class:`RunSpec` is plain picklable data: a worker process, or a Dask worker on another
machine, rebuilds everything it needs from it (built-in scenarios and registered planners by
name).
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

SCALES = ("smoke", "paper")


class PlanError(ValueError):
    """An unknown plan or scale, or bad overrides."""


def derive_seed(root_seed: int, plan: str, scenario: str, algorithm: str, run_index: int) -> int:
    """A 63-bit seed for one run, independent of execution order and executor."""
    key = [zlib.crc32(s.encode()) for s in (plan, scenario, algorithm)] + [int(run_index)]
    ss = np.random.SeedSequence(entropy=int(root_seed), spawn_key=tuple(key))
    return int(ss.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


@dataclass(frozen=True)
class RunSpec:
    """One run to execute: who, what, with which seed, and the kind-specific ``params``."""

    plan: str
    scale: str
    scenario: str
    algorithm: str
    run_index: int
    seed: int
    root_seed: int
    kind: str
    params: Mapping[str, Any] = field(default_factory=dict)

    @property
    def run_id(self) -> str:
        return f"{self.plan}/{self.scale}/{self.scenario}/{self.algorithm}/{self.run_index}"


@dataclass(frozen=True)
class Algorithm:
    """An algorithm configuration in a plan: a label, a registered planner name, its options."""

    label: str
    planner: str
    options: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Scale:
    """How big a plan runs: runs per cell and the budget (iterations, or, when ``evaluations``
    is set, function evaluations: the fair budget between algorithms whose iterations cost
    different numbers of evaluations)."""

    runs: int
    iterations: int
    pop_size: int | None = None
    evaluations: int | None = None
    scenarios: tuple[str, ...] | None = None  # this scale's scenarios (default: the plan's)
    options: Mapping[str, Any] = field(default_factory=dict)  # override every algorithm's


@dataclass(frozen=True)
class ExperimentPlan:
    """A grid of scenarios x algorithms x runs, run by the planner registry.

    Args:
        name, description: shown by ``uavplan bench list``.
        scenarios: built-in scenario names or scenario file paths.
        algorithms: the configurations compared.
        scales: at least ``smoke`` (CI) and ``paper`` (the full experiment).
        kind: how a run is executed (see :mod:`uavplan.bench.execute`).
        reference: the algorithm label statistics compare against.
    """

    name: str
    description: str
    scenarios: tuple[str, ...]
    algorithms: tuple[Algorithm, ...]
    scales: Mapping[str, Scale]
    kind: str = "planner"
    reference: str | None = None
    metric: str = "best_cost"

    def runs(
        self,
        scale: str = "smoke",
        runs: int | None = None,
        root_seed: int = 0,
        iterations: int | None = None,
    ) -> list[RunSpec]:
        """Every run of this plan at ``scale`` (``runs``/``iterations`` override the scale)."""
        if scale not in self.scales:
            raise PlanError(
                f"plan {self.name!r} has no scale {scale!r}; choose {list(self.scales)}"
            )
        sc = self.scales[scale]
        n_runs = sc.runs if runs is None else runs
        if n_runs < 1:
            raise PlanError(f"--runs must be >= 1, got {n_runs}")
        n_iter = sc.iterations if iterations is None else iterations
        out = []
        for scenario in sc.scenarios or self.scenarios:
            for alg in self.algorithms:
                options = dict(alg.options)
                if sc.pop_size is not None and "pop_size" not in options:
                    options["pop_size"] = sc.pop_size
                options.update(sc.options)
                for i in range(n_runs):
                    out.append(
                        RunSpec(
                            plan=self.name,
                            scale=scale,
                            scenario=scenario,
                            algorithm=alg.label,
                            run_index=i,
                            seed=derive_seed(root_seed, self.name, scenario, alg.label, i),
                            root_seed=root_seed,
                            kind=self.kind,
                            params={
                                "planner": alg.planner,
                                "options": options,
                                "iterations": n_iter,
                                "evaluations": None if iterations is not None else sc.evaluations,
                            },
                        )
                    )
        return out


_PLANS: dict[str, ExperimentPlan] = {}
_FACTORIES: list[Callable[[], list[ExperimentPlan]]] = []


def register_plan(plan: ExperimentPlan) -> ExperimentPlan:
    if plan.name in _PLANS:
        raise PlanError(f"plan {plan.name!r} is already registered")
    for s in ("smoke", "paper"):
        if s not in plan.scales:
            raise PlanError(f"plan {plan.name!r} needs a {s!r} scale")
    _PLANS[plan.name] = plan
    return plan


def available_plans() -> list[str]:
    _load_builtins()
    return sorted(_PLANS)


def get_plan(name: str) -> ExperimentPlan:
    _load_builtins()
    try:
        return _PLANS[name]
    except KeyError:
        raise PlanError(f"unknown plan {name!r}; available: {sorted(_PLANS)}") from None


_loaded = False


def _load_builtins() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    for p in builtin_plans():
        if p.name not in _PLANS:
            register_plan(p)


def builtin_plans() -> list[ExperimentPlan]:
    """The plans shipped with uavplan."""
    return [
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
        ),
        ExperimentPlan(
            name="functions",
            description=(
                "RSCDWOA (tent map; and the logistic map) vs WOA, PSO, GA, DE, GWO, ABC on f1-f9 "
                "of RSCDWOA Table 4, 30-D, 30 agents, the evaluations of 100 iterations"
            ),
            scenarios=tuple(f"f{i}" for i in range(1, 10)),
            algorithms=(
                Algorithm("rscdwoa", "rscdwoa", {"max_iterations": 100}),
                Algorithm(
                    "rscdwoa-logistic", "rscdwoa", {"max_iterations": 100, "chaos": "logistic"}
                ),
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
        ),
        ExperimentPlan(
            name="spso-scenario",
            description=(
                "PSO, SPSO, GA, DE, ABC, GWO, WOA, RSCDWOA and MAGA on the SPSO benchmark with "
                "SPSO's cost and budget (500 x 200 evaluations' worth), 20 runs"
            ),
            scenarios=("spso",),
            algorithms=(
                Algorithm("spso", "spso"),
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
        ),
        *_rggpso_plans(),
        *_ppswarm_plans(),
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
        ),
    ]


def _rggpso_plans() -> list[ExperimentPlan]:
    """RGG-PSO+ (Liu et al. 2024) Sect. 5: 1000 scenes x 10 runs, 100 particles, 200 iterations,
    N = 20 waypoints (the scenes' default); smoke scale: two scenes, one run, a small budget."""
    from uavplan.scenarios.generators import family_names

    paper_scenes = tuple(family_names())
    smoke_scenes = ("rgg-n05-i000", "rgg-n14-i000")
    scales = {
        "smoke": Scale(runs=1, iterations=15, pop_size=20, scenarios=smoke_scenes),
        "paper": Scale(runs=10, iterations=200, pop_size=100, scenarios=paper_scenes),
    }

    def alg(label: str) -> Algorithm:
        return Algorithm(label, label)

    return [
        ExperimentPlan(
            name="rggpso-rq1",
            description=(
                "RGG-PSO+ vs RGG-PSO, PSO, SPSO, GA, DE on the 1000-scene family, 10 runs: best "
                "normalized path length over iterations (Fig. 5)"
            ),
            scenarios=smoke_scenes,
            algorithms=tuple(alg(a) for a in ("rgg-pso+", "rgg-pso", "pso", "spso", "ga", "de")),
            scales=scales,
            reference="rgg-pso+",
            metric="path_length",
        ),
        ExperimentPlan(
            name="rggpso-rq2",
            description=(
                "RGG-PSO vs PSO: F-Measure (iterations before the first feasible particle) and "
                "the first feasible path's normalized length (Table 1)"
            ),
            scenarios=smoke_scenes,
            algorithms=(alg("rgg-pso"), alg("pso")),
            scales=scales,
            reference="rgg-pso",
            metric="path_length",
        ),
        ExperimentPlan(
            name="rggpso-rq3",
            description="RGG-PSO+ vs RGG-PSO vs PSO final normalized lengths (Table 2)",
            scenarios=smoke_scenes,
            algorithms=(alg("rgg-pso+"), alg("rgg-pso"), alg("pso")),
            scales=scales,
            reference="rgg-pso+",
            metric="path_length",
        ),
    ]


def _ppswarm_plans() -> list[ExperimentPlan]:
    """PPSwarm (Meng, Chen & Qu 2024) Sect. 5 on our four scenarios (``ppswarm1``-``4``, 40 UAVs;
    ``NAME@N`` is the same world with a generated fleet of N UAVs). Each configuration runs with
    its own ``N_iter`` (a scale's ``iterations = 0``); the smoke scale runs 4 UAVs with a tiny
    budget. Every fleet plan is checked by the independent verifier."""
    table2 = {  # Table 2: the baselines under LH prioritized planning, N_pop 300, N_iter 100
        "pso": {"optimizer": "pso", "w": 0.8, "c1": 1.45, "c2": 1.5},
        "de": {"optimizer": "de", "F": 0.8, "CR": 0.9},
        # ABC: one of our iterations is one phase, so 100 cycles are 201 iterations
        "abc": {"optimizer": "abc", "n_iter": 201},
        "gwo": {"optimizer": "gwo", "max_iterations": 100},
        "spso": {"optimizer": "spso", "w": 1.0, "c1": 1.5, "c2": 1.5},
    }
    scen4 = tuple(f"ppswarm{i}" for i in range(1, 5))
    smoke = Scale(
        runs=1,
        iterations=3,
        pop_size=12,
        scenarios=("ppswarm1@4",),
        options={"pop_size": 12, "rrt_iterations": 1500},
    )
    smoke_params = Scale(
        runs=1,
        iterations=2,
        scenarios=("ppswarm1@3",),
        options={"pop_size": 8, "n_restart": 2, "rrt_iterations": 1500},
    )
    plans = [
        ExperimentPlan(
            name="ppswarm-table3",
            description=(
                "PPSwarm vs PSO, DE, ABC, GWO, SPSO (LH prioritized planning), 40 UAVs, four "
                "scenarios, 20 runs: best/worst/mean/std cost and runtime (Table 3), "
                "convergence (Fig. 5), box plots (Fig. 6)"
            ),
            scenarios=scen4,
            # graded infeasibility for every method: with the literal infinite costs of Sect. 2
            # the uniformly seeded baselines end with most UAVs infeasible (see
            # uavplan.planners.prioritized); feasible paths still cost exactly F
            algorithms=(
                Algorithm("ppswarm", "ppswarm", {"constraints": "feasibility-first"}),
                *(
                    Algorithm(k, "prioritized", {**v, "constraints": "feasibility-first"})
                    for k, v in table2.items()
                ),
            ),
            scales={"smoke": smoke, "paper": Scale(runs=20, iterations=0, pop_size=300)},
            kind="fleet",
            reference="ppswarm",
        ),
        ExperimentPlan(
            name="ppswarm-table4",
            description=(
                "PPSwarm scalability on scenario 1: 40-500 UAVs with N_restart = 1 and 5 "
                "(Table 4, Fig. 7)"
            ),
            scenarios=tuple(f"ppswarm1@{n}" for n in (40, 100, 200, 300, 400, 500)),
            algorithms=(
                Algorithm("ppswarm-r1", "ppswarm", {"n_restart": 1}),
                Algorithm("ppswarm-r5", "ppswarm", {"n_restart": 5}),
                # ours, not the paper's: UAVs blocked at take-off may wait up to 12 x 5 s
                Algorithm("ppswarm-r1-wait", "ppswarm", {"n_restart": 1, "max_delays": 12}),
            ),
            scales={"smoke": smoke, "paper": Scale(runs=1, iterations=0, pop_size=300)},
            kind="fleet",
            reference="ppswarm-r5",
        ),
        ExperimentPlan(
            name="ppswarm-table5",
            description=(
                "Priority orders LH vs SH vs RND with 10, 20, 30, 40 UAVs on the four "
                "scenarios, 20 runs (Table 5)"
            ),
            scenarios=tuple(f"{s}@{n}" for s in scen4 for n in (10, 20, 30, 40)),
            algorithms=tuple(
                Algorithm(f"ppswarm-{o}", "ppswarm", {"order": o}) for o in ("lh", "sh", "rnd")
            ),
            scales={"smoke": smoke, "paper": Scale(runs=20, iterations=0, pop_size=300)},
            kind="fleet",
            reference="ppswarm-lh",
        ),
        ExperimentPlan(
            name="ppswarm-params",
            description=(
                "Sect. 5.3.3 parameter analysis on scenario 1 (10 UAVs), 30 restarts: N_iter "
                "20/40/60 with N_pop 100 and 300 and rho 0 (Fig. 9); rho 0-60 % (Fig. 10)"
            ),
            scenarios=("ppswarm1@10",),
            algorithms=(
                *(
                    Algorithm(
                        f"pop{p}-iter{it}-rho0",
                        "ppswarm",
                        {"pop_size": p, "n_iter": it, "rho": 0.0, "n_restart": 30},
                    )
                    for p in (100, 300)
                    for it in (20, 40, 60)
                ),
                *(
                    Algorithm(
                        f"pop{p}-iter{it}-rho{int(r * 100)}",
                        "ppswarm",
                        {"pop_size": p, "n_iter": it, "rho": r, "n_restart": 30},
                    )
                    for p, it in ((100, 20), (300, 20), (300, 40), (300, 60))
                    for r in (0.2, 0.4, 0.6)
                ),
            ),
            scales={"smoke": smoke_params, "paper": Scale(runs=20, iterations=0)},
            kind="fleet",
            reference="pop300-iter20-rho20",
        ),
    ]
    return plans
