"""Mission export formats, one module each, found by name (``uavplan export --format NAME``).

An exporter reads a typed plan (:class:`uavplan.io.plan_file.PlanFile`) and writes one file for
the fleet, or one file per UAV where the format holds a single vehicle, and returns the paths
written. A new format is a new module here that decorates its function with
:func:`register_exporter` (every module here is imported).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from uavplan.io.plan_file import PlanFile, TrajectoryKind

#: ``exporter(plan, out, kind) -> paths written``; ``out`` is a file for a fleet-wide format and
#: a folder for a per-UAV one; ``kind`` is which trajectory of each UAV is exported.
ExportFn = Callable[[PlanFile, Path, TrajectoryKind], list[Path]]


class ExportError(ValueError):
    """An unknown format, or a plan the format cannot hold."""


@dataclass(frozen=True)
class Exporter:
    """A registered format: its name, file suffix, whether it writes one file per UAV, a line
    of description and the function."""

    name: str
    suffix: str
    per_uav: bool
    description: str
    write: ExportFn


_FORMATS: dict[str, Exporter] = {}


def register_exporter(
    name: str, suffix: str, description: str, per_uav: bool = False
) -> Callable[[ExportFn], ExportFn]:
    """Decorator: register an export format."""

    def add(fn: ExportFn) -> ExportFn:
        if name in _FORMATS and _FORMATS[name].write is not fn:
            raise ExportError(f"export format {name!r} is already registered")
        _FORMATS[name] = Exporter(name, suffix, per_uav, description, fn)
        return fn

    return add


def exporters() -> dict[str, Exporter]:
    """The registered formats by name."""
    return dict(_FORMATS)


def get_exporter(name: str) -> Exporter:
    try:
        return _FORMATS[name]
    except KeyError:
        known = sorted(_FORMATS)
        raise ExportError(f"unknown export format {name!r}; choose from {known}") from None


from uavplan._discovery import import_submodules  # noqa: E402

import_submodules(__name__, __path__)  # registers every format module's exporters
