"""Import every module of a package (in name order), so that adding a planner, an optimizer, a
paper's experiments or an export format is adding one file: the registries fill themselves."""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Iterable


def import_submodules(package: str, path: Iterable[str], skip: Iterable[str] = ()) -> list[str]:
    """Import ``package.<name>`` for every module file in ``path`` (a package's ``__path__``)
    whose name does not start with ``_`` and is not in ``skip``; returns the names."""
    names = sorted(m.name for m in pkgutil.iter_modules(list(path)))
    names = [n for n in names if not n.startswith("_") and n not in set(skip)]
    for n in names:
        importlib.import_module(f"{package}.{n}")
    return names
