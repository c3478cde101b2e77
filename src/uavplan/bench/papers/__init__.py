"""Each paper's experiments, one module per paper: its plans (registered with
:func:`~uavplan.bench.plans.register_plan`), its run kinds if it needs its own
(:func:`~uavplan.bench.kinds.register_kind`) and its report sections (the plans' ``report``
hook). A new paper is a new module listed here."""

from uavplan.bench.papers import overhead, ppswarm, rggpso, rscdwoa, spso

__all__ = ["overhead", "ppswarm", "rggpso", "rscdwoa", "spso"]
