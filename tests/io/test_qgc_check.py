"""The independent check of QGroundControl's ``.plan`` loader rules (``qgc_plan_check.py``):
it accepts the sample plans MAVSDK ships (``data/qgc/``), refuses the one MAVSDK's own tests
expect to fail (``data/qgc/rejected/``), and refuses each single break of a valid document, naming
the field."""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from qgc_plan_check import ALTITUDE_TRIO, qgc_plan_problems

DATA = Path(__file__).parent / "data" / "qgc"
ACCEPTED = sorted(DATA.glob("*.plan"))
REJECTED = sorted((DATA / "rejected").glob("*.plan"))


def _valid() -> dict[str, Any]:
    """A plan using every part the check knows: trio, DO_JUMP, fence polygon and circle, breach
    return, rally point; it passes even the strict check."""

    def item(command: int, jid: int, frame: int, params: list[Any], **extra: Any) -> dict:
        return {
            "autoContinue": True,
            "command": command,
            "doJumpId": jid,
            "frame": frame,
            "params": params,
            "type": "SimpleItem",
            **extra,
        }

    trio = {"AltitudeMode": 1, "Altitude": 30, "AMSLAltAboveTerrain": None}
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "uavplan",
        "mission": {
            "version": 2,
            "firmwareType": 12,
            "vehicleType": 2,
            "cruiseSpeed": 15,
            "hoverSpeed": 5,
            "globalPlanAltitudeMode": 1,
            "plannedHomePosition": [47.3977, 8.5456, 488.9],
            "items": [
                item(22, 1, 3, [0, 0, 0, None, 47.3977, 8.5456, 30], **trio),
                item(16, 2, 3, [0, 0, 0, None, 47.3980, 8.5460, 30], **trio),
                item(178, 3, 2, [1, 12.5, -1, 0, 0, 0, 0]),
                item(16, 4, 0, [0, 0, 0, None, 47.3983, 8.5456, 520.0]),
                item(177, 5, 2, [2, 1, 0, 0, 0, 0, 0]),  # DO_JUMP to doJumpId 2, once
                item(21, 6, 3, [0, 0, 0, None, 47.3977, 8.5456, 0]),
            ],
        },
        "geoFence": {
            "version": 2,
            "polygons": [
                {
                    "version": 1,
                    "inclusion": False,
                    "polygon": [[47.3978, 8.5457], [47.3979, 8.5457], [47.3979, 8.5458]],
                }
            ],
            "circles": [
                {
                    "version": 1,
                    "inclusion": False,
                    "circle": {"center": [47.398, 8.546], "radius": 15},
                }
            ],
            "breachReturn": [47.3977, 8.5456, 50],
        },
        "rallyPoints": {"version": 2, "points": [[47.3977, 8.5457, 40]]},
    }


def _mutated(change: Callable[[dict[str, Any]], object]) -> dict[str, Any]:
    doc = _valid()
    change(doc)
    return doc


def _at(doc: dict[str, Any], path: tuple[Any, ...]) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def _names(problems: list[str], field: str) -> bool:
    """Some problem line's path (before the first ": ") names ``field``."""
    return any(field in line.split(": ", 1)[0] for line in problems)


# -- the fixtures ---------------------------------------------------------------------------------


def test_fixtures_are_present() -> None:
    assert len(ACCEPTED) >= 2 and REJECTED


@pytest.mark.parametrize("path", ACCEPTED, ids=lambda p: p.name)
def test_accepts_every_sample_plan(path: Path) -> None:
    assert qgc_plan_problems(json.loads(path.read_text())) == []


@pytest.mark.parametrize("path", REJECTED, ids=lambda p: p.name)
def test_refuses_the_sample_mavsdk_expects_to_fail(path: Path) -> None:
    problems = qgc_plan_problems(json.loads(path.read_text()))
    assert _names(problems, "mission") and _names(problems, "rallyPoints")


def test_qgc_written_sample_passes_strict() -> None:
    doc = json.loads((DATA / "qgroundcontrol_sample.plan").read_text())
    assert qgc_plan_problems(doc, strict=True) == []


def test_legacy_sections_load_but_fail_strict() -> None:
    """QGC ignores a version-1 fence and rally section: loads, but not what QGC writes."""
    doc = json.loads((DATA / "example_fly_qgc_mission.plan").read_text())
    assert qgc_plan_problems(doc) == []
    problems = qgc_plan_problems(doc, strict=True)
    assert _names(problems, "geoFence.version") and _names(problems, "rallyPoints.version")


