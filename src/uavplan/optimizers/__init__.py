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
    "ABC",
    "DE",
    "GA",
    "GWO",
    "MAGA",
    "PSO",
    "RSCDWOA",
    "SPSO",
    "WOA",
    "ABCConfig",
    "Budget",
    "DEConfig",
    "FunctionProblem",
    "GAConfig",
    "GWOConfig",
    "MAGAConfig",
    "OptimizeResult",
    "Optimizer",
    "OptimizerConfig",
    "OptimizerError",
    "PSOConfig",
    "Problem",
    "RSCDWOAConfig",
    "SPSOConfig",
    "WOAConfig",
    "available",
    "get",
    "minimize",
    "register",
    "run",
]

# Importing an optimizer's module registers it: the built-ins by name (they are public API),
# and any other module of this package found on disk.
from uavplan._discovery import import_submodules
from uavplan.optimizers.abc import ABC, ABCConfig
from uavplan.optimizers.de import DE, DEConfig
from uavplan.optimizers.ga import GA, GAConfig
from uavplan.optimizers.gwo import GWO, GWOConfig
from uavplan.optimizers.maga import MAGA, MAGAConfig
from uavplan.optimizers.pso import PSO, PSOConfig
from uavplan.optimizers.rscdwoa import RSCDWOA, RSCDWOAConfig
from uavplan.optimizers.spso import SPSO, SPSOConfig
from uavplan.optimizers.woa import WOA, WOAConfig

import_submodules(__name__, __path__)
