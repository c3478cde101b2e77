"""Optimizer interface: ask/tell over whole populations, budgets, history, callbacks, registry.

Public entry points (:meth:`Optimizer.ask`, :meth:`Optimizer.tell`, :func:`minimize`) are fixed
here and do the bookkeeping (evaluation count, best-so-far, history, termination); an algorithm
implements the hooks ``_initialize``, ``_ask`` and ``_tell`` only (the pymoo / nevergrad pattern).

A problem is anything with ``dim``, ``lower``, ``upper`` (arrays of length ``dim``) and
``evaluate(X (pop, dim)) -> (pop,)`` costs to minimize; ``block`` (optional, default 1) tells
operators that work gene-group-wise (GA crossover) how many genes form one waypoint.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, fields, is_dataclass, replace
from typing import Any, ClassVar, Protocol, TypeVar, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uavplan.compile_clock import Stopwatch
from uavplan.params import check_fields, option

FloatArray = NDArray[np.float64]


class OptimizerError(ValueError):
    """Misuse of an optimizer: a malformed ``tell``, an unknown name, a bad configuration."""


@runtime_checkable
class Problem(Protocol):
    """What an optimizer minimizes: a box-bounded, batch-evaluated objective."""

    @property
    def dim(self) -> int: ...

    @property
    def lower(self) -> FloatArray: ...

    @property
    def upper(self) -> FloatArray: ...

    def evaluate(self, X: FloatArray) -> FloatArray: ...


@dataclass(frozen=True)
class FunctionProblem:
    """Wrap a vectorized function ``f(X (pop, dim)) -> (pop,)`` with box bounds."""

    f: Callable[[FloatArray], FloatArray]
    lower: FloatArray
    upper: FloatArray
    block: int = 1
    name: str = "function"

    def __post_init__(self) -> None:
        lo = np.asarray(self.lower, dtype=np.float64).ravel()
        hi = np.asarray(self.upper, dtype=np.float64).ravel()
        if lo.shape != hi.shape or np.any(hi <= lo):
            raise OptimizerError("bounds need lower < upper with equal lengths")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    @property
    def dim(self) -> int:
        return int(self.lower.shape[0])

    def evaluate(self, X: FloatArray) -> FloatArray:
        return np.asarray(self.f(np.asarray(X, dtype=np.float64)), dtype=np.float64)


@dataclass(frozen=True)
class Budget:
    """When to stop: any limit reached ends the run (None = no limit of that kind)."""

    max_iterations: int | None = None
    max_evaluations: int | None = None
    max_time: float | None = None  # seconds of wall time

    def __post_init__(self) -> None:
        if self.max_iterations is None and self.max_evaluations is None and self.max_time is None:
            raise OptimizerError("a budget needs at least one limit")
        for name in ("max_iterations", "max_evaluations", "max_time"):
            v = getattr(self, name)
            if v is not None and v <= 0:
                raise OptimizerError(f"budget {name} must be positive, got {v}")

    @classmethod
    def of(cls, budget: Budget | int) -> Budget:
        """An int means a number of iterations."""
        return budget if isinstance(budget, Budget) else cls(max_iterations=int(budget))


@dataclass(frozen=True)
class OptimizeResult:
    """The outcome of :func:`minimize`: best point and cost, history, counts, time, seed."""

    x: FloatArray
    f: float
    history: FloatArray  # best-so-far cost after each iteration, (iterations,)
    evaluations: int
    iterations: int
    wall_time: float
    seed: int | None
    algorithm: str
    config: dict[str, Any] = field(default_factory=dict)
    evaluations_history: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64)
    )


@dataclass(frozen=True)
class OptimizerConfig:
    """Base of every optimizer's frozen hyperparameter dataclass (defaults = the paper's).
    Fields are declared with :func:`uavplan.params.option` (a line of documentation, the valid
    range or choices), checked when a config is built (:class:`OptimizerError` naming the
    field) and listed by ``uavplan planners NAME``."""

    pop_size: int = option(50, "population size", low=1)

    def __post_init__(self) -> None:
        bad = check_fields(self)
        if bad is not None:
            raise OptimizerError(f"{bad[0]} {bad[1]}")


C = TypeVar("C", bound=OptimizerConfig)

#: Called after every iteration with the optimizer; return True to stop early.
Callback = Callable[["Optimizer"], bool | None]


class Optimizer(ABC):
    """Ask/tell population optimizer. Subclasses set ``name`` and ``Config`` and implement
    ``_initialize``, ``_ask`` and ``_tell`` (and ``_setup`` to allocate state); all randomness
    comes from ``self.rng``.

    ``init`` (keyword): an optional first population (pop_size, dim) used instead of uniform
    random points (e.g. paths seeded by RRT* or RGG), clipped to the box.
    """

    name: ClassVar[str] = "optimizer"
    Config: ClassVar[type[OptimizerConfig]] = OptimizerConfig

    def __init__(
        self,
        problem: Problem,
        config: OptimizerConfig | None = None,
        seed: int | np.random.SeedSequence | np.random.Generator | None = None,
        *,
        init: ArrayLike | None = None,
        **overrides: Any,
    ) -> None:
        cfg = config if config is not None else self.Config()
        if not isinstance(cfg, self.Config):
            raise OptimizerError(f"{self.name} takes a {self.Config.__name__}, got {type(cfg)}")
        if overrides:
            known = {f.name for f in fields(cfg)}
            unknown = set(overrides) - known
            if unknown:
                raise OptimizerError(
                    f"{self.name}: unknown parameter(s) {sorted(unknown)}; known: {sorted(known)}"
                )
            cfg = replace(cfg, **overrides)
        self.config = cfg
        self.problem = problem
        self.lower = np.asarray(problem.lower, dtype=np.float64)
        self.upper = np.asarray(problem.upper, dtype=np.float64)
        self.dim = int(problem.dim)
        self.block = int(getattr(problem, "block", 1))
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.evaluations = 0
        self.iterations = 0
        self.best_x: FloatArray | None = None
        self.best_f = np.inf
        self.history: list[float] = []
        self.evaluations_history: list[int] = []
        self._pending: FloatArray | None = None
        #: the population of the last iteration as the algorithm took it, and its costs: what
        #: was told, unless the algorithm evaluated points of its own within the iteration
        #: (SPSO's asynchronous update re-evaluates the particles after a new global best)
        self.last_x: FloatArray = np.empty((0, self.dim))
        self.last_f: FloatArray = np.empty(0)
        self._initialized = False
        self.init = self._check_init(init)
        self._setup()

    def _setup(self) -> None:
        """Hook: allocate the algorithm's state (called at the end of ``__init__``)."""
        return None

    def _check_init(self, init: ArrayLike | None) -> FloatArray | None:
        """Validate a user-supplied first population (pop_size, dim); clip it to the box."""
        if init is None:
            return None
        X = np.array(init, dtype=np.float64)  # a copy: later edits of the caller's are ignored
        pop = self.config.pop_size
        if X.ndim != 2 or X.shape != (pop, self.dim):
            raise OptimizerError(
                f"{self.name}: init must have shape (pop_size, dim) = {(pop, self.dim)}, "
                f"got {X.shape}"
            )
        if not np.all(np.isfinite(X)):
            raise OptimizerError(f"{self.name}: init must be finite")
        return np.clip(X, self.lower, self.upper)

    def initial_population(self, n: int | None = None) -> FloatArray:
        """The ``init`` population if one was given, else ``n`` (default pop_size) uniform
        points in the box. Algorithms call this from ``_initialize``."""
        if self.init is not None:
            return self.init.copy()
        return self.uniform(self.config.pop_size if n is None else n)

    # ------------------------------------------------------------------ fixed public API
    def ask(self) -> FloatArray:
        """The next population to evaluate, (pop, dim)."""
        if self._pending is not None:
            raise OptimizerError(f"{self.name}: ask() called twice without tell()")
        if not self._initialized:
            X = self._initialize()
            self._initialized = True
        else:
            X = self._ask()
        X = np.asarray(X, dtype=np.float64)
        self._pending = X
        return X

    def tell(self, X: FloatArray, f: FloatArray) -> None:
        """Report the costs ``f`` (pop,) of the population ``X`` (pop, dim) from :meth:`ask`."""
        if self._pending is None:
            raise OptimizerError(f"{self.name}: tell() called without a pending ask()")
        X = np.asarray(X, dtype=np.float64)
        f = np.asarray(f, dtype=np.float64)
        if X.shape != self._pending.shape:
            raise OptimizerError(
                f"{self.name}: tell() got X of shape {X.shape}, ask() gave {self._pending.shape}"
            )
        if f.shape != (X.shape[0],):
            raise OptimizerError(
                f"{self.name}: tell() needs one cost per row of X ({X.shape[0]}), got {f.shape}"
            )
        if np.any(np.isnan(f)):
            raise OptimizerError(f"{self.name}: tell() got NaN costs (use inf for infeasible)")
        self._pending = None
        self.evaluations += X.shape[0]
        self.last_x, self.last_f = X, f
        self._tell(X, f)  # may replace last_x, last_f (an optimizer that evaluates on its own)
        i = int(np.argmin(self.last_f))
        if self.last_f[i] < self.best_f or self.best_x is None:
            self.best_f = float(self.last_f[i])
            self.best_x = self.last_x[i].copy()
        self.iterations += 1
        self.history.append(self.best_f)
        self.evaluations_history.append(self.evaluations)

    # ------------------------------------------------------------------ hooks
    @abstractmethod
    def _initialize(self) -> FloatArray:
        """First population (pop, dim)."""

    @abstractmethod
    def _ask(self) -> FloatArray:
        """Next population (pop, dim) from the current state."""

    @abstractmethod
    def _tell(self, X: FloatArray, f: FloatArray) -> None:
        """Update the state with evaluated ``X`` and costs ``f``."""

    # ------------------------------------------------------------------ helpers for subclasses
    def uniform(self, n: int) -> FloatArray:
        """``n`` points uniform in the box, (n, dim)."""
        return self.lower + self.rng.random((n, self.dim)) * (self.upper - self.lower)

    def clip(self, X: FloatArray) -> FloatArray:
        # minimum/maximum: the same as np.clip, without its dispatch overhead (hot path)
        return np.minimum(np.maximum(X, self.lower), self.upper)


