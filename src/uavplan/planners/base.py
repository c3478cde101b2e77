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
the valid ones. A planner built around a population optimizer (``Planner.inner_optimizer``, or a
config field ``optimizer``) takes that optimizer's options too, routed into
``optimizer_options``. :meth:`Planner.describe` is generated from the config.

Registry: :func:`register_planner` as a class decorator registers a planner under its ``name``;
called with a class and options it registers a *named configuration* of it (nevergrad's
``ConfiguredOptimizer``): ``ppswarm`` and ``prioritized`` are two configurations of one fleet
engine, and every optimizer is a configuration of the optimizer planner. Lookups
(``get_planner``, ``available_planners``) live in :mod:`uavplan.planners`, which imports the
planner modules; nothing here imports a planner.

Planners never print, plot or read files.
"""

from __future__ import annotations

import dataclasses
import math
import time
import typing
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import NDArray

from uavplan import optimizers
from uavplan.optimizers.base import Budget, OptimizerConfig, OptimizerError
from uavplan.problems.path_problem import PathProblem
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]

#: Progress callback: (iteration, best cost so far) -> True to stop early.
ProgressCallback = Callable[[int, float], bool | None]


class PlannerError(ValueError):
    """Unknown planner, bad configuration, or a task it cannot handle."""


class OptionError(PlannerError):
    """An option value out of its declared range, choices or type."""

    def __init__(self, option: str, why: str) -> None:
        self.option = option
        self.why = why
        super().__init__(f"option {option} {why}")


# ====================================================================================== options
def option(
    default: Any = dataclasses.MISSING,
    doc: str = "",
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    choices: Sequence[Any] | None = None,
    default_factory: Callable[[], Any] | None = None,
) -> Any:
    """A config field with its documentation and valid values.

    Args:
        default: the default (the paper's, cited in ``doc``); or ``default_factory``.
        doc: one line for ``describe_options`` and ``uavplan planners NAME``.
        low, high: the range of a number (inclusive unless ``low_open``/``high_open``).
        choices: the allowed values.
    """
    meta = {"doc": doc, "low": low, "high": high, "low_open": low_open, "high_open": high_open,
            "choices": tuple(choices) if choices is not None else None}  # fmt: skip
    if default_factory is not None:
        return field(default_factory=default_factory, metadata=meta)
    return field(default=default, metadata=meta)


_HINTS: dict[type, dict[str, Any]] = {}


def _type_hints(cls: type) -> dict[str, Any]:
    """A config class's field types (each base's annotations in its own module's names)."""
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _kinds(hint: Any) -> tuple[set[type], bool]:
    """The plain types a hint admits and whether it admits None."""
    args = typing.get_args(hint) if typing.get_origin(hint) in (typing.Union, type(int | None)) \
        else (hint,)  # fmt: skip
    out: set[type] = set()
    none_ok = False
    for a in args:
        if a is type(None):
            none_ok = True
            continue
        origin = typing.get_origin(a) or a
        if origin in (dict, Mapping) or (isinstance(origin, type) and issubclass(origin, Mapping)):
            out.add(dict)
        elif isinstance(origin, type):
            out.add(origin)
    return out, none_ok


def _is_kind(value: Any, kinds: set[type]) -> bool:
    if not kinds or object in kinds:
        return True
    if isinstance(value, bool | np.bool_):
        return bool in kinds
    if isinstance(value, int | np.integer):
        return bool(kinds & {int, float})
    if isinstance(value, float | np.floating):
        return float in kinds
    if isinstance(value, Mapping):
        return dict in kinds
    return any(isinstance(value, k) for k in kinds)


def _bad_value(value: Any, hint: Any, meta: Mapping[str, Any]) -> str | None:
    """Why ``value`` is not valid for a field of type ``hint`` declared with ``meta``, or None."""
    kinds, none_ok = _kinds(hint)
    if value is None:
        return None if none_ok else "must be given (not None)"
    if not _is_kind(value, kinds):
        return f"must be {_kind_words(kinds)}, got {value!r}"
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return f"must be a finite number, got {value!r}"
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        return f"must be one of {list(choices)}, got {value!r}"
    low, high = meta.get("low"), meta.get("high")
    if isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool):
        if low is not None and (value < low or (meta.get("low_open") and value == low)):
            return f"must be {'>' if meta.get('low_open') else '>='} {low:g}, got {value!r}"
        if high is not None and (value > high or (meta.get("high_open") and value == high)):
            return f"must be {'<' if meta.get('high_open') else '<='} {high:g}, got {value!r}"
    return None