# -- the valid document and what QGC lets go -------------------------------------------------------


def test_valid_document_passes_both_levels() -> None:
    doc = _valid()
    assert qgc_plan_problems(doc) == []
    assert qgc_plan_problems(doc, strict=True) == []
    assert doc == _valid()  # the check does not touch its input


@pytest.mark.parametrize(
    "path",
    [
        ("mission", "version"),
        ("mission", "vehicleType"),
        ("mission", "cruiseSpeed"),
        ("mission", "hoverSpeed"),
        ("mission", "globalPlanAltitudeMode"),
        ("mission", "items", 2, "doJumpId"),
        ("geoFence", "breachReturn"),
        ("geoFence", "version"),  # QGC then ignores the section
    ],
    ids=lambda p: ".".join(map(str, p)),
)
def test_optional_keys_may_go(path: tuple[Any, ...]) -> None:
    doc = _mutated(lambda d: _at(d, path[:-1]).pop(path[-1]))
    assert qgc_plan_problems(doc) == []


@pytest.mark.parametrize(
    "path, strict_only",
    [
        (("mission", "version"), True),
        (("mission", "vehicleType"), True),
        (("mission", "items", 2, "doJumpId"), True),
        (("geoFence", "version"), True),
        (("mission", "globalPlanAltitudeMode"), False),
    ],
    ids=lambda p: ".".join(map(str, p)) if isinstance(p, tuple) else str(p),
)
def test_strict_wants_what_qgc_writes(path: tuple[Any, ...], strict_only: bool) -> None:
    doc = _mutated(lambda d: _at(d, path[:-1]).pop(path[-1]))
    problems = qgc_plan_problems(doc, strict=True)
    assert _names(problems, ".".join(map(str, path)).replace(".2.", "[2].")) == strict_only


def test_the_whole_trio_may_go() -> None:
    def drop(d: dict[str, Any]) -> None:
        for key in ALTITUDE_TRIO:
            del d["mission"]["items"][0][key]

    assert qgc_plan_problems(_mutated(drop), strict=True) == []


def test_legacy_item_layouts_are_converted_as_qgc_does() -> None:
    def v1(d: dict[str, Any]) -> None:  # param1..param4 keys, params 5-7 in "coordinate"
        it = d["mission"]["items"][3]
        params = it.pop("params")
        it.update({f"param{k + 1}": 0 if p is None else p for k, p in enumerate(params[:4])})
        it["coordinate"] = params[4:]

    doc = _mutated(v1)
    assert qgc_plan_problems(doc) == []
    assert _names(qgc_plan_problems(doc, strict=True), "mission.items[3]")


# -- each break, named -----------------------------------------------------------------------------

REQUIRED = [
    ("groundStation",),
    ("fileType",),
    ("version",),
    ("mission",),
    ("geoFence",),
    ("rallyPoints",),
    ("mission", "plannedHomePosition"),
    ("mission", "items"),
    ("mission", "firmwareType"),
    ("mission", "items", 1, "type"),
    ("mission", "items", 1, "frame"),
    ("mission", "items", 1, "command"),
    ("mission", "items", 1, "params"),
    ("mission", "items", 1, "autoContinue"),
    ("geoFence", "circles"),
    ("geoFence", "polygons"),
    ("geoFence", "polygons", 0, "version"),
    ("geoFence", "polygons", 0, "inclusion"),
    ("geoFence", "polygons", 0, "polygon"),
    ("geoFence", "circles", 0, "version"),
    ("geoFence", "circles", 0, "inclusion"),
    ("geoFence", "circles", 0, "circle"),
    ("geoFence", "circles", 0, "circle", "center"),
    ("geoFence", "circles", 0, "circle", "radius"),
    ("rallyPoints", "version"),
    ("rallyPoints", "points"),
]


def _dotted(path: tuple[Any, ...]) -> str:
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else key)
    return out


@pytest.mark.parametrize("path", REQUIRED, ids=_dotted)
def test_each_required_key_removed(path: tuple[Any, ...]) -> None:
    problems = qgc_plan_problems(_mutated(lambda d: _at(d, path[:-1]).pop(path[-1])))
    assert any(line.startswith(f"{_dotted(path)}: required key is missing") for line in problems), (
        problems
    )


