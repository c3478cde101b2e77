"""``wpml``: DJI's waypoint format, one ``.kmz`` per UAV, as DJI Pilot 2 and FlightHub 2 load
it (DJI WPML 1.0.2, "DJI Cloud API: DJI WPML", template.kml and waylines.wpml): a zip archive
holding ``wpmz/template.kml`` (the editable template) and ``wpmz/waylines.wpml`` (what the
aircraft executes).

What is written, from the same thinned mission the MAVLink formats carry
(:meth:`~uavplan.io.missions.Mission.items`: waypoints, holds, speeds):

* ``wpml:missionConfig`` (both files): ``flyToWaylineMode`` ``safely`` (climb to the take-off
  security height, then to the first waypoint), ``finishAction`` from ``--end`` (``land``:
  ``autoLand`` at the last waypoint, ``rtl``: ``goHome``, ``none``: ``noAction``),
  ``exitOnRCLost`` ``executeLostAction`` with ``executeRCLostAction`` ``hover`` (a fleet's UAV
  that loses its link stops where it is rather than flying home through the others),
  ``takeOffSecurityHeight`` 20 m, ``globalTransitionalSpeed`` (the first leg's speed) and
  ``droneInfo`` (``--drone``: the enumeration values of DJI's product support list).
* ``waylines.wpml``'s ``Folder``: ``templateId`` 0, ``waylineId`` 0, ``executeHeightMode``
  ``relativeToStartPoint``, ``distance`` (m), ``duration`` (s, the plan's), ``autoFlightSpeed``
  (the median leg speed); per waypoint a ``Placemark``: ``Point/coordinates`` (lon,lat),
  ``wpml:index`` (0, 1, ... in order), ``wpml:executeHeight`` (above the take-off point),
  ``wpml:waypointSpeed`` (the plan's speed on the leg from it), ``wpml:waypointHeadingParam``
  (``followWayline``), ``wpml:waypointTurnParam`` (``toPointAndPassWithContinuityCurvature``:
  through the point without stopping, as the plan's curves are flown;
  ``toPointAndStopWithDiscontinuityCurvature`` where it holds and at the last point), with
  ``wpml:useStraightLine`` 1, and a ``hover`` action for the plan's holds.
* ``template.kml``: the same as a ``waypoint`` template (``waylineCoordinateSysParam`` WGS84 and
  ``relativeToStartPoint``, ``useGlobalHeight``/``Speed``/``HeadingParam``/``TurnParam`` 0 and
  the point's own values).

Heights are above the take-off point (the ground under the start), whatever ``--frame`` says:
WPML's other frames are ellipsoidal heights (uavplan has no geoid model: its altitudes are
above mean sea level) and DJI's own terrain following. The template's ``ellipsoidHeight``
carries that same relative height. DJI's aircraft are multirotors: a fixed-wing plan is
refused. Wayline speeds outside 1-15 m/s are refused (the aircraft would not keep the plan's
schedule).
"""

from __future__ import annotations

import dataclasses
import io
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from uavplan.io.atomic import write_bytes_atomic
from uavplan.io.missions import ExportError, Mission, register_exporter, uav_file

KML_NS = "http://www.opengis.net/kml/2.2"
WPML_NS = "http://www.dji.com/wpmz/1.0.2"
#: ``--drone``: (droneEnumValue, droneSubEnumValue) in DJI's product support enumeration.
DRONES = {"m300": (60, 0), "m350": (89, 0), "m30": (67, 0), "m30t": (67, 1), "m3e": (77, 0),
          "m3t": (77, 1), "m3m": (77, 2), "m3d": (91, 0), "m3td": (91, 1)}  # fmt: skip
#: The wayline speeds DJI's waypoint missions take, m/s.
SPEED_RANGE = (1.0, 15.0)
FINISH = {"land": "autoLand", "rtl": "goHome", "none": "noAction"}
PASS, STOP = "toPointAndPassWithContinuityCurvature", "toPointAndStopWithDiscontinuityCurvature"


