"""PPSwarm (Meng, Chen & Qu 2024, *Drones* 8, 192) and the prioritized baselines of its Table 2.

* ``ppswarm``: RRT* initial paths (Alg. 1), prioritized planning with LH priorities and
  ``N_restart = 5`` restarts that shuffle them (Alg. 3), PSO per UAV (Alg. 4, Eq. 14) over 300
  particles for ``N_iter = 20`` moves, seeded by Eq. (15) and, after a restart, Eq. (16) with
  ``rho = 20 %``; PSO ``w = 1``, ``c1 = c2 = 1.5`` (Table 1); Dubins smoothing (Sect. 4.4).
* ``prioritized``: the baselines' frame (Sect. 5.2.1: "all five comparison algorithms adopt the LH
  allocation scheme of prioritized planning"): one pass, LH priorities, uniform random first
  populations, ``N_iter = 100``, ``N_pop = 300`` (Table 2), and any registered optimizer
  (``optimizer="de"`` ...) with its Table 2 parameters passed as options.

The engine is :class:`uavplan.planners.prioritized.PrioritizedPlanner`; see it for every choice
where the paper is silent.
"""

from __future__ import annotations

from typing import Any

from uavplan.planners.base import _REGISTRY, register_planner
from uavplan.planners.prioritized import PrioritizedConfig, PrioritizedPlanner

#: PPSwarm Table 1.
PPSWARM = PrioritizedConfig(
    optimizer="pso",
    optimizer_params={"w": 1.0, "c1": 1.5, "c2": 1.5},
    pop_size=300,
    n_iter=20,
    n_restart=5,
    rho=0.2,
    order="lh",
    seeding="rrt-star",
)

#: PPSwarm Table 2's frame for the baselines (PSO's own w, c1, c2 there: 0.8, 1.45, 1.5).
BASELINE = PrioritizedConfig(
    optimizer="pso",
    optimizer_params={"w": 0.8, "c1": 1.45, "c2": 1.5},
    pop_size=300,
    n_iter=100,
    n_restart=1,
    rho=0.0,
    order="lh",
    seeding="uniform",
)


class PPSwarm(PrioritizedPlanner):
    name = "ppswarm"

    def __init__(self, **options: Any) -> None:
        super().__init__(PPSWARM, **options)


class Prioritized(PrioritizedPlanner):
    name = "prioritized"

    def __init__(self, **options: Any) -> None:
        base = BASELINE
        if "optimizer" in options and options["optimizer"] != "pso":
            # another optimizer's Table 2 parameters come as options; drop PSO's
            from dataclasses import replace

            base = replace(base, optimizer_params={})
        super().__init__(base, **options)


def register_all() -> None:
    for name, cls in (("ppswarm", PPSwarm), ("prioritized", Prioritized)):
        if name not in _REGISTRY:
            register_planner(name, lambda _c=cls, **kw: _c(**kw))
