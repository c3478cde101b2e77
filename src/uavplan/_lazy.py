"""Modules imported on first use (the standard library's ``importlib.util.LazyLoader``): the
experiment plans' modules use pandas, SciPy's statistics and matplotlib only when a report is
written, and ``uavplan bench list`` should not wait 2 s for them. Under ``TYPE_CHECKING`` the
modules import normally, so their types stay checked."""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType


def lazy_module(name: str) -> ModuleType:
    """``name`` as a module that is executed when one of its attributes is first read (already
    imported: the module itself)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:  # pragma: no cover - a missing dependency
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    loader = importlib.util.LazyLoader(spec.loader)
    spec.loader = loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    loader.exec_module(module)
    return module
