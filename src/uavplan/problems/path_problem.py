"""Evaluate a batch of paths for one task in a scenario: total cost, each term, feasibility.

A :class:`PathProblem` takes waypoints ``(pop, n_points, dim)`` (start and goal included) and
returns an :class:`Evaluation` with no Python loop over paths. Cost models (the weighted terms)
are named presets:

* ``spso``: SPSO's published cost (Phung & Ha 2021, ``MyCost.m``): 5 J1 + 1 J2 + 10 J3 + 1 J4,
  heights above ground read at the nearest DEM node as MATLAB's ``H(round(y), round(x))``.
* ``ppswarm``: PPSwarm's F1-F4 (Eqs. 2-10, 13); F5 (inter-UAV) is added by the fleet planner.
  The paper gives no b_c, a_1, a_2; we take b = (5, 1, 10, 1) from SPSO, whose settings PPSwarm
  says it follows, and a_1 = a_2 = 1 (angles in radians).
* ``hrmaga``: HR-MAGA Eq. (4) with w1 : w2 : w3 = 1 : 10 : 15 (its Table I).
* ``length2d``: RGG-PSO+'s path length with the penalty L (1 + 100 V) for the fraction V of the
  path inside obstacles.

Feasibility is decided separately from the cost, on continuous segments: inside the bounds; clear
of cylinders, circles, polygons and revealed uncertain areas (exact); above the terrain along
every segment (exact for the bilinear DEM); the altitude band at every waypoint (PPSwarm Eq. 7
and SPSO check it there; ``strict_altitude=True`` checks it along segments too); clear of moving
obstacles over continuous time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems import costs as C
from uavplan.world import geometry as G
from uavplan.world.geometry import scene2d_batch
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Evaluation:
    """Costs of a batch of paths: ``cost`` (pop,), ``terms`` name -> (pop,) weighted-before-sum
    raw values, ``feasible`` (pop,) bool, ``violations`` name -> (pop,) bool."""

    cost: FloatArray
    terms: dict[str, FloatArray]
    feasible: BoolArray
    violations: dict[str, BoolArray] = field(default_factory=dict)

    def row(self, i: int) -> dict[str, Any]:
        return {
            "cost": float(self.cost[i]),
            "terms": {k: float(v[i]) for k, v in self.terms.items()},
            "feasible": bool(self.feasible[i]),
        }


class Context:
    """Lazily computed quantities shared by the terms of one evaluation."""

    def __init__(self, problem: PathProblem, paths: FloatArray) -> None:
        self.problem = problem
        self.scenario = problem.scenario
        self.paths = paths

    @cached_property
    def seg_len(self) -> FloatArray:
        return C.segment_lengths(self.paths)

    @cached_property
    def length(self) -> FloatArray:
        if self.problem.dim == 2:  # the fused 2-D pass measures it anyway
            return self.scene2d[0]
        return np.asarray(self.seg_len.sum(axis=1))

    @cached_property
    def cyl_dist(self) -> FloatArray:
        p = self.problem
        return G.cylinder_distances(self.paths, p._cyl_centers, p._cyl_lo, p._cyl_hi)

    @cached_property
    def ground(self) -> FloatArray:
        sc = self.scenario
        if sc.terrain is None:
            return np.zeros(self.paths.shape[:2])
        return sc.terrain.lookup(self.paths[..., 0], self.paths[..., 1], self.problem.lookup)

    @cached_property
    def times(self) -> FloatArray:
        sc = self.scenario
        return C.path_times(self.paths, sc.uav.speed, self.problem.task.start_time)

    @cached_property
    def moving_dist(self) -> FloatArray:
        obs = self.scenario.moving_obstacles
        if not obs:
            return np.zeros((self.paths.shape[0], self.paths.shape[1] - 1, 0))
        return np.stack([o.min_distance(self.paths, self.times) for o in obs], axis=-1)

    @cached_property
    def scene2d(self) -> tuple[FloatArray, FloatArray, BoolArray, BoolArray, BoolArray]:
        """xy length, length inside circles and polygons, circle hit, polygon hit, node out of
        the box: (pop,) each, from one fused pass (:func:`uavplan.world.geometry.scene2d_batch`).
        """
        p = self.problem
        verts, starts = p._polys
        length, inside, circle_hit, polygon_hit, outside = scene2d_batch(
            self.paths,
            p._circ_centers,
            p._circ_radii,
            verts,
            starts,
            p._poly_margin,
            p._lo2,
            p._hi2,
        )
        return length, inside, circle_hit, polygon_hit, outside

    @cached_property
    def inside_2d(self) -> FloatArray:
        return self.scene2d[1]


TermFn = Callable[[Context], FloatArray]


@dataclass(frozen=True)
class Term:
    """A named, weighted cost term."""

    name: str
    weight: float
    fn: TermFn


# ---------------------------------------------------------------------------- term functions
def _t_length(ctx: Context) -> FloatArray:
    return ctx.length


def _t_threat(ctx: Context) -> FloatArray:
    p = ctx.problem
    out = C.threat_cost(ctx.cyl_dist, p._cyl_radii, ctx.scenario.uav.s1)
    if ctx.scenario.moving_obstacles:
        radii = np.array([o.radius for o in ctx.scenario.moving_obstacles])
        out = out + C.moving_threat_cost(ctx.moving_dist, radii, ctx.scenario.uav.s1)
    return out


def _t_threat_spso(ctx: Context) -> FloatArray:
    # SPSO adds drone_size itself: use the bare radii; each cylinder's margin is the drone size.
    p = ctx.problem
    return C.threat_cost_spso(ctx.cyl_dist, p._cyl_radii - p._cyl_margin, p._cyl_margin)


def _band_heights(ctx: Context) -> FloatArray:
    band = ctx.scenario.altitude
    z = ctx.paths[..., 2]
    return z - ctx.ground if band is not None and band.reference == "ground" else z


def _t_altitude(ctx: Context) -> FloatArray:
    band = ctx.scenario.altitude
    if band is None:
        return np.zeros(ctx.paths.shape[0])
    return C.altitude_cost(_band_heights(ctx), band.min, band.max)


def _t_altitude_spso(ctx: Context) -> FloatArray:
    band = ctx.scenario.altitude
    lo, hi = (band.min, band.max) if band is not None else (0.0, 0.0)
    z_rel = (ctx.paths[..., 2] - ctx.ground)[:, 1:-1]  # free nodes only, as MyCost.m
    return C.altitude_cost_spso(z_rel, lo, hi)


def _t_smooth(ctx: Context) -> FloatArray:
    return C.smoothness_cost(ctx.paths, 1.0, 1.0)


def _t_smooth_spso(ctx: Context) -> FloatArray:
    return C.smoothness_cost_spso(ctx.paths)


def _t_hrmaga_altitude(ctx: Context) -> FloatArray:
    terrain = ctx.scenario.terrain
    if terrain is None:
        return np.zeros(ctx.paths.shape[0])
    return C.hrmaga_altitude_cost(terrain.mean_height(ctx.paths))


def _t_danger(ctx: Context) -> FloatArray:
    areas = ctx.scenario.danger_areas
    centers = np.array([a.center for a in areas]).reshape(-1, 2)
    radii = np.array([a.radius for a in areas])
    return C.danger_length_cost(ctx.paths, centers, radii)


def _t_length2d(ctx: Context) -> FloatArray:
    return C.penalized_length_cost(ctx.length, ctx.inside_2d, 100.0)


PRESETS: dict[str, tuple[Term, ...]] = {
    "spso": (
        Term("length", 5.0, _t_length),
        Term("threat", 1.0, _t_threat_spso),
        Term("altitude", 10.0, _t_altitude_spso),
        Term("smoothness", 1.0, _t_smooth_spso),
    ),
    "ppswarm": (
        Term("length", 5.0, _t_length),
        Term("threat", 1.0, _t_threat),
        Term("altitude", 10.0, _t_altitude),
        Term("smoothness", 1.0, _t_smooth),
    ),
    "hrmaga": (
        Term("length", 1.0, _t_length),
        Term("terrain_height", 10.0, _t_hrmaga_altitude),
        Term("danger", 15.0, _t_danger),
    ),
    "length2d": (Term("length", 1.0, _t_length2d),),
}

#: How each preset reads terrain heights for its altitude terms.
LOOKUP = {"spso": "nearest"}


def cost_presets() -> list[str]:
    return sorted(PRESETS)


class PathProblem:
    """Costs and feasibility of paths for one task of a scenario.

    Args:
        scenario: the world.
        task: a :class:`Task`, a task id, or None for the first task.
        cost: a preset name (default: the scenario's), or a sequence of :class:`Term`.
        weights: override preset weights by term name.
        strict_altitude: check the altitude band along segments, not only at waypoints.
    """

    def __init__(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        cost: str | tuple[Term, ...] | None = None,
        weights: dict[str, float] | None = None,
        strict_altitude: bool = False,
    ) -> None:
        self.scenario = scenario
        self.task = task if isinstance(task, Task) else scenario.task(task)
        name = cost if cost is not None else scenario.cost
        if isinstance(name, str):
            if name not in PRESETS:
                raise ValueError(f"unknown cost preset {name!r}; choose from {cost_presets()}")
            self.cost_name = name
            terms = PRESETS[name]
        else:
            self.cost_name = "custom"
            terms = tuple(name)
        if weights:
            unknown = set(weights) - {t.name for t in terms}
            if unknown:
                raise ValueError(f"unknown cost term(s) {sorted(unknown)} for {self.cost_name}")
            terms = tuple(Term(t.name, weights.get(t.name, t.weight), t.fn) for t in terms)
        self.terms = terms
        self.lookup = LOOKUP.get(self.cost_name, "bilinear")
        self.strict_altitude = strict_altitude
        self.dim = scenario.dim
        self.start = np.asarray(self.task.start, dtype=np.float64)
        self.goal = np.asarray(self.task.goal, dtype=np.float64)
        cyl = scenario.cylinders
        self._cyl_centers = np.array([c.center for c in cyl], dtype=np.float64).reshape(-1, 2)
        self._cyl_radii = np.array([c.effective_radius for c in cyl], dtype=np.float64)
        self._cyl_margin = np.array([c.margin for c in cyl], dtype=np.float64)
        self._cyl_lo = np.array([c.z_min - c.margin for c in cyl], dtype=np.float64)
        self._cyl_hi = np.array([c.z_max + c.margin for c in cyl], dtype=np.float64)
        circ = scenario.circles
        self._circ_centers = np.array([c.center for c in circ], dtype=np.float64).reshape(-1, 2)
        self._circ_radii = np.array([c.effective_radius for c in circ], dtype=np.float64)
        self._polys = scenario.packed_polygons()
        self._poly_margin = np.array([p.margin for p in scenario.no_fly_polygons], dtype=np.float64)
        self._lo2 = np.ascontiguousarray(scenario.bounds.lo[:2], dtype=np.float64)
        self._hi2 = np.ascontiguousarray(scenario.bounds.hi[:2], dtype=np.float64)

    # ------------------------------------------------------------------ evaluation
    def _check(self, paths: FloatArray) -> FloatArray:
        p = np.asarray(paths, dtype=np.float64)
        if p.ndim == 2:
            p = p[None]
        if p.ndim != 3 or p.shape[-1] != self.dim or p.shape[1] < 2:
            raise ValueError(
                f"paths must be (pop, n_points >= 2, {self.dim}), got shape {np.shape(paths)}"
            )
        return np.ascontiguousarray(p)

    def evaluate(self, paths: FloatArray) -> Evaluation:
        """Total cost, terms and feasibility of ``paths`` (pop, n_points, dim)."""
        p = self._check(paths)
        ctx = Context(self, p)
        terms = {t.name: np.asarray(t.fn(ctx), dtype=np.float64) for t in self.terms}
        total = np.zeros(p.shape[0])
        for t in self.terms:
            total = total + t.weight * terms[t.name]
        violations = self._violations(ctx)
        feasible = np.ones(p.shape[0], dtype=bool)
        for v in violations.values():
            feasible &= ~v
        return Evaluation(total, terms, feasible, violations)

    def cost(self, paths: FloatArray) -> FloatArray:
        """Total cost only, (pop,)."""
        p = self._check(paths)
        ctx = Context(self, p)
        total = np.zeros(p.shape[0])
        for t in self.terms:
            total = total + t.weight * np.asarray(t.fn(ctx), dtype=np.float64)
        return total

    def feasible(self, paths: FloatArray) -> BoolArray:
        return self.evaluate(paths).feasible

    def _violations(self, ctx: Context) -> dict[str, BoolArray]:
        sc = self.scenario
        p = ctx.paths
        # in 2-D the fused scene pass tests the box too
        inbox = ~ctx.scene2d[4] if self.dim == 2 else np.all(sc.bounds.contains(p), axis=1)
        out: dict[str, BoolArray] = {"bounds": ~inbox}
        if len(self._cyl_radii):
            out["cylinders"] = np.any(ctx.cyl_dist < self._cyl_radii, axis=(1, 2))
        if len(self._circ_radii):
            out["circles"] = ctx.scene2d[2]
        if len(self._polys[1]) > 1:
            out["polygons"] = ctx.scene2d[3]
        if sc.dim == 3 and sc.terrain is not None:
            band = sc.altitude
            need = 0.0
            if self.strict_altitude and band is not None and band.reference == "ground":
                need = max(need, band.min)
            out["terrain"] = ~np.all(sc.terrain.clears(p, need), axis=1)
        if sc.dim == 3 and sc.altitude is not None:
            band = sc.altitude
            h = _band_heights(ctx)
            bad = np.any((h < band.min - 1e-9) | (h > band.max + 1e-9), axis=1)
            if self.strict_altitude and band.reference == "ground" and sc.terrain is not None:
                bad |= ~np.all(sc.terrain.stays_within(p, band.max + 1e-9), axis=1)
            out["altitude"] = bad
        if sc.moving_obstacles:
            radii = np.array([o.radius for o in sc.moving_obstacles])
            out["moving"] = np.any(ctx.moving_dist < radii, axis=(1, 2))
        return out

    # ------------------------------------------------------------------ helpers
    def with_endpoints(self, free: FloatArray) -> FloatArray:
        """Insert the task's start and goal around free waypoints (pop, n_free, dim)."""
        f = np.asarray(free, dtype=np.float64)
        out = np.empty((f.shape[0], f.shape[1] + 2, self.dim))
        out[:, 0] = self.start
        out[:, 1:-1] = f
        out[:, -1] = self.goal
        return out

    def times(self, paths: FloatArray) -> FloatArray:
        """Arrival times at the UAV's speed, (pop, n) seconds."""
        return C.path_times(self._check(paths), self.scenario.uav.speed, self.task.start_time)
