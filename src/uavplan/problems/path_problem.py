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

Feasibility is decided apart from the cost, on continuous segments, by the problem's
:class:`~uavplan.problems.validity.MotionValidator` (bounds, obstacles, terrain, altitude band,
moving obstacles, other UAVs): see that module. :meth:`PathProblem.evaluate_cv` returns the cost
and the constraint violation apart, for the constraint rules of
:mod:`uavplan.optimizers.constraints`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems import costs as C
from uavplan.problems import work
from uavplan.problems.validity import Batch, MotionValidator
from uavplan.world import geometry as G
from uavplan.world.kernel_arrays import read_only
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.terrain import Terrain

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Evaluation:
    """Costs of a batch of paths: ``cost`` (pop,), ``terms`` name -> (pop,) weighted-before-sum
    raw values, ``feasible`` (pop,) bool, ``violations`` name -> (pop,) bool, ``cv`` (pop,) the
    graded constraint violation (0 where feasible with a finite cost; see
    :meth:`PathProblem.evaluate_cv`)."""

    cost: FloatArray
    terms: dict[str, FloatArray]
    feasible: BoolArray
    violations: dict[str, BoolArray] = field(default_factory=dict)
    cv: FloatArray = field(default_factory=lambda: np.zeros(0))

    def row(self, i: int) -> dict[str, Any]:
        return {
            "cost": float(self.cost[i]),
            "terms": {k: float(v[i]) for k, v in self.terms.items()},
            "feasible": bool(self.feasible[i]),
        }


TermFn = Callable[[Batch], FloatArray]


@dataclass(frozen=True)
class Term:
    """A named, weighted cost term.

    ``check``: the name of a :class:`~uavplan.problems.validity.MotionValidator` check that
    this term mirrors (it is infinite exactly when that check fails, 0 otherwise, as PPSwarm's
    F5 and the separation check): :meth:`PathProblem.evaluate_cv` leaves such a term out of the
    cost, since the check (the constraint) decides it. ``lower``: a cheaper lower bound of
    ``fn`` (never above it, row by row), with which :meth:`PathProblem.evaluate_cv`'s
    ``below`` skips the exact term where even the bound leaves the cost too high.
    """

    name: str
    weight: float
    fn: TermFn
    check: str | None = None
    lower: TermFn | None = None


# ---------------------------------------------------------------------------- term functions
def _t_length(ctx: Batch) -> FloatArray:
    return ctx.length


def _t_threat(ctx: Batch) -> FloatArray:
    # PPSwarm's Eqs. (4)-(5), fused (C.threat_cost of G.cylinder_distances is the reference)
    w = ctx.world
    R = w.cyl_radii
    out = G.cylinder_threat(
        ctx.paths, w.cyl_centers, w.cyl_lo, w.cyl_hi, R, R + ctx.scenario.uav.s1, strict=False
    )
    if ctx.scenario.moving_obstacles:
        radii = np.array([o.radius for o in ctx.scenario.moving_obstacles])
        out = out + C.moving_threat_cost(ctx.moving_dist, radii, ctx.scenario.uav.s1)
    return out


def _t_threat_spso(ctx: Batch) -> FloatArray:
    # SPSO adds drone_size itself: use the bare radii; each cylinder's margin is the drone size.
    # Fused; C.threat_cost_spso of G.cylinder_distances (bare radii, margins as drone sizes) is
    # the reference, whose R + drone size this repeats operation for operation.
    w = ctx.world
    R = (w.cyl_radii - w.cyl_margin) + w.cyl_margin
    r_out = R + 10.0 * w.cyl_margin
    return G.cylinder_threat(ctx.paths, w.cyl_centers, w.cyl_lo, w.cyl_hi, R, r_out, strict=True)


