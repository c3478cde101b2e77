"""The planner framework: one way to write a planner.

A planner turns one task of a scenario into a path (OMPL's ``Planner::solve``); a fleet planner
turns all tasks into separated paths. As :class:`~uavplan.optimizers.base.Optimizer`'s
``ask``/``tell`` does for optimizers, the public entry points here are fixed and do the
bookkeeping, and a planner implements one hook:

* :meth:`Planner.plan` checks the input (dimension, task inside the bounds, budget), builds the
  task's :class:`~uavplan.problems.path_problem.PathProblem`, a :class:`Termination` (iterations,
  evaluations, wall time, the callback's stop) and a :class:`Tracker`, calls ``_plan(run)``, and
  assembles the :class:`PlanResult` (one final evaluation of the returned path, its times, its
  violations) in one place, :func:`make_result`.
* ``_plan(run)`` only searches: it counts its evaluations in ``run.tracker``, offers candidate
  paths (:meth:`Tracker.offer`), closes each iteration (:meth:`Tracker.end_iteration`, which
  says when to stop) and returns the path (or an :class:`Outcome` with reasons and figures).

Configuration: each planner has a frozen dataclass ``Config`` (a :class:`PlannerConfig` or
:class:`FleetPlannerConfig`) whose fields are declared with :func:`option` (documentation,
source, range or choices); defaults are the paper's. Keyword options are checked against it:
an unknown option, or a value out of its range, is refused with a :class:`PlannerError` naming
the valid ones. A planner built around a population optimizer (its specs' ``inner_optimizer``,
or a config field ``optimizer``) takes that optimizer's options too, routed into
``optimizer_options``. :meth:`Planner.describe` is generated from the config.

Registry: :func:`register_planner` as a class decorator registers a planner under its ``name``;
called with a class and options it registers a *named configuration* of it (nevergrad's
``ConfiguredOptimizer``): ``ppswarm`` and ``prioritized`` are two configurations of one fleet
engine, and every optimizer is a configuration of the optimizer planner. Lookups
(``get_planner``, ``available_planners``) live in :mod:`uavplan.planners`, which imports the
planner modules; nothing here imports a planner.

Modules: :mod:`~uavplan.planners.core.options` (``option``, config bases, errors),
:mod:`~uavplan.planners.core.results` (``PlanResult``, ``FleetResult``, ``make_result``),
:mod:`~uavplan.planners.core.run` (``Termination``, ``Tracker``, ``Run``, ``Outcome``),
:mod:`~uavplan.planners.core.registry` (``register_planner``), and this one (``Planner``,
``FleetPlanner``).

Planners never print, plot or read files.
"""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uavplan import optimizers
from uavplan.compile_clock import Stopwatch
from uavplan.optimizers.base import Budget, OptimizerConfig, OptimizerError
from uavplan.planners.core.flight import declare, fly
from uavplan.planners.core.options import (
    FleetPlannerConfig,
    OptionError,
    Options,
    PlannerConfig,
    PlannerError,
    bad_value,
    type_hints,
)
from uavplan.planners.core.results import FleetResult, PlanResult, make_result
from uavplan.planners.core.run import Outcome, ProgressCallback, Run, Termination, Tracker
from uavplan.problems import work
from uavplan.problems.path_problem import PRESETS, SEPARATION_TERM, PathProblem
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]


#: A single UAV's post-processing of the path its planner found, given to :meth:`Planner.plan`
#: by the layers that choose it (the CLI's polish, :func:`uavplan.planners.polish.polished`):
#: ``(scenario, task, problem, path) -> (path, note)``, an empty note when nothing changed. The
#: contract only calls it; what it does is policy, kept out of the core.
PathPolish = Callable[[Scenario, Task, PathProblem, FloatArray], tuple[FloatArray, dict[str, Any]]]


