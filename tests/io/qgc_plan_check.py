"""An independent check of QGroundControl ``.plan`` documents, written from reading QGC's loader
(``PlanMasterController::loadFromFile`` and what it calls), not from our exporter. No QGC code is
copied (QGC is GPLv3/Apache-2.0); the rules below are restated from what the loader does.

``qgc_plan_problems(doc)`` returns one line per problem, ``[]`` when QGC would load the document.
Each line starts with the JSON path of the offending value and ends with the QGC file the rule
comes from. Rules marked *(sanity)* are not load errors in QGC but make QGC load something other
than what was meant (a NaN coordinate, a polygon QGC treats as invalid, an ambiguous DO_JUMP
target); ``strict=True`` adds what QGC's own ``save`` always writes, so a file that passes it looks
like one QGC wrote.

JSON types follow Qt's ``QJsonValue``: *number* (``Double``: int or float, never bool), *bool*,
*string*, *array*, *object*, *null*. Where QGC declares a number, ``null`` is refused: the newest
``JsonHelper.cc`` accepts ``null`` only for keys it declares ``Null`` (older versions let ``null``
stand for NaN everywhere), so refusing it is what every version loads.

Rules and where they come from
------------------------------
Whole document
  * no NaN or +-Infinity anywhere: they are not JSON and QGC's parser refuses the file
    (``JsonHelper.cc`` ``isJsonFile``); MAVLink's NaN is written ``null``, and only where QGC
    reads ``null`` as NaN (``params``, ``AMSLAltAboveTerrain``).
  * the root is an object with ``groundStation`` (string), ``fileType`` (string, ``"Plan"``),
    ``version`` (number, exactly 1) (``JsonHelper.cc`` ``validateExternalQGCJsonFile`` /
    ``validateInternalQGCJsonFile``, ``PlanMasterController.cc`` ``kPlanFileVersion``), and the
    objects ``mission``, ``geoFence``, ``rallyPoints``, all three required even when empty
    (``PlanMasterController.cc`` ``loadFromFile``).

``mission`` (``MissionController.cc`` ``_loadJsonMissionFileV2``; ``MissionController::load``
calls it directly, so the mission's own ``version`` is *not* checked by the loader)
  * required: ``plannedHomePosition`` (array), ``items`` (array), ``firmwareType`` (number);
    optional numbers: ``vehicleType``, ``cruiseSpeed``, ``hoverSpeed``, ``globalPlanAltitudeMode``.
  * ``plannedHomePosition`` is ``[lat, lon, alt AMSL]``, exactly 3 values (``JsonHelper.cc``
    ``loadGeoCoordinate`` with altitude); QGC would read ``null`` as NaN, we refuse it (sanity).
  * lat in [-90, 90], lon in [-180, 180] for every coordinate (sanity: QGeoCoordinate is invalid
    outside them).
  * ``firmwareType``/``vehicleType`` whole numbers >= 0 (MAV_AUTOPILOT / MAV_TYPE),
    ``cruiseSpeed``/``hoverSpeed`` > 0, ``globalPlanAltitudeMode`` a whole number 0..5
    (``QGroundControlQmlGlobal.h`` ``AltMode``) (sanity).
  * every item is an object with a string ``type``: ``"SimpleItem"`` or ``"ComplexItem"``, any
    other is "Unknown item type". A ``ComplexItem`` needs a string ``complexItemType`` among
    ``survey``, ``CorridorScan``, ``StructureScan``, ``fwLandingPattern``, ``vtolLandingPattern``
    (QGC drops an unknown one); a survey's ``version`` is a number in 2..5
    (``SurveyComplexItem.cc``). Complex items' other contents are not checked here.
  * a DO_JUMP (command 177) item's ``params[0]`` is the ``doJumpId`` of an existing item
    ("Could not find doJumpId").
  * strict: ``version`` 2 and ``vehicleType``, ``cruiseSpeed``, ``hoverSpeed`` present
    (``MissionController::save``).

Simple items (``MissionItem.cc`` ``load``, ``SimpleMissionItem.cc`` ``load``)
  * required: ``type`` (string, ``"SimpleItem"``), ``frame`` (number), ``command`` (number),
    ``params`` (array), ``autoContinue`` (bool); optional ``doJumpId`` (number). QGC still
    converts two older layouts (``param1``..``param4`` keys; a ``coordinate`` ``[lat, lon, alt]``
    holding params 5-7); they are accepted as QGC converts them, and refused under ``strict``.
  * ``params`` holds exactly 7 values; the first 4 are numbers or ``null`` (NaN); QGC reads the
    last 3 with ``toDouble`` (a string silently becomes 0), we require number or ``null`` (sanity).
  * ``command`` a whole number 0..65535, ``frame`` a whole number 0..255 (MAVLink uint16/uint8)
    (sanity); in a global frame (0, 3, 5, 6, 10, 11) numeric ``params[4]``/``params[5]`` are a
    valid lat/lon (sanity).
  * ``doJumpId`` a whole number >= 1 and unique among the mission's simple items (sanity: QGC's
    save numbers them 1, 2, ... and DO_JUMP resolves to the first match); strict: present.
  * the altitude trio ``AltitudeMode``, ``Altitude``, ``AMSLAltAboveTerrain`` is all or none: any
    one makes all three required; ``AltitudeMode`` and ``Altitude`` numbers, ``AMSLAltAboveTerrain``
    a number or ``null`` (``SimpleMissionItem.cc``). QGC only reads the trio for commands that
    specify an altitude; we hold every item to it. ``AltitudeMode`` is 1..4 (relative, AMSL,
    calculated above terrain, terrain frame; ``QGroundControlQmlGlobal.h``) (sanity).

``geoFence`` (``GeoFenceController.cc`` ``load``)
  * without ``version``, or with ``version`` 1, QGC ignores the whole section (strict: refused).
    Otherwise ``version`` (number, exactly 2), ``circles`` (array), ``polygons`` (array) are
    required, ``breachReturn`` is an optional ``[lat, lon, alt]``.
  * each polygon is an object (``QGCFencePolygon.cc``): ``version`` (number, exactly 1),
    ``inclusion`` (bool), and (``QGCMapPolygon.cc``) ``polygon``, an array of ``[lat, lon]``
    pairs (``JsonHelper.cc`` ``loadGeoCoordinateArray`` without altitude); at least 3 vertices
    (sanity: ``QGCMapPolygon`` treats fewer as no polygon and never edits below 3).
  * each circle is an object (``QGCFenceCircle.cc``): ``version`` (number, exactly 1; the newest
    QGC checks it), ``inclusion`` (bool), and (``QGCMapCircle.cc``) ``circle``, an object with
    ``center`` ``[lat, lon]`` and ``radius`` (number; > 0, sanity).

``rallyPoints`` (``RallyPointController.cc`` ``load``)
  * with ``version`` 1 QGC ignores the section (strict: refused); otherwise ``version`` (number,
    exactly 2) and ``points`` (array) are required, each point ``[lat, lon, alt]``.
"""

