"""HR-MAGA and P-MAGA (Yang, Liu & Li, "Path planning of UAVs under dynamic environment based on a
hierarchical recursive multiagent genetic algorithm", IEEE CEC 2020).

* ``p-maga``: the multi-agent GA of Alg. 1 (:mod:`uavplan.optimizers.maga`) directly on the
  whole path: 26 free waypoints (27 segments, HR-MAGA's ``num ** v``), a 7 x 7 lattice, the
  world's checks as constraints (feasibility-first, as ``hr-maga``).

Both use the scenario's cost preset, as every planner here; the paper's loss, Eq. (4), is the
``hrmaga`` preset (length Eq. 7, terrain under the path Eq. 8, length inside danger areas
Eq. 9, weights 1 : 10 : 15, Table I), which the HR-MAGA scenarios and experiments set
(``cost="hrmaga"`` on any other scenario).
* ``hr-maga``: Alg. 2. Level 1 runs P-MAGA from start to goal on the coarsest map of a terrain
  pyramid (:mod:`uavplan.world.pyramid`) and keeps its three best agents (Alg. 1 line 17); each
  next level refines every segment of each of those paths as its own P-MAGA problem on a finer
  map (Alg. 2 lines 6-13), recursively down to the DEM itself (depth ``v = 3``); bottom-up, the
  three best sub-paths of each segment are combined (``Integration``, line 15: every one of the
  ``3 ** num`` combinations is scored and the best kept for each of the three parent paths), and
  the planner returns the best path, the three best in ``info["paths"]``.

Everything one level's P-MAGA problems need is batched: the level's sub-problems (1, then
``3 num = 9``, then 81) run in lockstep, one P-MAGA each, and every step evaluates all their
asked agents as one population on the level's
:class:`~uavplan.problems.path_problem.PathProblem` (they are independent: Alg. 2 visits them in
turn only because it is written recursively). Their lattices are one
:class:`~uavplan.optimizers.maga.MAGABatch`: a step is one Numba call for every sub-problem's
ask, one evaluation, one Numba call for the tells, each sub-problem drawing from its own
generator exactly as one :class:`~uavplan.optimizers.maga.ReferenceMAGA` object per
sub-problem does (``lockstep="reference"``, the first implementation, kept for the tests and the
benchmark: the same plan bit for bit).

Decisions where the paper is vague (and why)
--------------------------------------------
* **num and the 27 waypoints.** Table I: ``num = 3`` waypoints per recursion, ``v = 3``, "agent
  coding length 27 ... the layer-th power of num". We read a level's ``num`` waypoints as the
  points after the sub-path's start, the last being its (fixed) end: each sub-problem optimizes
  ``num - 1 = 2`` free waypoints, so a sub-path has ``num`` segments, and after ``v`` levels the
  path has ``num ** v = 27`` segments (26 free waypoints + the goal = 27 waypoints after the
  start). ``p-maga`` and the GA baseline get the same 26 free waypoints.
* **Local maps.** "The algorithm first plans on a local high-precision map": a sub-problem's
  genes live in the box around its two ends widened by ``local_margin = 0.5`` of their
  horizontal distance on each side (clipped to the scenario's bounds); the whole map on level 1.
  Without it, a sub-problem of a 27th of the path would mutate by 5 % of the whole map.
* **Maps per level** (:mod:`uavplan.world.pyramid`): checks on the level's conservative map (a
  coarse path that clears is a fine path that clears), Eq. (8) on its sampled map; the first
  level about ``first_samples = 40`` cells per side. Next to the task's start and goal (one
  coarse cell around them) the checks read the sampled map: the ends are placed on the fine
  map and may be under a conservative coarse one, which would make every agent of the level
  infeasible alike and leave the loss unoptimized (we saw it: level 1 never left the
  infeasible side on any of our maps).
* **Uncertain areas** (Eq. 2) are unknown on level 1 and known from ``uncertain_from_level = 2``
  on (the paper: "if there is an uncertain area on the planned point of the upper layer, the
  point can be reinitialized ... in the deeper planning"); an area the scenario marks as not
  revealed stays unknown (it is revealed in flight). A segment end inside a known area moves to
  the nearest point outside it (1 m beyond its edge, inside the bounds; lifted above the
  terrain by the band's floor when needed), and both segments meeting there use the moved point.
* **Constraints.** Eq. (4) has no terrain term and Eq. (6) only forbids turning back; we keep
  the loss as the paper's and pass the world's checks (bounds, terrain, revealed uncertain
  areas, cylinders if any, the altitude band) as constraints under Deb's feasibility-first rule
  (:mod:`uavplan.optimizers.constraints`), so a feasible agent always beats an infeasible one.
  Eq. (6) is enforced as the paper does, by the smoothing behaviour of P-MAGA (Fig. 3(c)); in
  the integration a combination with fewer turn-backs (``theta_k <= 0`` at any waypoint,
  junctions included) ranks first, then the loss.
* **Budget.** An iteration of the planner is one lockstep step (one evaluated batch of every
  live sub-problem of a level: a MAGA iteration, :mod:`uavplan.optimizers.maga`). An iteration
  budget is shared equally among the levels (a level that ends early, all its P-MAGAs at
  ``G`` generations, leaves the rest to the next ones); an evaluation budget among the
  sub-problems of all levels (a level of 81 sub-problems gets 81 times the first level's: each
  P-MAGA call the same, as Table I gives every call the same ``G``; the global first level then
  gets 1/91 of it at v = 3), or, with ``level1_share`` (a variant), that share to the first
  level and the rest in proportion to the later levels' sub-problems;
  P-MAGA stops at Table I's ``G = 200`` generations in any case. Table I's full schedule (200
  generations of 1 + sGen = 11 batches per level) is ``--iterations 6600``; the default, 300
  iterations (about 9 generations per level), plans in about a second of CPU here.
* **One optimizer per sub-problem.** The level's P-MAGAs share every evaluation batch, but each
  keeps its own state machine (phase, generation, self-learning lattices, generator), also
  inside the batched kernels. We tried one MAGA holding the level's sub-problems as
  independent lattices over normalized genes (3x faster: fewer Python calls). Its generations
  are synchronized, so a converged lattice with no self-learning agent sits idle while the
  others self-learn for ``sGen`` steps. It found fewer feasible paths: 10 of 20 against 14 of
  20 on ``hrmaga-jacksboro`` and ``hrmaga-topobathy``, 300 iterations, seeds 4-13. So we kept
  separate optimizers; :class:`~uavplan.optimizers.maga.MAGABatch` batches the computation, not
  the algorithm.
* **Integration at a junction** uses the moved segment ends, so the combined path is continuous
  by construction.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.optimizers.constraints import feasibility_first
from uavplan.optimizers.maga import MAGABatch, MAGAConfig, ReferenceMAGA, turn_cosines
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, PlannerError, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run, Termination, Tracker
from uavplan.planners.population.optimizer_planner import OptimizerPlanner
from uavplan.problems.path_problem import PathProblem, lookup_for
from uavplan.problems.validity import greedy_shortcut
from uavplan.world.obstacles import UncertainArea
from uavplan.world.pyramid import TerrainLevel, relaxed_near, terrain_pyramid
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]

#: one sub-path's three best results: (3, n_points, 3) paths, (3,) rule numbers
Best3 = tuple[FloatArray, FloatArray]


@dataclass(frozen=True)
class HRMAGAConfig(PlannerConfig):
    """Options of :class:`HRMAGA` (Table I where the paper gives them)."""

    v: int = option(3, "recursion depth: levels of the terrain pyramid (Table I)", low=1, high=5)
    num: int = option(
        3, "waypoints per recursion (Table I): num - 1 free ones, num segments", low=2, high=10
    )
    pop_size: int = option(49, "agents per lattice (Table I: 7 x 7)", low=4)
    P_c: float = option(0.5, "crossover rate (Table I)", low=0.0, high=1.0)
    P_m: float = option(0.3, "mutation rate (Table I)", low=0.0, high=1.0)
    sGen: int = option(10, "self-learning generations (MAGA [26]; not in the paper)", low=0)
    keep: int = option(3, "best paths kept per sub-problem (Alg. 1 line 17)", low=1, high=10)
    first_samples: int = option(40, "cells per side of the first level's map (Fig. 1(a))", low=2)
    local_margin: float = option(
        0.5, "sub-problem box: its ends' box widened by this share of their distance", low=0.0
    )
    G: int = option(200, "P-MAGA generations per sub-problem at most (Table I)", low=1)
    level1_share: float = option(
        0.0,
        "share of an evaluation budget the global first level gets, the rest in proportion "
        "to the later levels' sub-problems (0: every level in proportion, each P-MAGA call "
        "the same, as Table I gives every call the same G; a variant, not the paper's)",
        low=0.0,
        high=0.9,
    )
    repair_iterations: int = option(
        20, "lockstep steps of a repair in flight (ours; the paper gives none)", low=1
    )
    repair_shortcut: bool = option(
        True, "the way around is shortened by line of sight when that lowers its loss (ours)"
    )
    repair_detour: bool = option(
        True, "repair first tries the way around the revealed area's corners (ours; fast)"
    )
    uncertain_from_level: int = option(
        2, "first level that knows the uncertain areas (the paper: the finer ones)", low=1
    )
    lockstep: str = option(
        "batched",
        "a level's P-MAGAs as one Numba batch, or one object each (the reference: same numbers)",
        choices=("batched", "reference"),
    )


@dataclass
class _Sub:
    """One P-MAGA problem: free waypoints between ``start`` and ``goal`` in a gene box."""

    start: FloatArray
    goal: FloatArray
    lower: FloatArray
    upper: FloatArray
    block: int
    n_free: int
    ground: bool  # z gene = height above the level's conservative terrain

    @property
    def dim(self) -> int:
        return int(self.lower.shape[0])

    def evaluate(self, X: FloatArray) -> FloatArray:  # pragma: no cover - lockstep evaluates
        raise NotImplementedError("HR-MAGA evaluates its sub-problems together")


class HRMAGA(Planner):
    """Hierarchical recursive MAGA (Alg. 2); see the module docstring."""

    name = "hr-maga"
    Config = HRMAGAConfig
    config: HRMAGAConfig
    specs = PlannerSpecs(dims=(3,), default_iterations=300)

    def check_input(self, scenario: Scenario, task: Task) -> None:
        super().check_input(scenario, task)
        if scenario.terrain is None:
            raise PlannerError(
                f"{self.name} plans over a terrain (its pyramid of maps); {scenario.name!r} "
                "has none"
            )

    # ------------------------------------------------------------------ levels
    def _level_scenario(
        self, scenario: Scenario, level: TerrainLevel, lv: int, ends: FloatArray | None = None
    ) -> Scenario:
        """The world of level ``lv``: its conservative map (relaxed next to the task's fixed
        ``ends``, :func:`~uavplan.world.pyramid.relaxed_near`) and the uncertain areas it
        knows."""
        cfg = self.config
        known = lv >= cfg.uncertain_from_level
        areas = tuple(
            dataclasses.replace(u, revealed=u.revealed and known) for u in scenario.uncertain_areas
        )
        terrain = level.feasibility if ends is None else relaxed_near(level, ends)
        return dataclasses.replace(scenario, terrain=terrain, uncertain_areas=areas)

    def problem(
        self, scenario: Scenario, task: Task, reservations: ReservationTable | None = None
    ) -> PathProblem:
        """The task's problem on the full map, the band checked along whole segments (as the
        flight is checked)."""
        return self._problem(scenario, task, None, True)

    def _problem(
        self, scenario: Scenario, task: Task, level: TerrainLevel | None, strict: bool
    ) -> PathProblem:
        cfg = self.config
        try:
            return PathProblem(
                scenario, task, cost=cfg.cost, weights=cfg.weights, strict_altitude=strict,
                cost_terrain=None if level is None else level.cost,
                lookup=lookup_for(scenario.cost),  # as the flight reads the band
            )  # fmt: skip
        except ValueError as exc:
            raise PlannerError(f"{self.name}: {exc}") from None

    def _sub(
        self,
        sc: Scenario,
        a: FloatArray,
        b: FloatArray,
        local: bool,
        n_free: int | None = None,
        widen: float = 1.0,
    ) -> _Sub:
        cfg = self.config
        lo, hi = sc.bounds.lo.copy(), sc.bounds.hi.copy()
        if local:
            w = widen * cfg.local_margin * float(np.linalg.norm(b[:2] - a[:2]))
            lo[:2] = np.maximum(lo[:2], np.minimum(a[:2], b[:2]) - w)
            hi[:2] = np.minimum(hi[:2], np.maximum(a[:2], b[:2]) + w)
        ground = False
        if sc.altitude is not None:
            if sc.altitude.reference == "ground":
                lo[2], hi[2], ground = sc.altitude.min, sc.altitude.max, True
            else:
                lo[2], hi[2] = max(lo[2], sc.altitude.min), min(hi[2], sc.altitude.max)
        n_free = cfg.num - 1 if n_free is None else n_free
        return _Sub(a, b, np.tile(lo, n_free), np.tile(hi, n_free), 3, n_free, ground)

    def _decode(self, sub: _Sub, X: FloatArray, sc: Scenario) -> FloatArray:
        return _decode_rows(X, sub.start, sub.goal, sub.n_free, sub.ground, sc)

    def _solve_level(
        self, run: Run, problem: PathProblem, sc: Scenario, subs: list[_Sub],
        seeds: list[np.random.SeedSequence], steps: float, evaluations: float, group: int = 1,
    ) -> tuple[list[Best3], list[float]]:  # fmt: skip
        """Run one P-MAGA per sub-problem in lockstep; the ``keep`` best agents of each, and
        after every step the level's loss: the lowest, over the parent paths (``group``
        consecutive sub-problems each), of the sum of their sub-problems' best numbers (the
        smallest loss in the level's population, Eq. 13's ``loss_layer_i``).

        The sub-problems of one gene count are one :class:`~uavplan.optimizers.maga.MAGABatch`
        (a level's are all alike; a repair's runs may differ): a step is one ask of every batch,
        one evaluation per batch, one tell. ``lockstep="reference"`` runs one
        :class:`~uavplan.optimizers.maga.ReferenceMAGA` object per sub-problem instead
        (:meth:`_solve_level_reference`), which gives the same numbers."""
        if self.config.lockstep == "reference":
            return self._solve_level_reference(
                run, problem, sc, subs, seeds, steps, evaluations, group
            )
        cfg = self.config
        mcfg = MAGAConfig(pop_size=cfg.pop_size, P_c=cfg.P_c, P_m=cfg.P_m, sGen=cfg.sGen)
        dims = sorted({s.dim for s in subs})
        members = [[k for k, s in enumerate(subs) if s.dim == d] for d in dims]
        batches = [
            MAGABatch(
                np.stack([subs[k].lower for k in ks]),
                np.stack([subs[k].upper for k in ks]),
                3,
                mcfg,
                [seeds[k] for k in ks],
            )
            for ks in members
        ]
        starts = [np.stack([subs[k].start for k in ks]) for ks in members]
        goals = [np.stack([subs[k].goal for k in ks]) for ks in members]
        ground = [subs[ks[0]].ground for ks in members]  # the level's band: alike for all
        where = np.concatenate(members)  # batch order -> sub-problem order
        tr = run.tracker
        trace: list[float] = []
        used = n_steps = 0
        while n_steps < steps and used < evaluations:
            lives = [b.generation < cfg.G for b in batches]
            if not any(lv.any() for lv in lives):
                break
            for g, (b, lv) in enumerate(zip(batches, lives, strict=True)):
                X, owner = b.ask(lv)
                if len(X) == 0:
                    b.tell(np.empty(0))
                    continue
                n_free = X.shape[1] // 3
                paths = _decode_rows(X, starts[g][owner], goals[g][owner], n_free, ground[g], sc)
                f, cv = problem.evaluate_cv(paths, exact=True)
                b.tell(feasibility_first(f, cv))
                tr.evaluations += len(paths)
                used += len(paths)
            n_steps += 1
            bests = np.empty(len(subs))
            bests[where] = np.concatenate([b.best_f for b in batches])
            trace.append(float(bests.reshape(-1, group).sum(axis=1).min()))
            if tr.end_iteration(best=tr.cost):
                self._stopped = True
                break
        out: list[Best3] = [(np.empty(0), np.empty(0))] * len(subs)
        for b, ks in zip(batches, members, strict=True):
            for i, k in enumerate(ks):
                order = np.argsort(b.F[i], kind="stable")[: cfg.keep]
                out[k] = (self._decode(subs[k], b.L[i][order], sc), b.F[i][order])
        return out, trace

    def _solve_level_reference(
        self, run: Run, problem: PathProblem, sc: Scenario, subs: list[_Sub],
        seeds: list[np.random.SeedSequence], steps: float, evaluations: float, group: int = 1,
    ) -> tuple[list[Best3], list[float]]:  # fmt: skip
        """:meth:`_solve_level` with one :class:`~uavplan.optimizers.maga.ReferenceMAGA` per
        sub-problem, stepped in turn (the first implementation, kept as the reference: the
        tests compare the two plan by plan)."""
        cfg = self.config
        mcfg = MAGAConfig(pop_size=cfg.pop_size, P_c=cfg.P_c, P_m=cfg.P_m, sGen=cfg.sGen)
        opts = [
            ReferenceMAGA(s, mcfg, seed=np.random.default_rng(g))
            for s, g in zip(subs, seeds, strict=True)
        ]
        tr = run.tracker
        trace: list[float] = []
        used = n_steps = 0
        while n_steps < steps and used < evaluations:
            live = [k for k, o in enumerate(opts) if o.generation < cfg.G]
            if not live:
                break
            asks = [opts[k].ask() for k in live]
            decoded = [self._decode(subs[k], X, sc) for k, X in zip(live, asks, strict=True)]
            nums: list[FloatArray] = [np.empty(0)] * len(live)
            for n_pts in sorted({d.shape[1] for d in decoded}):  # one batch per path length
                same = [q for q, d in enumerate(decoded) if d.shape[1] == n_pts]
                paths = np.concatenate([decoded[q] for q in same])
                f, cv = problem.evaluate_cv(paths, exact=True)
                num = feasibility_first(f, cv)
                start = 0
                for q in same:
                    nums[q] = num[start : start + len(decoded[q])]
                    start += len(decoded[q])
                tr.evaluations += len(paths)
                used += len(paths)
            for k, X, num_k in zip(live, asks, nums, strict=True):
                opts[k].tell(X, num_k)
            n_steps += 1
            bests = np.array([o.best_f for o in opts])
            trace.append(float(bests.reshape(-1, group).sum(axis=1).min()))
            if tr.end_iteration(best=tr.cost):
                self._stopped = True
                break
        out = []
        for s, o in zip(subs, opts, strict=True):
            order = np.argsort(o.F, kind="stable")[: cfg.keep]
            out.append((self._decode(s, o.L[order], sc), o.F[order]))
        return out, trace

    # ------------------------------------------------------------------ integration
    @staticmethod
    def _turn_backs(paths: FloatArray) -> NDArray[np.int64]:
        return np.asarray(np.sum(turn_cosines(paths) <= 0, axis=1), dtype=np.int64)

    def _integrate(
        self, problem: PathProblem, groups: list[list[Best3]], tr: Tracker
    ) -> list[tuple[FloatArray, float]]:
        """Alg. 2 line 15 for parent paths, each given by its segments' best sub-paths: every
        combination, ranked by turn-backs, then the rule's number; the best one of each parent.
        All parents' combinations are scored in one batch per path length."""
        cands = []
        for parts in groups:
            combos = itertools.product(*[range(len(p[0])) for p in parts])
            cands.append(
                np.stack(
                    [
                        np.concatenate(
                            [parts[0][0][c[0]][:1]]
                            + [parts[j][0][c[j]][1:] for j in range(len(parts))]
                        )
                        for c in combos
                    ]
                )
            )
        nums: list[FloatArray] = [np.empty(0)] * len(cands)
        for n_pts in sorted({c.shape[1] for c in cands}):
            same = [q for q, c in enumerate(cands) if c.shape[1] == n_pts]
            paths = np.concatenate([cands[q] for q in same])
            f, cv = problem.evaluate_cv(paths, exact=True)
            tr.evaluations += len(paths)
            num = feasibility_first(f, cv)
            for q, part in zip(
                same, np.split(num, np.cumsum([len(cands[q]) for q in same])[:-1]), strict=True
            ):
                nums[q] = part
        out = []
        for paths, num in zip(cands, nums, strict=True):
            order = np.lexsort((num, self._turn_backs(paths)))
            out.append((paths[order[0]], float(num[order[0]])))
        return out

    # ------------------------------------------------------------------ uncertain areas
    @staticmethod
    def _admit_all(
        Q: FloatArray, areas: list[UncertainArea], sc: Scenario, level: float | None = None
    ) -> FloatArray:
        """Points ``Q`` (n, 3) made admissible on level scenario ``sc``: each moved to the
        nearest point 1 m outside every known uncertain area it is in (Sect. III-C, Alg. 2 line
        11; an edge whose outside point leaves the bounds is not a way out; ties go to the
        smaller x, then y), then its altitude put back into the band over this level's map (a
        coarse map is higher than the fine one, so a point at the top of the band there may be
        above it here). ``level``: put the altitude at this share of the band instead (0 its
        floor, 1 its ceiling). All points at once; the tests compare it with the same rule
        applied one point at a time."""
        out = np.array(Q, dtype=np.float64).reshape(-1, 3)
        lo, hi = sc.bounds.lo, sc.bounds.hi
        moving = np.ones(len(out), dtype=bool)
        for _ in range(len(areas) + 1):
            if not areas or not moving.any():
                break
            x, y = out[:, 0], out[:, 1]
            first = np.full(len(out), -1)  # the first area (in order) holding each point
            for k in range(len(areas) - 1, -1, -1):
                a = areas[k]
                first[(a.x <= x) & (x <= a.x + a.width) & (a.y <= y) & (y <= a.y + a.height)] = k
            moving &= first >= 0
            rows = np.flatnonzero(moving)
            if rows.size == 0:
                break
            ax = np.array([areas[k].x for k in first[rows]])
            ay = np.array([areas[k].y for k in first[rows]])
            aw = np.array([areas[k].width for k in first[rows]])
            ah = np.array([areas[k].height for k in first[rows]])
            px, py = x[rows], y[rows]
            dist = np.stack([px - ax, ax + aw - px, py - ay, ay + ah - py], axis=1)
            cx = np.stack([ax - 1.0, ax + aw + 1.0, px, px], axis=1)
            cy = np.stack([py, py, ay - 1.0, ay + ah + 1.0], axis=1)
            ok = (lo[0] <= cx) & (cx <= hi[0]) & (lo[1] <= cy) & (cy <= hi[1])
            # the smallest (distance, x, y) among the edges that stay in bounds
            d = np.where(ok, dist, np.inf)
            tie = ok & (d == d.min(axis=1)[:, None])
            tie &= np.where(tie, cx, np.inf) == np.where(tie, cx, np.inf).min(axis=1)[:, None]
            pick = np.argmin(np.where(tie, cy, np.inf), axis=1)
            stuck = ~ok.any(axis=1)
            r = np.arange(rows.size)
            go = rows[~stuck]
            out[go, 0], out[go, 1] = cx[r, pick][~stuck], cy[r, pick][~stuck]
            moving[rows[stuck]] = False
        x, y, z = out[:, 0], out[:, 1], out[:, 2].copy()
        band = sc.altitude
        if band is not None:
            base = top = np.zeros(len(x))
            if band.reference == "ground" and sc.terrain is not None:
                base = np.asarray(sc.terrain.lookup(x, y, _lookup(sc)), dtype=np.float64)
                top = base
                if sc.terrain.lower is not None:  # the ceiling's own grid
                    top = np.asarray(sc.terrain.lookup_low(x, y, _lookup(sc)), dtype=np.float64)
            if level is not None and math.isfinite(band.max):
                room = band.max - band.min if top is base else top + band.max - base - band.min
                z = base + band.min + level * room
            z = np.minimum(np.maximum(z, base + band.min), top + band.max)
        elif sc.terrain is not None:
            z = np.maximum(z, np.asarray(sc.terrain.height(x, y), dtype=np.float64))
        out[:, 2] = np.minimum(np.maximum(z, lo[2]), hi[2])
        return out

    @classmethod
    def _admit(
        cls, p: FloatArray, areas: list[UncertainArea], sc: Scenario, level: float | None = None
    ) -> FloatArray:
        """One point made admissible (:meth:`_admit_all`)."""
        return cls._admit_all(np.asarray(p)[None], areas, sc, level)[0]

    # ------------------------------------------------------------------ Alg. 2
    def _plan(self, run: Run) -> Outcome:
        cfg = self.config
        sc0 = run.scenario
        assert sc0.terrain is not None
        levels = terrain_pyramid(sc0.terrain, cfg.v, cfg.first_samples)
        n_sub = [(cfg.keep * cfg.num) ** lv for lv in range(cfg.v)]
        max_it, max_ev = run.max_iterations, run.budget.max_evaluations
        self._stopped = False
        root_seq = np.random.SeedSequence(run.seed)
        # nodes of the recursion, level by level: (parent node, segment j) -> its sub-problem
        start = np.asarray(run.task.start, dtype=np.float64)
        goal = np.asarray(run.task.goal, dtype=np.float64)
        ends: list[tuple[FloatArray, FloatArray]] = [(start, goal)]
        results: list[list[Best3]] = []
        traces: list[list[float]] = []
        problems: list[PathProblem] = []
        best_so_far: FloatArray | None = None
        for lv, level in enumerate(levels, start=1):
            sc = self._level_scenario(sc0, level, lv, np.stack([start, goal]))
            problem = self._problem(sc, run.task, level, strict=lv == cfg.v)
            problems.append(problem)
            subs = [self._sub(sc, a, b, local=lv > 1) for a, b in ends]
            tr = run.tracker
            left = cfg.v - lv + 1  # levels still to run, this one included
            steps = math.inf if max_it is None else (max_it - len(tr.history)) / left
            if max_ev is None:
                evals = math.inf
            elif cfg.level1_share > 0 and lv == 1:
                evals = max_ev * cfg.level1_share
            else:  # what is left, in proportion to the sub-problems of the levels to run
                evals = (max_ev - tr.evaluations) * len(subs) / sum(n_sub[lv - 1 :])
            if lv == cfg.v:
                steps = math.inf if max_it is None else max_it - len(tr.history)
            best, trace = self._solve_level(
                run,
                problem,
                sc,
                subs,
                root_seq.spawn(len(subs)),
                max(steps, 1),
                evals,
                1 if lv == 1 else cfg.num,
            )
            traces.append(trace)
            results.append(best)
            # the best full path so far: each node's best sub-path, joined (anytime result)
            best_so_far = self._join_best(results)
            ev = run.problem.evaluate(best_so_far[None])
            run.tracker.evaluations += 1
            run.tracker.offer(best_so_far, float(ev.cost[0]), bool(ev.feasible[0]))
            if lv == cfg.v or self._stopped:
                break
            nxt_sc = self._level_scenario(sc0, levels[lv], lv + 1, np.stack([start, goal]))
            known = [u for u in nxt_sc.uncertain_areas if u.revealed]
            ends = []
            for paths, _ in best:
                for p in paths:  # each kept path of this node
                    # every junction, the previous levels' too (a deterministic move: the
                    # sub-paths meeting there move it alike); never the task's start and goal
                    fixed = np.all(p == start, axis=1) | np.all(p == goal, axis=1)
                    pts = np.array(p, dtype=np.float64)
                    pts[~fixed] = self._admit_all(p[~fixed], known, nxt_sc)
                    ends.extend((pts[j], pts[j + 1]) for j in range(len(pts) - 1))
        # bottom-up integration (Alg. 2 line 15) on the finest level's problem reached
        paths3 = self._integrate_up(results, problems[-1], run.tracker)
        final = run.problem.evaluate(paths3)
        run.tracker.evaluations += len(paths3)
        order = np.lexsort((final.cost, ~final.feasible))
        for k in order:
            run.tracker.offer(paths3[k], float(final.cost[k]), bool(final.feasible[k]))
        tr = run.tracker
        if tr.history:  # found after the last iteration closed
            tr.amend(tr.cost, tr.cost if tr.feasible else math.inf)
        return Outcome(
            path=paths3[order[0]],
            info={
                "paths": [paths3[k].tolist() for k in order],
                "costs": [float(final.cost[k]) for k in order],
                "levels": len(results),
                "factors": [lv.factor for lv in levels[: len(results)]],
                "level_history": traces,
            },
        )

    def _join_best(self, results: list[list[Best3]]) -> FloatArray:
        """The path of every node's best sub-path, recursively (no integration search)."""
        cfg = self.config
        k = cfg.keep * cfg.num

        def node(lv: int, idx: int) -> FloatArray:
            paths, _ = results[lv][idx]
            if lv + 1 == len(results):
                return paths[0]
            kids = [node(lv + 1, idx * k + j) for j in range(cfg.num)]  # children of path 0
            return np.concatenate([kids[0][:1]] + [c[1:] for c in kids])

        return node(0, 0)

    def _integrate_up(
        self, results: list[list[Best3]], problem: PathProblem, tr: Tracker
    ) -> FloatArray:
        """The ``keep`` paths of the root after integrating every level bottom-up, each
        combination scored on ``problem`` (the finest level reached)."""
        cfg = self.config
        k = cfg.keep * cfg.num
        for lv in range(len(results) - 1, 0, -1):
            parents = results[lv - 1]
            groups = [
                [results[lv][pidx * k + i * cfg.num + j] for j in range(cfg.num)]
                for pidx, (ppaths, _) in enumerate(parents)
                for i in range(len(ppaths))
            ]
            best = iter(self._integrate(problem, groups, tr))  # every parent path at once
            merged: list[Best3] = []
            for ppaths, _ in parents:
                news, nums = [], []
                for _i in range(len(ppaths)):
                    path, val = next(best)
                    news.append(path)
                    nums.append(val)
                order = np.argsort(nums, kind="stable")
                merged.append((np.stack([news[o] for o in order]), np.asarray(nums)[order]))
            results[lv - 1] = merged
        return results[0][0][0]

    def _detour(
        self, problem: PathProblem, sc: Scenario, P: FloatArray, i: int, j: int
    ) -> tuple[FloatArray | None, int]:
        """The interior points of the best feasible way from ``P[i]`` to ``P[j + 1]`` around
        the no-fly polygons near the run, revealed uncertain areas included (ours, tried before
        any optimization: a repair must come within one control period). Both chains of the
        convex hull of the two ends and the polygons' corners (pushed out by 2 % of the
        polygon's size, or by half the ends' distance to it if less; the set grows while a
        chain meets another polygon, and a chain of an earlier, smaller set that met none stays
        a candidate: overlapping polygons leave notches, and an end in one is inside the grown
        set's hull), each edge cut in 1, 2, 4 or 8 pieces or in pieces of one
        terrain cell (at most 32), every new point admitted (:meth:`_admit`: out of the areas,
        into the band over the terrain) at the ends' interpolated altitude or at half or three
        quarters of the band; all candidates scored in one batch by the sub-problems' rule.
        ``None`` if none is feasible (then P-MAGA repairs the run); and the evaluations spent."""
        A, B = P[i], P[j + 1]
        areas = [u for u in sc.uncertain_areas if u.revealed]
        polys = [np.asarray(q.array, dtype=np.float64) for q in sc.no_fly_polygons]
        margins = [q.margin for q in sc.no_fly_polygons]
        used = 0

        def touched(xy: FloatArray) -> set[int]:
            """The polygons whose box meets the box of a segment of ``xy``."""
            lo = np.minimum(xy[:-1], xy[1:])[:, None, :]
            hi = np.maximum(xy[:-1], xy[1:])[:, None, :]
            plo = np.array([v.min(axis=0) - m for v, m in zip(polys, margins, strict=True)])[None]
            phi = np.array([v.max(axis=0) + m for v, m in zip(polys, margins, strict=True)])[None]
            hit = np.all((lo <= phi) & (hi >= plo), axis=-1).any(axis=0)
            return set(np.flatnonzero(hit).tolist())

        if not polys:
            return None, 0
        near = touched(P[i : j + 2, :2])
        XY = np.empty((0, 2))
        chains: tuple[list[int], list[int]] = ([], [])
        extra: list[tuple[FloatArray, list[int]]] = []
        for _ in range(4):  # grow the set while a way around meets another polygon
            pts = [A[:2], B[:2]]
            for q in sorted(near):
                v, c = polys[q], polys[q].mean(axis=0)
                size = float(np.max(v.max(axis=0) - v.min(axis=0)))
                gap = min(_box_gap(A[:2], v), _box_gap(B[:2], v)) - margins[q]
                m = margins[q] + max(min(0.02 * size, 0.5 * gap), 1e-3)  # ends stay outside
                r = np.linalg.norm(v - c, axis=1, keepdims=True)
                pts += list(v + math.sqrt(2.0) * m * (v - c) / np.maximum(r, 1e-12))
            XY = np.clip(np.asarray(pts, dtype=np.float64), sc.bounds.lo[:2], sc.bounds.hi[:2])
            chains = _hull_chains(XY)
            hits = [touched(XY[ch]) - near if len(ch) >= 2 else set() for ch in chains]
            more = set().union(*hits)
            if not more:
                break
            # a chain of this round that meets no other polygon stays a candidate: the grown
            # set's hull may hold an end (polygons that overlap leave a notch), then it is the way
            extra += [
                (XY, ch) for ch, h in zip(chains, hits, strict=True) if len(ch) >= 2 and not h
            ]
            near |= more
        ways: list[FloatArray] = []  # (n, 3) each: the way's points at the ends' altitude line
        for XYc, chain in [(XY, ch) for ch in chains] + extra:
            if len(chain) < 2:
                continue
            corners = XYc[chain]  # two points: the ends see each other past every polygon
            edges = np.linalg.norm(np.diff(corners, axis=0), axis=1)
            cell = sc.terrain.cell_size if sc.terrain is not None else math.inf
            by_cell = np.clip(np.ceil(edges / cell), 1, MAX_PIECES).astype(int)
            for pieces in ([1], [2], [4], [8], list(by_cell)):  # per edge; the last: a cell each
                ts = [_cuts(int(n)) for n in np.broadcast_to(pieces, len(edges))]
                xy = np.concatenate(
                    [
                        a + t[:, None] * (b - a)
                        for a, b, t in zip(corners[:-1], corners[1:], ts, strict=True)
                    ]
                    + [corners[-1:]]
                )
                xy = np.clip(xy, sc.bounds.lo[:2], sc.bounds.hi[:2])
                d = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
                z = A[2] + (B[2] - A[2]) * d / max(d[-1], 1e-12)
                if len(xy) < 3:
                    continue  # the straight segment: it failed
                ways.append(np.column_stack([xy, z]))
        cands: list[FloatArray] = []
        if ways:  # every way's inner points admitted at once, per altitude level
            inner = np.concatenate([w[1:-1] for w in ways])
            cut = np.cumsum([len(w) - 2 for w in ways])[:-1]
            levels = [  # the ends' line, or a share of the band
                np.split(self._admit_all(inner, areas, sc, level), cut)
                for level in (None, 0.5, 0.75)
            ]
            for k, w in enumerate(ways):
                for admitted in levels:
                    Q = w.copy()
                    Q[1:-1] = admitted[k]
                    Q[0], Q[-1] = A, B
                    cands.append(Q)
        if not cands:
            return None, 0
        best: tuple[float, FloatArray] | None = None
        for n_pts in sorted({len(c) for c in cands}):  # one batch per path length
            same = [c for c in cands if len(c) == n_pts]
            f, cv = problem.evaluate_cv(np.stack(same), exact=True)
            used += len(same)
            num = feasibility_first(f, cv)
            k = int(np.argmin(num))
            if cv[k] <= 0 and np.isfinite(f[k]) and (best is None or num[k] < best[0]):
                best = (float(num[k]), same[k])
        if best is not None and self.config.repair_shortcut:
            # line of sight over the chosen way: fewer, longer legs where they stay clear
            Q = best[1]
            S, _, _ = greedy_shortcut(problem.validator, Q)
            if len(S) < len(Q):
                f, cv = problem.evaluate_cv(S[None], exact=True)
                used += 1
                num_s = float(feasibility_first(f, cv)[0])
                if cv[0] <= 0 and num_s <= best[0]:
                    best = (num_s, S)
        return (None if best is None else best[1][1:-1]), used

    def repair(
        self,
        scenario: Scenario,
        task: Task,
        path: FloatArray,
        times: FloatArray,
        area: int,
        budget: Budget | int | None = None,
        seed: int | None = None,
    ) -> tuple[FloatArray, dict[str, Any]]:
        """Local repair (Sect. III-D: "HR-MAGA can effectively process the burst situation in
        real time by correcting the local path"): every maximal run of consecutive segments of
        the remaining ``path`` that fails the checks on the world as now known is re-optimized on
        the finest level as one P-MAGA sub-problem between the run's two ends (which are outside
        the area: a point inside it fails both its segments, so it is inside a run), with twice as
        many free waypoints as the run has segments (at least ``num - 1``: the way around needs
        more points than the way through had); the runs are solved in
        lockstep. Budget: ``repair_iterations`` lockstep steps unless ``budget`` says otherwise.
        When a run finds no feasible sub-path, up to two more attempts grow every run by two
        segments on each side and widen the boxes (x 2, x 3); then it plans from scratch."""
        cfg = self.config
        P = np.asarray(path, dtype=np.float64)
        problem = self._problem(scenario, task, None, True)
        ok = problem.validator.paths_valid(np.stack([P[:-1], P[1:]], axis=1))
        bad = np.flatnonzero(~ok)
        if bad.size == 0:
            return P, {"how": "none needed", "runs": 0, "evaluations": 0}
        runs: list[tuple[int, int]] = []  # (first bad segment, last bad segment)
        for k in bad:
            if runs and k == runs[-1][1] + 1:
                runs[-1] = (runs[-1][0], int(k))
            else:
                runs.append((int(k), int(k)))
        if cfg.repair_detour:
            found = [self._detour(problem, scenario, P, i, j) for i, j in runs]
            detours = [d for d, _ in found if d is not None]
            if len(detours) == len(runs):
                return _splice(P, runs, detours), {
                    "how": "detour",
                    "runs": len(runs),
                    "segments": int(bad.size),
                    "evaluations": sum(n for _, n in found),
                }
        b = Budget.of(budget if budget is not None else cfg.repair_iterations)
        steps = math.inf if b.max_iterations is None else b.max_iterations
        evals = math.inf if b.max_evaluations is None else b.max_evaluations
        seeds = np.random.SeedSequence(seed)
        used = 0
        for attempt in range(3):  # wider each time: runs grown by 2 segments a side, wider box
            if attempt:
                grown: list[tuple[int, int]] = []
                for i, j in runs:
                    i, j = max(i - 2, 0), min(j + 2, len(P) - 2)
                    if grown and i <= grown[-1][1] + 1:
                        grown[-1] = (grown[-1][0], j)
                    else:
                        grown.append((i, j))
                runs = grown
            subs = [
                self._sub(
                    scenario, P[i], P[j + 1], True, max(cfg.num - 1, 2 * (j - i + 1)), 1 + attempt
                )
                for i, j in runs
            ]
            tr = Tracker(Termination(b.max_iterations, b.max_evaluations, b.max_time), False)
            run = Run(scenario, task, problem, seed, b, b.max_iterations, tr)
            self._stopped = False
            best, _ = self._solve_level(
                run, problem, scenario, subs, seeds.spawn(len(subs)), steps, evals
            )
            used += tr.evaluations
            if all(np.isfinite(nums[0]) and nums[0] < 1e7 for _, nums in best):
                break
        else:
            fallback, info = Planner.repair(self, scenario, task, path, times, area, budget, seed)
            return fallback, {**info, "how": "from scratch (local repair found no feasible path)",
                              "runs": len(runs), "local_evaluations": used}  # fmt: skip
        return _splice(P, runs, [paths[0][1:-1] for paths, _n in best]), {
            "how": "local repair",
            "runs": len(runs),
            "segments": int(bad.size),
            "attempts": attempt + 1,
            "evaluations": used,
        }


