"""The planner a user gets without ``-a``: the one our own results show best for the kind of
scenario (``docs/results.md``).

* **2-D scene** (one UAV): ``spso``. On the RGG-PSO+ paper's 1,000 scenes (``rggpso-rq1``, 10
  runs each) its paths are the shortest of the six methods: 1.009 times the reference shortest
  path on average, against RGG-PSO+'s 1.102, and shorter than RGG-PSO+'s in 980 of 1,000
  scenes; on ``simple2d`` it returns 134.6 m (RGG-PSO+ 142.9 m; the straight line, blocked,
  127 m).
* **3-D world, one UAV**: ``spso``. On the SPSO benchmark it reaches the SPSO paper's cost
  (median 4,780 at the authors' budget, ``spso-scenario``); in the HR-MAGA comparison
  (``hrmaga-compare``, same budget, Deb's feasibility-first rule) it is feasible in 159 of 160
  runs (the polylines, as that plan counts) and has the lowest median
  loss on three maps of four (HR-MAGA and P-MAGA are better on ``hrmaga-spso``).
* **3-D world with danger or uncertain areas (HR-MAGA's world), one UAV**: ``hr-maga``. Its
  loss sees the danger areas and its levels see the uncertain areas, and it repairs locally
  when one is revealed (``hrmaga-replan``: flown feasible and verified in 40, 39 and 39 of 40
  runs on the spso, topobathy and virtual maps, 26 of 40 on jacksboro, where the first plan was
  infeasible as often). SPSO at the CLI's defaults (its own constraint rule) was feasible in 0
  of 10 seeds on ``hrmaga-jacksboro``, ``-popup``, ``-topobathy`` and ``-virtual`` and 7 of 10
  on ``hrmaga-spso`` (``benchmarks/default_paths.py``, docs/results.md).
  Its result varies from seed to seed (``benchmarks/default_paths.py``, seeds 0-9 on the
  five HR-MAGA maps: the cost under the map's own loss 1.0-2.1 times the best any run
  reached), so the CLI makes three runs (:func:`run_seeds`) and keeps the best
  (:func:`best_plan`); on those runs the best of each three consecutive seeds came within
  1.0-1.33 times that best, against 1.0-2.1 for single runs. It also runs SPSO once (about a
  second): on ``jacksboro`` (one danger and one uncertain area) SPSO's three runs were all
  feasible and within 1.023 of the best cost any planner reached, HR-MAGA's ten 1.03-1.28.
* **When the default's plan does not fly** (the CLI without ``-a``): :func:`fallback_planners`
  are tried in order and the first plan that flies is kept (``hr-maga`` on ``jacksboro``, seed
  2, ends in a cylinder; RRT* with a step scaled to the map flies). The console says so.
* **Several UAVs**: ``ppswarm``. Every UAV's flown trajectory is checked while planning and
  reserved for the others; 40 of 40 UAVs verified as flown on the PPSwarm scenarios and among
  ten moving obstacles (``ppswarm1-traffic``). A UAV it leaves failing or looping (``dense``,
  narrow passages: 1-2 UAVs of 40 in 6 of 10 seeds) is repaired after planning
  (:mod:`~uavplan.planners.fleet_polish`).
* **Several UAVs that fly at one constant speed** (``min_speed`` equal to the cruise speed:
  fixed-wing aircraft that can neither wait nor slow down, the RSCDWOA layouts):
  ``rscdwoa-apf``. It steps each UAV in time at its speed within its turn and climb limits,
  with the UAVs before it as moving obstacles. On ``rscdwoa-static`` every fused planner led
  400 of 400 UAV flights through, verified (100 runs each), and RSCDWOA-APF had the lowest
  median final cost (4.45e8; WOA-APF 4.49e8, PSO-APF 4.65e8, GA-APF 5.05e8); on
  ``rscdwoa-dynamic`` 80 of 80 (20 runs). PPSwarm's rescues (waiting, slower speeds) are not
  open to such UAVs: on ``rscdwoa-dynamic`` it led 19 of 20 flights through in 220-745 s per
  run, and ``uavplan plan rscdwoa-static -a ppswarm`` took 38 minutes (a loaded machine) for
  four UAVs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from uavplan.planners.fleet_plan import FleetPlan
    from uavplan.world.scenario import Scenario


@dataclass(frozen=True)
class Default:
    """The default of a scenario kind: the planner, why in one line, how many runs of it
    (independent root seeds, :func:`run_seeds`) the CLI makes, and other planners it also runs
    once (the root seed; not when the user sets options for the default), keeping the best
    plan of them all (:func:`best_plan`)."""

    planner: str
    why: str
    runs: int = 1
    also: tuple[str, ...] = ()


#: scenario kind -> its default
DEFAULTS = {
    "2-D scene": Default("spso", "the shortest paths on the RGG-PSO+ paper's 1,000 scenes"),
    "3-D single UAV": Default("spso", "the SPSO paper's cost on its benchmark"),
    "3-D single UAV with danger or uncertain areas": Default(
        "hr-maga",
        "its loss sees danger areas, its levels uncertain ones, and it repairs locally",
        runs=3,
        also=("spso",),
    ),
    "fleet": Default(
        "ppswarm", "every UAV's flight checked while planning: 40/40 verified as flown"
    ),
    "fleet of constant-speed UAVs": Default(
        "rscdwoa-apf",
        "it flies each UAV at its one speed in time around the others: 400/400 verified",
    ),
}


def run_seeds(seed: int, runs: int) -> list[int]:
    """The root seeds of ``runs`` independent runs: ``seed`` itself first (so one run is
    ``-a NAME --seed SEED``), then seeds spawned from it (``SeedSequence(seed).spawn``), each
    printed so that any run can be made alone."""
    spawned = np.random.SeedSequence(seed).spawn(max(runs - 1, 0))
    return [int(seed)] + [int(ss.generate_state(1)[0]) for ss in spawned]


def best_plan(plans: Sequence[FleetPlan]) -> FleetPlan:
    """The best of several plans of one scenario: one that flies (every UAV's flown trajectory
    passes every check) before one that does not, then the lowest total cost under the
    scenario's own objective, then the first."""

    def key(k: int) -> tuple[bool, float, int]:
        p = plans[k]
        cost = float(sum(r.cost for r in p.results))
        return (not p.feasible, cost if np.isfinite(cost) else np.inf, k)

    return plans[min(range(len(plans)), key=key)]