def _kind_words(kinds: set[type]) -> str:
    names = {int: "an integer", float: "a number", bool: "true or false", str: "a string",
             dict: "a mapping"}  # fmt: skip
    return " or ".join(sorted(names.get(k, k.__name__) for k in kinds))


@dataclass(frozen=True)
class Options:
    """Base of every planner configuration: checks each field against its :func:`option`
    declaration (type, range, choices) when built; ints given for numbers become floats."""

    def __post_init__(self) -> None:
        hints = _type_hints(type(self))
        for f in fields(self):
            v = getattr(self, f.name)
            why = _bad_value(v, hints.get(f.name, Any), f.metadata)
            if why is not None:
                raise OptionError(f.name, why)
            kinds, _ = _kinds(hints.get(f.name, Any))
            if float in kinds and isinstance(v, int) and not isinstance(v, bool):
                object.__setattr__(self, f.name, float(v))


@dataclass(frozen=True)
class PlannerConfig(Options):
    """Options every single-UAV planner has."""

    cost: str | None = option(None, "cost preset (default: the scenario's)")
    weights: dict[str, float] | None = option(None, "cost term weight overrides, by term name")
    track_feasibility: bool = option(
        True,
        "record the best feasible cost after every iteration (feasible_history, "
        "first_feasible_iteration); optimizer planners then check every candidate's feasibility",
    )


@dataclass(frozen=True)
class FleetPlannerConfig(Options):
    """Base of the fleet planners' configurations."""


def describe_options(config_cls: type[Options]) -> list[dict[str, Any]]:
    """Every option of a config class: name, default, doc, range or choices."""
    out = []
    for f in fields(config_cls):
        default = f.default if f.default is not dataclasses.MISSING else (
            f.default_factory() if f.default_factory is not dataclasses.MISSING else None
        )  # fmt: skip
        m = f.metadata
        rng = ""
        if m.get("choices") is not None:
            rng = " | ".join(str(c) for c in m["choices"])
        elif m.get("low") is not None or m.get("high") is not None:
            rng = "x"
            if m.get("low") is not None:
                rng = f"{m['low']:g} {'<' if m.get('low_open') else '<='} {rng}"
            if m.get("high") is not None:
                rng = f"{rng} {'<' if m.get('high_open') else '<='} {m['high']:g}"
        out.append({"name": f.name, "default": default, "doc": m.get("doc", ""), "range": rng})
    return out


# ==================================================================================== results
@dataclass(frozen=True)
class PlanResult:
    """One UAV's planned path and how it was found.

    Attributes:
        uav_id: the task id.
        waypoints: (n, dim) metres, start and goal included.
        times: (n,) seconds at the UAV's speed from the task's start time.
        cost: total cost under the planner's cost model; terms: each term's raw value.
        feasible: decided on continuous segments by the motion validator.
        evaluations, iterations, wall_time (s), history: best-so-far cost per iteration.
        algorithm, config, seed, cost_model: what produced it.
        violations: the checks the path fails (and planner reasons such as ``no_path``).
        feasible_history: best cost among feasible candidates so far, per iteration (inf
            before the first feasible one); empty when the planner did not track it.
        evaluations_history: evaluations used after each iteration (for plots against
            evaluations, the fair axis between algorithms).
        first_feasible_iteration: the 1-based iteration in which a feasible candidate was first
            evaluated (RGG-PSO+'s F-Measure counts the iterations before it), None if never or
            not tracked.
        info: planner-specific figures of the run (edge checks, tree size, merge kind, ...).
        smoothed, smoothed_times, smoothed_ok, smoothed_violations: a flyable version of
            ``waypoints`` (Dubins-smoothed dense polyline (m, dim) and its times (m,)), whether
            it keeps every clearance and what it breaks (None: not smoothed).
    """

    uav_id: str
    waypoints: FloatArray
    times: FloatArray
    cost: float
    terms: dict[str, float]
    feasible: bool
    evaluations: int
    iterations: int
    wall_time: float
    history: FloatArray
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    cost_model: str = ""
    violations: tuple[str, ...] = ()
    feasible_history: FloatArray = field(default_factory=lambda: np.zeros(0))
    first_feasible_iteration: int | None = None
    evaluations_history: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64)
    )
    info: dict[str, Any] = field(default_factory=dict)
    smoothed: FloatArray | None = None
    smoothed_times: FloatArray | None = None
    smoothed_ok: bool | None = None
    smoothed_violations: tuple[str, ...] = ()

    @property
    def length(self) -> float:
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))


