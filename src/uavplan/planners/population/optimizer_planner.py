"""A planner that wraps any registered optimizer with a waypoint encoding: every optimizer is
also a planner (``pso``, ``de``, ``spso``, ...; each a named configuration of
:class:`OptimizerPlanner`).

The optimizer searches ``n_waypoints`` free waypoints (x, y[, z]) between the task's start and
goal under the scenario's cost preset (see :mod:`uavplan.problems.path_problem`), on the
Cartesian encoding or, for optimizers that declare it (SPSO), the spherical one. One planner
iteration is one optimizer iteration (``ask``, evaluate, ``tell``). The result is the path of the
optimizer's best point (lowest cost under the constraint rule, feasible or not: the papers'
methods return their best particle).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any

from uavplan import optimizers
from uavplan._text import first_sentence
from uavplan.optimizers.base import fit_schedule
from uavplan.optimizers.constraints import RULES, Constrained
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, option
from uavplan.planners.core.registry import add_provider, is_registered, register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.problems.encoding import ENCODINGS


@dataclass(frozen=True)
class OptimizerPlannerConfig(PlannerConfig):
    """Options of :class:`OptimizerPlanner` (the optimizer's own options are routed into
    ``optimizer_options``: ``pop_size=500`` sets the optimizer's population)."""

    optimizer: str = option("pso", "the population optimizer (a registered optimizer name)")
    optimizer_options: dict[str, Any] = option(
        default_factory=dict, doc="the optimizer's options (pop_size, w, F, ...), given plainly"
    )
    n_waypoints: int | None = option(None, "free waypoints (default: the scenario's)", low=1)
    encoding: str | None = option(
        None,
        "waypoint encoding (default: the optimizer's; SPSO's is spherical)",
        choices=tuple(ENCODINGS),
    )
    constraints: str = option(
        "cost",
        "how constraints reach the optimizer: the paper's cost alone, infinity when violated, "
        "or Deb's feasibility-first rule (uavplan.optimizers.constraints)",
        choices=RULES,
    )


class OptimizerPlanner(Planner):
    """Plan with a population optimizer over encoded waypoints (see the module docstring)."""

    name = "optimizer"
    specs = PlannerSpecs(supports_reservations=True)
    Config = OptimizerPlannerConfig
    config: OptimizerPlannerConfig

    @property
    def encoding(self) -> str:
        cfg = self.config
        cls = optimizers.get(cfg.optimizer)
        return str(cfg.encoding or getattr(cls, "encoding", "cartesian"))

    def describe(self) -> dict[str, Any]:
        return {**super().describe(), "encoding": self.encoding}

    def _plan(self, run: Run) -> Any:
        cfg = self.config
        assert self.optimizer_config is not None
        enc = ENCODINGS[self.encoding](run.problem, cfg.n_waypoints)
        objective = Constrained(enc, cfg.constraints)
        config = fit_schedule(self.optimizer_config, run.budget, cfg.optimizer_options)
        opt = optimizers.get(cfg.optimizer)(objective, config, seed=run.seed)
        tr = run.tracker
        while True:
            X = opt.ask()
            f = objective.evaluate(X)
            opt.tell(X, f)
            tr.evaluations += len(X)
            # the feasible record of the particles as the optimizer took them (not of points
            # it evaluated and dropped within the iteration: SPSO's asynchronous update)
            feasible_best = enc.track(opt.last_x, opt.last_f) if cfg.track_feasibility else None
            if tr.end_iteration(best=opt.best_f, feasible_best=feasible_best):
                break
        assert opt.best_x is not None
        path = enc.decode(opt.best_x[None])[0]
        if getattr(opt.config, "update", "sync") == "async":  # SPSO's re-evaluations
            extra = int(getattr(opt, "speculative_evaluations", 0))
            return Outcome(path, info={"speculative_evaluations": extra})
        return path


def _summary(name: str) -> str:
    cls = optimizers.get(name)
    doc = cls.__doc__ or sys.modules[cls.__module__].__doc__ or name
    return f"{first_sentence(doc)} (optimizer over waypoints)"


def _provide() -> None:
    """Register an optimizer planner for every registered optimizer not yet a planner."""
    for name in optimizers.available():
        if not is_registered(name):
            register_planner(OptimizerPlanner, name=name, summary=_summary(name), optimizer=name)


add_provider(_provide)