@pytest.mark.parametrize("key", ALTITUDE_TRIO)
def test_incomplete_altitude_trio(key: str) -> None:
    problems = qgc_plan_problems(_mutated(lambda d: d["mission"]["items"][0].pop(key)))
    assert problems and all("mission.items[0]" in line for line in problems)
    assert _names(problems, f"mission.items[0].{key}") and "all or none" in problems[0]


def _set(path: tuple[Any, ...], value: Any) -> Callable[[dict[str, Any]], object]:
    def change(d: dict[str, Any]) -> None:
        _at(d, path[:-1])[path[-1]] = value

    return change


BREAKS: list[tuple[str, Callable[[dict[str, Any]], object], str]] = [
    # wrong JSON types
    ("fileType number", _set(("fileType",), 5), "fileType"),
    ("version bool", _set(("version",), True), "version"),
    ("groundStation null", _set(("groundStation",), None), "groundStation"),
    ("mission array", _set(("mission",), []), "mission"),
    ("firmwareType string", _set(("mission", "firmwareType"), "12"), "mission.firmwareType"),
    ("cruiseSpeed null", _set(("mission", "cruiseSpeed"), None), "mission.cruiseSpeed"),
    ("items object", _set(("mission", "items"), {}), "mission.items"),
    ("item not object", _set(("mission", "items", 2), [16]), "mission.items[2]"),
    ("autoContinue string", _set(("mission", "items", 1, "autoContinue"), "true"), "autoContinue"),
    ("command string", _set(("mission", "items", 1, "command"), "16"), "mission.items[1].command"),
    ("params object", _set(("mission", "items", 1, "params"), {}), "mission.items[1].params"),
    ("param1 string", _set(("mission", "items", 2, "params", 0), "1"), "items[2].params[0]"),
    ("param7 string", _set(("mission", "items", 1, "params", 6), "30"), "items[1].params[6]"),
    ("doJumpId string", _set(("mission", "items", 1, "doJumpId"), "2"), "items[1].doJumpId"),
    ("Altitude null", _set(("mission", "items", 0, "Altitude"), None), "items[0].Altitude"),
    ("AltitudeMode 0", _set(("mission", "items", 0, "AltitudeMode"), 0), "items[0].AltitudeMode"),
    ("inclusion number", _set(("geoFence", "polygons", 0, "inclusion"), 0), "inclusion"),
    ("radius string", _set(("geoFence", "circles", 0, "circle", "radius"), "15"), "radius"),
    ("circle array", _set(("geoFence", "circles", 0, "circle"), []), "geoFence.circles[0].circle"),
    ("points object", _set(("rallyPoints", "points"), {}), "rallyPoints.points"),
    # values
    ("fileType Mission", _set(("fileType",), "Mission"), "fileType"),
    ("plan version 2", _set(("version",), 2), "version"),
    ("fence version 3", _set(("geoFence", "version"), 3), "geoFence.version"),
    ("rally version 3", _set(("rallyPoints", "version"), 3), "rallyPoints.version"),
    ("polygon version 2", _set(("geoFence", "polygons", 0, "version"), 2), "polygons[0].version"),
    ("circle version 2", _set(("geoFence", "circles", 0, "version"), 2), "circles[0].version"),
    ("params of 6", lambda d: d["mission"]["items"][1]["params"].pop(), "mission.items[1].params"),
    ("params of 8", _set(("mission", "items", 1, "params"), [0] * 8), "mission.items[1].params"),
    ("NaN param", _set(("mission", "items", 1, "params", 3), math.nan), "items[1].params[3]"),
    ("inf home", _set(("mission", "plannedHomePosition", 2), math.inf), "plannedHomePosition[2]"),
    ("NaN radius", _set(("geoFence", "circles", 0, "circle", "radius"), math.nan), "radius"),
    ("lat 91 home", _set(("mission", "plannedHomePosition", 0), 91.0), "plannedHomePosition"),
    ("lat 91 item", _set(("mission", "items", 1, "params", 4), 91.0), "items[1].params"),
    ("lon 181 item", _set(("mission", "items", 3, "params", 5), 181.0), "items[3].params"),
    ("lat -91 vertex", _set(("geoFence", "polygons", 0, "polygon", 1, 0), -91.0), "polygon[1]"),
    ("lon 181 center", _set(("geoFence", "circles", 0, "circle", "center", 1), 181.0), "center"),
    ("lat 91 rally", _set(("rallyPoints", "points", 0, 0), 91.0), "rallyPoints.points[0]"),
    ("null home lat", _set(("mission", "plannedHomePosition", 0), None), "plannedHomePosition[0]"),
    ("home of 2", _set(("mission", "plannedHomePosition"), [47.0, 8.0]), "plannedHomePosition"),
    ("rally of 2", _set(("rallyPoints", "points", 0), [47.0, 8.0]), "rallyPoints.points[0]"),
    (
        "vertex of 3",
        _set(("geoFence", "polygons", 0, "polygon", 0), [47.0, 8.0, 1.0]),
        "polygon[0]",
    ),
    ("breach of 2", _set(("geoFence", "breachReturn"), [47.0, 8.0]), "geoFence.breachReturn"),
    ("2-vertex polygon", lambda d: d["geoFence"]["polygons"][0]["polygon"].pop(), "polygon"),
    ("radius 0", _set(("geoFence", "circles", 0, "circle", "radius"), 0), "radius"),
    ("duplicate doJumpId", _set(("mission", "items", 3, "doJumpId"), 2), "items[3].doJumpId"),
    ("doJumpId 0", _set(("mission", "items", 3, "doJumpId"), 0), "items[3].doJumpId"),
    ("doJumpId -4", _set(("mission", "items", 3, "doJumpId"), -4), "items[3].doJumpId"),
    ("doJumpId 1.5", _set(("mission", "items", 3, "doJumpId"), 1.5), "items[3].doJumpId"),
    ("DO_JUMP nowhere", _set(("mission", "items", 4, "params", 0), 99), "items[4].params[0]"),
    ("command 1e6", _set(("mission", "items", 1, "command"), 10**6), "items[1].command"),
    ("frame 2.5", _set(("mission", "items", 1, "frame"), 2.5), "items[1].frame"),
    ("firmwareType -1", _set(("mission", "firmwareType"), -1), "mission.firmwareType"),
    ("hoverSpeed 0", _set(("mission", "hoverSpeed"), 0), "mission.hoverSpeed"),
    ("altitude mode 9", _set(("mission", "globalPlanAltitudeMode"), 9), "globalPlanAltitudeMode"),
    ("unknown item type", _set(("mission", "items", 2, "type"), "Foo"), "items[2].type"),
    (
        "unknown complex type",
        _set(("mission", "items", 2), {"type": "ComplexItem", "complexItemType": "orbit"}),
        "items[2].complexItemType",
    ),
    (
        "survey version 9",
        _set(
            ("mission", "items", 2),
            {"type": "ComplexItem", "complexItemType": "survey", "version": 9},
        ),
        "items[2].version",
    ),
    ("polygon not object", _set(("geoFence", "polygons", 0), [[0, 0]]), "geoFence.polygons[0]"),
    ("root not object", lambda d: None, "<root>"),
]