#: the most pieces a detour's edge is cut into (per terrain cell up to this many)
MAX_PIECES = 32


@functools.cache
def _cuts(n: int) -> FloatArray:
    """``np.linspace(0, 1, n + 1)[:-1]``, computed once per ``n`` (read-only)."""
    t = np.linspace(0.0, 1.0, n + 1)[:-1]
    t.setflags(write=False)
    return t


def _splice(P: FloatArray, runs: list[tuple[int, int]], inner: list[FloatArray]) -> FloatArray:
    """``P`` with the interior of every run of segments ``(i, j)`` (from ``P[i]`` to
    ``P[j + 1]``) replaced by the matching ``inner`` points."""
    out = [P[: runs[0][0] + 1]]
    for r_idx, ((_, j), d) in enumerate(zip(runs, inner, strict=True)):
        out.append(d)
        nxt = runs[r_idx + 1][0] if r_idx + 1 < len(runs) else len(P) - 1
        out.append(P[j + 1 : nxt + 1])
    return np.concatenate(out)


def _box_gap(p: FloatArray, v: FloatArray) -> float:
    """Distance from point ``p`` to the bounding box of vertices ``v`` (0 inside)."""
    d = np.maximum(np.maximum(v.min(axis=0) - p, p - v.max(axis=0)), 0.0)
    return float(np.hypot(d[0], d[1]))


