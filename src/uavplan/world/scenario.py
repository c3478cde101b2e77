"""The world a planner sees: bounds, terrain, obstacles, UAV limits and tasks."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.world.dynamic import MovingObstacle
from uavplan.world.execution import ExecutionModel
from uavplan.world.geo import GeoOrigin
from uavplan.world.geometry import pack_polygons
from uavplan.world.obstacles import (
    AltitudeBand,
    Circle,
    Cylinder,
    DangerArea,
    Polygon,
    UncertainArea,
)
from uavplan.world.terrain import Terrain
from uavplan.world.tolerances import BAND_TOL, BOUNDS_TOL

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Bounds:
    """Axis-aligned box the paths must stay in: ``lower``/``upper`` of length ``dim`` metres."""

    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def __post_init__(self) -> None:
        lo = np.asarray(self.lower, dtype=np.float64)
        hi = np.asarray(self.upper, dtype=np.float64)
        if lo.shape != hi.shape or lo.ndim != 1 or lo.shape[0] not in (2, 3):
            raise ValueError(f"bounds need 2 or 3 lower and upper values, got {lo} and {hi}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.any(hi <= lo):
            raise ValueError(f"bounds need finite lower < upper, got {lo} and {hi}")
        object.__setattr__(self, "lower", tuple(float(v) for v in lo))
        object.__setattr__(self, "upper", tuple(float(v) for v in hi))

    @property
    def dim(self) -> int:
        return len(self.lower)

    @property
    def lo(self) -> FloatArray:
        return np.asarray(self.lower)

    @property
    def hi(self) -> FloatArray:
        return np.asarray(self.upper)

    def contains(self, points: FloatArray, tol: float = BOUNDS_TOL) -> NDArray[np.bool_]:
        p = np.asarray(points, dtype=np.float64)[..., : self.dim]
        return np.asarray(np.all((p >= self.lo - tol) & (p <= self.hi + tol), axis=-1))


@dataclass(frozen=True)
class UAV:
    """A UAV's limits.

    Attributes:
        speed: cruise speed, m/s (> 0); planners time their paths with it.
        turn_radius: minimum turn radius of the horizontal track, m (>= 0; 0: no limit, the UAV
            turns in place).
        s1: the distance of PPSwarm's threat cost (Eq. 5), m: a cost that grows as a path nears
            an obstacle, not a clearance any check keeps (the clearance a plan keeps is its
            execution model's tracking error); s2: separation between UAVs, m; size: m.
        min_speed: slowest allowed speed, m/s (>= 0; 0: it may hover).
        max_speed: fastest allowed speed, m/s (>= speed; None: ``speed``; see :attr:`v_max`).
        max_climb_angle, max_descent_angle: steepest climb and descent, degrees from the
            horizontal in (0, 90] (None: no limit).
        s2_axes: the separation between UAVs per axis, ``(S_x, S_y, S_z)`` metres (the
            RSCDWOA paper's ``[50, 50, 20]``): two UAVs are too close when they are closer than
            all three at once (an axis-aligned box). When given it replaces the sphere ``s2``
            in every separation check (the motion validator, the reservation table, the
            verifier); None: the sphere of radius ``s2``.
        airframe: the UAV's class and airframe for flight simulation
            (:data:`uavplan.world.airframes.AIRFRAMES`); None: by its limits
            (:func:`uavplan.world.airframes.airframe_of`).

    Defaults: PPSwarm Sect. 5.1 for speed, s1 and s2 (20 m/s, 15 m, 10 m); no turn, climb or
    minimum-speed limit (the PPSwarm scenario files set the paper's 20 m turn radius).
    """

    speed: float = 20.0
    turn_radius: float = 0.0
    s1: float = 15.0
    s2: float = 10.0
    size: float = 1.0
    min_speed: float = 0.0
    max_speed: float | None = None
    max_climb_angle: float | None = None
    max_descent_angle: float | None = None
    s2_axes: tuple[float, float, float] | None = None
    airframe: str | None = None

    def __post_init__(self) -> None:
        if self.airframe is not None:
            from uavplan.world.airframes import AIRFRAMES

            if self.airframe not in AIRFRAMES:
                raise ValueError(f"uav airframe {self.airframe!r}: choose from "
                                 f"{', '.join(sorted(AIRFRAMES))}")  # fmt: skip
        for name in ("speed", "turn_radius", "s1", "s2", "size", "min_speed"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0 or (name == "speed" and value == 0):
                raise ValueError(
                    f"uav {name} must be a finite number "
                    f"{'> 0' if name == 'speed' else '>= 0'}, got {value!r}"
                )
        if self.min_speed > self.speed:
            raise ValueError(
                f"uav min_speed {self.min_speed:g} m/s is above speed {self.speed:g} m/s "
                "(need min_speed <= speed)"
            )
        if self.max_speed is not None:
            if not np.isfinite(self.max_speed):
                raise ValueError(f"uav max_speed must be a finite number, got {self.max_speed!r}")
            if self.max_speed < self.speed:
                raise ValueError(
                    f"uav max_speed {self.max_speed:g} m/s is below speed {self.speed:g} m/s "
                    "(need speed <= max_speed)"
                )
        for name in ("max_climb_angle", "max_descent_angle"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and 0 < value <= 90):
                raise ValueError(f"uav {name} must be in (0, 90] degrees, got {value!r}")

        if self.s2_axes is not None:
            axes = tuple(float(a) for a in self.s2_axes)
            if len(axes) != 3 or not all(np.isfinite(a) and a > 0 for a in axes):
                raise ValueError(
                    f"uav s2_axes must be three finite distances > 0 (x, y, z), "
                    f"got {self.s2_axes!r}"
                )
            object.__setattr__(self, "s2_axes", axes)

    @property
    def separation_radius(self) -> float:
        """The radius of the smallest sphere holding the separation region: ``s2``, or the
        half-diagonal of the ``s2_axes`` box (what a planner that reasons with spheres keeps)."""
        if self.s2_axes is None:
            return float(self.s2)
        return float(np.linalg.norm(self.s2_axes))

    @property
    def v_max(self) -> float:
        """The fastest allowed speed, m/s: ``max_speed`` if given, else ``speed``."""
        return float(self.speed if self.max_speed is None else self.max_speed)


@dataclass(frozen=True)
class Task:
    """A UAV's mission: fly from ``start`` to ``goal`` (absolute metres), leaving at
    ``start_time`` seconds. ``cruise``: the height, in the altitude band's reference, that
    PPSwarm's altitude cost (Eqs. 6-7) pulls the UAV toward instead of the band's middle (a
    planner's cruise layer, :mod:`uavplan.world.cruise_layers`; None: the band's middle)."""

    id: str
    start: tuple[float, ...]
    goal: tuple[float, ...]
    start_time: float = 0.0
    cruise: float | None = None

    def __post_init__(self) -> None:
        s = np.asarray(self.start, dtype=np.float64)
        g = np.asarray(self.goal, dtype=np.float64)
        if s.shape != g.shape or s.ndim != 1 or s.shape[0] not in (2, 3):
            raise ValueError(f"task {self.id}: start and goal need 2 or 3 coordinates")
        object.__setattr__(self, "start", tuple(float(v) for v in s))
        object.__setattr__(self, "goal", tuple(float(v) for v in g))


@dataclass(frozen=True, eq=False)
class Scenario:
    """Everything a planner needs to know about the world and the mission.

    ``dim`` is 2 for flat scenes (circles and polygons; no terrain) or 3. Coordinates are metres in
    a local frame (x east, y north, z up). ``cost`` and ``n_waypoints`` are the defaults a planner
    uses for this scenario (a cost preset name from :mod:`uavplan.problems.costs`).
    """

    name: str
    bounds: Bounds
    tasks: tuple[Task, ...]
    terrain: Terrain | None = None
    circles: tuple[Circle, ...] = ()
    polygons: tuple[Polygon, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    danger_areas: tuple[DangerArea, ...] = ()
    uncertain_areas: tuple[UncertainArea, ...] = ()
    moving_obstacles: tuple[MovingObstacle, ...] = ()
    altitude: AltitudeBand | None = None
    uav: UAV = field(default_factory=UAV)
    cost: str = "ppswarm"
    n_waypoints: int = 10
    description: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)
    #: where the local frame sits on Earth (None: not geo-referenced; mission export needs it)
    origin: GeoOrigin | None = None
    #: the execution error the plan must tolerate (:mod:`uavplan.world.execution`); None: the
    #: nominal model (flown exactly)
    execution: ExecutionModel | None = None

    def __post_init__(self) -> None:
        if not self.tasks:
            raise ValueError("a scenario needs at least one task")
        for t in self.tasks:
            if len(t.start) != self.dim:
                raise ValueError(
                    f"task {t.id} has {len(t.start)} coordinates, scenario is {self.dim}-D"
                )
        if self.dim == 2 and (self.terrain is not None or self.cylinders):
            raise ValueError("a 2-D scenario has no terrain and no cylinders (use circles)")

    @property
    def dim(self) -> int:
        return self.bounds.dim

    def task(self, task_id: str | int | None = None) -> Task:
        """The task by id or index (the first one by default)."""
        if task_id is None:
            return self.tasks[0]
        if isinstance(task_id, int):
            return self.tasks[task_id]
        for t in self.tasks:
            if t.id == task_id:
                return t
        raise KeyError(f"no task {task_id!r} in scenario {self.name!r}")

    # ---------------------------------------------------------------- packed arrays for kernels
    @property
    def no_fly_polygons(self) -> tuple[Polygon, ...]:
        """Polygons plus revealed uncertain areas."""
        return self.polygons + tuple(u.as_polygon() for u in self.uncertain_areas if u.revealed)

    def packed_polygons(self) -> tuple[FloatArray, NDArray[np.int64]]:
        return pack_polygons([p.array for p in self.no_fly_polygons])

    def ground(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """Terrain height (0 where the scenario has no terrain)."""
        if self.terrain is None:
            return np.zeros(np.broadcast_shapes(np.shape(x), np.shape(y)))
        return self.terrain.height(x, y)

    def point_problems(self, point: FloatArray) -> list[str]:
        """Why a single point (a start or a goal) is not a valid place to be; empty if it is."""
        p = np.asarray(point, dtype=np.float64)
        out: list[str] = []
        if not bool(self.bounds.contains(p)):
            out.append(f"outside the bounds {list(self.bounds.lower)}..{list(self.bounds.upper)}")
        for i, c in enumerate(self.circles):
            if bool(c.contains(p)):
                out.append(f"inside circle {i}")
        for i, poly in enumerate(self.no_fly_polygons):
            if bool(poly.contains(p[:2])):
                out.append(f"inside polygon {i}")
        if self.dim == 3:
            z = float(p[2])
            for i, cyl in enumerate(self.cylinders):
                d = float(np.hypot(p[0] - cyl.center[0], p[1] - cyl.center[1]))
                if (
                    d < cyl.effective_radius
                    and cyl.z_min - cyl.margin <= z <= cyl.z_max + cyl.margin
                ):
                    out.append(f"inside cylinder {i}")
            g = float(self.ground(p[0], p[1]))
            if self.terrain is not None and z < g:
                out.append(f"under the terrain (z={z:g} m, ground {g:.1f} m)")
            if self.altitude is not None:
                ground = self.altitude.reference == "ground"
                h = z - g if ground else z
                hc = h
                if ground and self.terrain is not None and self.terrain.lower is not None:
                    hc = z - float(self.terrain.height_low(p[0], p[1]))
                what = "above ground" if ground else "altitude"
                lo_ok = self.altitude.min - BAND_TOL <= h
                hi_ok = hc <= self.altitude.max + BAND_TOL
                if not (lo_ok and hi_ok):
                    shown = h if not lo_ok or hc == h else hc
                    out.append(
                        f"{what} {shown:.1f} m outside the band [{self.altitude.min:g}, "
                        f"{self.altitude.max:g}]"
                    )
                    if lo_ok and h <= self.altitude.max + BAND_TOL:  # the gap alone
                        out.append(
                            f"(the terrain's floor grid is at {g:.1f} m here and its ceiling "
                            f"grid at {z - hc:.1f} m: the band is held above the highest and "
                            "below the lowest ground the raster can have between the nodes; "
                            "a smaller terrain cell_size narrows the gap)"
                        )
        return out
