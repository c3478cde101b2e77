"""Population optimizers on a common ask/tell interface, found by name in a registry."""

from uavplan.optimizers.base import (
    Budget,
    FunctionProblem,
    Optimizer,
    OptimizerConfig,
    OptimizerError,
    OptimizeResult,
    Problem,
    available,
    get,
    minimize,
    register,
    run,
)

__all__ = [
    "Budget",
    "FunctionProblem",
    "OptimizeResult",
    "Optimizer",
    "OptimizerConfig",
    "OptimizerError",
    "Problem",
    "available",
    "get",
    "minimize",
    "register",
    "run",
]