#: RRT*'s steering step as a share of the map's horizontal diagonal when it is a fallback
#: (its default, 50 m, is the PPSwarm paper's for a 1 km map; a 30 km map needs longer steps).
FALLBACK_STEP_SHARE = 0.02


def fallback_rrt_options(scenario: Scenario) -> dict[str, object]:
    """RRT* as a fallback (here and in :mod:`~uavplan.planners.fleet_polish`): every edge
    checked as flown; its step scaled to the map (at least its default 50 m); informed, anytime
    within its iteration budget, its shortest tree paths tightened."""
    lo, hi = scenario.bounds.lo, scenario.bounds.hi
    step = max(50.0, FALLBACK_STEP_SHARE * float(np.hypot(hi[0] - lo[0], hi[1] - lo[1])))
    return {
        "step": step,
        "goal_radius": step,
        "near_radius": 2 * step,
        "informed": True,
        "stop_at_goal": False,
        "tighten": True,
    }


def fallback_planners(scenario: Scenario) -> list[tuple[str, dict[str, object]]]:
    """The planners (name, options) tried in order when the default's plan does not fly (the
    CLI without ``-a``): RRT* (:func:`fallback_rrt_options`), then RGG-PSO+ (a graph path, then
    optimized). None for fleets (minutes per try): a fleet's failing UAVs are re-planned one by
    one instead (:mod:`~uavplan.planners.fleet_polish`)."""
    if len(scenario.tasks) > 1:
        return []
    return [("rrt-star", fallback_rrt_options(scenario)), ("rgg-pso+", {})]


def scenario_kind(scenario: Scenario) -> str:
    """``2-D scene``, ``3-D single UAV`` (``... with danger or uncertain areas``), ``fleet``
    (more than one task) or ``fleet of constant-speed UAVs`` (``min_speed`` equal to the
    speed, 3-D)."""
    if len(scenario.tasks) > 1:
        uav = scenario.uav
        if scenario.dim == 3 and uav.min_speed > 0 and uav.min_speed >= uav.v_max:
            return "fleet of constant-speed UAVs"
        return "fleet"
    if scenario.dim == 2:
        return "2-D scene"
    if scenario.danger_areas or scenario.uncertain_areas:
        return "3-D single UAV with danger or uncertain areas"
    return "3-D single UAV"


def default_planner(scenario: Scenario) -> tuple[str, str, str]:
    """``(planner name, scenario kind, why)`` for a scenario planned without ``-a``."""
    kind = scenario_kind(scenario)
    d = DEFAULTS[kind]
    return d.planner, kind, d.why
