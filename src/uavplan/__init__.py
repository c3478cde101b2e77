"""uavplan: safe, flyable UAV paths through real 3-D worlds, and honest planner comparisons.

Layers (see docs/architecture.md): ``world`` (what is out there), ``problems`` (how good is a
batch of paths), ``optimizers`` and ``planners`` (how to find better ones), and the CLI.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("uavplan")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
