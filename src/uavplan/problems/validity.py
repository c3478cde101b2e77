"""The motion validator: is a point, a segment or a timed path clear of the world?

OMPL splits validity into a ``StateValidityChecker`` (is this state valid) and a
``MotionValidator`` (is the motion between two states valid); :class:`MotionValidator` answers
both, for whole batches, and is the only validity path of uavplan: the cost problems
(:class:`~uavplan.problems.path_problem.PathProblem`), RRT*, the RGG, the RGG-PSO+ merge, the
shortcut routines and the fleet engine all ask it. Every question is batched: points ``(m,
dim)``, segments ``a (m, dim) -> b (m, dim)`` with optional times, paths ``(pop, n, dim)`` with
optional times ``(pop, n)``.

**Checks**, in the order they are reported (each one only when the world has what it checks):

* ``bounds``: every waypoint inside the scenario's box (the box is convex, so whole segments).
* ``cylinders``: no segment passes closer than ``radius + margin`` to a cylinder's axis within
  its heights (exact).
* ``circles``, ``polygons`` (no-fly polygons and revealed uncertain areas): in 2-D and 3-D the
  ground track stays out of them (exact; polygons may be non-convex).
* ``terrain``: every point of every segment above the bilinear DEM (exact); with
  ``strict_altitude`` and a band above ground, at least the band's minimum above it.
* ``altitude``: the altitude band at every waypoint (PPSwarm Eq. 7 and SPSO check it there,
  heights above ground read as ``lookup`` says); with ``strict_altitude`` and a band above
  ground, along the whole segment too.
* ``moving``: no moving obstacle closer than its radius over continuous time, the path flown at
  its times (by default at the UAV's speed from the task's start time).
* ``separation``: with a :class:`~uavplan.world.reservations.ReservationTable` of other UAVs'
  timed trajectories, no reserved UAV closer than the table's separation at any instant.
* with ``kinematics=True``, the UAV's limits along the timed path, flown straight between
  its points at a constant speed per segment (the verifier's semantics, implemented apart
  there): ``speed`` (every segment within ``[min_speed, v_max]``), ``climb`` (every segment's
  climb or descent angle within the declared limits), ``turn`` (with a turn radius: at every
  interior point the heading change is at most ``MAX_SAMPLE_TURN_DEG`` and the curvature
  estimate, the heading change over the mean length of the two segments, at most
  ``(1 + TURN_RTOL) / turn_radius``; consecutive points with the same x, y are merged).
  Under the world's execution model (not nominal) a named fixed wing's ``climb`` also asks
  the heights it flies in its calibration's wind (:func:`uavplan.world.execution.height_lag`):
  that flight must pass the static checks and end within the model's vertical error of its
  goal (the verifier's "heights flown in the wind").
  A planned polyline is a geometric path and is not checked for them; the trajectory a UAV
  flies (:mod:`uavplan.planners.core.flight`) is.

A point is valid when the zero-length segment at it is; a segment without times is flown from
the task's start time at the UAV's speed.

:class:`Batch` holds the quantities an evaluation shares between the cost terms and the checks
(segment lengths, cylinder distances, ground heights, times, moving-obstacle distances, the
fused 2-D scene pass, separation conflicts), each computed once and only when asked for.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems import _validity_kernels as VK
from uavplan.problems import costs as C
from uavplan.problems import work
from uavplan.world import _terrain_kernels as tk
from uavplan.world import geometry as G
from uavplan.world.dynamic import min_distances, robust_min_distances
from uavplan.world.kernel_arrays import read_only, writable
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.terrain import Terrain
from uavplan.world.tolerances import (
    ANGLE_TOL_DEG,
    BAND_TOL,
    BOUNDS_TOL,
    MAX_SAMPLE_TURN_DEG,
    SPEED_RTOL,
    SPEED_SLACK,
    TURN_RTOL,
)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Every check, in report order.
CHECKS = (
    "bounds",
    "cylinders",
    "circles",
    "polygons",
    "terrain",
    "altitude",
    "moving",
    "separation",
    "speed",
    "climb",
    "turn",
)
#: The order :meth:`MotionValidator.passing` runs the checks in: the cheap ones (per waypoint,
#: or per segment against a few shapes) before the terrain walk and the reservation table.
CASCADE = ("bounds", "cylinders", "circles", "polygons", "altitude", "speed", "climb", "turn",
           "terrain", "moving", "separation")  # fmt: skip
#: The checks the fused kernel answers together in a 3-D world.
STATIC = frozenset(("bounds", "cylinders", "terrain", "altitude", "climb"))
#: The checks that read time: a take-off delay changes their verdicts and no other.
TIME_CHECKS = frozenset(("moving", "separation"))
#: Segments checked per kernel call by :meth:`MotionValidator.segments_valid` (bounds memory).
SEGMENT_CHUNK = 65536
#: :meth:`MotionValidator.graded_violation`: what one failed check adds to the violation.
CHECK_WEIGHT = 100.0


@dataclass(frozen=True)
class PackedWorld:
    """The scenario's obstacles as contiguous arrays for the batched kernels.

    Cylinders: ``cyl_centers`` (J, 2), ``cyl_radii`` (J,) radius + margin, ``cyl_margin`` (J,),
    ``cyl_lo``/``cyl_hi`` (J,) heights grown by the margin. Circles: ``circ_centers`` (C, 2),
    ``circ_radii`` (C,) radius + margin. Polygons (no-fly polygons and revealed uncertain
    areas): ``poly_verts``/``poly_starts`` (packed, see :func:`uavplan.world.geometry.
    pack_polygons`), ``poly_margin`` (K,). ``scene_prep``: what the 2-D scene pass needs of the
    circles and polygons (:func:`uavplan.world.geometry.scene_prep`: boxes, convexity, hulls,
    the obstacle grid from 64 obstacles on), once per world.
    ``lo2``/``hi2``: the box's x, y range.
    """

    cyl_centers: FloatArray
    cyl_radii: FloatArray
    cyl_margin: FloatArray
    cyl_lo: FloatArray
    cyl_hi: FloatArray
    circ_centers: FloatArray
    circ_radii: FloatArray
    poly_verts: FloatArray
    poly_starts: NDArray[np.int64]
    poly_margin: FloatArray
    lo2: FloatArray
    hi2: FloatArray
    scene_prep: tuple[Any, ...]

    @classmethod
    def of(cls, scenario: Scenario) -> PackedWorld:
        cyl = scenario.cylinders
        circ = scenario.circles
        verts, starts = scenario.packed_polygons()
        margins = np.array([p.margin for p in scenario.no_fly_polygons], dtype=np.float64)
        circ_centers = np.array([c.center for c in circ], dtype=np.float64).reshape(-1, 2)
        circ_radii = np.array([c.effective_radius for c in circ], dtype=np.float64)
        gridded = np.bool_(len(circ_radii) + len(margins) >= G.GRID_MIN_OBSTACLES)
        return cls(
            cyl_centers=np.array([c.center for c in cyl], dtype=np.float64).reshape(-1, 2),
            cyl_radii=np.array([c.effective_radius for c in cyl], dtype=np.float64),
            cyl_margin=np.array([c.margin for c in cyl], dtype=np.float64),
            cyl_lo=np.array([c.z_min - c.margin for c in cyl], dtype=np.float64),
            cyl_hi=np.array([c.z_max + c.margin for c in cyl], dtype=np.float64),
            circ_centers=circ_centers,
            circ_radii=circ_radii,
            poly_verts=verts,
            poly_starts=starts,
            poly_margin=margins,
            lo2=np.ascontiguousarray(scenario.bounds.lo[:2], dtype=np.float64),
            hi2=np.ascontiguousarray(scenario.bounds.hi[:2], dtype=np.float64),
            scene_prep=G.by_content(
                "scene prep",
                G.scene_prep,
                circ_centers,
                circ_radii,
                verts,
                starts,
                margins,
                gridded,
            ),
        )

    @property
    def n_polygons(self) -> int:
        return len(self.poly_starts) - 1


class Batch:
    """A batch of paths ``(pop, n, dim)`` (and their times) being evaluated, with the lazily
    computed quantities that cost terms and checks share.

    Args:
        validator: whose world, task and settings apply.
        paths: (pop, n >= 2, dim) metres, C-contiguous float64.
        times: (pop, n) seconds, or None for the UAV's speed from the task's start time.
    """

    def __init__(
        self, validator: MotionValidator, paths: FloatArray, times: FloatArray | None = None
    ) -> None:
        self.validator = validator
        self.scenario = validator.scenario
        self.world = validator.world
        self.paths = paths
        if times is not None:
            self.times = np.asarray(np.broadcast_to(times, paths.shape[:2]), dtype=np.float64)

    def subset(self, rows: NDArray[np.intp]) -> Batch:
        """The batch of the paths ``rows`` (same times)."""
        t = self.__dict__.get("times")
        return Batch(
            self.validator,
            np.ascontiguousarray(self.paths[rows]),
            None if t is None else np.asarray(t)[rows],
        )

    @cached_property
    def seg_len(self) -> FloatArray:
        """(pop, n - 1) metres."""
        return C.segment_lengths(self.paths)

    @cached_property
    def length(self) -> FloatArray:
        """(pop,) metres."""
        if self.validator.dim == 2:  # the fused 2-D pass measures it anyway
            return self.scene2d[0]
        return np.asarray(self.seg_len.sum(axis=1))

    @cached_property
    def cyl_hits(self) -> tuple[FloatArray, BoolArray]:
        """(pop,) each: the metres inside cylinders and whether the path enters one
        (:func:`uavplan.world.geometry.cylinder_hits`: indexed from 64 cylinders on), what the
        cylinder check and the graded violation need."""
        w = self.world
        return G.cylinder_hits(self.paths, w.cyl_centers, w.cyl_lo, w.cyl_hi, w.cyl_radii)

    @cached_property
    def cyl_overlap(self) -> tuple[FloatArray, FloatArray]:
        """(pop,) each: the metres inside cylinders (``max(0, R - d)`` summed over segments and
        cylinders) and the least ``d - R``, from one fused pass (what
        :func:`uavplan.world.geometry.cylinder_distances` would give, without its (pop, n - 1, J)
        array)."""
        w = self.world
        return G.cylinder_overlap(self.paths, w.cyl_centers, w.cyl_lo, w.cyl_hi, w.cyl_radii)

    @cached_property
    def ground(self) -> FloatArray:
        """(pop, n) terrain height under each waypoint, read as the validator's ``lookup``."""
        sc = self.scenario
        if sc.terrain is None:
            return np.zeros(self.paths.shape[:2])
        return sc.terrain.lookup(self.paths[..., 0], self.paths[..., 1], self.validator.lookup)

    @cached_property
    def band_heights(self) -> FloatArray:
        """(pop, n) heights in the altitude band's reference (above ground, or absolute)."""
        band = self.scenario.altitude
        z = self.paths[..., 2]
        return z - self.ground if band is not None and band.reference == "ground" else z

    @cached_property
    def band_heights_ceiling(self) -> FloatArray:
        """(pop, n) :attr:`band_heights` over the terrain's ceiling grid
        (``Terrain.ceiling_heights``), what the band's maximum is held against."""
        sc = self.scenario
        band = sc.altitude
        if sc.terrain is None or sc.terrain.lower is None:
            return self.band_heights
        if band is None or band.reference != "ground":
            return self.band_heights
        low = sc.terrain.lookup_low(self.paths[..., 0], self.paths[..., 1], self.validator.lookup)
        return np.asarray(self.paths[..., 2] - low)

    @cached_property
    def times(self) -> FloatArray:
        """(pop, n) seconds: at the UAV's speed from the task's start time unless given."""
        return C.path_times(self.paths, self.scenario.uav.speed, self.validator.task.start_time)

    @cached_property
    def moving_dist(self) -> FloatArray:
        """(pop, n - 1, K): exact minimum distance over time to each moving obstacle; under a
        scenario's execution model whose schedule may drift, over the times the UAV can be at
        each point (:func:`uavplan.world.dynamic.robust_min_distances`)."""
        sc = self.scenario
        model = sc.execution
        if model is not None and model.timed:
            delta0, rho = model.timing(sc.uav.speed)
            return robust_min_distances(sc.moving_obstacles, self.paths, self.times, delta0, rho)
        return min_distances(sc.moving_obstacles, self.paths, self.times)

    @cached_property
    def scene2d(self) -> tuple[FloatArray, FloatArray, BoolArray, BoolArray, BoolArray]:
        """xy length, length inside circles and polygons, circle hit, polygon hit, node out of
        the box: (pop,) each, from one fused pass (:func:`uavplan.world.geometry.scene2d_batch`).
        """
        w = self.world
        length, inside, circle_hit, polygon_hit, outside = G.scene2d_batch(
            self.paths,
            w.circ_centers,
            w.circ_radii,
            w.poly_verts,
            w.poly_starts,
            w.poly_margin,
            w.lo2,
            w.hi2,
            w.scene_prep,
        )
        return length, inside, circle_hit, polygon_hit, outside

    @cached_property
    def paths3(self) -> FloatArray:
        """The paths with z = 0 added in 2-D (the reservation table is 3-D)."""
        if self.paths.shape[-1] == 3:
            return self.paths
        return np.concatenate([self.paths, np.zeros((*self.paths.shape[:-1], 1))], axis=-1)

    @cached_property
    def conflicts(self) -> BoolArray:
        """(pop,) whether each path comes closer than the separation to a reserved UAV (a
        flight whose heights lag in the wind held off by its lag: the table's ``held``)."""
        table = self.validator.reservations
        if table is None or len(table) == 0:
            return np.zeros(self.paths.shape[0], dtype=bool)
        return table.conflicts(self.paths3, self.times, held=self.validator._slope_wind > 0)


