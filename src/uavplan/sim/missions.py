"""An exported mission read back into what an autopilot flies: per UAV the waypoints in the
local frame, the ground speed commanded on each leg, the hold at each waypoint, and the
take-off time of the launch schedule. The items are those ``uavplan export`` writes for a
per-vehicle format (:meth:`uavplan.io.missions.Mission.items`: thinned to ``max_items``,
``MAV_CMD_DO_CHANGE_SPEED`` where the speed changes), converted to WGS84 and back, so what is
flown is what the files say, not the planner's trajectory."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

NAV_WAYPOINT, NAV_TAKEOFF, DO_CHANGE_SPEED = 16, 22, 178


@dataclass(frozen=True)
class Legs:
    """One UAV's mission as flown: ``points`` (n, 3) local metres, ``speeds`` (n - 1,) the
    ground speed commanded on the leg from each point, ``holds`` (n,) seconds at each point,
    ``takeoff`` the launch schedule's time (s), ``items`` how many mission items it has."""

    uav: str
    points: FloatArray
    speeds: FloatArray
    holds: FloatArray
    takeoff: float
    items: int


def mission_legs(mission: Any, default_speed: float) -> list[Legs]:
    """Every UAV's exported mission (``mission``: a :class:`~uavplan.io.missions.Mission`
    with the ``amsl`` frame) as :class:`Legs`. ``default_speed``: the speed before the first
    speed command (the UAV's cruise speed, as an autopilot's default)."""
    origin = mission.origin
    out = []
    for tr in mission.trajectories():
        items = mission.items(tr)
        geo: list[tuple[float, float, float]] = []
        holds: list[float] = []
        speeds: list[float] = []
        current = float(default_speed)
        for it in items:
            if it.command == NAV_WAYPOINT:
                geo.append((it.params[4], it.params[5], it.params[6]))
                holds.append(float(it.params[0]))
                speeds.append(current)  # the speed in force when the point is reached
            elif it.command == DO_CHANGE_SPEED and it.params[1] > 0:
                current = float(it.params[1])
                if speeds:
                    speeds[-1] = current  # it acts from the waypoint before it
        P = origin.to_local(np.asarray(geo, dtype=np.float64))
        out.append(Legs(tr.id, P, np.asarray(speeds[:-1], dtype=np.float64),
                        np.asarray(holds, dtype=np.float64),
                        float(mission.report[tr.id]["takeoff_s"]), len(items)))  # fmt: skip
    return out
