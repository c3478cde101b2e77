"""Reactive planners: the artificial potential field stepped in time (``apf``) and the fused
planners whose sub-goals an optimizer places (RSCDWOA-APF, WOA-APF, PSO-APF, GA-APF; Zhang et
al.). Every module is imported, so that its planners register."""

from uavplan._discovery import import_submodules

MODULES = import_submodules(__name__, __path__)
