"""PPSwarm (Meng, Chen & Qu 2024, *Drones* 8, 192) and the prioritized baselines of its Table 2:
two named configurations of one engine,
:class:`uavplan.planners.fleet.prioritized.PrioritizedPlanner`
(see it for every choice where the paper is silent).

* ``ppswarm``: RRT* initial paths (Alg. 1), prioritized planning with LH priorities and
  ``N_restart = 5`` restarts that shuffle them (Alg. 3), PSO per UAV (Alg. 4, Eq. 14) over 300
  particles for ``N_iter = 20`` moves, seeded by Eq. (15) and, after a restart, Eq. (16) with
  ``rho = 20 %``; PSO ``w = 1``, ``c1 = c2 = 1.5`` (Table 1); Dubins smoothing (Sect. 4.4).
* ``prioritized``: the baselines' frame (Sect. 5.2.1: "all five comparison algorithms adopt the LH
  allocation scheme of prioritized planning"): one pass, LH priorities, uniform random first
  populations, ``N_iter = 100``, ``N_pop = 300`` (Table 2), and any registered optimizer
  (``optimizer="de"`` ...) with its Table 2 parameters passed as options (another optimizer
  than PSO drops PSO's Table 2 parameters).
"""

from __future__ import annotations

from typing import Any

from uavplan.planners.core.registry import register_planner
from uavplan.planners.fleet.prioritized import PrioritizedPlanner

#: PPSwarm Table 1.
PPSWARM: dict[str, Any] = {
    "optimizer": "pso",
    "optimizer_options": {"w": 1.0, "c1": 1.5, "c2": 1.5},
    "pop_size": 300,
    "n_iter": 20,
    "n_restart": 5,
    "rho": 0.2,
    "order": "lh",
    "seeding": "rrt-star",
}

#: PPSwarm Table 2's frame for the baselines (PSO's own w, c1, c2 there: 0.8, 1.45, 1.5).
BASELINE: dict[str, Any] = {
    "optimizer": "pso",
    "optimizer_options": {"w": 0.8, "c1": 1.45, "c2": 1.5},
    "pop_size": 300,
    "n_iter": 100,
    "n_restart": 1,
    "rho": 0.0,
    "order": "lh",
    "seeding": "uniform",
}

register_planner(
    PrioritizedPlanner,
    name="ppswarm",
    summary="PPSwarm: RRT*-seeded PSO per UAV in prioritized planning with restarts",
    **PPSWARM,
)
register_planner(
    PrioritizedPlanner,
    name="prioritized",
    summary="PPSwarm's baseline frame: LH prioritized planning with any optimizer per UAV",
    **BASELINE,
)