def _t_altitude(ctx: Batch) -> FloatArray:
    band = ctx.scenario.altitude
    if band is None:
        return np.zeros(ctx.paths.shape[0])
    return C.altitude_cost(ctx.band_heights, band.min, band.max, ctx.validator.task.cruise)


def _t_altitude_spso(ctx: Batch) -> FloatArray:
    band = ctx.scenario.altitude
    lo, hi = (band.min, band.max) if band is not None else (0.0, 0.0)
    z_rel = (ctx.paths[..., 2] - ctx.ground)[:, 1:-1]  # free nodes only, as MyCost.m
    return C.altitude_cost_spso(z_rel, lo, hi)


def _t_smooth(ctx: Batch) -> FloatArray:
    return C.smoothness_cost(ctx.paths, 1.0, 1.0)


def _t_smooth_spso(ctx: Batch) -> FloatArray:
    return C.smoothness_cost_spso(ctx.paths)


def _t_hrmaga_altitude(ctx: Batch) -> FloatArray:
    terrain = ctx.validator.cost_terrain
    if terrain is None:
        return np.zeros(ctx.paths.shape[0])
    return C.hrmaga_altitude_cost(terrain.mean_height(ctx.paths))


def _t_hrmaga_altitude_lower(ctx: Batch) -> FloatArray:
    terrain = ctx.validator.cost_terrain
    if terrain is None:
        return np.zeros(ctx.paths.shape[0])
    return C.hrmaga_altitude_cost(terrain.mean_height_lower(ctx.paths))


def _t_danger(ctx: Batch) -> FloatArray:
    areas = ctx.scenario.danger_areas
    centers = np.array([a.center for a in areas]).reshape(-1, 2)
    radii = np.array([a.radius for a in areas])
    return C.danger_length_cost(ctx.paths, centers, radii)


def _t_length2d(ctx: Batch) -> FloatArray:
    return C.penalized_length_cost(ctx.length, ctx.scene2d[1], 100.0)


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
        Term("terrain_height", 10.0, _t_hrmaga_altitude, lower=_t_hrmaga_altitude_lower),
        Term("danger", 15.0, _t_danger),
    ),
    "length2d": (Term("length", 1.0, _t_length2d),),
    # the path's length alone, metres, in 2-D or 3-D (OMPL's path-length objective): what RRT*
    # minimises; feasibility stays the validator's, as with every preset
    "length": (Term("length", 1.0, _t_length),),
}

#: How each preset reads terrain heights for its altitude terms (bilinear unless named here).
LOOKUP = {"spso": "nearest"}


def lookup_for(cost: str | None) -> str:
    """How the cost preset ``cost`` reads terrain heights: :data:`LOOKUP`'s, else bilinear."""
    return LOOKUP.get(cost or "", "bilinear")


def _world_args(v: MotionValidator, r_in: FloatArray, r_out: FloatArray) -> tuple[Any, ...]:
    """The world's arguments of :func:`uavplan.problems.costs.path_cost_batch` after
    ``model, paths`` (cylinders as structure of arrays, the terrain, the band), once per
    problem; ``threat`` and ``moving`` are left as None, for each batch to set."""
    w, sc = v.world, v.scenario
    _, cyl = G.soa(np.zeros((0, 2, 3)), w.cyl_centers, w.cyl_lo, w.cyl_hi, r_in, r_out)
    t = sc.terrain
    if t is not None:
        H, x0, y0, dx, dy = t.heights, t.x0, t.y0, t.dx, t.dy
    else:
        H, x0, y0, dx, dy = read_only(np.zeros((1, 1))), 0.0, 0.0, 1.0, 1.0  # as heights
    band = sc.altitude
    lo, hi = (band.min, band.max) if band is not None else (0.0, 0.0)
    mid = C.altitude_target(lo, hi, v.task.cruise)
    ground = band is not None and band.reference == "ground"
    return (*cyl, None, None, H, t is not None, v.lookup == "nearest", float(x0), float(y0),
            float(dx), float(dy), band is not None, ground, float(lo), float(hi),
            float(mid))  # fmt: skip