@dataclass(frozen=True)
class FleetResult:
    """A whole fleet's plan from a :class:`FleetPlanner`.

    Attributes:
        results: one :class:`PlanResult` per task, in the scenario's task order.
        priority: task ids in the order they were planned in the kept solution.
        cost: total cost (sum of the UAVs' costs; inf if any is infeasible).
        feasible: every UAV feasible, including separation from the others.
        history: the fleet's cost per low-level iteration (see the planner's docs).
        restart_costs: the fleet cost after each restart.
        wall_time: seconds; info: planner-specific figures (timings, smoothing report).
    """

    results: tuple[PlanResult, ...]
    priority: tuple[str, ...]
    cost: float
    feasible: bool
    history: FloatArray
    restart_costs: FloatArray
    wall_time: float
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    info: dict[str, Any] = field(default_factory=dict)


def first_finite(history: Sequence[float] | FloatArray) -> int | None:
    """1-based index of the first finite entry, or None."""
    finite = np.flatnonzero(np.isfinite(np.asarray(history, dtype=np.float64)))
    return int(finite[0]) + 1 if len(finite) else None


def make_result(
    problem: PathProblem,
    path: FloatArray,
    *,
    algorithm: str,
    history: Sequence[float] | FloatArray,
    evaluations: int,
    evaluations_history: Sequence[int] | NDArray[np.int64],
    wall_time: float,
    feasible_history: Sequence[float] | FloatArray = (),
    config: dict[str, Any] | None = None,
    seed: int | None = None,
    reasons: tuple[str, ...] = (),
    info: dict[str, Any] | None = None,
) -> PlanResult:
    """The :class:`PlanResult` of ``path`` (n, dim): evaluated once on ``problem`` (cost, terms,
    feasibility, violations), timed at the UAV's speed; ``reasons`` (e.g. ``"no_path"``) make
    it infeasible and join its violations. Every planner's result is assembled here."""
    p = np.asarray(path, dtype=np.float64)
    ev = problem.evaluate(p[None])
    fh = np.asarray(feasible_history, dtype=np.float64)
    return PlanResult(
        uav_id=problem.task.id,
        waypoints=p,
        times=problem.times(p[None])[0],
        cost=float(ev.cost[0]),
        terms={k: float(v[0]) for k, v in ev.terms.items()},
        feasible=bool(ev.feasible[0]) and not reasons,
        evaluations=int(evaluations),
        iterations=len(history),
        wall_time=float(wall_time),
        history=np.asarray(history, dtype=np.float64),
        algorithm=algorithm,
        config=dict(config or {}),
        seed=seed,
        cost_model=problem.cost_name,
        violations=tuple(k for k, v in ev.violations.items() if v[0]) + tuple(reasons),
        feasible_history=fh,
        first_feasible_iteration=first_finite(fh),
        evaluations_history=np.asarray(evaluations_history, dtype=np.int64),
        info=dict(info or {}),
    )


# ==================================================================================== a run
@dataclass
class Termination:
    """When a run stops (OMPL's ``PlannerTerminationCondition``): any limit reached, or the
    callback asking to stop. ``max_iterations`` None: no iteration limit."""

    max_iterations: int | None
    max_evaluations: int | None = None
    max_time: float | None = None
    callback: ProgressCallback | None = None
    t0: float = field(default_factory=time.perf_counter)

    def reached(self, iterations: int, evaluations: int, best: float) -> bool:
        """Called once per iteration; the callback is always called first."""
        stop = bool(self.callback(iterations, best)) if self.callback is not None else False
        if self.max_iterations is not None and iterations >= self.max_iterations:
            stop = True
        if self.max_evaluations is not None and evaluations >= self.max_evaluations:
            stop = True
        if self.max_time is not None and time.perf_counter() - self.t0 >= self.max_time:
            stop = True
        return stop


