"""Prioritized fleet planning with a low-level population optimizer (PPSwarm and its baselines).

Meng, Q., Chen, K. & Qu, Q. (2024). PPSwarm: Multi-UAV path planning based on hybrid PSO in
complex scenarios. *Drones* 8, 192.

* **High level** (Alg. 2-3): every UAV gets an initial path (RRT*, Alg. 1, or none); UAVs are
  planned one at a time in priority order, each avoiding the UAVs planned before it; after each
  pass (a *restart*) the priorities are shuffled and the fleet is planned again.
* **Low level** (Alg. 4): a population optimizer over the UAV's free waypoints (Cartesian
  encoding, Sect. 4.1.3) minimizing F = sum b_c F_c (Eqs. 2-13). Its first population is seeded
  from the initial path by Eq. (15) in the first restart, and from the UAV's previous population
  with a share ``rho`` of random paths by Eq. (16) in later ones. PSO (Eq. 14) is PPSwarm's; any
  registered optimizer can replace it, which is how the paper's baselines run (Table 2: LH
  priorities, one pass, uniform random first populations).
* **Collisions between UAVs** (Eqs. 11-12, Sect. 4.3, Alg. 5): the chosen paths of the UAVs
  already planned are kept in a :class:`~uavplan.world.reservations.ReservationTable`; a
  candidate that comes closer than S2 to one of them at any instant costs infinity.

Choices where the paper is silent or vague (all parameters of :class:`PrioritizedConfig`):

* **Infeasible means infinite cost**, as Sect. 2 says of every constraint; we apply it to the
  continuous checks of :class:`~uavplan.problems.path_problem.PathProblem` with
  ``strict_altitude=True`` (terrain and altitude band along whole segments, cylinders exact),
  so that the kept path of a UAV is always flyable, not only at its waypoints.
* **Eq. (15)**: ``alpha`` is not given; we use 0.1 (particles within a tenth of the box from the
  RRT* path, as the thin lines of Fig. 2 suggest), blending in the optimizer's gene space (x, y
  and height above ground). ``randpath(T_m)`` is a path of uniform random free waypoints.
* **Eq. (16)**: ``x_i^last`` are the particle positions the optimizer evaluated last.
* **RRT*'s lengths** (step, goal and near radii; the paper gives none): its defaults on a map
  up to 2.5 km across (the paper's), else scaled to the map
  (:func:`~uavplan.planners.sampling.rrt_star.map_scaled_lengths`: a step of 2 % of the
  diagonal); ``rrt_params`` overrides them. With the 50 m step a UAV 90 km from its goal gets
  no RRT* path within the 5,000 iterations, and the tree's Python loop (among moving
  obstacles) spends them all.
* **The RRT* path as a particle**: its vertices are kept and the remaining free waypoints are
  spread along its segments in proportion to their lengths, so the particle is the same polyline
  (and as feasible); a path with more vertices than free waypoints is shortcut first, then
  resampled by arc length. Without an RRT* path (not found, or ``seeding="uniform"``) the
  straight start-goal line stands in for ``P^m``.
* **Priorities**: ``lh`` plans the longer tasks first, ``sh`` the shorter, ``rnd`` at random
  (Sect. 5.3.1). A task's length is its RRT* path length when the planner has one (Alg. 3 line 4,
  SortbyCost: "higher costs receiving higher priorities"), else the start-goal distance.
* **Which solution is returned**: Alg. 3 returns the last restart's; we return the best restart's
  (fewest infeasible UAVs, then lowest total cost), since Table 4 reports best costs falling with
  restarts. The fleet history (Fig. 5) has one value per low-level iteration of each restart:
  the sum over UAVs of each UAV's best cost after that many iterations of its own optimizer.
* A UAV whose optimizer found no feasible path keeps its best (infeasible) path, which is still
  reserved so that later UAVs avoid it; the fleet is then infeasible.
* **Constraints** (``constraints``, :mod:`uavplan.optimizers.constraints`): the default
  ``"inf"`` is Sect. 2 (every violation costs infinity). With it, an optimizer started from
  uniform random paths sees no difference between its particles until one happens to be
  feasible, and on our scenarios the baselines then end with most UAVs infeasible;
  ``"feasibility-first"`` (Deb's rule) keeps a feasible path's cost exactly F and gives an
  infeasible one ``1e7`` plus how badly it fails (the problem's graded violation: metres
  inside cylinders and outside the band at the waypoints, 100 per failed continuous check:
  terrain, band along segments, bounds, separation). Only the optimizer sees it; reported
  costs stay F (inf when infeasible).
* **Departure delays** (not in the paper, whose mode is ``max_delays = 0``; ours by default
  ``max_delays = 24``): a UAV whose flight is blocked may take off ``delay_step = 5`` s later,
  up to ``max_delays`` times (first its best candidates re-timed, then a fresh low-level run
  from the later start); the delays are reported. 24 rather than 12: on ``ppswarm4@500``
  (N_restart 1) 12 left 2 UAVs blocked in 1 of 2 seeds, 24 none in both (``fleet-scale``
  ran with 12, docs/results.md). Under an execution model whose schedule drifts
  (:mod:`uavplan.world.execution`) the reservations are tubes that grow along each flight and
  can fill every slot within ``max_delays``: a UAV whose flight clears everything but time is
  then re-timed on, step by step, at worst to the second after every UAV before it has
  landed (docs/decisions.md, "Execution model").
* Iterations: ``N_iter`` counts iterations as every optimizer here does, the first one being the
  evaluation of the first population (Alg. 4 line 3), so a restart evaluates ``N_iter`` swarms
  per UAV (Alg. 4 read literally moves ``N_iter`` times after that: one swarm more).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, overload

import numpy as np
from numpy.typing import NDArray

from uavplan import optimizers
from uavplan.compile_clock import Stopwatch
from uavplan.optimizers.base import Budget, OptimizerConfig
from uavplan.optimizers.constraints import RULES, Constrained, infinite_if_violated
from uavplan.optimizers.pso import PSO
from uavplan.planners.core.base import FleetOutcome, FleetPlanner, separated_problem
from uavplan.planners.core.flight import TIMINGS, Flight, declare, fly
from uavplan.planners.core.options import FleetPlannerConfig, PlannerError, option
from uavplan.planners.core.results import PlanResult, make_result
from uavplan.planners.core.run import ProgressCallback
from uavplan.planners.fleet.fleet_objective import FleetObjective
from uavplan.problems.encoding import ENCODINGS, CartesianEncoding
from uavplan.problems.path_problem import PRESETS, PathProblem
from uavplan.problems.validity import TIME_CHECKS
from uavplan.world.cruise_layers import layered
from uavplan.world.geometry import as_3d, track_crosses_itself
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task
from uavplan.world.tolerances import RESERVE_TOL

FloatArray = NDArray[np.float64]

ORDERS = ("lh", "sh", "rnd")
SMOOTH_TIMINGS = TIMINGS
FLIGHTS = ("in-loop", "after", "none")
SEEDINGS = ("rrt-star", "uniform")


#: How priorities change after a restart (``restart_order``).
RESTART_ORDERS = ("shuffle", "failed-first")


@dataclass(frozen=True)
class PrioritizedConfig(FleetPlannerConfig):
    """Fleet planner settings. Defaults: PPSwarm Table 1 (N_iter 20, N_restart 5, N_pop 300,
    rho 20 %, PSO w = 1, c1 = c2 = 1.5) and Sect. 5.1; the rest documented in the module."""

    optimizer: str = option("pso", "low-level optimizer (Alg. 4: PSO; the baselines' others)")
    optimizer_options: dict[str, Any] = option(
        default_factory=dict, doc="the low-level optimizer's options (w, c1, F, CR, ...)"
    )
    pop_size: int = option(300, "N_pop: particles per UAV (Table 1)", low=1)
    n_iter: int = option(20, "N_iter: low-level iterations per UAV and restart (Table 1)", low=1)
    n_restart: int = option(5, "N_restart: passes over the fleet (Table 1)", low=1)
    rho: float = option(0.2, "Eq. 16: share of random paths after a restart (Table 1)", low=0,
                        high=1)  # fmt: skip
    alpha: float = option(0.1, "Eq. 15: blend of random paths into the RRT* seed (ours: not "
                          "given)", low=0, high=1)  # fmt: skip
    order: str = option("lh", "priorities: longer first, shorter first, random", choices=ORDERS)
    seeding: str = option("rrt-star", "first populations from RRT* paths (Alg. 1) or uniform",
                          choices=SEEDINGS)  # fmt: skip
    rrt_iterations: int | None = option(None, "RRT* iterations (default: its max_iterations)",
                                        low=1)  # fmt: skip
    rrt_params: dict[str, Any] = option(default_factory=dict, doc="RRT* options (step, ...; "
                                        "default: its lengths scaled to the map)")  # fmt: skip
    n_waypoints: int | None = option(None, "free waypoints (default: the scenario's)", low=1)
    cost: str | None = option(
        None, "cost preset (default: the scenario's; PPSwarm's scenarios: ppswarm, F1-F4); F5, "
        "the separation term, is added", choices=tuple(PRESETS)
    )  # fmt: skip
    weights: dict[str, float] | None = option(None, "cost term weight overrides")
    dt: float = option(1.0, "reservation table's time bucket, s", low=0, low_open=True)
    constraints: str = option(
        "inf", "how violations reach the optimizer (Sect. 2: infinity)", choices=RULES
    )
    max_delays: int = option(
        24, "take-off delays a UAV whose flight (in-loop; else polyline) is blocked may try: "
        "first its candidates re-timed, then re-planned from the later start (ours; the "
        "paper's: 0)", low=0
    )  # fmt: skip
    delay_step: float = option(5.0, "one take-off delay, s", low=0, low_open=True)
    flight: str = option(
        "in-loop",
        "each UAV's flight (Dubins-smoothed, timed) is checked while planning and is what is "
        "reserved and guaranteed (in-loop); or the paper's mode: polylines reserved and "
        "guaranteed, smoothed after as information (after) or not at all (none)",
        choices=FLIGHTS,
    )
    flight_candidates: int = option(
        8, "in-loop: the best distinct polylines of a UAV's last population whose flights are "
        "tried, best first", low=1
    )  # fmt: skip
    smooth_step: float = option(5.0, "sample spacing of smoothed paths, m", low=0, low_open=True)
    smooth_timing: str = option("planned", "smoothed flights keep the planned times or fly at "
                                "constant speed (the paper's)", choices=SMOOTH_TIMINGS)  # fmt: skip
    separation_margin: float = option(0.0, "plan this much wider than S2, m (ours)", low=0)
    speed_steps: int = option(
        0, "in-loop: slower constant speeds tried, evenly from cruise down to max(min_speed, "
        "cruise / 2), for a UAV whose flights all fail (ours; 0: none)", low=0
    )  # fmt: skip
    restart_order: str = option(
        "shuffle", "priorities after a restart: shuffled (Alg. 3 line 13) or the UAVs that "
        "failed in it first, the rest shuffled (ours)", choices=RESTART_ORDERS
    )  # fmt: skip
    layers: int = option(
        1, "cruise altitude layers by heading: the altitude cost pulls each UAV toward the "
        "middle of its heading sector's layer of the band instead of the band's middle "
        "(ours, aviation's semicircular rule; 1: the paper's)", low=1
    )  # fmt: skip


def polyline_with_n_vertices(path: FloatArray, n: int) -> FloatArray:
    """The polyline ``path`` (k, d) as exactly ``n >= k`` vertices, start and goal included: the
    original vertices are kept and the extra ones placed on the segments in proportion to their
    lengths (largest remainders), so the geometry is unchanged."""
    p = np.asarray(path, dtype=np.float64)
    k = p.shape[0]
    if n < k:
        raise ValueError(f"cannot keep {k} vertices in {n}")
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    extra = n - k
    if extra == 0:
        return p.copy()
    if seg.sum() <= 0:
        return np.repeat(p[:1], n, axis=0)
    share = seg / seg.sum() * extra
    add = np.floor(share).astype(int)
    rest = extra - add.sum()
    if rest:
        add[np.argsort(-(share - add), kind="stable")[:rest]] += 1
    out = [p[0]]
    for i in range(k - 1):
        m = add[i] + 1
        t = np.arange(1, m + 1)[:, None] / m
        out.extend(p[i] + t * (p[i + 1] - p[i]))
    return np.asarray(out)


def resample_by_length(path: FloatArray, n: int) -> FloatArray:
    """``n`` points equally spaced along the polyline (start and goal included)."""
    p = np.asarray(path, dtype=np.float64)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    u = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(u, s, p[:, d]) for d in range(p.shape[1])], axis=1)


class PrioritizedPlanner(FleetPlanner):
    """Prioritized planning with restarts and a low-level population optimizer (PPSwarm's
    engine; its named configurations are in :mod:`uavplan.planners.fleet.ppswarm`).

    ``budget`` (iterations) sets ``n_iter`` when given: the low-level optimizer's iterations per
    UAV per restart.
    """

    name = "prioritized-engine"
    Config = PrioritizedConfig
    config: PrioritizedConfig

    def __init__(self, config: PrioritizedConfig | None = None, **options: Any) -> None:
        super().__init__(config, **options)
        self.optimizer_cls = optimizers.get(self.config.optimizer)

    def _optimizer_config(self) -> OptimizerConfig:
        """The low-level optimizer's config; its population is ``pop_size`` (N_pop) unless
        ``optimizer_options`` sets one."""
        cfg = self.config
        return self.build_optimizer_config(
            cfg.optimizer, {"pop_size": cfg.pop_size, **cfg.optimizer_options}
        )

    @property
    def opt_config(self) -> OptimizerConfig:
        assert self.optimizer_config is not None
        return self.optimizer_config

    # ------------------------------------------------------------------ high level (Alg. 3)
    def _plan_fleet(
        self,
        scenario: Scenario,
        budget: Budget | None,
        seed: int | None,
        callback: ProgressCallback | None,
    ) -> FleetOutcome:
        cfg = self.config
        n_iter = cfg.n_iter
        if budget is not None:
            if budget.max_iterations is None:
                raise PlannerError(f"{self.name} takes an iteration budget (N_iter)")
            n_iter = int(budget.max_iterations)
        tasks = layered(scenario.tasks, scenario.altitude if scenario.dim == 3 else None,
                        cfg.layers)  # fmt: skip
        M = len(tasks)
        root = np.random.SeedSequence(seed)
        s_rrt, s_opt, s_order = root.spawn(3)
        order_rng = np.random.default_rng(s_order)
        n_free = int(cfg.n_waypoints if cfg.n_waypoints is not None else scenario.n_waypoints)
        in_loop = cfg.flight == "in-loop"
        drift = scenario.execution is not None and scenario.execution.timed

        def ok(res: PlanResult) -> bool:
            """What the mode guarantees: the flight (in-loop) or the polyline (paper)."""
            return bool(res.flown_ok) if in_loop else res.feasible

        # Alg. 3 lines 1-3: initial paths
        t0 = time.perf_counter()
        init_paths, rrt_found = self._initial_paths(scenario, n_free, s_rrt)
        t_rrt = time.perf_counter() - t0
        lengths = np.linalg.norm(np.diff(np.stack(init_paths), axis=1), axis=2).sum(axis=1)
        # line 4: priorities
        if cfg.order == "lh":
            priority = list(np.argsort(-lengths, kind="stable"))
        elif cfg.order == "sh":
            priority = list(np.argsort(lengths, kind="stable"))
        else:
            priority = list(order_rng.permutation(M))

        opt_seeds = s_opt.spawn(cfg.n_restart * M)
        current = [p.copy() for p in init_paths]  # P^m, as full paths
        last_pop: list[FloatArray | None] = [None] * M
        best: tuple[Any, ...] | None = None
        restart_costs: list[float] = []
        restart_failed: list[list[str]] = []  # each restart's UAVs left failing, in order
        fleet_history: list[float] = []
        per_uav_cost = np.full(M, np.inf)
        evaluations = 0
        stop = False
        for r in range(cfg.n_restart):
            table = ReservationTable.for_scenario(scenario, cfg.separation_margin, dt=cfg.dt)
            results: list[PlanResult | None] = [None] * M
            delayed: dict[str, float] = {}
            histories: list[FloatArray] = []
            for idx, m in enumerate(priority):
                task = tasks[m]
                rng = np.random.default_rng(opt_seeds[r * M + idx])
                res, pop, cands = self._low_level(
                    scenario, task, table, current[m], last_pop[m], r, n_iter, n_free, rng
                )
                evaluations += res.evaluations
                if in_loop:
                    res = self._in_loop_flight(scenario, table, cands)
                # not in the paper: a UAV that finds no conflict-free path may wait on the
                # ground at its start and take off later (the same swarm seeding again).
                # Under an execution model whose schedule drifts, the candidates are first
                # tried at every later take-off before any is re-planned (cheap, and what a
                # drifting schedule most needs: a later slot), then re-planned at delays of
                # 1, 2, 4, 8, ... steps
                retimed = False
                if in_loop and drift and not ok(res):
                    found = self._retimed_flight(scenario, table, task, cands, res)
                    if found is not None:
                        res, wait = found
                        delayed[task.id] = wait
                    retimed = True
                steps: Sequence[int] = range(1, cfg.max_delays + 1)
                if retimed:  # re-planned at doubling delays only: every one was tried above
                    steps = sorted({min(2**i, cfg.max_delays) for i in range(8)} - {0})
                    steps = [k for k in steps if k <= cfg.max_delays]
                for k in steps:
                    if ok(res):
                        break
                    later = replace(task, start_time=task.start_time + k * cfg.delay_step)
                    if in_loop and not retimed:  # first the same candidates, later (cheap)
                        res2 = self._in_loop_flight(
                            scenario, table, self._waited(scenario, later, table, cands)
                        )
                        if ok(res2):
                            res = replace(res2, info={**res2.info, "rescue": "wait"})
                            delayed[task.id] = later.start_time - task.start_time
                            break
                    res2, pop2, cands2 = self._low_level(
                        scenario, later, table, current[m], last_pop[m], r, n_iter, n_free, rng
                    )
                    evaluations += res2.evaluations
                    if in_loop:
                        res2 = self._in_loop_flight(scenario, table, cands2)
                    if ok(res2):
                        res, pop = res2, pop2
                        res = replace(res, info={**res.info, "rescue": "delay"})
                        delayed[task.id] = later.start_time - task.start_time
                results[m] = res
                last_pop[m] = pop
                current[m] = res.waypoints
                pts, ts = res.flown_trajectory() if in_loop else (res.waypoints, res.times)
                table.add(task.id, as_3d(pts), ts, RESERVE_TOL if in_loop else 0.0)
                histories.append(res.history)
                per_uav_cost[m] = res.cost if ok(res) else np.inf
                if callback is not None:  # progress per UAV; a stop request ends the restart
                    stop = bool(callback(r * M + idx + 1, float(np.sum(per_uav_cost)))) or stop
            fleet_history.extend(self._fleet_curve(histories))
            finished = tuple(res for res in results if res is not None)
            n_bad = sum(not ok(res) for res in finished)
            total = float(sum(res.cost for res in finished))
            restart_costs.append(np.inf if n_bad else total)
            restart_failed.append([tasks[m].id for m in priority
                                   if results[m] is not None and not ok(results[m])])  # fmt: skip
            key = (n_bad, total)
            if best is None or key < best[0]:
                best = (key, finished, [tasks[m].id for m in priority], r, dict(delayed))
            if stop:
                break
            priority = list(order_rng.permutation(M))  # line 13: shuffle
            if cfg.restart_order == "failed-first":  # ours: the blocked UAVs plan first
                failed = {m for m, x in enumerate(results) if x is not None and not ok(x)}
                priority = [m for m in priority if m in failed] + [
                    m for m in priority if m not in failed
                ]
        assert best is not None
        (n_bad, total), chosen, prio, best_restart, delays = best
        results_t = tuple(chosen)
        info: dict[str, Any] = {
            "rrt_time": t_rrt,
            "rrt_found": int(sum(rrt_found)),
            "best_restart": int(best_restart) + 1,
            "evaluations": int(evaluations),
            "n_infeasible": int(n_bad),
            "n_iter": n_iter,
            "delayed": delays,
            "restart_failed": restart_failed,
            # what each UAV was kept S2 from: the flights (in-loop) or the polylines (paper)
            "separated": "flights" if in_loop else "polylines",
        }
        t0 = time.perf_counter()
        if cfg.flight == "after":
            results_t, report = smooth_fleet(scenario, results_t, prio, cfg)
            info["smoothing"] = report
        elif cfg.flight == "in-loop":
            info["flights"] = flight_report(results_t)
        if cfg.flight != "in-loop":  # the paper's mode guarantees the polylines
            results_t = declare_polylines(scenario, results_t, prio, cfg)
        info["smoothing_time"] = time.perf_counter() - t0
        return FleetOutcome(
            results=results_t,
            priority=tuple(prio),
            history=np.asarray(fleet_history),
            restart_costs=np.asarray(restart_costs),
            info=info,
            cost=float(total) if n_bad == 0 else float("inf"),
        )

    @staticmethod
    def _fleet_curve(histories: list[FloatArray]) -> list[float]:
        """One value per low-level iteration of a restart: the sum over UAVs of each one's
        best cost after that many iterations of its own optimizer."""
        if not histories:
            return []
        n = max(len(h) for h in histories)
        h = np.array([np.pad(x, (0, n - len(x)), mode="edge") for x in histories])
        return [float(v) for v in h.sum(axis=0)]

    def _initial_paths(
        self, scenario: Scenario, n_free: int, ss: np.random.SeedSequence
    ) -> tuple[list[FloatArray], list[bool]]:
        """P^m for every UAV as a full path of ``n_free + 2`` vertices (Alg. 3 lines 1-3)."""
        cfg = self.config
        out: list[FloatArray] = []
        found: list[bool] = []
        seeds = ss.spawn(len(scenario.tasks))
        for task, s in zip(scenario.tasks, seeds, strict=True):
            start = np.asarray(task.start, dtype=np.float64)
            goal = np.asarray(task.goal, dtype=np.float64)
            path: FloatArray | None = None
            if cfg.seeding == "rrt-star":
                from uavplan.planners.sampling.rrt_star import (
                    RRTStarConfig,
                    map_scaled_lengths,
                    rrt_star,
                    validity_problem,
                )
                from uavplan.problems.validity import greedy_shortcut

                try:
                    rc = RRTStarConfig(**{**map_scaled_lengths(scenario), **cfg.rrt_params})
                except (TypeError, PlannerError) as exc:
                    raise PlannerError(f"{self.name}: rrt_params: {exc}") from None
                res = rrt_star(
                    scenario, task, rc, np.random.default_rng(s), max_iterations=cfg.rrt_iterations
                )
                path = res.path
                if path is not None and path.shape[0] > n_free + 2:
                    path = greedy_shortcut(validity_problem(scenario, task), path)[0]
            found.append(path is not None)
            if path is None:
                path = np.stack([start, goal])
            if path.shape[0] <= n_free + 2:
                full = polyline_with_n_vertices(path, n_free + 2)
            else:
                full = resample_by_length(path, n_free + 2)
            full[0], full[-1] = start, goal
            out.append(full)
        return out, found

    # ------------------------------------------------------------------ low level (Alg. 4)
    def _low_level(
        self,
        scenario: Scenario,
        task: Task,
        table: ReservationTable,
        P_m: FloatArray,
        x_last: FloatArray | None,
        restart: int,
        n_iter: int,
        n_free: int,
        rng: np.random.Generator,
    ) -> tuple[PlanResult, FloatArray, Candidates]:
        """One UAV's low-level run: its best result, the last positions (Eq. 16's
        ``x_last``) and, for in-loop flights, the best distinct feasible polylines of the last
        population (the best result first)."""
        cfg = self.config
        problem = separated_problem(scenario, task, table, cfg.cost, cfg.weights)
        enc_name = str(getattr(self.optimizer_cls, "encoding", "cartesian"))
        enc: Any = ENCODINGS[enc_name](problem, n_free)
        objective = Constrained(enc, cfg.constraints)
        N_pop = self.opt_config.pop_size
        lo, hi = enc.lower, enc.upper
        rand = rng.uniform(lo, hi, size=(N_pop, enc.dim))  # randpath(T_m)
        if cfg.seeding == "uniform" and restart == 0:
            init = rand
        elif restart == 0 or x_last is None:  # Eq. (15)
            if not isinstance(enc, CartesianEncoding):
                raise PlannerError(f"{cfg.optimizer}: RRT* seeding needs the Cartesian encoding")
            P_gene = np.clip(enc.encode(np.asarray(P_m)[None])[0], lo, hi)
            init = (1.0 - cfg.alpha) * P_gene[None] + cfg.alpha * rand
            init[0] = P_gene
        else:  # Eq. (16)
            init = np.array(x_last, copy=True)
            n_rand = int(np.floor(cfg.rho * N_pop))
            init[:n_rand] = rand[:n_rand]
        opt = self.optimizer_cls(objective, self.opt_config, seed=rng, init=init)
        clock = Stopwatch()  # kernel compilation left out
        X_last = init
        evaluate = self._swarm_evaluator(problem, enc, objective, opt)
        for _ in range(n_iter):
            X = opt.ask()
            f = evaluate(X)
            opt.tell(X, f)
            X_last = X
        assert opt.best_x is not None
        elapsed = clock.elapsed

        def result(path: FloatArray) -> PlanResult:
            return _candidate(
                problem,
                path,
                cfg.flight == "in-loop",
                algorithm=self.name,
                history=opt.history,
                evaluations=opt.evaluations,
                evaluations_history=opt.evaluations_history,
                wall_time=elapsed,
            )

        best = result(enc.decode(opt.best_x[None])[0])
        others: list[FloatArray] = []
        if cfg.flight == "in-loop" and cfg.flight_candidates > 1:
            paths = enc.decode(np.asarray(X_last))
            # the feasible rows by cost (what problem.evaluate's feasibility and cost give, bit
            # for bit: the checks cascade, and the cost only of the rows that pass them)
            b = problem.validator.batch(paths)
            ok = problem.validator.passing(b)
            feasible = np.zeros(len(paths), dtype=bool)
            feasible[ok] = True
            key = np.full(len(paths), np.inf)
            if ok.size:
                key[ok] = problem.cost(b.paths[ok])
            order = np.argsort(key, kind="stable")
            seen = {best.waypoints.round(6).tobytes()}
            for i in order[: 4 * cfg.flight_candidates]:
                k = paths[i].round(6).tobytes()
                if not feasible[i] or k in seen:
                    continue
                seen.add(k)
                others.append(paths[i])
                if len(others) >= cfg.flight_candidates - 1:
                    break
        waitable: list[FloatArray] = []
        if cfg.flight == "in-loop" and scenario.execution is not None and scenario.execution.timed:
            # under a drifting schedule most blocked UAVs are blocked by time alone: the
            # polylines of the last swarm that pass every check that does not read time, best
            # first by cost, are what a later take-off can clear (the swarm's best, whose
            # cost is infinite when no particle keeps S2, may cross an obstacle instead), and
            # the path the swarm was seeded from (RRT*'s, or the last restart's)
            paths = np.concatenate([enc.decode(np.asarray(X_last)), np.asarray(P_m)[None]])
            b = problem.validator.batch(paths)
            ok = problem.validator.passing(b, skip=TIME_CHECKS)
            if ok.size:
                seen = set()
                for i in ok[np.argsort(problem.cost(b.paths[ok]), kind="stable")]:
                    k = paths[i].round(6).tobytes()
                    # a track that crosses itself is flyable but no plan to hand out
                    if k not in seen and not track_crosses_itself(paths[i]):
                        seen.add(k)
                        waitable.append(paths[i])
                    if len(waitable) >= 3:
                        break
        return best, np.asarray(X_last), Candidates(best, others, result, waitable)

    def _swarm_evaluator(
        self, problem: PathProblem, enc: Any, objective: Constrained, opt: Any
    ) -> Callable[[FloatArray], FloatArray]:
        """What evaluates the swarm of a low-level run: ``objective.evaluate`` (the reference),
        or, under the "inf" rule with PSO, only the particles that can matter: PSO keeps a
        particle's position only if its cost is below its personal best, and a check can
        only make a cost infinite, so a particle whose cost without the checks is not below
        it cannot change the swarm and is not checked (the same swarm, bit for bit:
        ``PathProblem.evaluate_cv(below=...)``); in one kernel where
        :class:`~uavplan.planners.fleet.fleet_objective.FleetObjective` applies."""
        lazy = (self.config.constraints == "inf" and type(opt) is PSO
                and isinstance(enc, CartesianEncoding))  # fmt: skip
        if not lazy:
            return objective.evaluate
        fused = FleetObjective.of(problem, enc)
        if fused is not None:
            return lambda X: fused.evaluate(X, opt.pbest_f)

        def below(X: FloatArray) -> FloatArray:
            enc.evaluations += len(X)
            f, cv = problem.evaluate_cv(enc.decode(X), exact=False, below=opt.pbest_f)
            return infinite_if_violated(f, cv)

        return below

    def _waited(
        self,
        scenario: Scenario,
        later: Task,
        table: ReservationTable,
        cands: Sequence[PlanResult],
    ) -> list[PlanResult]:
        """The candidates' polylines re-timed to take off at ``later.start_time``, evaluated
        there (the same path, waiting on the ground at its start)."""
        cfg = self.config
        problem = separated_problem(scenario, later, table, cfg.cost, cfg.weights)
        return [
            _candidate(
                problem,
                c.waypoints,
                True,
                algorithm=self.name,
                history=c.history,
                evaluations=c.evaluations,
                evaluations_history=c.evaluations_history,
                wall_time=0.0,
            )
            for c in (cands[i] for i in range(min(3, len(cands))))
        ]

    def _retimed_flight(
        self,
        scenario: Scenario,
        table: ReservationTable,
        task: Task,
        cands: Candidates,
        tried: PlanResult | None = None,
    ) -> tuple[PlanResult, float] | None:
        """The first of a UAV's candidates whose flight passes taking off ``k`` delay steps
        later, ``k = 1 .. max_delays`` (fewest steps first), and the wait: each candidate's
        flights are made and checked against the world and the kinematic limits once (a
        take-off delay moves the schedule, not the curves), and only the checks that read time
        (separation, moving obstacles) are run again per delay. The candidates: ``tried``'s
        flight (the one just flown) when it fails only checks that read time; the polylines of
        the last swarm that pass every check that does not read time, and the path the swarm
        was seeded from, then the best three feasible ones (four at most). Under a
        drifting schedule the steps go on past ``max_delays`` to the first free slot, at worst
        one after every UAV in the table has landed (:meth:`ReservationTable.clear_time`)."""
        from uavplan.planners.core.flight import (
            candidate_flights,
            check_flights,
            first_clear,
            flight_validator,
        )

        cfg = self.config
        timing = "constant" if scenario.moving_obstacles else cfg.smooth_timing
        world = flight_validator(scenario, task, None)
        short = flight_validator(scenario, task, None, kinematics=False)
        per_cand: list[tuple[PlanResult, list[Flight]]] = []
        if (
            tried is not None
            and tried.flown is not None
            and tried.flown_violations
            and set(tried.flown_violations) <= TIME_CHECKS
        ):  # the flight just tried fails by time alone: it first
            own = Flight(np.asarray(tried.flown), np.asarray(tried.flown_times),
                         tried.flown_kind, "declared", ())  # fmt: skip
            per_cand.append((tried, [own]))
        firsts = [cands[i] for i in range(min(3, len(cands)))]
        pool: list[PlanResult] = []
        seen: set[bytes] = set()
        # the polylines clear of everything but time first (a later take-off is all they
        # need), then the feasible ones among the best three; four at most
        waitable = cands.waitable() if isinstance(cands, Candidates) else []
        for c in [*waitable, *(c for c in firsts if c.feasible or not waitable)]:
            key = np.asarray(c.waypoints).round(6).tobytes()
            if key not in seen and len(pool) < 4:
                seen.add(key)
                pool.append(c)
        for c in pool:
            flights = candidate_flights(scenario, c.waypoints, c.times, timing, cfg.smooth_step,
                                        shortcut=short)  # fmt: skip
            good = [f for f in check_flights(world, flights) if f.ok]
            good.sort(key=lambda f: f.length)
            per_cand.append((c, good))
        waits = [k * cfg.delay_step for k in range(1, cfg.max_delays + 1)]
        if table.timed and cfg.max_delays and len(table) and any(g for _, g in per_cand):
            # under a drifting schedule the tubes of the UAVs before it may fill every slot
            # within max_delays; a UAV clear of everything but them takes the first free
            # slot after that, at worst when all of them have landed (whatever they drift)
            clear = table.clear_time() + table.delta0 - task.start_time
            if clear > waits[-1]:
                more = np.arange(waits[-1] + cfg.delay_step, clear, cfg.delay_step)
                waits += [float(w) for w in more] + [float(math.floor(clear) + 1.0)]
        flat = [(c, f) for c, good in per_cand for f in good]
        # waits per table query (each query stops at the flight's first clear wait)
        found = first_clear(
            scenario,
            table,
            [f for _, f in flat],
            waits,
            lambda i: replace(task, start_time=task.start_time + waits[i]),
            64,
        )
        if found is None:
            return None
        i, k, later, flight = found
        c = flat[k][0]
        waited = self._waited(scenario, later, table, _One(c))[0]
        d = declare(waited, flight)
        cost = d.cost
        if not math.isfinite(cost) and "cost_unchecked" in waited.info:
            cost = float(waited.info["cost_unchecked"])
        return replace(d, cost=cost, info={**d.info, "rescue": "wait"}), waits[i]

    def _in_loop_flight(
        self,
        scenario: Scenario,
        table: ReservationTable,
        candidates: Candidates | list[PlanResult],
    ) -> PlanResult:
        """The first candidate whose flight passes every check, with that flight declared:
        the feasible polylines best first, then the best one if its polyline is not feasible
        (its flight, not the polyline, is what must keep S2: a curve can pass where a corner
        could not); then, if none passes, the same candidates flown at slower constant speeds
        (``speed_steps``). If none passes, the best feasible candidate (else the best) with its
        best, failing, flight. A declared flight that passes where its polyline fails costs F
        without the terms that mirror a check (``cost_unchecked``). ``info["rescue"]`` says
        what found the flight: ``first`` (the best candidate's), ``candidate`` (a later
        one's), ``slower``."""
        cfg = self.config
        task_of = {t.id: t for t in scenario.tasks}
        first: tuple[PlanResult, Flight] | None = None
        n = len(candidates)
        if isinstance(candidates, Candidates):  # not made into results before they are flown
            order = [i for i in range(n) if i > 0 or candidates[0].feasible]
        else:
            order = [i for i in range(n) if candidates[i].feasible]
        if not candidates[0].feasible:
            order.append(0)
        uav = scenario.uav
        floor = max(uav.min_speed, 0.5 * uav.speed)
        speeds: list[float | None] = [None]
        speeds += [uav.speed - k * (uav.speed - floor) / cfg.speed_steps
                   for k in range(1, cfg.speed_steps + 1)]  # fmt: skip
        for v in speeds:
            for i in order:
                r = candidates[i]
                f = fly(scenario, task_of[r.uav_id], r.waypoints, r.times, table,
                        cfg.smooth_timing, cfg.smooth_step, cruise=v)  # fmt: skip
                if f.ok:
                    how = "slower" if v is not None else (
                        "first" if i == 0 else "candidate")  # fmt: skip
                    d = declare(r, f)
                    cost = d.cost
                    if not math.isfinite(cost) and "cost_unchecked" in r.info:
                        cost = float(r.info["cost_unchecked"])
                    return replace(d, cost=cost, info={**d.info, "rescue": how})
                if first is None:
                    first = (r, f)
        assert first is not None
        return declare(*first)


class _One(Sequence[PlanResult]):
    """One candidate as a :class:`Candidates`-like sequence."""

    def __init__(self, r: PlanResult) -> None:
        self._r = r

    def __len__(self) -> int:
        return 1

    @overload
    def __getitem__(self, i: int) -> PlanResult: ...
    @overload
    def __getitem__(self, i: slice) -> list[PlanResult]: ...
    def __getitem__(self, i: int | slice) -> PlanResult | list[PlanResult]:
        return [self._r][i]


class Candidates(Sequence[PlanResult]):
    """A UAV's in-loop flight candidates: its best result, then the other distinct polylines
    of its last swarm that pass every check, best first; each made into a result (one
    evaluation) only when asked for: most UAVs fly their best."""

    def __init__(
        self,
        best: PlanResult,
        paths: list[FloatArray],
        make: Callable[[FloatArray], PlanResult],
        waitable: list[FloatArray] | None = None,
    ) -> None:
        self._items: list[PlanResult | None] = [best, *([None] * len(paths))]
        self._paths = [best.waypoints, *paths]
        self._make = make
        self._waitable = list(waitable or [])

    def waitable(self) -> list[PlanResult]:
        """The polylines that pass every check that does not read time, best first (made
        into results when asked for); empty unless the low level was asked for them."""
        return [self._make(p) for p in self._waitable]

    def __len__(self) -> int:
        return len(self._items)

    @overload
    def __getitem__(self, i: int) -> PlanResult: ...
    @overload
    def __getitem__(self, i: slice) -> list[PlanResult]: ...
    def __getitem__(self, i: int | slice) -> PlanResult | list[PlanResult]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        item = self._items[i]
        if item is None:
            item = self._items[i] = self._make(self._paths[i])
        return item


def _candidate(problem: PathProblem, path: FloatArray, in_loop: bool, **kw: Any) -> PlanResult:
    """A low-level candidate's result; in-loop, a polyline that fails a check also carries
    F without the terms that mirror a check (``cost_unchecked``): its cost if its flight, which
    is what is flown and checked, passes where the polyline does not (a curve can keep S2 or
    clear an obstacle where a corner could not)."""
    r = make_result(problem, path, **kw)
    if in_loop and not r.feasible:
        f = float(problem.evaluate_cv(r.waypoints[None])[0][0])
        r = replace(r, info={**r.info, "cost_unchecked": f})
    return r


def flight_report(results: tuple[PlanResult, ...]) -> dict[str, Any]:
    """How the in-loop flights came out: the UAVs whose flight fails a check, the variants
    flown, the flown length against the planned polylines'."""
    flown = sum(
        float(np.sum(np.linalg.norm(np.diff(r.flown_trajectory()[0], axis=0), axis=1)))
        for r in results
    )
    planned = sum(r.length for r in results)
    rescues = ("first", "candidate", "slower", "wait", "delay")
    return {
        "not_clear": [r.uav_id for r in results if not r.flown_ok],
        "rescue": {k: sum(r.info.get("rescue") == k for r in results) for k in rescues},
        "kinds": {k: sum(r.flown_kind == k for r in results) for k in ("smoothed", "polyline")},
        "flown_length": flown,
        "planned_length": planned,
        "checked": len(results),
    }


def declare_polylines(
    scenario: Scenario,
    results: tuple[PlanResult, ...],
    priority: list[str],
    cfg: PrioritizedConfig,
) -> tuple[PlanResult, ...]:
    """The paper's mode: every UAV is declared to fly its planned polyline, checked as flown
    (the world, the polylines of the UAVs before it and the kinematic limits: a UAV with a
    turn radius cannot fly a polyline's corners, and this says so)."""
    from uavplan.planners.core.flight import check_flights, flight_validator

    by_id = {r.uav_id: r for r in results}
    tasks = {t.id: t for t in scenario.tasks}
    table = ReservationTable.for_scenario(scenario, cfg.separation_margin, dt=cfg.dt)
    out: dict[str, PlanResult] = {}
    for uid in priority:
        r = by_id[uid]
        task = replace(tasks[uid], start_time=float(r.times[0]))
        polyline = Flight(r.waypoints, r.times, "polyline", "polyline", ())
        f = check_flights(flight_validator(scenario, task, table), [polyline])[0]
        table.add(uid, as_3d(r.waypoints), r.times)
        out[uid] = declare(r, f)
    return tuple(out[r.uav_id] for r in results)


def smooth_fleet(
    scenario: Scenario,
    results: tuple[PlanResult, ...],
    priority: list[str],
    cfg: PrioritizedConfig,
) -> tuple[tuple[PlanResult, ...], dict[str, Any]]:
    """The paper's mode (``flight="after"``): Dubins-smooth every UAV's path (Sect. 4.4) after
    planning, as information, and check the smoothed paths: against the world (the same
    continuous checks as planning), the UAVs smoothed before it in priority order (separation
    S2, continuous time) and the kinematic limits (:func:`uavplan.planners.core.flight.fly`'s
    variants and checks).

    Two variants are smoothed for each UAV: the paper's curves through every waypoint
    (headings bisecting the turns) and the corner-cutting curves between segment midpoints
    (:func:`midpoint_poses`); with "planned" timing both also on the polyline shortcut by
    line of sight (:func:`~uavplan.problems.validity.greedy_shortcut`: fewer, gentler turns
    where the world and the UAVs before it allow). The one with the fewest kinds of violation
    is kept, the shorter one on a tie (through-the-waypoint curves loop around sharp turns);
    the report counts the variants kept.

    ``cfg.smooth_timing``: "planned" (default) keeps to the schedule the separation was planned
    for: the UAV reaches each pose at its planned time, or, where the curve is longer than
    the planned segment, as soon as it can at its speed (never faster; the largest lateness,
    s, is reported as ``max_late``), flying each piece at a constant speed; "constant" flies
    the smoothed path at the UAV's speed from its take-off time (the paper's model: every
    curve longer than its segment delays everything after it). A scenario
    with moving obstacles is smoothed with "constant" timing, the timing its world check uses.

    A path no variant keeps clear is reported (``smoothed_ok = False`` and its violations)
    and its planned polyline stays in the table that the UAVs after it are checked against.
    The plan still declares the polylines (:func:`declare_polylines`)."""
    from uavplan.planners.core.flight import (
        best_flight,
        candidate_flights,
        check_flights,
        flight_validator,
    )

    by_id = {r.uav_id: r for r in results}
    table = ReservationTable.for_scenario(scenario, dt=cfg.dt)
    out: dict[str, PlanResult] = {}
    not_clear: list[str] = []
    failed: list[str] = []
    variants: dict[str, int] = {}
    max_late = 0.0
    timing = "constant" if scenario.moving_obstacles else cfg.smooth_timing
    for uid in priority:
        r = by_id[uid]
        task = next(t for t in scenario.tasks if t.id == uid)
        task = replace(task, start_time=float(r.times[0]))  # a delayed take-off keeps its delay
        short = flight_validator(scenario, task, table, kinematics=False)
        flights = candidate_flights(scenario, r.waypoints, r.times, timing, cfg.smooth_step, short)
        flights = [f for f in flights if f.kind == "smoothed"]
        if not flights:
            failed.append(uid)
            out[uid] = r
            continue
        f = best_flight(check_flights(flight_validator(scenario, task, table), flights))
        assert f is not None
        max_late = max(max_late, f.late)
        variants[f.variant] = variants.get(f.variant, 0) + 1
        if f.ok:
            table.add(uid, as_3d(f.points), f.times)
        else:  # the planned polyline stays in the table: later UAVs are checked against it
            not_clear.append(uid)
            table.add(uid, as_3d(r.waypoints), r.times)
        out[uid] = replace(
            r,
            smoothed=f.points,
            smoothed_times=f.times,
            smoothed_ok=f.ok,
            smoothed_violations=f.violations,
        )
    report = {
        "not_clear": not_clear,
        "failed": failed,
        "variants": variants,
        "checked": len(results),
        "timing": timing,
        "max_late": max_late,
    }
    return tuple(out[r.uav_id] for r in results), report