#: The capabilities that used to be separate class attributes of a planner, refused there now
#: (:meth:`Planner.__init_subclass__`): declare them in ``specs``.
SPEC_FIELDS = (
    "dims",
    "default_iterations",
    "inner_optimizer",
    "supports_reservations",
    "deterministic",
    "anytime",
    "steps_in_time",
    "handles_moving",
)


@dataclass(frozen=True)
class PlannerSpecs:
    """What a planner class can do, in one record the framework reads (:meth:`Planner.plan`'s
    checks and budget, the CLI, single-UAV planners run as a fleet, the contract tests), instead
    of flags spread over the class.

    dims: the scenario dimensions it plans.
    default_iterations: its iteration budget when none is given.
    inner_optimizer: the population optimizer it is built on, if fixed (otherwise the config's
        ``optimizer`` field names it, if it has one).
    supports_reservations: whether its search keeps clear of other UAVs' flights (it evaluates
        whole timed paths on the run's problem); planners that check edges without time
        cannot.
    deterministic: whether the seed is unused (the same plan from every seed).
    anytime: whether it uses its whole iteration budget (False: it may end earlier, e.g. on
        arrival, and its history is as long as the iterations it ran).
    steps_in_time: whether its path is a trajectory stepped in time within the UAV's limits
        (flown as planned if it passes every check, see
        :func:`~uavplan.planners.core.flight.fly`).
    handles_moving: whether its search sees moving obstacles in time (False: refused on such a
        scenario).
    """

    dims: tuple[int, ...] = (2, 3)
    default_iterations: int = 200
    inner_optimizer: str | None = None
    supports_reservations: bool = False
    deterministic: bool = False
    anytime: bool = True
    steps_in_time: bool = False
    handles_moving: bool = True


