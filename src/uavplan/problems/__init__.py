"""Path problems: batched cost terms, feasibility and encodings."""

from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import (
    PRESETS,
    Evaluation,
    PathProblem,
    Term,
    cost_presets,
    preset_problem,
)

__all__ = [
    "PRESETS",
    "CartesianEncoding",
    "Evaluation",
    "PathProblem",
    "Term",
    "cost_presets",
    "preset_problem",
]