class Tracker:
    """What a run records: evaluations, the incumbent (the best path offered, a feasible one
    before any infeasible one, then the lowest cost), and per iteration the best cost so far,
    the best feasible cost so far (when tracked) and the evaluations used."""

    def __init__(self, termination: Termination, track_feasibility: bool = True) -> None:
        self.termination = termination
        self.track_feasibility = track_feasibility
        self.evaluations = 0
        self.history: list[float] = []
        self.feasible_history: list[float] = []
        self.evaluations_history: list[int] = []
        self.path: FloatArray | None = None
        self.cost = math.inf
        self.feasible = False

    def offer(self, path: FloatArray, cost: float, feasible: bool) -> bool:
        """A candidate result; kept if it beats the incumbent (feasible first, then cost)."""
        if (feasible, -cost) > (self.feasible, -self.cost):
            self.path, self.cost, self.feasible = np.asarray(path), float(cost), bool(feasible)
            return True
        return False

    def end_iteration(self, best: float | None = None, feasible_best: float | None = None) -> bool:
        """Close an iteration: record ``best`` (default: the incumbent's cost) and
        ``feasible_best`` (default: the incumbent's cost if it is feasible) as running minima,
        and the evaluations; True when the run must stop."""
        b = self.cost if best is None else float(best)
        self.history.append(min(self.history[-1], b) if self.history else b)
        if self.track_feasibility:
            if feasible_best is None:
                feasible_best = self.cost if self.feasible else math.inf
            prev = self.feasible_history[-1] if self.feasible_history else math.inf
            self.feasible_history.append(min(prev, float(feasible_best)))
        self.evaluations_history.append(self.evaluations)
        return self.termination.reached(len(self.history), self.evaluations, self.history[-1])

    def amend(self, best: float, feasible_best: float) -> None:
        """Fold a result found after the last iteration closed into that iteration's record."""
        self.history[-1] = min(self.history[-1], float(best))
        if self.track_feasibility:
            self.feasible_history[-1] = min(self.feasible_history[-1], float(feasible_best))
        self.evaluations_history[-1] = self.evaluations


@dataclass
class Run:
    """Everything ``_plan`` works with: the scenario, the task, its problem, the seed, the
    budget, the resolved iteration limit, the termination and the tracker."""

    scenario: Scenario
    task: Task
    problem: PathProblem
    seed: int | None
    budget: Budget
    max_iterations: int | None
    tracker: Tracker

    @property
    def termination(self) -> Termination:
        return self.tracker.termination


@dataclass(frozen=True)
class Outcome:
    """What ``_plan`` may return instead of a bare path: the path (None: the tracker's
    incumbent, or the straight start-goal segment if there is none), ``reasons`` that make it
    infeasible (``"no_path"``...), and ``info`` (planner figures for :attr:`PlanResult.info`)."""

    path: FloatArray | None = None
    reasons: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)


C = TypeVar("C", bound=Options)


