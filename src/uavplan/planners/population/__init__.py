"""Population-based planners: every registered optimizer as a planner over waypoints
(:mod:`.optimizer_planner`) and HR-MAGA / P-MAGA (Yang, Liu & Li 2020). Every module is
imported, so that its planners register."""

from uavplan._discovery import import_submodules

MODULES = import_submodules(__name__, __path__)