class MotionValidator:
    """Validity of points, segments and timed paths for one task of a scenario.

    Args:
        scenario: the world.
        task: the task (for its start time; default: the scenario's first).
        strict_altitude: check the altitude band (and the band's floor above the terrain)
            along whole segments, not only at the waypoints.
        lookup: how terrain heights under waypoints are read for the band check
            (``"bilinear"``, or ``"nearest"`` as SPSO's cost reads them).
        reservations: other UAVs' timed trajectories to keep clear of (``separation``).
        kinematics: also check the UAV's kinematic limits (``speed``, ``climb``, ``turn``).
        climb: check the climb and descent angles of straight segments without the other
            kinematic limits (a planner's edges: no smoothing flattens a segment steeper than
            the UAV climbs, while corners are for the smoothing to round).
        cost_terrain: the map the cost terms read terrain heights from (a terrain pyramid
            level's sampled map, :mod:`uavplan.world.pyramid`), where the checks read the
            scenario's (that level's conservative map); default the scenario's terrain.
    """

    def __init__(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        *,
        strict_altitude: bool = False,
        lookup: str = "bilinear",
        reservations: ReservationTable | None = None,
        kinematics: bool = False,
        cost_terrain: Terrain | None = None,
        climb: bool = False,
    ) -> None:
        self.scenario = scenario
        self.cost_terrain = cost_terrain if cost_terrain is not None else scenario.terrain
        self.kinematics = bool(kinematics)
        self.climb = bool(climb)
        self.task = task if isinstance(task, Task) else scenario.task(task)
        self.dim = scenario.dim
        self.strict_altitude = bool(strict_altitude)
        self.lookup = lookup
        self.reservations = reservations
        self.world = PackedWorld.of(scenario)

    # ------------------------------------------------------------------ batches
    def check_paths(self, paths: FloatArray) -> FloatArray:
        """``paths`` as a C-contiguous, writable (pop, n >= 2, dim) float64 array (a single
        (n, dim) path becomes a batch of one; read-only paths are copied, so that every kernel
        has one signature, :mod:`uavplan.world.kernel_arrays`); ValueError naming the shape
        otherwise."""
        p = np.asarray(paths, dtype=np.float64)
        if p.ndim == 2:
            p = p[None]
        if p.ndim != 3 or p.shape[-1] != self.dim or p.shape[1] < 2:
            raise ValueError(
                f"paths must be (pop, n_points >= 2, {self.dim}), got shape {np.shape(paths)}"
            )
        return writable(p)

    def batch(self, paths: FloatArray, times: FloatArray | None = None) -> Batch:
        return Batch(self, self.check_paths(paths), times)

    def checks(self) -> tuple[str, ...]:
        """The checks that apply to this world (see the module docstring), in report order
        (worked out once per reservations/kinematics setting: RRT* asks for every edge)."""
        key = (self.reservations is not None, self.kinematics)
        cache = self.__dict__.setdefault("_checks_cache", {})
        if key not in cache:
            cache[key] = self._applicable_checks()
        return cache[key]

    def _applicable_checks(self) -> tuple[str, ...]:
        sc = self.scenario
        w = self.world
        out = ["bounds"]
        if len(w.cyl_radii):
            out.append("cylinders")
        if len(w.circ_radii):
            out.append("circles")
        if w.n_polygons > 0:
            out.append("polygons")
        if sc.dim == 3 and sc.terrain is not None:
            out.append("terrain")
        if sc.dim == 3 and sc.altitude is not None:
            out.append("altitude")
        if sc.moving_obstacles:
            out.append("moving")
        if self.reservations is not None:
            out.append("separation")
        uav = sc.uav
        if self.kinematics:
            out.append("speed")
        limits = (uav.max_climb_angle, uav.max_descent_angle)
        if (self.kinematics or self.climb) and sc.dim == 3 and any(a is not None for a in limits):
            out.append("climb")
        if self.kinematics and uav.turn_radius > 0:
            out.append("turn")
        return tuple(out)

    # ------------------------------------------------------------------ the checks
    def violations(self, b: Batch, skip: Iterable[str] = ()) -> dict[str, BoolArray]:
        """Each applicable check's failures, (pop,) bool per check name, in report order."""
        skipped = set(skip)
        work.checked(*b.paths.shape[:2])
        return {c: self._check(c, b) for c in self.checks() if c not in skipped}

    @cached_property
    def _static_cylinders(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The cylinders the fused static kernel tests: all of them, or none where the world
        has enough for the grid (:func:`uavplan.world.geometry.cylinder_hits`), which
        :meth:`passing` then asks after the kernel."""
        w = self.world
        if self._cylinders_by_grid:
            none = np.zeros(0)
            return np.zeros((0, 2)), none, none, none
        return w.cyl_centers, w.cyl_radii, w.cyl_lo, w.cyl_hi

    @property
    def _cylinders_by_grid(self) -> bool:
        return len(self.world.cyl_radii) >= G.GRID_MIN_CYLINDERS

    @property
    def _scene_by_grid(self) -> bool:
        """Whether the world's circles and polygons are many enough for the 2-D scene pass's
        obstacle grid, which :meth:`passing` then asks after the fused kernel."""
        w = self.world
        return len(w.circ_radii) + w.n_polygons >= G.GRID_MIN_OBSTACLES

    @cached_property
    def _static_scene(self) -> tuple[object, ...]:
        """The circles and polygons the fused static kernel tests (their ground tracks, as
        :func:`uavplan.world.geometry.segment_scene_hit`): all of them, or none where the
        world has enough for the obstacle grid."""
        w = self.world
        if self._scene_by_grid or not (len(w.circ_radii) or w.n_polygons):
            verts, starts = np.zeros((0, 2)), np.zeros(1, dtype=np.int64)
            prep = G.scene_prep(np.zeros((0, 2)), np.zeros(0), verts, starts, np.zeros(0))
        else:
            verts, starts, prep = w.poly_verts, w.poly_starts, w.scene_prep
        circ, poly, convex, edges, hull_s, maxv = prep[:6]
        arrays = (verts, starts, circ, poly, convex, edges, hull_s)
        return (*(np.ascontiguousarray(a) for a in arrays), int(maxv))

    @cached_property
    def _static_fused(self) -> frozenset[str]:
        """The checks the fused static kernel answers alone in this world."""
        fused = STATIC | {"circles", "polygons"}
        if self._cylinders_by_grid:
            fused -= {"cylinders"}
        if self._scene_by_grid:
            fused -= {"circles", "polygons"}
        return fused

    @cached_property
    def _static_args(self) -> tuple[object, ...] | None:
        """The arguments of the fused static-world kernel, or None where it does not apply
        (2-D)."""
        sc = self.scenario
        if self.dim != 3:
            return None
        terrain = sc.terrain
        if terrain is not None and self.lookup not in ("bilinear", "nearest"):
            return None
        band = sc.altitude
        ground = band is not None and band.reference == "ground"
        strict = self.strict_altitude and ground and terrain is not None
        need = float(band.min) if (band is not None and self.strict_altitude and ground) else 0.0
        need = max(0.0, need)
        if terrain is not None:
            H = terrain.heights
            flat, off, shp = terrain._pyramid
            nH, (nflat, noff, nshp) = terrain._neg
            ny, nx = H.shape
            eps = 64.0 * np.finfo(np.float64).eps
            tol_u, tol_v = eps * max(1.0, float(nx - 1)), eps * max(1.0, float(ny - 1))
            grid = np.array(
                [terrain.x0, terrain.y0, terrain.dx, terrain.dy, nx - 1, ny - 1, tol_u, tol_v]
            )
        else:
            H = nH = read_only(np.zeros((2, 2)))  # as a terrain's heights: one signature
            flat, off, shp = nflat, noff, nshp = tk.build_max_pyramid(H)
            grid = np.array([0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0])
        return (
            np.ascontiguousarray(sc.bounds.lo, dtype=np.float64),
            np.ascontiguousarray(sc.bounds.hi, dtype=np.float64),
            BOUNDS_TOL,
            *self._static_cylinders,
            terrain is not None, H, flat, off, shp, nH, nflat, noff, nshp, grid, need,
            band is not None, ground, self.lookup == "nearest",
            float(band.min) if band is not None else 0.0,
            float(band.max) if band is not None else 0.0,
            BAND_TOL, strict, *self._climb_limits, *self._static_scene,
        )  # fmt: skip

    @property
    def _climb_limits(self) -> tuple[float, float]:
        """The static kernel's climb and descent limits, degrees (inf: not checked)."""
        uav = self.scenario.uav
        if "climb" not in self.checks():
            return math.inf, math.inf
        up, down = uav.max_climb_angle, uav.max_descent_angle
        return (math.inf if up is None else float(up)), (math.inf if down is None else float(down))

    @cached_property
    def segment_kernel(self) -> tuple[Any, tuple[object, ...]] | None:
        """``(kernel, args)`` such that ``kernel(paths, args)`` is :meth:`paths_valid` of
        untimed 3-D paths, callable from other Numba code without a Python round trip (the fused
        static kernel's serial build), where that kernel answers every applicable check alone:
        a 3-D world of bounds, fewer than ``GRID_MIN_CYLINDERS`` cylinders, fewer than
        ``GRID_MIN_OBSTACLES`` circles and polygons, terrain read bilinearly and the altitude
        band. None elsewhere (2-D, moving obstacles, reservations, kinematics, the obstacle
        grids): then ask :meth:`paths_valid`."""
        args = self._static_args
        if args is None or not set(self.checks()) <= self._static_fused:
            return None
        return VK.static_world_ok.serial, args

    def static_kernel_args(self) -> tuple[object, ...] | None:
        """The fused static kernel's arguments after the paths
        (:func:`uavplan.problems._validity_kernels.static_path_ok`'s after ``p``) when that
        kernel alone is :meth:`passing` but for ``separation`` (a 3-D world whose every other
        check it makes: no moving obstacles, no indexed cylinders, circles or polygons, no
        kinematics), else None: what a kernel that checks a whole population in one pass
        needs."""
        args = self._static_args
        if args is None or set(self.checks()) - {"separation"} - self._static_fused:
            return None
        return args

    def passing(self, b: Batch, skip: Iterable[str] = ()) -> NDArray[np.intp]:
        """The rows of ``b`` that pass every applicable check (but ``skip``), found by
        cascading: the cheap checks first, each later one only on the paths still passing
        (the same verdicts as :meth:`violations`, without telling the failures apart). In a
        3-D world the bounds, cylinder, circle, polygon, terrain and band checks run as one
        fused kernel (:mod:`uavplan.problems._validity_kernels`); from 64 cylinders on the
        kernel leaves the cylinders to the indexed check that follows it, and from
        ``GRID_MIN_OBSTACLES`` circles and polygons those to the 2-D scene pass."""
        skipped = set(skip)
        work.checked(*b.paths.shape[:2])
        applicable = self.checks()
        names = [c for c in CASCADE if c in applicable and c not in skipped]
        names += [c for c in applicable if c not in names and c not in skipped]
        idx = np.arange(b.paths.shape[0])
        args = self._static_args
        fused = self._static_fused
        lag = False  # the fused kernel checks the climb angles, and not the heights' lag
        if args is not None and not skipped & fused:
            idx = idx[VK.static_world_ok(b.paths, args)]
            names = [c for c in names if c not in fused]
            lag = "climb" in fused and "climb" in applicable
        for c in names:
            if not idx.size:
                break
            sub = b if idx.size == b.paths.shape[0] else b.subset(idx)
            idx = idx[~self._check(c, sub)]
        if idx.size and lag and self._slope_wind:
            sub = b if idx.size == b.paths.shape[0] else b.subset(idx)
            idx = idx[~self._lag_fails(sub)]  # the fused kernel checked the angles alone
        return idx

    @cached_property
    def _slope_wind(self) -> float:
        """The wind a timed flight's heights are flown in (:func:`uavplan.world.execution.
        slope_wind`: under the world's execution model, for a named fixed wing), 0: none;
        only for the flights themselves (``kinematics``)."""
        from uavplan.world.execution import slope_wind

        sc = self.scenario
        if not self.kinematics or sc.dim != 3:
            return 0.0
        return slope_wind(sc.uav, sc.execution)

    def _lag_fails(self, b: Batch) -> BoolArray:
        """(pop,) whether a flight, flown as high as its airframe's flight-path angle in the
        wind lets it follow its planned heights (:func:`uavplan.world.execution.height_lag`),
        ends farther from its goal's height than the model's vertical tracking error, or
        leaves the world's static clearances (bounds, obstacles, the terrain and the band:
        under a model the world is the widened one, so the model's vertical tracking error
        comes on top of the lag)."""
        from uavplan.world.execution import height_lag
        from uavplan.world.tolerances import LAG_TOL

        uav = self.scenario.uav
        off = height_lag(b.paths, b.times, self._slope_wind, uav.max_climb_angle,
                         uav.max_descent_angle)  # fmt: skip
        model = self.scenario.execution
        end = max(LAG_TOL, model.track_v if model is not None else 0.0)
        bad = np.abs(off[:, -1]) > end  # it reaches its goal farther than the model's error
        rows = np.flatnonzero(~bad & (np.max(np.abs(off), axis=1) > LAG_TOL))
        if not rows.size:
            return bad
        lagged = np.array(b.paths[rows])
        lagged[..., 2] += off[rows]
        sub = Batch(self, np.ascontiguousarray(lagged), np.asarray(b.times)[rows])
        static = [c for c in self.checks() if c in STATIC and c != "climb"]
        ok = self.passing(sub, skip=set(self.checks()) - set(static))
        bad[rows] = True
        bad[rows[ok]] = False
        return bad

    def _check(self, name: str, b: Batch) -> BoolArray:
        sc = self.scenario
        p = b.paths
        band = sc.altitude
        if name == "bounds":  # in 2-D the fused scene pass tests the box too
            inbox = ~b.scene2d[4] if self.dim == 2 else np.all(sc.bounds.contains(p), axis=1)
            return np.asarray(~inbox)
        if name == "cylinders":
            return b.cyl_hits[1]
        if name == "circles":
            return b.scene2d[2]
        if name == "polygons":
            return b.scene2d[3]
        if name == "terrain":
            assert sc.terrain is not None
            need = 0.0
            if self.strict_altitude and band is not None and band.reference == "ground":
                need = max(need, band.min)
            return np.asarray(~np.all(sc.terrain.clears(p, need), axis=1))
        if name == "altitude":
            assert band is not None
            h, hc = b.band_heights, b.band_heights_ceiling
            bad = np.any((h < band.min - BAND_TOL) | (hc > band.max + BAND_TOL), axis=1)
            if self.strict_altitude and band.reference == "ground" and sc.terrain is not None:
                bad |= ~np.all(sc.terrain.stays_within(p, band.max + BAND_TOL), axis=1)
            return np.asarray(bad)
        if name == "moving":
            radii = np.array([o.radius for o in sc.moving_obstacles])
            if not self._slope_wind:
                return np.asarray(np.any(b.moving_dist < radii, axis=(1, 2)))
            # a fixed wing's heights lag its plan in the wind: each segment held that much
            # farther off (the larger of its ends' lags), as the verifier holds it
            from uavplan.world.execution import lag_extents

            uav = sc.uav
            extra = lag_extents(b.paths, b.times, self._slope_wind, uav.max_climb_angle,
                                uav.max_descent_angle)[1]  # fmt: skip
            return np.asarray(np.any(b.moving_dist < radii + extra[:, :, None], axis=(1, 2)))
        if name == "separation":
            return b.conflicts
        if name == "speed":
            return speed_violations(b.paths, b.times, sc.uav.min_speed, sc.uav.v_max)
        if name == "climb":
            bad = climb_violations(b.paths, sc.uav.max_climb_angle, sc.uav.max_descent_angle)
            return bad | self._lag_fails(b) if self._slope_wind else bad
        if name == "turn":
            return turn_violations(b.paths, sc.uav.turn_radius)
        raise ValueError(f"unknown check {name!r}; checks: {CHECKS}")

    def graded_violation(self, b: Batch, violations: dict[str, BoolArray]) -> FloatArray:
        """How badly each path fails, (pop,) >= 0: :data:`CHECK_WEIGHT` per failed check, plus
        the metres inside cylinders (summed over segments and cylinders) and outside the
        altitude band at the waypoints. A measure for feasibility-first selection: it is 0
        only for paths that pass every check (near the band's edges, within its tolerance,
        the metres outside may be tiny but non-zero on a valid path: callers keep it for the
        paths that fail)."""
        V = np.zeros(b.paths.shape[0])
        for v in violations.values():
            V += CHECK_WEIGHT * v
        w = self.world
        if len(w.cyl_radii):
            V += b.cyl_hits[0]
        band = self.scenario.altitude
        if band is not None and self.dim == 3:
            h, hc = b.band_heights, b.band_heights_ceiling
            V += np.sum(np.maximum(0.0, band.min - h) + np.maximum(0.0, hc - band.max), axis=1)
        return V

    # ------------------------------------------------------------------ questions
    def paths_valid(self, paths: FloatArray, times: FloatArray | None = None) -> BoolArray:
        """Whether each path (pop, n, dim), flown at ``times`` (pop, n), passes every check."""
        b = self.batch(paths, times)
        ok = np.zeros(b.paths.shape[0], dtype=bool)
        ok[self.passing(b)] = True
        return ok

    def segments_valid(
        self,
        a: FloatArray,
        b: FloatArray,
        t0: FloatArray | float | None = None,
        t1: FloatArray | float | None = None,
    ) -> BoolArray:
        """Whether each segment ``a[i] -> b[i]`` ((m, dim) each) is valid, (m,) bool; flown
        from ``t0`` to ``t1`` (seconds, (m,) or scalars), by default from the task's start time
        at the UAV's speed. Checked in chunks of :data:`SEGMENT_CHUNK`."""
        A = np.asarray(a, dtype=np.float64).reshape(-1, self.dim)
        B = np.asarray(b, dtype=np.float64).reshape(-1, self.dim)
        if A.shape != B.shape:
            raise ValueError(f"segment ends differ in shape: {A.shape} and {B.shape}")
        timed = t0 is not None or t1 is not None
        if timed:
            if t0 is None or t1 is None:
                raise ValueError("give both t0 and t1, or neither")
            T = np.stack(np.broadcast_arrays(np.asarray(t0, float), np.asarray(t1, float)), -1)
            T = np.broadcast_to(T, (len(A), 2))
        out = np.zeros(len(A), dtype=bool)
        for s in range(0, len(A), SEGMENT_CHUNK):
            seg = np.stack([A[s : s + SEGMENT_CHUNK], B[s : s + SEGMENT_CHUNK]], axis=1)
            out[s : s + SEGMENT_CHUNK] = self.paths_valid(
                seg, T[s : s + SEGMENT_CHUNK] if timed else None
            )
        return out

    def is_valid(self, points: FloatArray, t: FloatArray | float | None = None) -> BoolArray:
        """Whether each point (m, dim) is valid (at time ``t``): the zero-length segment at it."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, self.dim)
        return self.segments_valid(P, P, t, t) if t is not None else self.segments_valid(P, P)

    def clearance(
        self, paths: FloatArray, times: FloatArray | None = None
    ) -> dict[str, FloatArray]:
        """How much room each path (pop, n, dim) keeps, per applicable check, (pop,) metres:
        positive when clear, 0 or negative when touching or violating.

        ``bounds``: the least distance of a waypoint inside the box; ``cylinders``,
        ``circles``: the least distance from the axis (centre) minus radius and margin;
        ``polygons``: the least distance to a polygon minus its margin (0 when a path enters
        one: inside, the depth is not measured); ``terrain``: the least height above the
        terrain (minus the band's floor when ``strict_altitude`` requires it); ``altitude``:
        the least distance of a waypoint inside the band; ``moving``: the least distance over
        time minus the obstacle's radius; ``separation``: the least distance to a reserved
        UAV minus the separation (inf when none comes within the separation's search radius).
        """
        b = self.batch(paths, times)
        sc = self.scenario
        w = self.world
        p = b.paths
        out: dict[str, FloatArray] = {}
        for c in self.checks():
            if c == "bounds":
                gap = np.minimum(p - sc.bounds.lo, sc.bounds.hi - p)
                out[c] = np.asarray(gap.min(axis=(1, 2)))
            elif c == "cylinders":
                out[c] = b.cyl_overlap[1]
            elif c == "circles":
                n = len(w.circ_radii)
                d = G.cylinder_distances(p, w.circ_centers, np.full(n, -np.inf), np.full(n, np.inf))
                out[c] = np.asarray((d - w.circ_radii).min(axis=(1, 2)))
            elif c == "polygons":
                d = G.segment_polygon_distance(
                    np.ascontiguousarray(p[..., :2]), w.poly_verts, w.poly_starts
                )
                out[c] = np.asarray((d - w.poly_margin).min(axis=(1, 2)))
            elif c == "terrain":
                assert sc.terrain is not None
                band = sc.altitude
                need = 0.0
                if self.strict_altitude and band is not None and band.reference == "ground":
                    need = band.min
                out[c] = np.asarray(sc.terrain.min_clearance(p).min(axis=1) - need)
            elif c == "altitude":
                band = sc.altitude
                assert band is not None
                h, hc = b.band_heights, b.band_heights_ceiling
                out[c] = np.asarray(np.minimum(h - band.min, band.max - hc).min(axis=1))
            elif c == "moving":
                radii = np.array([o.radius for o in sc.moving_obstacles])
                out[c] = np.asarray((b.moving_dist - radii).min(axis=(1, 2)))
            elif c == "separation":
                table = self.reservations
                assert table is not None
                if len(table) == 0:
                    out[c] = np.full(p.shape[0], np.inf)
                else:
                    out[c] = table.min_distance(b.paths3, b.times) - table.separation
        return out


# ---------------------------------------------------------------------------- kinematics
def speed_violations(paths: FloatArray, times: FloatArray, v_min: float, v_max: float) -> BoolArray:
    """(pop,) whether some segment of the timed paths (pop, n, dim) is flown faster than
    ``v_max`` or slower than ``v_min`` (m/s; an instantaneous jump is infinitely fast). Relative
    slack ``SPEED_RTOL`` and ``SPEED_SLACK`` m per segment for round-off."""
    d = np.sqrt(np.sum(np.diff(paths, axis=1) ** 2, axis=-1))
    dt = np.diff(times, axis=1)
    fast = d > v_max * (1 + SPEED_RTOL) * np.maximum(dt, 0.0) + SPEED_SLACK
    bad = fast | (dt < 0)
    if v_min > 0:
        bad |= (dt > 0) & (d + SPEED_SLACK < v_min * (1 - SPEED_RTOL) * dt)
    return np.asarray(np.any(bad, axis=1))


def climb_violations(
    paths: FloatArray, max_climb: float | None, max_descent: float | None
) -> BoolArray:
    """(pop,) whether some segment of the paths (pop, n, 3) climbs more steeply than
    ``max_climb`` or descends more steeply than ``max_descent`` (degrees; None: no limit)."""
    d = np.diff(paths, axis=1)
    h = np.hypot(d[..., 0], d[..., 1])
    ang = np.degrees(np.arctan2(d[..., 2], h))
    moving = (h > 0) | (d[..., 2] != 0)
    bad = np.zeros(h.shape, dtype=bool)
    if max_climb is not None:
        bad |= moving & (ang > max_climb + ANGLE_TOL_DEG)
    if max_descent is not None:
        bad |= moving & (-ang > max_descent + ANGLE_TOL_DEG)
    return np.asarray(np.any(bad, axis=1))


def limit_climb(
    path: FloatArray,
    max_climb: float | None,
    max_descent: float | None,
    share: float = 0.9,
) -> FloatArray | None:
    """``path`` (n, 3) with its interior heights moved as little as a greedy pass can so that
    no segment climbs or descends more steeply than ``share`` of ``max_climb`` and
    ``max_descent`` (degrees, as slopes: the tangent is scaled; None: no limit); the
    horizontal track, the start and the goal unchanged. None when no heights do it (the start
    and goal too far apart vertically for the track between them).

    The heights each vertex can take are those reachable from the start going forward and
    from the goal going backward within the slopes (two interval sweeps); each vertex in turn
    then takes the height nearest its own inside both its interval and the slopes from the
    vertex before, which the backward interval guarantees is not empty. ``share`` < 1 leaves
    room for the smoothed flight, whose arcs shorten the track near each vertex."""
    P = np.array(path, dtype=np.float64)
    n = len(P)
    if n < 3 or P.shape[1] != 3:
        return P if not climb_violations(P[None], max_climb, max_descent)[0] else None
    h = np.hypot(*np.diff(P[:, :2], axis=0).T)
    up = h * (math.tan(math.radians(max_climb)) * share if max_climb is not None else np.inf)
    down = h * (math.tan(math.radians(max_descent)) * share if max_descent is not None
                else np.inf)  # fmt: skip
    up, down = np.nan_to_num(up, nan=0.0), np.nan_to_num(down, nan=0.0)  # inf * 0: level
    lo, hi = np.empty(n), np.empty(n)  # reachable backward from the goal
    lo[-1] = hi[-1] = P[-1, 2]
    for i in range(n - 2, -1, -1):
        lo[i], hi[i] = lo[i + 1] - up[i], hi[i + 1] + down[i]
    if not lo[0] <= P[0, 2] <= hi[0]:
        return None
    for i in range(1, n - 1):
        a = max(lo[i], P[i - 1, 2] - down[i - 1])
        b = min(hi[i], P[i - 1, 2] + up[i - 1])
        P[i, 2] = min(max(P[i, 2], a), b)
    return P


def turn_estimates(xy: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Heading change (rad) and curvature estimate (1/m) at every interior point of one
    planar polyline (m, 2), after merging consecutive points with the same x, y: the heading
    change over the mean length of the two segments."""
    seg = np.diff(xy, axis=0)
    L = np.hypot(seg[:, 0], seg[:, 1])
    keep = L > 1e-9
    seg, L = seg[keep], L[keep]
    if len(L) < 2:
        return np.zeros(0), np.zeros(0)
    a, b = seg[:-1], seg[1:]
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    dot = a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]
    theta = np.abs(np.arctan2(cross, dot))
    return theta, theta / (0.5 * (L[:-1] + L[1:]))


def turn_violations(paths: FloatArray, turn_radius: float) -> BoolArray:
    """(pop,) whether some interior point of the paths (pop, n, dim) turns by more than
    ``MAX_SAMPLE_TURN_DEG`` or with a curvature estimate above ``(1 + TURN_RTOL) /
    turn_radius`` (horizontal; see :func:`turn_estimates`)."""
    out = np.zeros(paths.shape[0], dtype=bool)
    if turn_radius <= 0:
        return out
    k_max = (1 + TURN_RTOL) / turn_radius
    sharp = np.radians(MAX_SAMPLE_TURN_DEG)
    for i in range(paths.shape[0]):  # the flown check: a few candidates, not a population
        theta, kappa = turn_estimates(paths[i, :, :2])
        out[i] = bool(np.any(theta > sharp) or np.any(kappa > k_max))
    return out


def greedy_shortcut(
    validator: MotionValidator, path: FloatArray, times: FloatArray | None = None
) -> tuple[FloatArray, FloatArray | None, int]:
    """Shortcut a polyline by line of sight: from each kept vertex jump to the farthest later
    vertex whose straight segment is valid (flown between the two planned ``times`` when given,
    so never faster than along the polyline), the next vertex when none is. Start and goal are
    kept; never longer than ``path``.

    Args:
        validator: decides every segment.
        path: (n, dim) metres; times: (n,) seconds or None (the validator's default timing).
    Returns:
        The kept vertices, their times (None without ``times``), and the segments checked.
    """
    wp = np.asarray(path, dtype=np.float64)
    t = None if times is None else np.asarray(times, dtype=np.float64)
    n = wp.shape[0]
    keep, a, checks = [0], 0, 0
    while a < n - 1:
        js = np.arange(n - 1, a, -1)  # farthest first
        A = np.broadcast_to(wp[a], (js.size, wp.shape[1]))
        if t is None:
            ok = validator.segments_valid(A, wp[js])
        else:
            ok = validator.segments_valid(A, wp[js], np.full(js.size, t[a]), t[js])
        checks += js.size
        a = int(js[int(np.argmax(ok))]) if ok.any() else a + 1
        keep.append(a)
    return wp[keep], (None if t is None else t[keep]), checks


#: :func:`band_repair`: the share of the altitude band kept as a margin on each side of an
#: inserted point (so that the short segments around it stay inside on a curved DEM).
BAND_REPAIR_MARGIN = 0.1


def band_repair(
    validator: MotionValidator, path: FloatArray, max_points: int = 1000, rounds: int = 24
) -> FloatArray | None:
    """Make a 3-D polyline hold the altitude band and the terrain along whole segments by
    terrain following: interior waypoints outside the band are moved vertically into it, then
    every segment that ``validator`` rejects is split at its midpoint, the new point's height
    put into the band (its interpolated height clipped to the band less
    :data:`BAND_REPAIR_MARGIN` of its width on each side), for at most ``rounds`` rounds and
    ``max_points`` points. The horizontal track is unchanged (no loop can appear), start and
    goal are kept. Returns the repaired path when every segment then passes ``validator``, else
    None (a segment fails for a reason splitting cannot cure, such as a cylinder). Not in any
    paper: the CLI's polish (:meth:`uavplan.planners.core.base.Planner.plan`) uses it."""
    sc = validator.scenario
    band = sc.altitude
    P = np.array(path, dtype=np.float64)
    if sc.dim != 3 or band is None or len(P) < 2:
        return P if validator.paths_valid(P[None])[0] else None
    margin = BAND_REPAIR_MARGIN * (band.max - band.min)
    z_lo, z_hi = float(sc.bounds.lo[2]), float(sc.bounds.hi[2])

    def limits(q: FloatArray) -> tuple[FloatArray, FloatArray]:
        if sc.terrain is None:
            g_lo = g_hi = np.zeros(len(q))
        else:
            g1 = sc.terrain.height(q[:, 0], q[:, 1])
            g2 = sc.terrain.lookup(q[:, 0], q[:, 1], validator.lookup)
            g_lo, g_hi = np.maximum(g1, g2), np.minimum(g1, g2)
            if sc.terrain.lower is not None:  # the ceiling is held against its own grid
                g3 = sc.terrain.height_low(q[:, 0], q[:, 1])
                g4 = sc.terrain.lookup_low(q[:, 0], q[:, 1], validator.lookup)
                g_hi = np.minimum(g3, g4)
        if band.reference == "ground":
            lo, hi = g_lo + band.min, g_hi + band.max
        else:
            lo = np.full(len(q), band.min)
            hi = np.full(len(q), band.max)
            if sc.terrain is not None:
                lo = np.maximum(lo, g_lo)
        return np.maximum(lo, z_lo), np.minimum(hi, z_hi)

    inner = P[1:-1]
    if len(inner):
        lo, hi = limits(inner)
        out = (inner[:, 2] < lo) | (inner[:, 2] > hi)
        inner[out, 2] = np.clip(inner[out, 2], lo[out] + margin, hi[out] - margin)
    for _ in range(rounds):
        ok = validator.segments_valid(P[:-1], P[1:])
        if ok.all():
            return P
        bad = np.flatnonzero(~ok)
        if len(P) + len(bad) > max_points:
            return None
        mid = 0.5 * (P[bad] + P[bad + 1])
        lo, hi = limits(mid)
        mid[:, 2] = np.clip(mid[:, 2], lo + margin, np.maximum(hi - margin, lo + margin))
        P = np.insert(P, bad + 1, mid, axis=0)
    return P if validator.segments_valid(P[:-1], P[1:]).all() else None


def shortest_subsequence(
    validator: MotionValidator, path: FloatArray, max_interior: int
) -> tuple[FloatArray | None, int]:
    """The shortest sub-sequence of ``path``'s vertices (first and last kept) whose segments are
    all valid and which has at most ``max_interior`` interior vertices (an exact dynamic
    program over the visibility DAG of the vertices; every pair is checked in one batch), or
    None; and the number of segments checked. RGG-PSO+ fits its graph paths into particles of
    ``N`` waypoints with it; unlike :func:`greedy_shortcut` it is optimal for the cap."""
    p = np.asarray(path, dtype=np.float64)
    K = len(p)
    i, j = np.triu_indices(K, k=1)
    ok = validator.segments_valid(p[i], p[j])
    W = np.full((K, K), np.inf)
    W[i[ok], j[ok]] = np.linalg.norm(p[j[ok]] - p[i[ok]], axis=1)
    # f[c, v]: shortest chain 0 -> v visiting c nodes after 0 (v included)
    f = np.full(K, np.inf)
    f[0] = 0.0
    preds: list[NDArray[np.intp]] = []
    best_c, best_len = -1, np.inf
    for c in range(1, max_interior + 2):
        tot = f[:, None] + W
        arg = np.argmin(tot, axis=0)
        f = tot[arg, np.arange(K)]
        preds.append(arg)
        if f[K - 1] < best_len:
            best_c, best_len = c, float(f[K - 1])
    if best_c < 0:
        return None, len(i)
    out = [K - 1]
    for c in range(best_c - 1, -1, -1):
        out.append(int(preds[c][out[-1]]))
    return np.asarray(p[out[::-1]]), len(i)