class Planner(ABC):
    """Plans one task. Subclasses set ``name``, ``Config`` and ``specs`` and implement
    :meth:`_plan`.

    Class attributes:
        name: the registry name (a named configuration's instances carry that name).
        Config: the frozen config dataclass.
        specs: what it can do (:class:`PlannerSpecs`; a subclass inherits its parent's and
            changes fields with ``dataclasses.replace(Parent.specs, ...)``).
    """

    name: ClassVar[str] = "planner"
    Config: ClassVar[type[Options]] = PlannerConfig
    specs: ClassVar[PlannerSpecs] = PlannerSpecs()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        stray = [f for f in SPEC_FIELDS if f in vars(cls)]
        if stray:
            raise TypeError(f"{cls.__qualname__} sets {', '.join(stray)} as class attributes; "
                            f"declare them in specs = PlannerSpecs({stray[0]}=...)")  # fmt: skip
        if not isinstance(cls.specs, PlannerSpecs):
            raise TypeError(f"{cls.__qualname__}.specs must be a PlannerSpecs")

    def __init__(
        self,
        config: Options | None = None,
        *,
        name: str | None = None,
        defaults: Mapping[str, Any] | None = None,
        **options: Any,
    ) -> None:
        """``config`` (default: the config class's defaults) with a named configuration's
        ``defaults`` applied, then ``options``."""
        if name is not None:
            self.name = name  # type: ignore[misc]
        base = config if config is not None else self._default_config()
        if not isinstance(base, self.Config):
            raise PlannerError(f"{self.name} takes a {self.Config.__name__}, got {type(base)}")
        if defaults:
            base = self.configure(base, defaults)
        self.config = self.configure(base, options)
        self.optimizer_config = self._optimizer_config()

    # ------------------------------------------------------------------ configuration
    def _default_config(self) -> Options:
        return self.Config()

    def optimizer_name(self) -> str | None:
        """The inner population optimizer's registry name (None: the planner has none)."""
        named = getattr(self.config, "optimizer", None)
        return str(named) if named is not None else self.specs.inner_optimizer

    def configure(self, base: Options, options: Mapping[str, Any]) -> Options:
        """``base`` with ``options`` applied: the config's own fields directly, the inner
        optimizer's fields into ``optimizer_options``; anything else is refused, naming the
        valid options. Changing ``optimizer`` drops the base's options of the old one."""
        own = {f.name for f in fields(base)}
        direct = {k: v for k, v in options.items() if k in own}
        named = direct.get("optimizer", getattr(base, "optimizer", None))
        opt_name = str(named) if named is not None else self.specs.inner_optimizer
        opt_fields = _optimizer_fields(opt_name, self.name)
        routed = {k: v for k, v in options.items() if k not in own and k in opt_fields}
        unknown = sorted(set(options) - set(direct) - set(routed))
        if unknown:
            valid = sorted(own - {"optimizer_options"})
            extra = f" and {opt_name}'s {sorted(opt_fields)}" if opt_fields else ""
            raise PlannerError(f"{self.name}: unknown option(s) {unknown}; it takes {valid}{extra}")
        if "optimizer_options" in own:
            kept: dict[str, Any] = dict(getattr(base, "optimizer_options") or {})  # noqa: B009
            if "optimizer" in direct and direct["optimizer"] != getattr(base, "optimizer", None):
                kept = {}
            direct["optimizer_options"] = {**kept, **dict(direct.get("optimizer_options", {})),
                                           **routed}  # fmt: skip
        try:
            return replace(base, **direct)
        except OptionError as exc:
            raise PlannerError(f"{self.name}: {exc}") from None

    def _optimizer_config(self) -> OptimizerConfig | None:
        """The inner optimizer's config from ``optimizer_options`` (None without one)."""
        opt_name = self.optimizer_name()
        if opt_name is None:
            return None
        return self.build_optimizer_config(
            opt_name, dict(getattr(self.config, "optimizer_options", None) or {})
        )

    def build_optimizer_config(self, opt_name: str, params: Mapping[str, Any]) -> OptimizerConfig:
        """Optimizer ``opt_name``'s config from ``params``, each value's type checked against
        the config's fields first (a clear error instead of a failed comparison)."""
        cls = optimizers.get(opt_name).Config
        hints = type_hints(cls)
        where = self.name if opt_name == self.name else f"{self.name}: {opt_name}"
        for k, v in params.items():
            why = bad_value(v, hints.get(k, Any), {})
            if why is not None:
                raise PlannerError(f"{where}: option {k} {why}")
        try:
            return cls(**params)
        except (OptimizerError, TypeError) as exc:
            raise PlannerError(f"{where}: {exc}") from None

    def option_names(self) -> list[str]:
        """Every option this planner takes: its config's fields and its inner optimizer's."""
        own = {f.name for f in fields(self.config)} - {"optimizer_options"}
        return sorted(own | _optimizer_fields(self.optimizer_name(), self.name))

    def describe(self) -> dict[str, Any]:
        """The planner's name and every option (generated from the config)."""
        out: dict[str, Any] = {"name": self.name, **dataclasses.asdict(self.config)}
        if self.optimizer_config is not None:
            out["optimizer"] = self.optimizer_name()
            out["optimizer_config"] = dataclasses.asdict(self.optimizer_config)
        return out

    # ------------------------------------------------------------------ planning
    def problem(
        self, scenario: Scenario, task: Task, reservations: ReservationTable | None = None
    ) -> PathProblem:
        """The task's problem under the configured cost model (the result is judged on it).
        With ``reservations`` (other UAVs' flights), the cost gains PPSwarm's F5 (infinite on a
        conflict) and the band is checked along whole segments, as in the fleet engine."""
        cost = getattr(self.config, "cost", None)
        weights = getattr(self.config, "weights", None)
        strict = bool(getattr(self.config, "flight_check", False))
        try:
            if reservations is None:
                return PathProblem(
                    scenario, task, cost=cost, weights=weights, strict_altitude=strict
                )
            return separated_problem(scenario, task, reservations, cost, weights)
        except ValueError as exc:
            raise PlannerError(f"{self.name}: {exc}") from None

    def iteration_limit(self, budget: Budget) -> int | None:
        """The run's iteration limit for ``budget`` (hook: planners whose iterations an
        evaluation budget cannot bound cap them at :attr:`default_iterations`)."""
        return budget.max_iterations

    def check_input(self, scenario: Scenario, task: Task) -> None:
        """Refuse what this planner cannot plan: a dimension it does not handle, a task
        outside the bounds or of the wrong dimension, moving obstacles it cannot see in time."""
        if scenario.moving_obstacles and not self.specs.handles_moving:
            from uavplan.planners.core.registry import registry

            able = sorted(n for n, e in registry().items() if e.cls.specs.handles_moving)
            raise PlannerError(
                f"{self.name} cannot plan around moving obstacles (its search has no time); "
                f"{scenario.name!r} has {len(scenario.moving_obstacles)}: plan it with one of "
                f"{', '.join(able)}"
            )
        if scenario.dim not in self.specs.dims:
            raise PlannerError(
                f"{self.name} plans {' or '.join(f'{d}-D' for d in self.specs.dims)} scenarios; "
                f"{scenario.name!r} is {scenario.dim}-D"
            )
        for what, p in (("start", task.start), ("goal", task.goal)):
            if len(p) != scenario.dim:
                raise PlannerError(
                    f"task {task.id}: {what} has {len(p)} coordinates, the scenario is "
                    f"{scenario.dim}-D"
                )
            if not bool(scenario.bounds.contains(np.asarray(p))):
                raise PlannerError(
                    f"task {task.id}: {what} {list(p)} is outside the bounds "
                    f"{list(scenario.bounds.lower)}..{list(scenario.bounds.upper)}"
                )

    def budget(self, budget: Budget | int | None) -> Budget:
        try:
            return Budget.of(budget if budget is not None else self.specs.default_iterations)
        except (OptimizerError, TypeError, ValueError) as exc:
            raise PlannerError(f"{self.name}: budget: {exc}") from None

    def plan(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
        reservations: ReservationTable | None = None,
        polish: PathPolish | None = None,
    ) -> PlanResult:
        """Plan ``task`` (default: the first) of ``scenario`` within ``budget`` (an int:
        iterations; default :attr:`default_iterations`) from ``seed``; ``callback(iteration,
        best)`` after every iteration may return True to stop. ``reservations``: other UAVs'
        flights to keep S2 from (planners with :attr:`supports_reservations` only).
        ``polish``: the found path is then passed through it (:data:`PathPolish`; the CLI's is
        :func:`uavplan.planners.polish.polished`: terrain following, tightening and
        line-of-sight shortcuts; ``info["polished"]`` says what changed); not for planners that
        step in time, nor with reservations. The CLI polishes unless ``--raw``; the
        experiments never do (the papers' numbers are the optimizers' own).

        The result declares its flight (:mod:`uavplan.planners.core.flight`): the polyline itself,
        or with a turn radius its Dubins-smoothed version, checked as it will be flown;
        ``info["work"]`` counts what the run computed (:mod:`uavplan.problems.work`)."""
        t = task if isinstance(task, Task) else _task(scenario, task)
        self.check_input(scenario, t)
        if reservations is not None and not self.specs.supports_reservations:
            raise PlannerError(
                f"{self.name} cannot keep clear of other UAVs while it searches (its search does "
                "not see time): plan fleets with a fleet planner (uavplan planners lists them)"
            )
        b = self.budget(budget)
        with work.counting() as done:  # info["work"]: what the whole run computed
            result = self._run(scenario, t, b, seed, callback, reservations, polish)
        return replace(result, info={**result.info, "work": done.record()})

    def _run(
        self,
        scenario: Scenario,
        t: Task,
        b: Budget,
        seed: int | None,
        callback: ProgressCallback | None,
        reservations: ReservationTable | None,
        polish: PathPolish | None,
    ) -> PlanResult:
        """The run behind :meth:`plan`: search, polish, the result and its declared flight."""
        clock = Stopwatch()  # the reported time (and a time budget) leave kernel compilation out
        problem = self.problem(scenario, t, reservations)
        termination = Termination(
            self.iteration_limit(b), b.max_evaluations, b.max_time, callback, clock
        )
        tracker = Tracker(termination, bool(getattr(self.config, "track_feasibility", True)))
        run = Run(scenario, t, problem, seed, b, termination.max_iterations, tracker, reservations)
        out = self._plan(run)
        outcome = out if isinstance(out, Outcome) else Outcome(path=out)
        path = outcome.path if outcome.path is not None else tracker.path
        reasons = outcome.reasons
        if path is None:  # nothing found: the straight segment, infeasible
            path = np.stack([problem.start, problem.goal])
            reasons = reasons or ("no_path",)
        info = dict(outcome.info)
        steps = self.specs.steps_in_time
        if polish is not None and not reasons and reservations is None and not steps:
            path, note = polish(scenario, t, problem, np.asarray(path, dtype=np.float64))
            if note:
                info["polished"] = note
        result = make_result(
            problem,
            path,
            algorithm=self.name,
            history=tracker.history,
            evaluations=tracker.evaluations,
            evaluations_history=tracker.evaluations_history,
            wall_time=clock.elapsed,
            feasible_history=tracker.feasible_history,
            config=self.describe(),
            seed=seed,
            reasons=reasons,
            info=info,
        )
        flight = fly(
            scenario,
            t,
            result.waypoints,
            result.times,
            reservations,
            as_planned=self.specs.steps_in_time,
        )
        if reasons:  # a planner's reason (no path found) fails the flight too
            flight = dataclasses.replace(flight, violations=flight.violations + reasons)
        return dataclasses.replace(declare(result, flight), wall_time=clock.elapsed)

    @abstractmethod
    def _plan(self, run: Run) -> FloatArray | Outcome | None:
        """Search; record into ``run.tracker``; return the path (or an :class:`Outcome`)."""

    def repair(
        self,
        scenario: Scenario,
        task: Task,
        path: FloatArray,
        times: FloatArray,
        area: int,
        budget: Budget | int | None = None,
        seed: int | None = None,
    ) -> tuple[FloatArray, dict[str, Any]]:
        """A new remaining path after uncertain area ``area`` was revealed in flight
        (:mod:`uavplan.planners.replanning`): from ``task.start`` (the UAV's predicted
        position, at ``task.start_time``) to its goal, on ``scenario`` (the world as now known);
        ``path``/``times``: the remaining plan, starting there. The default plans again from
        scratch; planners that can repair locally override it. Returns the path and figures."""
        r = self.plan(scenario, task, budget, seed)
        return np.asarray(r.waypoints), {"how": "from scratch", "evaluations": r.evaluations}


