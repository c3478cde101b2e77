"""What the command groups share: error exits without a traceback, ``--param`` parsing, loading
a scenario named on the command line."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import typer
from rich.console import Console

if TYPE_CHECKING:
    from uavplan.world.scenario import Scenario

#: messages stay one line each (no wrapping at the terminal's width), also when piped
err = Console(stderr=True, soft_wrap=True, highlight=False)
out = Console(soft_wrap=True)


#: modules whose Numba kernels every plan uses (their cache tells a first run)
_KERNEL_MODULES = (
    "world/geometry/cylinders.py",
    "world/_terrain_kernels.py",
    "problems/_validity_kernels.py",
)


def kernels_cached() -> bool:
    """Whether Numba's cache holds kernels of the modules every plan uses (beside the package,
    or under ``NUMBA_CACHE_DIR``)."""
    import os
    from pathlib import Path

    import uavplan

    root = Path(uavplan.__file__).resolve().parent
    cache = os.environ.get("NUMBA_CACHE_DIR")
    for rel in _KERNEL_MODULES:
        stem = Path(rel).stem
        folder = (root / rel).parent / "__pycache__"
        found = list(folder.glob(f"{stem}.*.nbi")) if folder.is_dir() else []
        if not found and cache:
            found = list(Path(cache).rglob(f"{stem}.*.nbi"))
        if not found:
            return False
    return True


def compile_notice() -> None:
    """One line on stderr before the first plan on this machine: the kernels compile once."""
    if not kernels_cached():
        err.print("compiling kernels once (about 10-20 s; later runs reuse them)",
                  markup=False, highlight=False)  # fmt: skip


def print_table(table: Any) -> None:
    """A table whole: as wide as it needs when the output is not a terminal (a file or a pipe
    has no width to keep to), cells folded rather than cut on a terminal."""
    if out.is_terminal:
        for col in table.columns:
            col.overflow = "fold"
        out.print(table)
        return
    from rich.measure import Measurement

    need = Measurement.get(out, out.options.update_width(10_000), table).maximum
    wide = Console(file=out.file, width=max(out.width, need), soft_wrap=True, highlight=False)
    wide.print(table)


def fail(lines: list[str] | str, code: int = 2) -> typer.Exit:
    """Print problem lines to stderr and return the Exit to raise (no traceback)."""
    for line in [lines] if isinstance(lines, str) else lines:
        err.print(line, markup=False, highlight=False)
    return typer.Exit(code)


def parse_params(params: list[str]) -> dict[str, Any]:
    parsed: dict[str, Any] = {}
    for item in params:
        if "=" not in item:
            raise fail(f"--param {item!r}: expected NAME=VALUE")
        k, v = item.split("=", 1)
        value: Any = v
        for conv in (int, float):
            try:
                value = conv(v)
                break
            except ValueError:
                continue
        if v.lower() in ("true", "false"):
            value = v.lower() == "true"
        parsed[k.strip()] = value
    return parsed


def world_of_plan(world: Scenario, ref: str, execution: Any, starts: dict[str, Any]) -> Scenario:
    """``world`` with its generated fleet placed where ``uavplan plan`` placed it under the plan's
    ``execution`` model (:func:`uavplan.strategy.world.fleet_as_planned`), when the plan's
    paths (``starts``: the first point of each UAV's path by id) begin there; else ``world``."""
    from uavplan.strategy.world import fleet_as_planned

    placed = fleet_as_planned(world, ref, execution)
    if placed is world:
        return world
    import numpy as np

    tasks = {t.id: t for t in placed.tasks}
    for uid, p in starts.items():
        t = tasks.get(uid)
        q = np.asarray(p, dtype=np.float64)
        if t is None or float(np.linalg.norm(np.asarray(t.start)[: q.shape[0]] - q)) > 1e-3:
            return world
    return placed


def load_world(name: str, quiet: bool = False) -> Scenario | None:
    """The scenario a command names (built-in, generated or file); its problems end the command
    with exit code 2, or, with ``quiet``, give None (a plan's own scenario name that is not a
    built-in one)."""
    from uavplan.io.scenario_file import ScenarioFileError
    from uavplan.scenarios import resolve

    try:
        return resolve(name)
    except ScenarioFileError as exc:
        if quiet:
            return None
        raise fail(exc.problems) from None
    except (OSError, ValueError) as exc:
        if quiet:
            return None
        raise fail(f"{name}: {exc}") from None