def _hull_chains(pts: FloatArray) -> tuple[list[int], list[int]]:
    """The two chains of the convex hull of 2-D points ``pts`` from ``pts[0]`` to ``pts[1]``
    (indices, ends included); empty when either end is not a hull vertex. Andrew's monotone
    chain (a dozen points: a library call would cost more than the work)."""
    order = sorted(range(len(pts)), key=lambda k: (pts[k][0], pts[k][1]))

    def cross(o: int, a: int, b: int) -> float:
        return float(
            (pts[a][0] - pts[o][0]) * (pts[b][1] - pts[o][1])
            - (pts[a][1] - pts[o][1]) * (pts[b][0] - pts[o][0])
        )

    lower: list[int] = []
    upper: list[int] = []
    for k in order:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], k) <= 0:
            lower.pop()
        lower.append(k)
    for k in reversed(order):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], k) <= 0:
            upper.pop()
        upper.append(k)
    ring = lower[:-1] + upper[:-1]  # counter-clockwise
    if 0 not in ring or 1 not in ring:
        return [], []
    a, b = ring.index(0), ring.index(1)
    n = len(ring)
    one = [ring[(a + t) % n] for t in range((b - a) % n + 1)]
    other = [ring[(a - t) % n] for t in range((a - b) % n + 1)]
    return one, other