def separated_problem(
    scenario: Scenario,
    task: Task,
    table: ReservationTable | None,
    cost: str | None = None,
    weights: dict[str, float] | None = None,
) -> PathProblem:
    """A UAV's problem among other UAVs: the cost preset (default: the scenario's) plus F5
    (PPSwarm Eqs. 11-12, the ``separation`` term) against the reservation table of the UAVs
    planned before it, with the band checked along whole segments (``strict_altitude``)."""
    preset = cost if cost is not None else scenario.cost
    if preset not in PRESETS:
        raise PlannerError(f"unknown cost preset {preset!r}; choose from {sorted(PRESETS)}")
    return PathProblem(
        scenario,
        task,
        cost=(*PRESETS[preset], SEPARATION_TERM),
        weights=weights,
        strict_altitude=True,
        reservations=table,
        lookup="bilinear",
        name=f"{preset}+separation",
    )


def _task(scenario: Scenario, task: str | int | None) -> Task:
    try:
        return scenario.task(task)
    except (KeyError, IndexError):
        raise PlannerError(
            f"no task {task!r} in scenario {scenario.name!r} (tasks: "
            f"{[t.id for t in scenario.tasks][:10]})"
        ) from None


def _optimizer_fields(opt_name: str | None, planner: str) -> set[str]:
    if opt_name is None:
        return set()
    try:
        return {f.name for f in fields(optimizers.get(opt_name).Config)}
    except OptimizerError as exc:
        raise PlannerError(f"{planner}: {exc}") from None