from __future__ import annotations

import math
from typing import Any

#: MAV_FRAME values whose params 5/6 are latitude/longitude (GLOBAL, GLOBAL_RELATIVE_ALT, and
#: their _INT and TERRAIN_ALT variants)
GLOBAL_FRAMES = frozenset({0, 3, 5, 6, 10, 11})
MAV_CMD_DO_JUMP = 177
COMPLEX_ITEM_TYPES = frozenset(
    {"survey", "CorridorScan", "StructureScan", "fwLandingPattern", "vtolLandingPattern"}
)
ALTITUDE_TRIO = ("AltitudeMode", "Altitude", "AMSLAltAboveTerrain")

# JSON type names as Qt calls them; "NumberOrNull" is QGC's "Null" declaration (a number or null)
_TYPE_NAMES = {
    "Double": "a number",
    "NumberOrNull": "a number or null",
    "Bool": "a bool",
    "String": "a string",
    "Array": "an array",
    "Object": "an object",
}


def _json_type(v: Any) -> str:
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, (int, float)):
        return "number"
    if isinstance(v, str):
        return "string"
    if isinstance(v, list):
        return "array"
    if isinstance(v, dict):
        return "object"
    return type(v).__name__


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_whole(v: Any) -> bool:
    return _is_num(v) and math.isfinite(v) and float(v).is_integer()