def _decode_rows(
    X: FloatArray, start: FloatArray, goal: FloatArray, n_free: int, ground: bool, sc: Scenario
) -> FloatArray:
    """Paths ``(n, n_free + 2, 3)`` from gene rows ``X`` ``(n, 3 n_free)`` between ``start``
    and ``goal`` (``(3,)``, or ``(n, 3)`` one per row); ``ground``: the z genes are heights
    above the level's map."""
    n = X.shape[0]
    out = np.empty((n, n_free + 2, 3))
    out[:, 1:-1] = X.reshape(n, n_free, 3)
    if ground:
        assert sc.terrain is not None
        free = out[:, 1:-1]
        free[..., 2] += sc.terrain.lookup(free[..., 0], free[..., 1], _lookup(sc))
    out[:, 0], out[:, -1] = start, goal
    return out


def _lookup(sc: Scenario) -> str:
    """How the scenario's band reads terrain heights under waypoints (as its flight does)."""
    return lookup_for(sc.cost)


register_planner(
    HRMAGA, name="hr-maga", summary="HR-MAGA: hierarchical recursive P-MAGA over a terrain pyramid"
)
register_planner(
    OptimizerPlanner,
    name="p-maga",
    summary="P-MAGA: HR-MAGA's multi-agent GA on the whole path (26 free waypoints, Eq. 4)",
    optimizer="maga",
    n_waypoints=26,
    constraints="feasibility-first",
)
