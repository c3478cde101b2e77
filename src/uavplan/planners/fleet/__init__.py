"""Fleets: the prioritized engine and PPSwarm's named configurations (Meng, Chen & Qu 2024), a
single-UAV planner run as a fleet (:mod:`.sequential`), every task planned (:mod:`.fleet_plan`)
and a fleet repaired after planning (:mod:`.fleet_polish`). Above the other families: it seeds
with RRT* and runs any planner in its frame. Every module is imported, so that its planners
register."""

from uavplan._discovery import import_submodules

MODULES = import_submodules(__name__, __path__)