def _w(parent: ET.Element, tag: str, text: object | None = None) -> ET.Element:
    el = ET.SubElement(parent, f"{{{WPML_NS}}}{tag}")
    if text is not None:
        el.text = str(text)
    return el


def _k(parent: ET.Element, tag: str) -> ET.Element:
    return ET.SubElement(parent, f"{{{KML_NS}}}{tag}")


def _num(v: float) -> str:
    return f"{v:.3f}".rstrip("0").rstrip(".")


def waypoints(mission: Mission, k: int) -> list[tuple[float, float, float, float, float]]:
    """UAV ``k``'s waypoints as ``(lat, lon, height above take-off, speed on the leg from it,
    hold s)``, from its thinned MAVLink mission in the ``relative`` frame (take-off, speed
    commands and the end are not waypoints in WPML); the thinning is recorded in ``mission``'s
    report as for the MAVLink formats."""
    relative = Mission(mission.plan, mission.scenario,
                       dataclasses.replace(mission.options, frame="relative"))  # fmt: skip
    tr = relative.trajectories()[k]
    items = relative.items(tr)
    mission.report[tr.id] = relative.report[tr.id]
    out: list[list[float]] = []
    speed = 0.0
    for it in items:
        if it.command == 16:  # MAV_CMD_NAV_WAYPOINT: hold, ..., lat, lon, height above home
            out.append([it.params[4], it.params[5], it.params[6], speed, float(it.params[0])])
        elif it.command == 178 and it.params[1] > 0:  # MAV_CMD_DO_CHANGE_SPEED
            speed = float(it.params[1])
            if out:
                out[-1][3] = speed  # it acts from the waypoint before it
    return [(a, b, c, d, e) for a, b, c, d, e in out]


def _mission_config(parent: ET.Element, mission: Mission, first_speed: float) -> None:
    cfg = _w(parent, "missionConfig")
    _w(cfg, "flyToWaylineMode", "safely")
    _w(cfg, "finishAction", FINISH[mission.options.end])
    _w(cfg, "exitOnRCLost", "executeLostAction")
    _w(cfg, "executeRCLostAction", "hover")
    _w(cfg, "takeOffSecurityHeight", 20)
    _w(cfg, "globalTransitionalSpeed", _num(first_speed))
    drone = _w(cfg, "droneInfo")
    enum, sub = DRONES[mission.options.drone]
    _w(drone, "droneEnumValue", enum)
    _w(drone, "droneSubEnumValue", sub)


def _placemark(
    folder: ET.Element, j: int, wp: tuple[float, ...], last: bool, template: bool
) -> None:
    lat, lon, h, speed, hold = wp
    pm = _k(folder, "Placemark")
    ET.SubElement(_k(pm, "Point"), f"{{{KML_NS}}}coordinates").text = f"{lon:.8f},{lat:.8f}"
    _w(pm, "index", j)
    if template:
        _w(pm, "ellipsoidHeight", _num(h))
        _w(pm, "height", _num(h))
        for flag in ("useGlobalHeight", "useGlobalSpeed", "useGlobalHeadingParam",
                     "useGlobalTurnParam"):  # fmt: skip
            _w(pm, flag, 0)
    else:
        _w(pm, "executeHeight", _num(h))
    _w(pm, "waypointSpeed", _num(speed))
    _w(_w(pm, "waypointHeadingParam"), "waypointHeadingMode", "followWayline")
    turn = _w(pm, "waypointTurnParam")
    _w(turn, "waypointTurnMode", STOP if (hold > 0 or last) else PASS)
    _w(turn, "waypointTurnDampingDist", 0)
    _w(pm, "useStraightLine", 1)
    if hold > 0:
        group = _w(pm, "actionGroup")
        _w(group, "actionGroupId", j)
        _w(group, "actionGroupStartIndex", j)
        _w(group, "actionGroupEndIndex", j)
        _w(group, "actionGroupMode", "sequence")
        _w(_w(group, "actionTrigger"), "actionTriggerType", "reachPoint")
        action = _w(group, "action")
        _w(action, "actionId", 0)
        _w(action, "actionActuatorFunc", "hover")
        _w(_w(action, "actionActuatorFuncParam"), "hoverTime", _num(hold))


