"""``qgc``: QGroundControl ``.plan`` files, one per UAV (a plan holds one vehicle).

What QGC's loader requires (read from its sources; ``tests/io/qgc_plan_check.py`` checks every
file we write against those rules, and MAVSDK's sample plans too): ``fileType: "Plan"``,
``version: 1``, ``groundStation``, and all of ``mission`` (``firmwareType``,
``plannedHomePosition`` ``[lat, lon, AMSL]``, ``items``), ``geoFence`` (version 2, ``circles``,
``polygons``; another version and QGC ignores the fence) and ``rallyPoints`` (version 2,
``points``), even when empty. We also write what QGC's own save writes (mission version 2,
``vehicleType``, ``cruiseSpeed``, ``hoverSpeed``, every item's ``doJumpId``): the check's
strict mode. Items are ``SimpleItem`` with
``command``, ``frame``, 7 ``params`` (``null`` where MAVLink means NaN: JSON has no NaN),
``autoContinue`` and ``doJumpId``; the optional ``AltitudeMode``/``Altitude``/
``AMSLAltAboveTerrain`` trio is left out (QGC then takes the altitude frame from ``frame``).
The scenario's cylinders and circles become exclusion circles, its polygons and revealed
uncertain areas exclusion polygons (:meth:`Mission.keep_out`). A Dubins-smoothed flight is
written as its dense points (QGC's simple items have no arcs)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from uavplan.io.atomic import write_texts_atomic
from uavplan.io.missions import Mission, register_exporter, uav_file

#: MAV_AUTOPILOT and MAV_TYPE numbers
FIRMWARE = {"px4": 12, "ardupilot": 3, "generic": 0}
FIXED_WING, QUADROTOR = 1, 2


def qgc_document(mission: Mission, k: int) -> dict[str, Any]:
    """UAV ``k``'s ``.plan`` document."""
    tr = mission.trajectories()[k]
    home = mission.home(tr)
    speeds = mission.segment_speeds(tr)
    moving = speeds[speeds > 0]
    cruise = float(np.median(moving)) if len(moving) else 1.0
    mission_items = mission.items(tr)
    params = np.round(np.array([it.params for it in mission_items], dtype=np.float64), 8).tolist()
    items = [
        {
            "autoContinue": True,
            "command": it.command,
            "doJumpId": j,
            "frame": it.frame,
            "params": [None if v != v else v for v in row],  # NaN -> null, as QGC writes it
            "type": "SimpleItem",
        }
        for j, (it, row) in enumerate(zip(mission_items, params, strict=True), start=1)
    ]
    circles, polygons = mission.keep_out()
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "uavplan",
        "mission": {
            "version": 2,
            "firmwareType": FIRMWARE[mission.options.firmware],
            "vehicleType": FIXED_WING if mission.is_fixed_wing() else QUADROTOR,
            "cruiseSpeed": round(cruise, 3),
            "hoverSpeed": round(cruise, 3),
            "plannedHomePosition": [
                round(float(home[0]), 8),
                round(float(home[1]), 8),
                round(float(home[2]), 3),
            ],
            "items": items,
        },
        "geoFence": {
            "version": 2,
            "circles": [
                {
                    "circle": {"center": [round(la, 8), round(lo, 8)], "radius": round(r, 3)},
                    "inclusion": False,
                    "version": 1,
                }
                for la, lo, r in circles
            ],
            "polygons": [
                {"inclusion": False, "polygon": np.round(P, 8).tolist(), "version": 1}
                for P in polygons
            ],
        },
        "rallyPoints": {"version": 2, "points": []},
    }


@register_exporter(
    "qgc", ".plan", "QGroundControl .plan (mission, geofence, rally points)", per_uav=True
)
def write_qgc(mission: Mission, out: Path) -> list[Path]:
    files = [
        (
            uav_file(out, tr.id, ".plan"),
            json.dumps(qgc_document(mission, k), allow_nan=False) + "\n",
        )
        for k, tr in enumerate(mission.trajectories())
    ]
    return write_texts_atomic(files)