def _spso_prepare(v: MotionValidator) -> tuple[Any, ...]:
    w = v.world
    R = (w.cyl_radii - w.cyl_margin) + w.cyl_margin  # as _t_threat_spso
    return (C.SPSO, *_world_args(v, R, R + 10.0 * w.cyl_margin))


def _ppswarm_prepare(v: MotionValidator) -> tuple[Any, ...]:
    R = v.world.cyl_radii  # as _t_threat
    return (C.PPSWARM, *_world_args(v, R, R + v.scenario.uav.s1))


#: An empty per-path term: not given (:func:`uavplan.problems.costs.path_cost_batch`).
_NONE = np.zeros(0)


def _fused(
    ctx: Batch, args: tuple[Any, ...], weights: FloatArray, early: bool
) -> tuple[FloatArray, FloatArray]:
    """The four terms of SPSO's or PPSwarm's cost in one pass
    (:func:`uavplan.problems.costs.path_cost_batch`): the weighted total and the (pop, 4)
    terms, the same as the terms of the :data:`PRESETS` (``_t_length`` ...), the references
    the tests compare it with."""
    model, cx, cy, lo, hi, r_in, r_out, _, _, *world = args
    p = ctx.paths  # 3-D, C-contiguous float64 (MotionValidator.check_paths)
    threat = moving = _NONE
    if G.gridded(p, len(cx)):  # the indexed pass, then the kernel
        threat = G.cylinder_threat(p, ctx.world.cyl_centers, lo, hi, r_in, r_out, model == C.SPSO)
    moving_obstacles = ctx.scenario.moving_obstacles
    if model == C.PPSWARM and moving_obstacles:
        radii = np.array([o.radius for o in moving_obstacles])
        moving = C.moving_threat_cost(ctx.moving_dist, radii, ctx.scenario.uav.s1)
    total, terms = C.path_cost_batch(
        model, p, cx, cy, lo, hi, r_in, r_out, threat, moving, *world, weights, bool(early)
    )
    return np.asarray(total), np.asarray(terms)


@dataclass(frozen=True)
class Fused:
    """Cost terms computed together in one kernel: ``fns`` (the term functions it replaces, in
    order, when they lead a problem's terms), ``prepare(validator) -> args`` (what the kernel
    needs of the world, once per problem), ``compute(batch, args, weights, early) -> (total,
    terms)``, the terrain ``lookups`` it can read heights with and the dimension it serves."""

    fns: tuple[TermFn, ...]
    prepare: Callable[[MotionValidator], tuple[Any, ...]]
    compute: Callable[[Batch, tuple[Any, ...], FloatArray, bool], tuple[FloatArray, FloatArray]]
    lookups: tuple[str, ...]
    dim: int


#: The fused kernels, tried in order by :class:`PathProblem`.
FUSED = (
    Fused(
        (_t_length, _t_threat_spso, _t_altitude_spso, _t_smooth_spso),
        _spso_prepare,
        _fused,
        ("nearest",),
        3,
    ),
    Fused(
        (_t_length, _t_threat, _t_altitude, _t_smooth),
        _ppswarm_prepare,
        _fused,
        ("bilinear", "nearest"),
        3,
    ),
)
#: The dimensions a preset's terms compute in, where not both: SPSO's altitude term reads z.
PRESET_DIMS: dict[str, tuple[int, ...]] = {"spso": (3,)}


def cost_presets() -> list[str]:
    return sorted(PRESETS)


def preset_problem(name: str, dim: int) -> str | None:
    """Why the cost preset ``name`` cannot cost a ``dim``-D scenario's paths, or None."""
    if name not in PRESETS:
        return f"unknown cost preset {name!r}; choose from {', '.join(cost_presets())}"
    dims = PRESET_DIMS.get(name, (2, 3))
    if dim not in dims:
        return (
            f"the {name} cost is for {' or '.join(f'{d}-D' for d in dims)} scenarios, not {dim}-D"
        )
    return None


