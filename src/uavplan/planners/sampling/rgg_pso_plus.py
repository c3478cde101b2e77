"""RGG-PSO+ (Liu et al. 2024, J. Intell. Robot. Syst.): RGG-PSO with divide and conquer (Algs.
3 and 4) over the variable-length particles of :mod:`uavplan.problems.variable_length`.

With ``T`` iterations:

1. RGG-PSO on the whole task for ``T_w = round(whole_fraction T)`` iterations (at least 1;
   ``whole_fraction = 0.5``: 100 of 200, the paper's "100 iterations per sub-path within 200").
2. Divide (Alg. 3): split the current best path (``L`` nodes, start and goal included) at node
   ``idx = floor(L / 2)`` (the paper's ``ceil(len / 2)`` with ``len`` counting segments; with
   ``len`` = nodes and 0-based indices, L = 3 would give an empty second half), into
   ``path[:idx + 1]`` and ``path[idx:]``; each half becomes its own task (start and goal = its
   end nodes; the second leaves at the first's arrival time) and is optimized by RGG-PSO
   seeded with the half itself (Alg. 3 line 3: "PSO(path_1)") plus RGG candidates of the
   sub-task. Both halves run in lockstep for the remaining ``T - T_w`` iterations (one overall
   iteration = one swarm step of every active sub-swarm), so every sub-path gets ``T - T_w``
   iterations and the run has ``T`` in all. With ``depth > 1`` a half divides again the same way
   within its own budget.
3. Conquer (Alg. 4, :func:`conquer`): over every node pair ``(i, j)`` build
   ``path_1[:i + 1] + path_2[j:]`` (the paper's ``path_1[0:node_1]`` read inclusively, so the
   tested junction is ``node_1 -> node_2``); every merge is evaluated in full (cost and
   feasibility; equivalent to the paper's junction test when both halves are feasible, and safe
   when they are not) and the lowest-cost feasible one is kept. The plain concatenation is the
   merge ``(len(path_1) - 1, 0)``. If no merge is feasible, the pre-divide best is kept if
   feasible. The result is the cheaper of the best merge and the pre-divide best (feasible ones
   first), so RGG-PSO+ never returns a path worse than its own pre-divide best.

**Bookkeeping.** ``history`` is the best whole-task cost so far per overall iteration: the
swarm's best in the whole phase, then the whole-task cost of the concatenation of the halves'
current bests (each half's best feasible path if it has one), evaluated on the whole task's
problem when it changed; the last iteration includes the conquer result. ``evaluations`` counts
every cost evaluation: swarm evaluations of every (sub-)swarm, those monitoring evaluations and
every Alg. 4 merge; the final re-evaluation of the returned path is not counted (as in every
planner). RGG edge checks are feasibility tests, reported in ``PlanResult.info["edge_checks"]``.
Budgets: ``T`` is the budget's iterations (200 if none); an evaluation-only budget plans the
``T`` whose expected swarm evaluations fit it; evaluation, time and callback limits stop the run
early, and the halves are then conquered as they are. All randomness comes from
``numpy.random.SeedSequence(seed)``, spawned per (sub-)swarm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import Budget
from uavplan.planners.core.options import option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.planners.sampling.rgg_pso import RGGPSOConfig, RGGPSOPlanner, Stats, conquer
from uavplan.problems.variable_length import evaluate_many, evaluate_paths, particle_to_path
from uavplan.world.reservations import ReservationTable
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]


class _Solver:
    """One (sub-)task of RGG-PSO+: whole-path swarm, then (maybe) two halves in lockstep."""

    def __init__(
        self,
        planner: RGGPSOPlusPlanner,
        scenario: Scenario,
        task: Task,
        iterations: int,
        depth: int,
        ss: np.random.SeedSequence,
        stats: Stats,
        seed_path: FloatArray | None = None,
        reservations: ReservationTable | None = None,
    ) -> None:
        self.planner = planner
        self.scenario = scenario
        self.reservations = reservations
        self.problem = planner.problem(scenario, task, reservations)
        swarm_ss, self._kids_ss = ss.spawn(2)
        self.enc, self.opt = planner.swarm(self.problem, swarm_ss, stats, seed_path)
        self.stats = stats
        self.T = int(iterations)
        self.depth = int(depth)
        whole = round(planner.config.whole_fraction * self.T)
        self.T_w = self.T if self.depth <= 0 else min(self.T, max(1, whole))
        self.t = 0
        self.children: list[_Solver] | None = None
        #: (path, cost, feasible) on this solver's problem
        self.pre: tuple[FloatArray, float, bool] | None = None
        self.final: tuple[FloatArray, float, bool] | None = None
        self.split: int | None = None
        self.merge = ""

    def step(self) -> None:
        """One iteration: every active (sub-)swarm asks, their batches are evaluated together
        where their problems allow (:func:`~uavplan.problems.variable_length.evaluate_many`:
        the halves share one world and cost), each is told its costs, then the clocks advance
        (and a solver whose iterations are spent finishes)."""
        asked = self._ask()
        costs = evaluate_many([s.enc for s, _ in asked], [X for _, X in asked])
        for (s, X), f in zip(asked, costs, strict=True):
            s.opt.tell(X, f)
        self._advance()

    def _ask(self) -> list[tuple[_Solver, FloatArray]]:
        """Divide where it is time to (Alg. 3), then each active swarm's next batch."""
        if self.children is None and self.t >= self.T_w and not self._divide():
            self.T_w = self.T
        if self.children is None:
            return [(self, self.opt.ask())]
        return [b for c in self.children for b in c._ask()]

    def _advance(self) -> None:
        for c in self.children or ():
            c._advance()
        self.t += 1
        if self.t >= self.T:
            self.finish()

    def _divide(self) -> bool:
        """Alg. 3: split the current best path at its middle node into two sub-tasks."""
        if self.depth <= 0:
            return False
        path, cost, feasible = self.enc.best()
        L = len(path)
        if L < 3:
            return False
        idx = L // 2
        p1, p2 = path[: idx + 1], path[idx:]
        if np.array_equal(p1[0], p1[-1]) or np.array_equal(p2[0], p2[-1]):
            return False
        task = self.problem.task
        t_split = task.start_time + float(
            np.sum(np.linalg.norm(np.diff(p1, axis=0), axis=1)) / self.scenario.uav.speed
        )
        t1 = Task(f"{task.id}/1", tuple(p1[0]), tuple(p1[-1]), task.start_time)
        t2 = Task(f"{task.id}/2", tuple(p2[0]), tuple(p2[-1]), t_split)
        s1, s2 = self._kids_ss.spawn(2)
        rest = self.T - self.t
        d = self.depth - 1
        self.children = [
            _Solver(
                self.planner, self.scenario, t1, rest, d, s1, self.stats, p1, self.reservations
            ),
            _Solver(
                self.planner, self.scenario, t2, rest, d, s2, self.stats, p2, self.reservations
            ),
        ]
        self.pre = (path, cost, feasible)
        self.split = idx
        return True

    def current(self) -> FloatArray:
        """The current best path of this (sub-)task."""
        if self.final is not None:
            return self.final[0]
        if self.children is None:
            return self.enc.best()[0]
        a, b = (c.current() for c in self.children)
        return particle_to_path(np.concatenate([a, b[1:]]))

    def finish(self) -> None:
        """Stop: a whole-path solver keeps its best; a divided one conquers (Alg. 4)."""
        if self.final is not None:
            return
        if self.children is None:
            self.final = self.enc.best()
            return
        for c in self.children:
            c.finish()
        a, b = (c.current() for c in self.children)
        res = conquer(self.problem, a, b)
        self.stats.evaluations += res.evaluations
        assert self.pre is not None
        pre_path, pre_cost, pre_feasible = self.pre
        options: list[tuple[float, FloatArray, str]] = []
        if res.best is not None:
            m = res.best
            kind = "concatenation" if (m.i, m.j) == (res.concatenation.i, 0) else "shortcut"
            options.append((m.cost, m.path, kind))
        if pre_feasible:
            options.append((pre_cost, pre_path, "pre-divide"))
        if options:
            cost, path, kind = min(options, key=lambda o: o[0])
            self.final = (path, cost, True)
        else:  # nothing feasible at all: the cheaper of the concatenation and the pre-divide best
            cat = res.concatenation
            if cat.cost <= pre_cost:
                self.final, kind = (cat.path, cat.cost, False), "concatenation (infeasible)"
            else:
                self.final, kind = (pre_path, pre_cost, False), "pre-divide (infeasible)"
        self.merge = kind