def kmz_bytes(mission: Mission, k: int) -> bytes:
    """UAV ``k``'s ``.kmz``: ``wpmz/template.kml`` and ``wpmz/waylines.wpml``."""
    tr = mission.trajectories()[k]
    if mission.is_fixed_wing():
        raise ExportError(f"{mission.plan.source}: --format wpml: DJI's aircraft are "
                          "multirotors and this plan's UAV is a fixed wing")  # fmt: skip
    wps = waypoints(mission, k)
    speeds = np.array([w[3] for w in wps[:-1]] or [0.0])
    lo, hi = SPEED_RANGE
    if np.any((speeds < lo - 1e-9) | (speeds > hi + 1e-9)):
        raise ExportError(f"{mission.plan.source}: {tr.id}: --format wpml: leg speeds "
                          f"{speeds.min():.3g}-{speeds.max():.3g} m/s, and DJI's waylines fly "
                          f"{lo:g}-{hi:g} m/s: the aircraft would not keep the plan's "
                          "schedule")  # fmt: skip
    ET.register_namespace("", KML_NS)
    ET.register_namespace("wpml", WPML_NS)
    now = str(int(time.time() * 1000))
    files = {}
    for name, template in (("template.kml", True), ("waylines.wpml", False)):
        root = ET.Element(f"{{{KML_NS}}}kml")
        doc = _k(root, "Document")
        if template:
            _w(doc, "author", "uavplan")
            _w(doc, "createTime", now)
            _w(doc, "updateTime", now)
        _mission_config(doc, mission, float(speeds[0]))
        folder = _k(doc, "Folder")
        if template:
            _w(folder, "templateType", "waypoint")
        _w(folder, "templateId", 0)
        if template:
            sys_ = _w(folder, "waylineCoordinateSysParam")
            _w(sys_, "coordinateMode", "WGS84")
            _w(sys_, "heightMode", "relativeToStartPoint")
        else:
            _w(folder, "executeHeightMode", "relativeToStartPoint")
            _w(folder, "waylineId", 0)
            P = np.asarray(tr.points, dtype=np.float64)
            _w(folder, "distance", _num(float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())))
            _w(folder, "duration", _num(float(tr.times[-1] - tr.times[0])))
        _w(folder, "autoFlightSpeed", _num(float(np.median(speeds))))
        if template:
            _w(folder, "globalHeight", _num(wps[0][2]))
            _w(folder, "gimbalPitchMode", "manual")
            _w(_w(folder, "globalWaypointHeadingParam"), "waypointHeadingMode", "followWayline")
            _w(folder, "globalWaypointTurnMode", PASS)
            _w(folder, "globalUseStraightLine", 1)
        for j, wp in enumerate(wps):
            _placemark(folder, j, wp, j == len(wps) - 1, template)
        files[name] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():
            info = zipfile.ZipInfo(f"wpmz/{name}", date_time=(2000, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
    return buf.getvalue()


@register_exporter(
    "wpml", ".kmz", "DJI WPML waylines (.kmz with template.kml and waylines.wpml; DJI Pilot 2, "
    "FlightHub 2)", per_uav=True,
)  # fmt: skip
def write_wpml(mission: Mission, out: Path) -> list[Path]:
    if mission.options.frame != "relative":
        mission.warnings.append("wpml heights are written above the take-off point (DJI's "
                                "relativeToStartPoint), whatever --frame says")  # fmt: skip
    return [write_bytes_atomic(uav_file(out, tr.id, ".kmz"), kmz_bytes(mission, k))
            for k, tr in enumerate(mission.trajectories())]  # fmt: skip
