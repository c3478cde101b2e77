"""The independent plan verifier: is every UAV's timed path flyable, and do the UAVs keep their
distance from each other? (:mod:`uavplan.verify.verifier` says exactly what is checked.)

Written apart from the planner's cost and feasibility code on purpose, so that a bug in the
planner's geometry cannot hide itself: ``pyproject.toml``'s import-linter contracts forbid this
package to import any planning code (problems, optimizers, smoothing, planners), even
indirectly, and the world's kernels (geometry, terrain kernels, the reservation table,
visibility) directly; ``tests/verify/test_independence.py`` lists what it may import. It reads
plans through :mod:`uavplan.io.plan_file` and the scenario as data.

Modules: :mod:`~uavplan.verify.report` (violations, the report), :mod:`~uavplan.verify.timing`
(times, speed, bounds), :mod:`~uavplan.verify.kinematics` (turn radius, climb and descent
angles), :mod:`~uavplan.verify.obstacles` (cylinders, circles, polygons),
:mod:`~uavplan.verify.terrain` (terrain, altitude band), :mod:`~uavplan.verify.separation`
(UAV pairs and moving obstacles over continuous time), :mod:`~uavplan.verify.verifier` (all of
them on a plan).
"""

from uavplan.io.plan_file import PlanFormatError, Trajectory
from uavplan.verify.report import KINDS, VerifyReport, Violation
from uavplan.verify.verifier import verify_plan, verify_trajectories

__all__ = [
    "KINDS",
    "PlanFormatError",
    "Trajectory",
    "VerifyReport",
    "Violation",
    "verify_plan",
    "verify_trajectories",
]