# ---------------------------------------------------------------------- registry
_REGISTRY: dict[str, type[Optimizer]] = {}

O = TypeVar("O", bound=type[Optimizer])


def register(cls: O) -> O:
    """Class decorator: register an optimizer under its lowercase ``name``."""
    key = cls.name.lower()
    if key in _REGISTRY and _REGISTRY[key] is not cls:
        raise OptimizerError(f"optimizer name {key!r} is already registered")
    _REGISTRY[key] = cls
    return cls


def available() -> list[str]:
    """Names of the registered optimizers (importing this module imports the package, whose
    ``__init__`` imports, and so registers, the built-in ones)."""
    return sorted(_REGISTRY)


def get(name: str) -> type[Optimizer]:
    """The optimizer class registered under ``name``."""
    try:
        return _REGISTRY[name.lower()]
    except KeyError:
        raise OptimizerError(f"unknown optimizer {name!r}; available: {available()}") from None


def config_dict(config: Any) -> dict[str, Any]:
    return asdict(config) if is_dataclass(config) and not isinstance(config, type) else {}


def minimize(
    problem: Problem,
    algorithm: str | type[Optimizer],
    budget: Budget | int,
    seed: int | None = None,
    config: OptimizerConfig | None = None,
    callback: Callback | None = None,
    **overrides: Any,
) -> OptimizeResult:
    """Run an optimizer on ``problem`` until ``budget`` is spent.

    Args:
        problem: see :class:`Problem`.
        algorithm: a registered name or an :class:`Optimizer` subclass.
        budget: a :class:`Budget` or a number of iterations.
        seed: root seed; the same seed gives the same bits.
        config: hyperparameters (the algorithm's defaults otherwise); ``overrides`` replace fields.
        callback: called after each iteration; returning True stops the run.

    Optimizers whose config has a ``max_iterations`` schedule (GWO, WOA, RSCDWOA: ``a`` falls
    from 2 to 0 over the run) get the budget's iteration count there unless it is set
    explicitly (in ``config`` or ``overrides``).
    """
    cls = get(algorithm) if isinstance(algorithm, str) else algorithm
    cfg = fit_schedule(config if config is not None else cls.Config(), budget, overrides)
    opt = cls(problem, cfg, seed=seed, **overrides)
    return run(opt, budget, seed=seed, callback=callback)