@dataclass(frozen=True)
class FleetOutcome:
    """What a fleet planner's ``_plan_fleet`` returns; :meth:`FleetPlanner.plan_fleet` adds the
    fleet's cost, verdict, time, name, config and seed."""

    results: tuple[PlanResult, ...]
    priority: tuple[str, ...]
    history: FloatArray
    restart_costs: FloatArray
    info: dict[str, Any] = field(default_factory=dict)
    #: the fleet's cost as the planner judges it (inf when what it guarantees fails somewhere);
    #: None: the sum of the UAVs' costs if every planned polyline is feasible, else inf
    cost: float | None = None


class FleetPlanner(Planner):
    """Plans all tasks of a scenario together (UAV-UAV separation included).

    Subclasses implement :meth:`_plan_fleet`; planning a single task plans a fleet of one.
    """

    Config: ClassVar[type[Options]] = FleetPlannerConfig

    def plan_fleet(
        self,
        scenario: Scenario,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
        tasks: tuple[str, ...] | None = None,
    ) -> FleetResult:
        """Plan every task of ``scenario`` (or those named in ``tasks``); ``info["work"]`` counts
        what the whole fleet's planning computed (:mod:`uavplan.problems.work`)."""
        sc = scenario
        if tasks is not None:
            chosen = tuple(t for t in scenario.tasks if t.id in set(tasks))
            if not chosen:
                raise PlannerError(f"none of the tasks {list(tasks)} is in {scenario.name!r}")
            sc = dataclasses.replace(scenario, tasks=chosen)
        for t in sc.tasks:
            self.check_input(sc, t)
        b = self.budget(budget) if budget is not None else None
        clock = Stopwatch()
        with work.counting() as done:
            out = self._plan_fleet(sc, b, seed, callback)
        planned = all(r.feasible for r in out.results)
        total = float(sum(r.cost for r in out.results))
        return FleetResult(
            results=out.results,
            priority=out.priority,
            cost=out.cost if out.cost is not None else (total if planned else math.inf),
            flown_feasible=all(r.flown_feasible for r in out.results),
            planned_feasible=planned,
            history=np.asarray(out.history),
            restart_costs=np.asarray(out.restart_costs),
            wall_time=clock.elapsed,
            algorithm=self.name,
            config=self.describe(),
            seed=seed,
            info={**out.info, "work": done.record()},
        )

    @abstractmethod
    def _plan_fleet(
        self,
        scenario: Scenario,
        budget: Budget | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> FleetOutcome: ...

    def plan(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
        reservations: ReservationTable | None = None,
        polish: PathPolish | None = None,
    ) -> PlanResult:
        """A fleet of one: ``task`` alone (fleet planners keep clear of each other's UAVs
        themselves, not of flights reserved outside; ``polish`` does not apply)."""
        if reservations is not None:
            raise ValueError(f"planner {self.name!r} does not keep clear of reserved flights")
        t = task if isinstance(task, Task) else _task(scenario, task)
        self.check_input(scenario, t)
        one = dataclasses.replace(scenario, tasks=(t,))
        fleet = self.plan_fleet(one, budget, seed, callback)
        r = fleet.results[0]
        return replace(r, info={**r.info, "work": fleet.info["work"]})

    def _plan(self, run: Run) -> FloatArray | Outcome | None:  # pragma: no cover - unused
        raise NotImplementedError("fleet planners plan through plan_fleet")