@dataclass(frozen=True)
class RGGPSOPlusConfig(RGGPSOConfig):
    """RGG-PSO+'s options: RGG-PSO's plus the divide."""

    depth: int = option(1, "recursion depth of the divide (1: the paper's one split)", low=0)
    whole_fraction: float = option(
        0.5, "share of the iterations on the whole path before dividing (0.5: 100 of 200)",
        low=0, high=1, low_open=True, high_open=True,
    )  # fmt: skip


@register_planner
class RGGPSOPlusPlanner(RGGPSOPlanner):
    """RGG-PSO+: RGG-PSO with divide and conquer (Algs. 3, 4; see the module docstring)."""

    name = "rgg-pso+"
    Config = RGGPSOPlusConfig
    config: RGGPSOPlusConfig

    def iteration_limit(self, b: Budget) -> int | None:
        """The overall iteration count T the divide is planned on: the budget's iterations; for
        an evaluation-only budget the T whose planned swarm evaluations fit it (the swarm count
        doubles at each divide level: ``pop (f + 2 f (1 - f) + ... + 2^depth (1 - f)^depth)``
        per iteration on average, ``f = whole_fraction``). Any limit still stops the run early
        (the halves are then conquered as they are)."""
        if b.max_iterations is not None:
            return b.max_iterations
        if b.max_evaluations is None:
            return self.specs.default_iterations
        f, d = self.config.whole_fraction, self.config.depth
        swarms = sum(2**level * f * (1 - f) ** level for level in range(d)) + (2 * (1 - f)) ** d
        assert self.optimizer_config is not None
        return max(1, int(b.max_evaluations / (self.optimizer_config.pop_size * swarms)))

    def _plan(self, run: Run) -> Outcome:
        T = run.max_iterations
        assert T is not None
        stats = Stats()
        root = _Solver(
            self, run.scenario, run.task, T, self.config.depth,
            np.random.SeedSequence(run.seed), stats, reservations=run.reservations,
        )  # fmt: skip
        tr = run.tracker
        seen: tuple[FloatArray, float, bool] | None = None

        def record() -> bool:
            nonlocal seen
            if root.children is None:
                h, fh = root.opt.best_f, root.enc.feasible_history[-1]
            elif root.final is not None:
                _, h, feas = root.final
                fh = h if feas else np.inf
            else:
                path = root.current()
                if seen is None or not np.array_equal(seen[0], path):
                    c, f = evaluate_paths(root.problem, [path])
                    stats.evaluations += 1
                    seen = (path, float(c[0]), bool(f[0]))
                h, fh = seen[1], seen[1] if seen[2] else np.inf
            tr.evaluations = stats.evaluations
            return tr.end_iteration(best=h, feasible_best=fh)

        while root.final is None:
            root.step()
            stop = record()
            if stop and root.final is None:
                root.finish()  # conquer what the halves have so far
                assert root.final is not None
                _, h, feas = root.final
                tr.evaluations = stats.evaluations
                tr.amend(h, h if feas else np.inf)
        assert root.final is not None
        info = stats.info()
        info.update(
            pre_divide_cost=root.pre[1] if root.pre is not None else None,
            pre_divide_feasible=root.pre[2] if root.pre is not None else None,
            split_index=root.split,
            divided_at=root.T_w if root.pre is not None else None,
            merge=root.merge,
        )
        return Outcome(root.final[0], info=info)
