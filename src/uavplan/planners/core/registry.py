"""The planner registry: :func:`register_planner` (a class decorator, or a named configuration of
a class), the entries, and providers that add entries before lookups (the optimizer planner
registers one per optimizer). Lookups by name are in :mod:`uavplan.planners`."""

from __future__ import annotations

import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from uavplan._text import first_sentence
from uavplan.planners.core.base import FleetPlanner, Planner
from uavplan.planners.core.options import PlannerError


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
    doc = summary or first_sentence(cls.__doc__ or "")
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