def _t_separation(ctx: Batch) -> FloatArray:
    return np.where(ctx.conflicts, np.inf, 0.0)


#: PPSwarm's F5 (Eqs. 11-12): infinite when the path comes closer than S2 to a UAV of the
#: reservation table at some instant (the ``separation`` check), else 0.
SEPARATION_TERM = Term("separation", 1.0, _t_separation, check="separation")


class PathProblem:
    """Costs and feasibility of paths for one task of a scenario.

    Args:
        scenario: the world.
        task: a :class:`Task`, a task id, or None for the first task.
        cost: a preset name (default: the scenario's), or a sequence of :class:`Term`.
        weights: override preset weights by term name.
        strict_altitude: check the altitude band along segments, not only at waypoints.
        reservations: other UAVs' timed trajectories to keep clear of (the ``separation``
            check; see :class:`~uavplan.problems.validity.MotionValidator`).
        lookup: how terrain heights under waypoints are read (default: as the preset reads
            them, :data:`LOOKUP`; ``"bilinear"`` for custom terms).
        name: the cost model's name (default: the preset's, ``"custom"`` for terms).
        cost_terrain: the map the cost terms read heights from (default: the scenario's; a
            terrain pyramid level's sampled map while the checks use its conservative one).
        fused: compute the leading terms in one kernel where one does (:data:`FUSED`); False
            computes every term apart (the references the fused kernels are tested against).

    Feasibility is the :attr:`validator`'s verdict; the cost terms and the checks of one
    evaluation share one :class:`~uavplan.problems.validity.Batch`.
    """

    def __init__(
        self,
        scenario: Scenario,
        task: Task | str | int | None = None,
        cost: str | tuple[Term, ...] | None = None,
        weights: dict[str, float] | None = None,
        strict_altitude: bool = False,
        reservations: ReservationTable | None = None,
        lookup: str | None = None,
        name: str | None = None,
        cost_terrain: Terrain | None = None,
        fused: bool = True,
    ) -> None:
        self.scenario = scenario
        self.task = task if isinstance(task, Task) else scenario.task(task)
        preset = cost if cost is not None else scenario.cost
        if isinstance(preset, str):
            why = preset_problem(preset, scenario.dim)
            if why is not None:
                raise ValueError(why)
            self.cost_name = preset
            terms = PRESETS[preset]
        else:
            self.cost_name = "custom"
            terms = tuple(preset)
        if weights:
            unknown = set(weights) - {t.name for t in terms}
            if unknown:
                raise ValueError(f"unknown cost term(s) {sorted(unknown)} for {self.cost_name}")
            terms = tuple(Term(t.name, weights.get(t.name, t.weight), t.fn, t.check) for t in terms)
        self.terms = terms
        self.lookup = lookup if lookup is not None else lookup_for(self.cost_name)
        if name is not None:
            self.cost_name = name
        self.validator = MotionValidator(
            scenario,
            self.task,
            strict_altitude=strict_altitude,
            lookup=self.lookup,
            reservations=reservations,
            cost_terrain=cost_terrain,
        )
        self.dim = scenario.dim
        #: the kernel that computes the leading terms together (:data:`FUSED`), if one does
        self.fused: Fused | None = None
        fns = tuple(t.fn for t in terms)
        for f in FUSED if fused else ():
            if fns[: len(f.fns)] == f.fns and self.lookup in f.lookups and self.dim == f.dim:
                self.fused = f
                self._fused_weights = np.array([t.weight for t in terms[: len(f.fns)]], float)
                self._fused_args = f.prepare(self.validator)
                break
        self.start = np.asarray(self.task.start, dtype=np.float64)
        self.goal = np.asarray(self.task.goal, dtype=np.float64)

    @property
    def strict_altitude(self) -> bool:
        return self.validator.strict_altitude

    # ------------------------------------------------------------------ evaluation
    def _total(self, b: Batch, checks_too: bool = True) -> FloatArray:
        work.add(cost_paths=b.paths.shape[0])
        terms = self.terms
        if self.fused is not None:  # the leading terms in one kernel, stopping early
            total = self.fused.compute(b, self._fused_args, self._fused_weights, True)[0]
            terms = terms[len(self.fused.fns) :]
        else:
            total = np.zeros(b.paths.shape[0])
        for t in terms:
            if checks_too or t.check is None:
                total = total + t.weight * np.asarray(t.fn(b), dtype=np.float64)
        return total

    def evaluate(self, paths: FloatArray, times: FloatArray | None = None) -> Evaluation:
        """Total cost, terms, feasibility and graded violation of ``paths`` (pop, n_points,
        dim), flown at ``times`` (pop, n_points) seconds (default: the UAV's speed from the
        task's start time)."""
        b = self.validator.batch(paths, times)
        work.add(cost_paths=b.paths.shape[0])
        rest = self.terms
        if self.fused is not None:
            total, fused = self.fused.compute(b, self._fused_args, self._fused_weights, False)
            k = len(self.fused.fns)
            terms = {t.name: fused[:, i] for i, t in enumerate(self.terms[:k])}
            rest = self.terms[k:]
        else:
            terms, total = {}, np.zeros(b.paths.shape[0])
        for t in rest:
            terms[t.name] = np.asarray(t.fn(b), dtype=np.float64)
            total = total + t.weight * terms[t.name]
        violations = self.validator.violations(b)
        feasible = np.ones(b.paths.shape[0], dtype=bool)
        for v in violations.values():
            feasible &= ~v
        cv = self._cv(b, violations, feasible, total)
        return Evaluation(total, terms, feasible, violations, cv)

    def _cv(
        self, b: Batch, violations: dict[str, BoolArray], feasible: BoolArray, f: FloatArray
    ) -> FloatArray:
        """The graded violation of the paths that fail a check or cost infinity, else 0."""
        bad = ~feasible | ~np.isfinite(f)
        if not bad.any():
            return np.zeros(b.paths.shape[0])
        return np.where(bad, self.validator.graded_violation(b, violations), 0.0)

    def cost(self, paths: FloatArray) -> FloatArray:
        """Total cost only, (pop,)."""
        return self._total(self.validator.batch(paths))

    def evaluate_cv(
        self, paths: FloatArray, exact: bool = True, below: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """Cost and constraint violation apart (pymoo's ``F`` and ``G``): ``(f, cv)``, (pop,)
        each, ``cv >= 0`` and 0 for a path that passes every check.

        ``f`` leaves out the terms that mirror a check (:attr:`Term.check`). With ``exact``,
        ``cv`` is the graded violation (:meth:`MotionValidator.graded_violation`) of every path
        that fails a check or has an infinite cost, 0 otherwise. Without, ``cv`` only tells
        apart (1 = fails a check; ``f`` is then set to inf, which is what the "inf" rule
        needs), and the work stops early: the world's checks cascade, cheap ones first
        (:meth:`MotionValidator.passing`), the cost only for the paths that pass them, then
        separation only for those left with a finite cost.

        ``below`` (pop,), without ``exact``: only the rows whose cost ``f`` is below it are
        checked (the cost first, then the checks of those rows); every other row is reported
        ``(inf, 1)`` unchecked. Its ``f`` would be ``>= below`` whatever the checks say (a
        check can only make it inf), which is all that an optimizer that keeps a point only
        when it improves on ``below`` (PSO's personal bests) needs to know; the rows checked
        get the values the call without ``below`` gives, bit for bit (every quantity is
        computed per row).
        """
        b = self.validator.batch(paths)
        if below is not None and not exact:
            return self._evaluate_below(b, np.asarray(below, dtype=np.float64))
        if exact:
            total = self._total(b, checks_too=False)
            violations = self.validator.violations(b)
            feasible = np.ones(b.paths.shape[0], dtype=bool)
            for v in violations.values():
                feasible &= ~v
            return total, self._cv(b, violations, feasible, total)
        n = b.paths.shape[0]
        cv = np.ones(n)
        total = np.full(n, np.inf)
        ok = self.validator.passing(b, skip=("separation",))  # the world, cheap checks first
        if ok.size:
            sub = b if ok.size == n else b.subset(ok)
            f = self._total(sub, checks_too=False)  # the cost only where it can count
            total[ok] = f
            cv[ok] = 0.0
            fin = np.isfinite(f)
            table = self.validator.reservations
            if fin.any() and table is not None and len(table):
                rows = ok[fin]
                bad = (sub if fin.all() else sub.subset(np.flatnonzero(fin))).conflicts
                cv[rows[bad]] = 1.0
                total[rows[bad]] = np.inf
        return total, cv

    def _evaluate_below(self, b: Batch, below: FloatArray) -> tuple[FloatArray, FloatArray]:
        """:meth:`evaluate_cv` with ``below``: the cost of every row, the checks of the rows
        whose cost is below ``below`` (the same cascade, on those rows only). Where a term has
        a cheaper lower bound (:attr:`Term.lower`: an expensive term), the rows the bound
        leaves (:meth:`_maybe_below`) are checked first (but for separation) and the exact
        cost is computed only for those that pass: a row's answer is the same either way."""
        n = b.paths.shape[0]
        total = np.full(n, np.inf)
        cv = np.ones(n)

        def part(rows: NDArray[np.intp]) -> Batch:
            return b if rows.size == n else b.subset(rows)

        rows = self._maybe_below(b, below)
        if rows is None:  # the cost first: cheap beside the checks
            f = self._total(b, checks_too=False)
            rows = np.flatnonzero(f < below)
            if rows.size:
                rows = rows[self.validator.passing(part(rows), skip=("separation",))]
        else:  # the world's checks first, then the expensive cost where they pass
            if rows.size:
                rows = rows[self.validator.passing(part(rows), skip=("separation",))]
            f = np.full(n, np.inf)
            if rows.size:
                f[rows] = self._total(part(rows), checks_too=False)
            rows = rows[f[rows] < below[rows]]
        table = self.validator.reservations
        if rows.size and table is not None and len(table):
            rows = rows[~part(rows).conflicts]
        total[rows] = f[rows]
        cv[rows] = 0.0
        return total, cv

    def _maybe_below(self, b: Batch, below: FloatArray) -> NDArray[np.intp] | None:
        """The rows whose cost may be below ``below`` where some term has a lower bound
        (:attr:`Term.lower`, with a weight >= 0, and no fused leading terms): the cost with
        those terms at their bounds (a lower bound of the cost) below ``below`` (with a
        relative 1e-9 for the sums' order). None where no term has one."""
        n = b.paths.shape[0]
        terms = [t for t in self.terms if t.check is None]
        if self.fused is not None or not any(t.lower is not None for t in terms):
            return None
        if any(t.lower is not None and t.weight < 0 for t in terms):
            return None
        bound = np.zeros(n)
        for t in terms:
            fn = t.lower if t.lower is not None else t.fn
            bound = bound + t.weight * np.asarray(fn(b), dtype=np.float64)
        slack = 1e-9 * np.abs(np.where(np.isfinite(below), below, 0.0))
        return np.flatnonzero(~(bound > below + slack))

    def feasible(self, paths: FloatArray) -> BoolArray:
        return self.validator.paths_valid(paths)

    # ------------------------------------------------------------------ helpers
    def _check(self, paths: FloatArray) -> FloatArray:
        return self.validator.check_paths(paths)

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
