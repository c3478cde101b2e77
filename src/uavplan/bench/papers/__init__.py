"""Each paper's experiments, one module per paper: its plans (registered with
:func:`~uavplan.bench.plans.register_plan`), its run kinds if it needs its own
(:func:`~uavplan.bench.kinds.register_kind`) and its report sections (the plans' ``report``
hook). Every module here is imported, so a new paper is a new module."""

from uavplan._discovery import import_submodules

MODULES = import_submodules(__name__, __path__)
