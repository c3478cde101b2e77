"""Optimizer-fused APF (``rscdwoa-apf``, ``woa-apf``, ``pso-apf``, ``ga-apf``): a population
optimizer chooses the sub-goals the artificial potential field flies through.

The RSCDWOA paper (Zhang et al., Sect. 5.1 and Fig. 6) fuses its optimizer with the APF so that
the UAV escapes the field's local minima (Sect. 5.3, Fig. 12) and its trajectory is smoothed
(Sect. 5.4, Figs. 14 and 16), and leaves open what the optimizer decides. Ours:

* **decision variables**: ``n_subgoals`` sub-goals (x, y, and z in 3-D) inside the scenario's
  box, or, with ``subgoal_corridor``, within that fraction of the horizontal start-goal
  distance of the straight line (each sub-goal then a fraction along the line, an offset
  across it and a height; ours, a control: over the whole box of the RSCDWOA layouts most
  random sub-goal pairs already lead around a trap a few kilometres wide, so leading out cannot
  tell optimizers apart; within about one obstacle's radius of influence of the line the trap
  is in the way);
  the UAV flies the field of :mod:`uavplan.planners.potential.apf` (same gains, kinematics and
  obstacles, other UAVs' flights included) with its attraction towards the first sub-goal,
  then, once within ``subgoal_radius`` of it, the next, and last the goal;
* **fitness**: the flight's length plus ``curvature_weight`` times the start-goal distance
  times the mean squared curvature of the horizontal track relative to the largest allowed one
  (``1 / turn_radius``; without a turn radius ``1 / (v dt)``), so that 1 means "always at the
  tightest turn"; with Deb's feasibility-first rule on the constraint violation: the motion
  validator's graded violation of the flight (obstacles, band, moving obstacles, other UAVs),
  plus ``1 + remaining distance / start-goal distance`` for a flight that stalls or runs out of
  steps. A feasible flight always beats an infeasible one;
* every candidate of a population is one flight of the field (a Numba loop); the planner's
  iterations are the optimizer's; the best flight so far is the path.

The classical APF is one candidate of the search space (sub-goals on the straight line), so the
fused planner can only match or improve on it in the fitness.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.optimizers.base import FunctionProblem, fit_schedule
from uavplan.optimizers.base import get as get_optimizer
from uavplan.optimizers.constraints import feasibility_first
from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerError, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.planners.potential.apf import APFConfig, FieldParams, field_params, fly_field
from uavplan.problems.validity import turn_estimates

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FusedAPFConfig(APFConfig):
    """The APF's options plus the optimizer's."""

    optimizer: str = option("rscdwoa", "the optimizer choosing the sub-goals")
    optimizer_options: dict[str, Any] = option(
        default_factory=dict, doc="the optimizer's options (w, F, CR, ...), given plainly"
    )
    pop_size: int = option(30, "candidates per iteration (the paper gives none)", low=2)
    n_subgoals: int = option(2, "sub-goals before the goal", low=1, high=10)
    subgoal_radius: float | None = option(
        None, "a sub-goal is passed within this distance, m (None: the goal radius)", low=0
    )
    curvature_weight: float = option(1.0, "weight of the mean squared curvature", low=0.0)
    subgoal_corridor: float | None = option(
        None, "sub-goals within this fraction of the horizontal start-goal distance of the "
        "straight line (None: anywhere in the scenario's box)", low=0.0,
    )  # fmt: skip
    max_steps: int | None = option(
        None, "steps per flight at most (None: four times the straight line's)", low=1
    )


def curvature(points: FloatArray) -> FloatArray:
    """Curvature of the horizontal track at every interior point, 1/m: the flight check's
    estimate (:func:`~uavplan.problems.validity.turn_estimates`)."""
    return turn_estimates(np.asarray(points, dtype=np.float64)[:, :2])[1]


class FusedAPFPlanner(Planner):
    """APF whose sub-goals a population optimizer chooses (see the module docstring)."""

    name = "apf-fused"
    Config = FusedAPFConfig
    config: FusedAPFConfig
    # 40 iterations: the paper's Fig. 16 converges within 40 rounds
    specs = PlannerSpecs(default_iterations=40, supports_reservations=True, steps_in_time=True)

    def _plan(self, run: Run) -> Outcome:
        cfg = self.config
        sc, task, tr = run.scenario, run.task, run.tracker
        start = np.asarray(task.start, dtype=np.float64)
        goal = np.asarray(task.goal, dtype=np.float64)
        L0 = float(np.linalg.norm(goal - start)) or 1.0
        prm: FieldParams = field_params(cfg, sc, L0)
        steps = cfg.max_steps or int(4 * L0 / (prm.v * prm.dt)) + 100
        k_max = 1.0 / sc.uav.turn_radius if sc.uav.turn_radius > 0 else 1.0 / (prm.v * prm.dt)
        res = run.reservations
        others = res.trajectories() if res is not None else []
        sep = res.radius if res is not None else 0.0
        lo, hi = sc.bounds.lo.astype(float), sc.bounds.hi.astype(float)
        # the sub-goals' variables: points of the box, or per sub-goal (fraction along the line,
        # offset across it in units of the corridor's half-width, height) in a corridor
        along = (goal - start)[:2]
        L_h = float(np.linalg.norm(along)) or 1.0
        across = np.array([-along[1], along[0]]) / L_h
        w = float(cfg.subgoal_corridor or 0.0) * L_h

        def subgoals(x: FloatArray) -> FloatArray:
            V = x.reshape(K, dim)
            if cfg.subgoal_corridor is None:
                return V
            P = np.empty_like(V)
            P[:, :2] = start[:2] + V[:, :1] * along + V[:, 1:2] * w * across
            P[:, :2] = np.clip(P[:, :2], sc.bounds.lo[:2], sc.bounds.hi[:2])
            if dim > 2:
                P[:, 2:] = V[:, 2:]
            return P

        K, dim = int(cfg.n_subgoals), sc.dim
        best: dict[str, Any] = {"f": np.inf, "path": None, "status": None}

        def one(x: FloatArray) -> tuple[float, float, FloatArray, str]:
            traj = fly_field(
                sc, start, goal, prm, steps, float(task.start_time), others=others,
                separation=sep, via=subgoals(x), via_radius=cfg.subgoal_radius,
            )  # fmt: skip
            P = traj.points
            val = run.problem.validator
            b = val.batch(np.ascontiguousarray(P[None]))
            passes = val.passing(b).size > 0  # the fused checks, cheap ones first
            cv = np.zeros(1) if passes else val.graded_violation(b, val.violations(b))
            kappa = curvature(P)
            f = float(np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1)))
            if kappa.size:
                f += cfg.curvature_weight * L0 * float(np.mean((kappa / k_max) ** 2))
            v = float(cv[0])
            if traj.status != "arrived":
                v += 1.0 + float(np.linalg.norm(P[-1] - goal)) / L0
            return f, v, P, traj.status

        arrived: list[float] = []  # per evaluated batch: the share of flights that arrive

        def batch(X: FloatArray) -> FloatArray:
            fs, vs = np.empty(len(X)), np.empty(len(X))
            n_in = 0
            for i, x in enumerate(X):
                f, v, P, status = one(x)
                fs[i], vs[i] = f, v
                n_in += status == "arrived"
                num = float(feasibility_first(np.array([f]), np.array([v]))[0])
                if num < best["f"]:
                    best.update(f=num, path=P, status=status)
                    if v == 0:
                        ev = run.problem.evaluate(P[None])
                        tr.offer(P, float(ev.cost[0]), bool(ev.feasible[0]))
            tr.evaluations += len(X)
            arrived.append(n_in / max(len(X), 1))
            return np.asarray(feasibility_first(fs, vs))

        v_lo, v_hi = lo[:dim].copy(), hi[:dim].copy()
        if cfg.subgoal_corridor is not None:
            v_lo[:2], v_hi[:2] = (0.0, -1.0), (1.0, 1.0)
        problem = FunctionProblem(
            batch, np.tile(v_lo, K), np.tile(v_hi, K), block=dim, name="apf-subgoals"
        )
        try:
            cls = get_optimizer(cfg.optimizer)
            # the optimizer's schedule (WOA's and RSCDWOA's a, PSO's inertia) fitted to the
            # run's iterations, as the optimizer planner does: left at the optimizer's own
            # t_max, a 40-iteration run ended with WOA's a near 1.2 instead of 0
            assert self.optimizer_config is not None  # a fused planner has an optimizer
            config = fit_schedule(self.optimizer_config, run.budget, cfg.optimizer_options)
            opt = cls(problem, config, seed=np.random.SeedSequence(run.seed),
                      pop_size=cfg.pop_size)  # fmt: skip
        except Exception as exc:  # an optimizer that does not take this size, an unknown name
            raise PlannerError(f"{self.name}: optimizer {cfg.optimizer!r}: {exc}") from None
        # the classical APF's flight first: sub-goals evenly on the straight line
        line = np.concatenate([start + (goal - start) * (k + 1) / (K + 1) for k in range(K)])
        if cfg.subgoal_corridor is not None:
            line = np.concatenate([np.r_[(k + 1) / (K + 1), 0.0, line[k * dim + 2 : k * dim + dim]]
                                   for k in range(K)])  # fmt: skip
        batch(line[None])
        fitness: list[float] = []
        while True:
            X = opt.ask()
            opt.tell(X, batch(X))
            fitness.append(float(best["f"]))
            if tr.end_iteration():
                break
        path = best["path"]
        reasons: tuple[str, ...] = ()
        if best["status"] != "arrived":
            reasons = ("local_minimum",) if best["status"] == "stalled" else ("no_path",)
        kappa = curvature(path) if path is not None else np.zeros(0)
        return Outcome(
            path=path,
            reasons=reasons,
            info={
                "status": best["status"],
                "fitness": best["f"],
                "max_curvature_per_km": float(kappa.max() * 1000) if kappa.size else 0.0,
                "optimizer": cfg.optimizer,
                "fitness_history": fitness,  # best feasibility-first number per iteration
                # per iteration the share of the candidates whose flight arrives (the first
                # entry is the classical APF's flight alone)
                "arrived_history": arrived,
                "subgoal_corridor_m": w,  # the corridor's half-width (0: the whole box)
            },
        )


for _opt in ("rscdwoa", "woa", "pso", "ga"):
    register_planner(
        FusedAPFPlanner,
        name=f"{_opt}-apf",
        summary=f"APF whose sub-goals {_opt.upper()} chooses (RSCDWOA Sect. 5.1, Fig. 6)",
        optimizer=_opt,
    )