def _has_type(v: Any, kind: str) -> bool:
    if kind == "Double":
        return _is_num(v)
    if kind == "NumberOrNull":
        return v is None or _is_num(v)
    if kind == "Bool":
        return isinstance(v, bool)
    if kind == "String":
        return isinstance(v, str)
    if kind == "Array":
        return isinstance(v, list)
    if kind == "Object":
        return isinstance(v, dict)
    raise ValueError(kind)


def _join(path: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


class _Check:
    def __init__(self, strict: bool) -> None:
        self.strict = strict
        self.out: list[str] = []

    def problem(self, path: str, message: str, source: str) -> None:
        self.out.append(f"{path or '<root>'}: {message} [{source}]")

    def keys(
        self, obj: dict[str, Any], path: str, spec: list[tuple[str, str, bool]], source: str
    ) -> bool:
        """QGC's ``validateKeys``: required keys present, present keys of their type."""
        ok = True
        for key, kind, required in spec:
            where = _join(path, key)
            if key not in obj:
                if required:
                    self.problem(where, "required key is missing", source)
                    ok = False
            elif not _has_type(obj[key], kind):
                self.problem(
                    where, f"must be {_TYPE_NAMES[kind]}, is {_json_type(obj[key])}", source
                )
                ok = False
        return ok

    def version(self, obj: dict[str, Any], path: str, expected: int, source: str) -> None:
        v = obj.get("version")
        if _is_num(v) and v != expected:
            self.problem(_join(path, "version"), f"must be {expected}, is {v}", source)

    def coordinate(self, v: Any, path: str, altitude: bool, source: str) -> bool:
        """``loadGeoCoordinate``: [lat, lon] or [lat, lon, alt]; we refuse null (NaN)."""
        n = 3 if altitude else 2
        shape = "[lat, lon, alt]" if altitude else "[lat, lon]"
        if not isinstance(v, list):
            self.problem(path, f"must be an array {shape}, is {_json_type(v)}", source)
            return False
        if len(v) != n:
            self.problem(path, f"must hold {n} values {shape}, has {len(v)}", source)
            return False
        ok = True
        for i, x in enumerate(v):
            if not _is_num(x):
                what = "null (QGC would read NaN; sanity)" if x is None else _json_type(x)
                self.problem(_join(path, i), f"must be a number, is {what}", source)
                ok = False
        if ok:
            ok = self.lat_lon(v[0], v[1], path, source)
        return ok

    def lat_lon(self, lat: float, lon: float, path: str, source: str) -> bool:
        ok = True
        if math.isfinite(lat) and not -90.0 <= lat <= 90.0:
            self.problem(path, f"latitude {lat} outside [-90, 90] (sanity)", source)
            ok = False
        if math.isfinite(lon) and not -180.0 <= lon <= 180.0:
            self.problem(path, f"longitude {lon} outside [-180, 180] (sanity)", source)
            ok = False
        return ok

    def non_finite(self, v: Any, path: str) -> None:
        if isinstance(v, float) and not math.isfinite(v):
            token = "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")
            self.problem(
                path,
                f"{token} is not valid JSON (QGC's parser refuses the file); write null for NaN",
                "JsonHelper.cc",
            )
        elif isinstance(v, dict):
            for k, x in v.items():
                self.non_finite(x, _join(path, str(k)))
        elif isinstance(v, list):
            for i, x in enumerate(v):
                self.non_finite(x, _join(path, i))

    # -- sections -------------------------------------------------------------------------------

    def plan(self, doc: Any) -> None:
        if not isinstance(doc, dict):
            self.problem("", f"must be an object, is {_json_type(doc)}", "JsonHelper.cc")
            return
        self.non_finite(doc, "")
        src = "JsonHelper.cc"
        self.keys(
            doc,
            "",
            [
                ("groundStation", "String", True),
                ("fileType", "String", True),
                ("version", "Double", True),
            ],
            src,
        )
        if isinstance(doc.get("fileType"), str) and doc["fileType"] != "Plan":
            self.problem("fileType", f'must be "Plan", is "{doc["fileType"]}"', src)
        self.version(doc, "", 1, "PlanMasterController.cc")
        src = "PlanMasterController.cc"
        self.keys(
            doc,
            "",
            [
                ("mission", "Object", True),
                ("geoFence", "Object", True),
                ("rallyPoints", "Object", True),
            ],
            src,
        )
        if isinstance(doc.get("mission"), dict):
            self.mission(doc["mission"], "mission")
        if isinstance(doc.get("geoFence"), dict):
            self.geofence(doc["geoFence"], "geoFence")
        if isinstance(doc.get("rallyPoints"), dict):
            self.rally(doc["rallyPoints"], "rallyPoints")

    def mission(self, m: dict[str, Any], path: str) -> None:
        src = "MissionController.cc"
        self.keys(
            m,
            path,
            [
                ("plannedHomePosition", "Array", True),
                ("items", "Array", True),
                ("firmwareType", "Double", True),
                ("vehicleType", "Double", False),
                ("cruiseSpeed", "Double", False),
                ("hoverSpeed", "Double", False),
                ("globalPlanAltitudeMode", "Double", False),
            ],
            src,
        )
        if self.strict:
            for key in ("version", "vehicleType", "cruiseSpeed", "hoverSpeed"):
                if key not in m:
                    self.problem(_join(path, key), "missing (strict: QGC's save writes it)", src)
            if "version" in m and m["version"] != 2:
                self.problem(_join(path, "version"), f"must be 2, is {m['version']!r}", src)
        for key in ("firmwareType", "vehicleType"):
            v = m.get(key)
            if _is_num(v) and not (_is_whole(v) and v >= 0):
                self.problem(_join(path, key), f"must be a whole number >= 0, is {v} (sanity)", src)
        for key in ("cruiseSpeed", "hoverSpeed"):
            v = m.get(key)
            if _is_num(v) and math.isfinite(v) and not v > 0:
                self.problem(_join(path, key), f"must be > 0, is {v} (sanity)", src)
        v = m.get("globalPlanAltitudeMode")
        if _is_num(v) and not (_is_whole(v) and 0 <= v <= 5):
            self.problem(
                _join(path, "globalPlanAltitudeMode"),
                f"must be a whole number 0..5 (AltMode), is {v} (sanity)",
                "QGroundControlQmlGlobal.h",
            )
        home = m.get("plannedHomePosition")
        if isinstance(home, list):
            self.coordinate(home, _join(path, "plannedHomePosition"), True, "JsonHelper.cc")
        items = m.get("items")
        if not isinstance(items, list):
            return
        jump_ids: dict[Any, int] = {}
        jumps: list[tuple[str, Any]] = []
        for i, item in enumerate(items):
            where = _join(_join(path, "items"), i)
            if not isinstance(item, dict):
                self.problem(where, f"must be an object, is {_json_type(item)}", src)
                continue
            if not self.keys(item, where, [("type", "String", True)], src):
                continue
            kind = item["type"]
            if kind == "SimpleItem":
                self.simple_item(item, where, i, jump_ids, jumps)
            elif kind == "ComplexItem":
                self.complex_item(item, where)
            else:
                self.problem(
                    _join(where, "type"),
                    f'unknown item type "{kind}" (SimpleItem or ComplexItem)',
                    src,
                )
        for where, target in jumps:
            if target not in jump_ids:
                self.problem(
                    _join(where, "params") + "[0]",
                    f"DO_JUMP target doJumpId {target!r} is not the doJumpId of any item",
                    src,
                )

    def simple_item(
        self,
        item: dict[str, Any],
        path: str,
        index: int,
        jump_ids: dict[Any, int],
        jumps: list[tuple[str, Any]],
    ) -> None:
        src = "MissionItem.cc"
        converted = dict(item)
        if "params" not in item:
            # the oldest layout: param1..param4 keys (QGC converts it)
            legacy = [f"param{k}" for k in range(1, 5)]
            if any(k in item for k in legacy):
                if self.keys(item, path, [(k, "Double", True) for k in legacy], src):
                    converted["params"] = [item[k] for k in legacy]
                if self.strict:
                    self.problem(path, "legacy param1..param4 layout (strict: use params)", src)
        if "coordinate" in item:
            # params 5-7 in a separate coordinate (QGC converts it)
            if self.keys(item, path, [("coordinate", "Array", True)], src):
                where = _join(path, "coordinate")
                ok = self.coordinate(item["coordinate"], where, True, "JsonHelper.cc")
                if ok and isinstance(converted.get("params"), list):
                    converted["params"] = [*converted["params"], *item["coordinate"]]
            if self.strict:
                self.problem(path, "legacy coordinate layout (strict: use params[4:7])", src)
        self.keys(
            converted,
            path,
            [
                ("type", "String", True),
                ("frame", "Double", True),
                ("command", "Double", True),
                ("params", "Array", True),
                ("autoContinue", "Bool", True),
                ("doJumpId", "Double", False),
            ],
            src,
        )
        command, frame = converted.get("command"), converted.get("frame")
        if _is_num(command) and not (_is_whole(command) and 0 <= command <= 65535):
            self.problem(
                _join(path, "command"),
                f"must be a whole number 0..65535, is {command} (sanity)",
                src,
            )
        if _is_num(frame) and not (_is_whole(frame) and 0 <= frame <= 255):
            self.problem(
                _join(path, "frame"), f"must be a whole number 0..255, is {frame} (sanity)", src
            )
        params = converted.get("params")
        where = _join(path, "params")
        if isinstance(params, list):
            if len(params) != 7:
                self.problem(where, f"must hold 7 values, has {len(params)}", src)
            else:
                for k, p in enumerate(params):
                    if not (p is None or _is_num(p)):
                        note = "" if k < 4 else " (sanity: QGC would read it as 0)"
                        self.problem(
                            _join(where, k),
                            f"must be a number or null, is {_json_type(p)}{note}",
                            src,
                        )
                lat, lon = params[4], params[5]
                if frame in GLOBAL_FRAMES and _is_num(lat) and _is_num(lon):
                    self.lat_lon(lat, lon, f"{where}[4:6]", src)
                if command == MAV_CMD_DO_JUMP:
                    jumps.append((path, params[0]))
        # doJumpId
        if "doJumpId" in item:
            jid = item["doJumpId"]
            if _is_num(jid):
                if not (_is_whole(jid) and jid >= 1):
                    self.problem(
                        _join(path, "doJumpId"),
                        f"must be a whole number >= 1, is {jid} (sanity)",
                        src,
                    )
                elif jid in jump_ids:
                    self.problem(
                        _join(path, "doJumpId"),
                        f"{jid} repeats the doJumpId of item {jump_ids[jid]} (sanity)",
                        src,
                    )
                else:
                    jump_ids[jid] = index
        elif self.strict:
            self.problem(_join(path, "doJumpId"), "missing (strict: QGC's save writes it)", src)
        self.altitude_trio(item, path)

    def altitude_trio(self, item: dict[str, Any], path: str) -> None:
        src = "SimpleMissionItem.cc"
        present = [k for k in ALTITUDE_TRIO if k in item]
        if not present:
            return
        for k in ALTITUDE_TRIO:
            if k not in item:
                self.problem(
                    _join(path, k),
                    f"missing: {', '.join(present)} given, the altitude trio "
                    f"{'/'.join(ALTITUDE_TRIO)} is all or none",
                    src,
                )
        self.keys(
            item,
            path,
            [
                ("AltitudeMode", "Double", False),
                ("Altitude", "Double", False),
                ("AMSLAltAboveTerrain", "NumberOrNull", False),
            ],
            src,
        )
        mode = item.get("AltitudeMode")
        if _is_num(mode) and not (_is_whole(mode) and 1 <= mode <= 4):
            self.problem(
                _join(path, "AltitudeMode"),
                f"must be 1..4 (relative, AMSL, calc. above terrain, terrain frame), is {mode}"
                " (sanity)",
                "QGroundControlQmlGlobal.h",
            )

    def complex_item(self, item: dict[str, Any], path: str) -> None:
        src = "MissionController.cc"
        if not self.keys(item, path, [("complexItemType", "String", True)], src):
            return
        kind = item["complexItemType"]
        if kind not in COMPLEX_ITEM_TYPES:
            self.problem(
                _join(path, "complexItemType"),
                f'unsupported complex item type "{kind}" (QGC drops the item)',
                src,
            )
        elif kind == "survey":
            src = "SurveyComplexItem.cc"
            if self.keys(item, path, [("version", "Double", True)], src):
                v = item["version"]
                if not (_is_whole(v) and 2 <= v <= 5):
                    self.problem(_join(path, "version"), f"must be 2..5 for a survey, is {v}", src)

    def geofence(self, g: dict[str, Any], path: str) -> None:
        src = "GeoFenceController.cc"
        v = g.get("version")
        if "version" not in g or (_is_num(v) and v == 1):
            if self.strict:
                self.problem(
                    _join(path, "version"),
                    f"{'missing' if 'version' not in g else 'version 1'}: QGC ignores the whole"
                    " section (strict: write version 2)",
                    src,
                )
            return
        self.keys(
            g,
            path,
            [
                ("version", "Double", True),
                ("circles", "Array", True),
                ("polygons", "Array", True),
                ("breachReturn", "Array", False),
            ],
            src,
        )
        self.version(g, path, 2, src)
        if isinstance(g.get("breachReturn"), list):
            self.coordinate(g["breachReturn"], _join(path, "breachReturn"), True, "JsonHelper.cc")
        polygons = g.get("polygons")
        for i, poly in enumerate(polygons if isinstance(polygons, list) else []):
            where = _join(_join(path, "polygons"), i)
            if not isinstance(poly, dict):
                self.problem(where, f"must be an object, is {_json_type(poly)}", src)
                continue
            self.fence_polygon(poly, where)
        circles = g.get("circles")
        for i, circle in enumerate(circles if isinstance(circles, list) else []):
            where = _join(_join(path, "circles"), i)
            if not isinstance(circle, dict):
                self.problem(where, f"must be an object, is {_json_type(circle)}", src)
                continue
            self.fence_circle(circle, where)

    def fence_polygon(self, poly: dict[str, Any], path: str) -> None:
        src = "QGCFencePolygon.cc"
        self.keys(poly, path, [("version", "Double", True), ("inclusion", "Bool", True)], src)
        self.version(poly, path, 1, src)
        src = "QGCMapPolygon.cc"
        if not self.keys(poly, path, [("polygon", "Array", True)], src):
            return
        vertices = poly["polygon"]
        where = _join(path, "polygon")
        for k, vertex in enumerate(vertices):
            self.coordinate(vertex, _join(where, k), False, "JsonHelper.cc")
        if len(vertices) < 3:
            self.problem(where, f"needs at least 3 vertices, has {len(vertices)} (sanity)", src)

    def fence_circle(self, circle: dict[str, Any], path: str) -> None:
        src = "QGCFenceCircle.cc"
        self.keys(circle, path, [("version", "Double", True), ("inclusion", "Bool", True)], src)
        self.version(circle, path, 1, src)
        src = "QGCMapCircle.cc"
        if not self.keys(circle, path, [("circle", "Object", True)], src):
            return
        body, where = circle["circle"], _join(path, "circle")
        self.keys(body, where, [("center", "Array", True), ("radius", "Double", True)], src)
        if isinstance(body.get("center"), list):
            self.coordinate(body["center"], _join(where, "center"), False, "JsonHelper.cc")
        r = body.get("radius")
        if _is_num(r) and math.isfinite(r) and not r > 0:
            self.problem(_join(where, "radius"), f"must be > 0, is {r} (sanity)", src)

    def rally(self, r: dict[str, Any], path: str) -> None:
        src = "RallyPointController.cc"
        v = r.get("version")
        if _is_num(v) and v == 1:
            if self.strict:
                self.problem(
                    _join(path, "version"),
                    "version 1: QGC ignores the whole section (strict: write version 2)",
                    src,
                )
            return
        if not self.keys(r, path, [("version", "Double", True), ("points", "Array", True)], src):
            return
        self.version(r, path, 2, src)
        for i, point in enumerate(r["points"]):
            self.coordinate(point, _join(_join(path, "points"), i), True, "JsonHelper.cc")


def qgc_plan_problems(doc: dict[str, Any], *, strict: bool = False) -> list[str]:
    """Every reason QGroundControl would refuse (or misread) the ``.plan`` document ``doc`` (as
    parsed by :func:`json.loads`), one line each; ``[]`` when it would load it. ``strict`` also
    requires what QGC's own save writes (see the module docstring for the rules)."""
    check = _Check(strict)
    check.plan(doc)
    return check.out
