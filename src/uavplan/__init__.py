"""uavplan: safe, flyable UAV paths through real 3-D worlds, and honest planner comparisons.

Layers (see docs/architecture.md): ``world`` (what is out there), ``problems`` (how good is a
batch of paths), ``optimizers`` and ``planners`` (how to find better ones), and the CLI.

Numba's compiled kernels are cached beside the package (``cache=True``); where the package's
folder is not writable (a system-wide or read-only install), they go to a user cache folder
instead (``$XDG_CACHE_HOME/uavplan/numba``, else ``~/.cache/uavplan/numba``), so that they are
compiled once, not at every start. ``NUMBA_CACHE_DIR``, when set, is left as it is.
"""

import os
import sys
from pathlib import Path
from typing import Any


def __getattr__(name: str) -> str:
    """``__version__`` from the installed metadata, read on first use (importlib.metadata
    costs a tenth of ``uavplan --help``'s start)."""
    if name != "__version__":
        raise AttributeError(f"module 'uavplan' has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        v = version("uavplan")
    except PackageNotFoundError:  # pragma: no cover - a source tree without install
        v = "0.0.0+unknown"
    globals()["__version__"] = v
    return v


def numba_cache_dir(package: Path, env: dict[str, str], writable: bool | None = None) -> str | None:
    """Where Numba should cache: None (its default, beside the package) when
    ``NUMBA_CACHE_DIR`` is set or the package folder is writable (``writable``: as tested by
    ``os.access`` unless given); else the user cache folder."""
    if writable is None:
        writable = os.access(package, os.W_OK)
    if env.get("NUMBA_CACHE_DIR") or writable:
        return None
    base = env.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return str(Path(base) / "uavplan" / "numba")


_cache = numba_cache_dir(Path(__file__).resolve().parent, dict(os.environ))
if _cache is not None:
    os.environ["NUMBA_CACHE_DIR"] = _cache


def _html(obj: Any) -> str:
    # bound late, by name: the package's root is imported by every layer (its version), and
    # only a notebook that shows a plan needs the figures
    from importlib import import_module

    return str(import_module("uavplan.viz.notebook").html(obj))


#: What shows itself in Jupyter: (module, class) of plans, UAV results and scenarios.
DISPLAYED = (
    ("uavplan.planners.fleet.fleet_plan", "FleetPlan"),
    ("uavplan.planners.core.results", "PlanResult"),
    ("uavplan.world.scenario", "Scenario"),
)


def notebook_display(shell: Any = None) -> bool:
    """Have IPython (``shell``, else the running one) show plans, UAV results and scenarios as
    HTML: the summary table and the figure (:mod:`uavplan.viz.notebook`). Registered by class
    name, so nothing is imported before one is shown; done on ``import uavplan`` inside
    IPython. False outside IPython."""
    if shell is None:
        ipython = sys.modules.get("IPython")
        shell = ipython.get_ipython() if ipython is not None else None
    if shell is None:
        return False
    formatter = shell.display_formatter.formatters["text/html"]
    for module, name in DISPLAYED:
        formatter.for_type_by_name(module, name, _html)
    return True


notebook_display()

__all__ = ["__version__", "notebook_display", "numba_cache_dir"]
