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


class PlanError(ValueError):
    """An unknown plan or scale, or bad overrides."""


def derive_seed(root_seed: int, plan: str, scenario: str, algorithm: str, run_index: int) -> int:
    """A 63-bit seed for one run, independent of execution order and executor."""
    key = [zlib.crc32(s.encode()) for s in (plan, scenario, algorithm)] + [int(run_index)]
    ss = np.random.SeedSequence(entropy=int(root_seed), spawn_key=tuple(key))
    return int(ss.generate_state(1, dtype=np.uint64)[0]) >> 1


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
    """An algorithm configuration in a plan: a label, a registered planner name, its options,
    and per scale an iteration budget of its own (``iterations``, e.g. a paper's protocol
    that gives each algorithm its own generations; the scale's evaluation budget then does not
    apply to it), else the scale's."""

    label: str
    planner: str
    options: Mapping[str, Any] = field(default_factory=dict)
    iterations: Mapping[str, int] = field(default_factory=dict)


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
        kind: how a run is executed (a registered run kind, :mod:`uavplan.bench.kinds`).
        reference: the algorithm label statistics compare against.
        metric: the run column the generic statistics compare.
        report: the plan's own report sections and figures (its paper's tables beside ours):
            ``report(runs, plan_name) -> (sections, figures)``; None for the generic report only.
    """

    name: str
    description: str
    scenarios: tuple[str, ...]
    algorithms: tuple[Algorithm, ...]
    scales: Mapping[str, Scale]
    kind: str = "planner"
    reference: str | None = None
    metric: str = "best_cost"
    report: Callable[[Any, str], ReportSections] | None = None

    def n_runs(self, scale: str = "smoke") -> int:
        """How many runs :meth:`runs` gives at ``scale``, counted without deriving their seeds
        (``bench list`` counts 60,000 paper runs of one plan)."""
        sc = self._scale(scale)
        return len(sc.scenarios or self.scenarios) * len(self.algorithms) * sc.runs

    def _scale(self, scale: str) -> Scale:
        if scale not in self.scales:
            raise PlanError(
                f"plan {self.name!r} has no scale {scale!r}; choose {list(self.scales)}"
            )
        return self.scales[scale]

    def runs(
        self,
        scale: str = "smoke",
        runs: int | None = None,
        root_seed: int = 0,
        iterations: int | None = None,
    ) -> list[RunSpec]:
        """Every run of this plan at ``scale`` (``runs``/``iterations`` override the scale)."""
        sc = self._scale(scale)
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
                own = alg.iterations.get(scale) if iterations is None else None
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
                                "iterations": n_iter if own is None else own,
                                "evaluations": None
                                if iterations is not None or own is not None
                                else sc.evaluations,
                            },
                        )
                    )
        return out


#: What a plan's report hook returns: (sections, figures); a section is (title, note, table
#: or None), a figure (file name, title, matplotlib figure).
ReportSections = tuple[list[tuple[str, str, Any]], list[tuple[str, str, Any]]]

_PLANS: dict[str, ExperimentPlan] = {}


def register_plan(plan: ExperimentPlan) -> ExperimentPlan:
    """Register a plan under its name (each paper's module under :mod:`uavplan.bench.papers`
    registers its own; the catalog, :mod:`uavplan.bench.catalog`, lists them)."""
    if plan.name in _PLANS and _PLANS[plan.name] is not plan:
        raise PlanError(f"plan {plan.name!r} is already registered")
    for s in ("smoke", "paper"):
        if s not in plan.scales:
            raise PlanError(f"plan {plan.name!r} needs a {s!r} scale")
    _PLANS[plan.name] = plan
    return plan


def registered_plans() -> dict[str, ExperimentPlan]:
    """The plans registered so far (see :mod:`uavplan.bench.catalog` for all built-in ones)."""
    return dict(_PLANS)