@pytest.mark.parametrize("change, field", [b[1:] for b in BREAKS], ids=[b[0] for b in BREAKS])
def test_each_break_is_named(change: Callable[[dict[str, Any]], object], field: str) -> None:
    doc: Any = [] if field == "<root>" else _mutated(change)
    problems = qgc_plan_problems(doc)
    assert problems, "the break went unnoticed"
    assert _names(problems, field), problems
    assert all(isinstance(line, str) and "\n" not in line for line in problems)


def test_problem_lines_cite_a_qgc_file() -> None:
    doc = _mutated(lambda d: d["mission"]["items"][1]["params"].pop())
    doc["geoFence"]["polygons"][0]["polygon"].pop()
    problems = qgc_plan_problems(doc)
    assert len(problems) == 2
    assert problems[0].endswith("[MissionItem.cc]") and problems[1].endswith("[QGCMapPolygon.cc]")


def test_every_break_of_a_fixture_is_seen_too() -> None:
    """The same breaks hold on a QGC-written document, not only on ours."""
    base = json.loads((DATA / "qgroundcontrol_sample.plan").read_text())
    for change, field in [
        (lambda d: d["mission"]["items"][1]["params"].pop(), "mission.items[1].params"),
        (lambda d: d["mission"]["items"][0].pop("Altitude"), "mission.items[0].Altitude"),
        (lambda d: d["mission"]["items"][3].update(doJumpId=2), "mission.items[3].doJumpId"),
        (lambda d: d.pop("rallyPoints"), "rallyPoints"),
    ]:
        doc = copy.deepcopy(base)
        change(doc)
        assert _names(qgc_plan_problems(doc), field)
