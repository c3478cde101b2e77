"""World model: terrain, obstacles, moving obstacles, UAV limits and tasks."""

from uavplan.world.dynamic import MovingObstacle
from uavplan.world.obstacles import (
    AltitudeBand,
    Circle,
    Cylinder,
    DangerArea,
    Polygon,
    UncertainArea,
)
from uavplan.world.scenario import UAV, Bounds, Scenario, Task
from uavplan.world.terrain import Terrain

__all__ = [
    "UAV",
    "AltitudeBand",
    "Bounds",
    "Circle",
    "Cylinder",
    "DangerArea",
    "MovingObstacle",
    "Polygon",
    "Scenario",
    "Task",
    "Terrain",
    "UncertainArea",
]
