"""A run's memory, estimated before it starts (:func:`estimate_run`), and the memory the process
may still use (:func:`available_memory`): ``uavplan plan`` refuses a run whose estimate does not
fit, with both figures, instead of running out of memory part way (``docs/scenario-format.md``,
"Limits").

The estimate adds up what grows with the input, each term an upper-side figure per item:

* the terrain: the DEM's heights and what is built from them once (the clearance max-pyramid,
  the kernels' tables, the cost's sampled maps): :data:`TERRAIN_BYTES_PER_CELL` per node;
  HR-MAGA's pyramid of coarse maps adds :data:`PYRAMID_BYTES_PER_CELL` per node;
* the population: each of its paths' points held in the optimizer's arrays (positions,
  velocities, bests, the trial) and one evaluation's batch (segments, heights, times):
  :data:`POPULATION_BYTES_PER_POINT` per coordinate; plus one float64 per path segment and
  obstacle (the per-obstacle distances the unfused checks return). HR-MAGA keeps one
  population per sub-problem, up to ``9 ** (v - 1)`` of them at its finest level;
* a fleet: every UAV's flown trajectory, its results and its reservation-table pieces,
  :data:`FLIGHT_BYTES_PER_SAMPLE` per sample, a flight sampled at most 5 m apart (a turn
  radius R: ``min(5, R / 4)``) over about twice the box's diagonal;

What the process holds already (the interpreter, NumPy, Numba, the kernels: about 350 MB) is not
counted: the available memory is what is left beside it.
"""

from __future__ import annotations

import dataclasses
import math
import os
import resource
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from uavplan.planners.core.base import Planner
    from uavplan.world import Scenario

#: Bytes per DEM node: heights (8), the max-pyramid (about 8 / 3), the kernels' and the
#: cost's maps; rounded up.
TERRAIN_BYTES_PER_CELL = 48
#: Bytes per DEM node of HR-MAGA's pyramid (a conservative and a sampled map per level).
PYRAMID_BYTES_PER_CELL = 32
#: Bytes per coordinate of a population's path points (16 float64 copies).
POPULATION_BYTES_PER_POINT = 128
#: Bytes per sample of a UAV's flight (the flown trajectory and its times, the result's copies,
#: the reservation table's pieces and grid entries).
FLIGHT_BYTES_PER_SAMPLE = 400


@dataclass(frozen=True)
class MemoryEstimate:
    """A run's estimated memory, bytes, by part."""

    terrain: int
    population: int
    fleet: int

    @property
    def total(self) -> int:
        return self.terrain + self.population + self.fleet

    def describe(self) -> str:
        parts = ", ".join(f"{k} {gib(v)}" for k, v in dataclasses.asdict(self).items() if v)
        return f"about {gib(self.total)} ({parts})"


def gib(n: float) -> str:
    return f"{n / 2**30:.2f} GiB" if n >= 2**28 else f"{n / 2**20:.0f} MiB"


def _pop_size(planner: Planner) -> int:
    """The population a planner's search holds (1 for a planner without one)."""
    for cfg in (getattr(planner, "config", None), getattr(planner, "optimizer_config", None)):
        size = getattr(cfg, "pop_size", None)
        if isinstance(size, int):
            return size
    return 1


def estimate_run(
    scenario: Scenario, planner: Planner, pop_size: int | None, n_waypoints: int | None
) -> MemoryEstimate:
    """The memory ``planner`` will use on ``scenario`` with these options (see the module)."""
    pop = pop_size or _pop_size(planner)
    n_points = (n_waypoints or scenario.n_waypoints) + 2
    dim = scenario.dim
    cells = 0 if scenario.terrain is None else int(math.prod(scenario.terrain.shape))
    terrain = cells * TERRAIN_BYTES_PER_CELL
    config: Any = getattr(planner, "config", None)
    copies = 1
    if hasattr(config, "v") and hasattr(config, "num") and scenario.terrain is not None:
        terrain += cells * PYRAMID_BYTES_PER_CELL  # HR-MAGA: its pyramid
        copies = 9 ** max(0, int(config.v) - 1)  # populations of its finest level
    n_obstacles = len(scenario.cylinders) + len(scenario.circles) + len(scenario.polygons)
    per_path = n_points * dim * POPULATION_BYTES_PER_POINT + (n_points - 1) * n_obstacles * 8
    population = copies * pop * per_path
    fleet = 0
    n_uavs = len(scenario.tasks)
    if n_uavs > 1:
        lo, hi = scenario.bounds.lower, scenario.bounds.upper
        diagonal = math.dist(lo, hi)
        radius = scenario.uav.turn_radius
        step = min(5.0, radius / 4) if radius > 0 else 5.0
        samples = max(n_points, 2.0 * diagonal / step)
        fleet = int(n_uavs * samples * FLIGHT_BYTES_PER_SAMPLE)
    return MemoryEstimate(terrain, population, fleet)


def proc_field_kib(path: str, key: str) -> int | None:
    """A ``key: value kB`` field of a Linux ``/proc`` file (``/proc/meminfo``,
    ``/proc/self/status``) in KiB; None off Linux or when absent."""
    try:
        with open(path, encoding="ascii") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def _meminfo(key: str) -> int | None:
    kib = proc_field_kib("/proc/meminfo", key)
    return None if kib is None else kib * 1024


def _vm_size() -> int:
    return (proc_field_kib("/proc/self/status", "VmSize") or 0) * 1024


def available_memory() -> tuple[int | None, str]:
    """The memory this process may still take, bytes, and where the figure comes from: the
    system's available memory (``MemAvailable``, else the free pages), and the address-space
    limit (``RLIMIT_AS``) less what the process maps already, whichever is smaller. None when
    neither can be read."""
    found: list[tuple[int, str]] = []
    avail = _meminfo("MemAvailable")
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError):
            avail = None
    if avail is not None:
        found.append((avail, "available memory"))
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        found.append((max(0, soft - _vm_size()), "address-space limit (ulimit -v) left"))
    if not found:
        return None, "unknown"
    return min(found)


def memory_problem(estimate: MemoryEstimate) -> str | None:
    """Why a run of this estimate should not start, or None when it fits."""
    avail, where = available_memory()
    if avail is None or estimate.total <= avail:
        return None
    return (
        f"this run needs {estimate.describe()} more and the {where} is {gib(avail)}: use a "
        "smaller population (--pop-size), fewer waypoints or UAVs, or a coarser DEM"
    )
