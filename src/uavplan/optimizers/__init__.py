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
    "DE",
    "GA",
    "PSO",
    "SPSO",
    "Budget",
    "DEConfig",
    "FunctionProblem",
    "GAConfig",
    "OptimizeResult",
    "Optimizer",
    "OptimizerConfig",
    "OptimizerError",
    "PSOConfig",
    "RSCDWOA",
    "RSCDWOAConfig",
    "Problem",
    "SPSOConfig",
    "available",
    "get",
    "minimize",
    "register",
    "run",
]

# Built-in optimizers: importing their modules registers them.
from uavplan.optimizers.de import DE, DEConfig
from uavplan.optimizers.ga import GA, GAConfig
from uavplan.optimizers.pso import PSO, PSOConfig
from uavplan.optimizers.rscdwoa import RSCDWOA, RSCDWOAConfig
from uavplan.optimizers.spso import SPSO, SPSOConfig