def fit_schedule(
    config: OptimizerConfig,
    budget: Budget | int | None,
    explicit: Mapping[str, Any] | None = None,
) -> OptimizerConfig:
    """``config`` with ``max_iterations`` set to the budget's iterations, if the config has that
    field still at its default, the budget counts iterations and the caller did not set it in
    ``explicit``."""
    defaults = {f.name: f.default for f in fields(config)}
    if "max_iterations" not in defaults or "max_iterations" in (explicit or {}) or budget is None:
        return config
    b = Budget.of(budget)
    if b.max_iterations is None or config.max_iterations != defaults["max_iterations"]:  # type: ignore[attr-defined]
        return config
    return replace(config, max_iterations=b.max_iterations)  # type: ignore[call-arg]


def run(
    opt: Optimizer,
    budget: Budget | int,
    seed: int | None = None,
    callback: Callback | None = None,
) -> OptimizeResult:
    """Drive an already built optimizer with ask/tell until ``budget`` is spent."""
    b = Budget.of(budget)
    t0 = time.perf_counter()
    clock = Stopwatch()  # the reported time leaves kernel compilation out
    while True:
        X = opt.ask()
        f = opt.problem.evaluate(X)
        opt.tell(X, f)
        if callback is not None and callback(opt):
            break
        if b.max_iterations is not None and opt.iterations >= b.max_iterations:
            break
        if b.max_evaluations is not None and opt.evaluations >= b.max_evaluations:
            break
        if b.max_time is not None and time.perf_counter() - t0 >= b.max_time:
            break
    assert opt.best_x is not None
    return OptimizeResult(
        x=opt.best_x,
        f=opt.best_f,
        history=np.asarray(opt.history),
        evaluations=opt.evaluations,
        iterations=opt.iterations,
        wall_time=clock.elapsed,
        seed=seed,
        algorithm=opt.name,
        config=config_dict(opt.config),
        evaluations_history=np.asarray(opt.evaluations_history, dtype=np.int64),
    )