# ==================================================================================== planners
class Planner(ABC):
    """Plans one task. Subclasses set ``name``, ``Config`` and implement :meth:`_plan`.

    Class attributes:
        name: the registry name (a named configuration's instances carry that name).
        Config: the frozen config dataclass.
        dims: the scenario dimensions handled.
        default_iterations: the iteration budget when none is given.
        inner_optimizer: the population optimizer this planner is built on, if fixed
            (otherwise the config's ``optimizer`` field names it, if it has one).
    """

    name: ClassVar[str] = "planner"
    Config: ClassVar[type[Options]] = PlannerConfig
    dims: ClassVar[tuple[int, ...]] = (2, 3)
    default_iterations: ClassVar[int] = 200
    inner_optimizer: ClassVar[str | None] = None

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

    def optimizer_name(self, config: Options | None = None) -> str | None:
        """The inner population optimizer's registry name (None: the planner has none)."""
        cfg = config if config is not None else getattr(self, "config", None)
        named = getattr(cfg, "optimizer", None) if cfg is not None else None
        return str(named) if named is not None else self.inner_optimizer

    def configure(self, base: Options, options: Mapping[str, Any]) -> Options:
        """``base`` with ``options`` applied: the config's own fields directly, the inner
        optimizer's fields into ``optimizer_options``; anything else is refused, naming the
        valid options. Changing ``optimizer`` drops the base's options of the old one."""
        own = {f.name for f in fields(base)}
        direct = {k: v for k, v in options.items() if k in own}
        named = direct.get("optimizer", getattr(base, "optimizer", None))
        opt_name = str(named) if named is not None else self.inner_optimizer
        opt_fields = _optimizer_fields(opt_name, self.name)
        routed = {k: v for k, v in options.items() if k not in own and k in opt_fields}
        unknown = sorted(set(options) - set(direct) - set(routed))
        if unknown:
            valid = sorted(own - {"optimizer_options"})
            extra = f" and {opt_name}'s {sorted(opt_fields)}" if opt_fields else ""
            raise PlannerError(
                f"{self.name}: unknown option(s) {unknown}; it takes {valid}{extra}"
            )
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
        hints = _type_hints(cls)
        where = self.name if opt_name == self.name else f"{self.name}: {opt_name}"
        for k, v in params.items():
            why = _bad_value(v, hints.get(k, Any), {})
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
    def problem(self, scenario: Scenario, task: Task) -> PathProblem:
        """The task's problem under the configured cost model (the result is judged on it)."""
        try:
            return PathProblem(
                scenario,
                task,
                cost=getattr(self.config, "cost", None),
                weights=getattr(self.config, "weights", None),
            )
        except ValueError as exc:
            raise PlannerError(f"{self.name}: {exc}") from None

    def iteration_limit(self, budget: Budget) -> int | None:
        """The run's iteration limit for ``budget`` (hook: planners whose iterations an
        evaluation budget cannot bound cap them at :attr:`default_iterations`)."""
        return budget.max_iterations

    def check_input(self, scenario: Scenario, task: Task) -> None:
        """Refuse what this planner cannot plan: a dimension it does not handle, a task
        outside the bounds or of the wrong dimension."""
        if scenario.dim not in self.dims:
            raise PlannerError(
                f"{self.name} plans {' or '.join(f'{d}-D' for d in self.dims)} scenarios; "
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
            return Budget.of(budget if budget is not None else self.default_iterations)
        except (OptimizerError, TypeError, ValueError) as exc:
            raise PlannerError(f"{self.name}: budget: {exc}") from None

    def plan(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        budget: Budget | int | None = None,
        seed: int | None = None,
        callback: ProgressCallback | None = None,
    ) -> PlanResult:
        """Plan ``task`` (default: the first) of ``scenario`` within ``budget`` (an int:
        iterations; default :attr:`default_iterations`) from ``seed``; ``callback(iteration,
        best)`` after every iteration may return True to stop."""
        t = task if isinstance(task, Task) else _task(scenario, task)
        self.check_input(scenario, t)
        b = self.budget(budget)
        t0 = time.perf_counter()
        problem = self.problem(scenario, t)
        termination = Termination(
            self.iteration_limit(b), b.max_evaluations, b.max_time, callback, t0
        )
        tracker = Tracker(termination, bool(getattr(self.config, "track_feasibility", True)))
        run = Run(scenario, t, problem, seed, b, termination.max_iterations, tracker)
        out = self._plan(run)
        outcome = out if isinstance(out, Outcome) else Outcome(path=out)
        path = outcome.path if outcome.path is not None else tracker.path
        reasons = outcome.reasons
        if path is None:  # nothing found: the straight segment, infeasible
            path = np.stack([problem.start, problem.goal])
            reasons = reasons or ("no_path",)
        return make_result(
            problem,
            path,
            algorithm=self.name,
            history=tracker.history,
            evaluations=tracker.evaluations,
            evaluations_history=tracker.evaluations_history,
            wall_time=time.perf_counter() - t0,
            feasible_history=tracker.feasible_history,
            config=self.describe(),
            seed=seed,
            reasons=reasons,
            info=outcome.info,
        )

    @abstractmethod
    def _plan(self, run: Run) -> FloatArray | Outcome | None:
        """Search; record into ``run.tracker``; return the path (or an :class:`Outcome`)."""


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
        """Plan every task of ``scenario`` (or those named in ``tasks``)."""
        sc = scenario
        if tasks is not None:
            chosen = tuple(t for t in scenario.tasks if t.id in set(tasks))
            if not chosen:
                raise PlannerError(f"none of the tasks {list(tasks)} is in {scenario.name!r}")
            sc = dataclasses.replace(scenario, tasks=chosen)
        for t in sc.tasks:
            self.check_input(sc, t)
        b = self.budget(budget) if budget is not None else None
        t0 = time.perf_counter()
        out = self._plan_fleet(sc, b, seed, callback)
        n_bad = sum(not r.feasible for r in out.results)
        total = float(sum(r.cost for r in out.results))
        return FleetResult(
            results=out.results,
            priority=out.priority,
            cost=total if n_bad == 0 else math.inf,
            feasible=n_bad == 0,
            history=np.asarray(out.history),
            restart_costs=np.asarray(out.restart_costs),
            wall_time=time.perf_counter() - t0,
            algorithm=self.name,
            config=self.describe(),
            seed=seed,
            info=out.info,
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
    ) -> PlanResult:
        """A fleet of one: ``task`` alone."""
        t = task if isinstance(task, Task) else _task(scenario, task)
        one = dataclasses.replace(scenario, tasks=(t,))
        return self.plan_fleet(one, budget, seed, callback).results[0]

    def _plan(self, run: Run) -> FloatArray | Outcome | None:  # pragma: no cover - unused
        raise NotImplementedError("fleet planners plan through plan_fleet")


# ==================================================================================== registry
@dataclass(frozen=True)
class PlannerEntry:
    """A registered planner: a class, or a named configuration of one (``options`` applied
    before the caller's)."""

    name: str
    cls: type[Planner]
    options: Mapping[str, Any] = field(default_factory=dict)
    summary: str = ""

    def __call__(self, **options: Any) -> Planner:
        return self.cls(name=self.name, defaults=self.options, **options)

    @property
    def fleet(self) -> bool:
        return issubclass(self.cls, FleetPlanner)


_REGISTRY: dict[str, PlannerEntry] = {}
_PROVIDERS: list[Callable[[], None]] = []

P = TypeVar("P", bound=type[Planner])


@typing.overload
def register_planner(cls: P, /) -> P: ...


@typing.overload
def register_planner(
    cls: type[Planner], /, *, name: str, summary: str = "", **options: Any
) -> PlannerEntry: ...


def register_planner(
    cls: type[Planner], /, *, name: str | None = None, summary: str = "", **options: Any
) -> Any:
    """Register a planner class under its ``name`` (use as a class decorator), or a named
    configuration of it (``register_planner(Engine, name="ppswarm", n_restart=5)``; returns
    the entry). The options are checked now: a bad one fails at registration."""
    key = (name or cls.name).lower()
    if key in _REGISTRY and (_REGISTRY[key].cls is not cls or _REGISTRY[key].options != options):
        raise PlannerError(f"planner {key!r} is already registered")
    doc = summary or (cls.__doc__ or "").strip().split("\n")[0]
    entry = PlannerEntry(key, cls, dict(options), doc)
    entry()  # a bad configuration fails here, at import, not at its first use
    _REGISTRY[key] = entry
    return cls if name is None else entry


def unregister_planner(name: str) -> None:
    """Remove ``name`` from the registry (a plugin being reloaded, a test's planner)."""
    _REGISTRY.pop(name.lower(), None)


def is_registered(name: str) -> bool:
    """Whether ``name`` is registered (without running the providers)."""
    return name.lower() in _REGISTRY


def add_provider(provider: Callable[[], None]) -> None:
    """A function run before every registry lookup that may register more planners (the
    optimizer planner registers one per optimizer, including optimizers registered later)."""
    _PROVIDERS.append(provider)


def registry() -> dict[str, PlannerEntry]:
    """The registered planners (after running the providers)."""
    for provide in _PROVIDERS:
        provide()
    return _REGISTRY
