"""``--format wpml``: DJI's waylines archive. Its structure (``wpmz/template.kml`` and
``wpmz/waylines.wpml``), every element DJI WPML requires of the mission, the wayline and each
waypoint, and the waypoints read back: positions, heights above take-off, speeds, holds."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.missions import ExportError, ExportOptions, Mission, get_exporter
from uavplan.io.missions.wpml import DRONES, PASS, STOP
from uavplan.io.plan_file import parse_plan
from uavplan.scenarios import resolve

NS = {"k": "http://www.opengis.net/kml/2.2", "wpml": "http://www.dji.com/wpmz/1.0.2"}


def _doc(speed: float = 8.0) -> dict[str, Any]:
    """Two quadrotors across the SPSO map at ``speed``, 150 m above its ground; uav1 hovers
    6 s at its second point."""
    sc = resolve("quadrotors")
    assert sc.terrain is not None and sc.origin is not None
    uavs = []
    for k, y0 in enumerate((100.0, 300.0)):
        xy = np.array([[100.0, y0], [400.0, y0 + 50], [700.0, y0 + 100]])
        P = np.column_stack([xy, sc.terrain.height(xy[:, 0], xy[:, 1]) + 150.0])
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P[:, :2], axis=0), axis=1)
                                             / speed)])  # fmt: skip
        if k == 1:
            P = np.vstack([P[:2], P[1:2], P[2:]])
            t = np.concatenate([t[:2], [t[1] + 6.0], t[2:] + 6.0])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": t.tolist(),
                     "feasible": True})  # fmt: skip
    return {"format": "uavplan.plan/2", "scenario": "quadrotors", "feasible": True,
            "origin": sc.origin.record(), "uavs": uavs}  # fmt: skip


def _mission(doc: dict[str, Any], **options: Any) -> Mission:
    return Mission(parse_plan(doc), resolve("quadrotors"), ExportOptions(**options))


REQUIRED_CONFIG = ("flyToWaylineMode", "finishAction", "exitOnRCLost", "executeRCLostAction",
                   "takeOffSecurityHeight", "globalTransitionalSpeed",
                   "droneInfo/wpml:droneEnumValue", "droneInfo/wpml:droneSubEnumValue")  # fmt: skip
REQUIRED_POINT = ("index", "waypointSpeed", "waypointHeadingParam/wpml:waypointHeadingMode",
                  "waypointTurnParam/wpml:waypointTurnMode", "useStraightLine")  # fmt: skip


def _text(el: ET.Element, path: str) -> str:
    found = el.find(f"wpml:{path}", NS)
    assert found is not None and found.text is not None, path
    return found.text


def test_the_archive_holds_both_files_with_every_required_element(tmp_path: Path) -> None:
    m = _mission(_doc(), drone="m30t")
    paths = get_exporter("wpml").write(m, tmp_path)
    assert [p.name for p in paths] == ["uav0.kmz", "uav1.kmz"]
    sc = resolve("quadrotors")
    for path, tr in zip(paths, m.trajectories(), strict=True):
        with zipfile.ZipFile(path) as z:
            assert sorted(z.namelist()) == ["wpmz/template.kml", "wpmz/waylines.wpml"]
            docs = {n: ET.fromstring(z.read(f"wpmz/{n}")) for n in ("template.kml",
                                                                   "waylines.wpml")}  # fmt: skip
        for name, root in docs.items():
            cfg = root.find("k:Document/wpml:missionConfig", NS)
            assert cfg is not None
            for field in REQUIRED_CONFIG:
                _text(cfg, field)
            assert (_text(cfg, "droneInfo/wpml:droneEnumValue"),
                    _text(cfg, "droneInfo/wpml:droneSubEnumValue")) == tuple(
                        str(v) for v in DRONES["m30t"])  # fmt: skip
            assert _text(cfg, "finishAction") == "autoLand"
            folder = root.find("k:Document/k:Folder", NS)
            assert folder is not None and _text(folder, "templateId") == "0"
            marks = folder.findall("k:Placemark", NS)
            assert [int(_text(p, "index")) for p in marks] == list(range(len(marks)))
            for p in marks:
                for field in REQUIRED_POINT:
                    _text(p, field)
            if name == "waylines.wpml":
                assert _text(folder, "executeHeightMode") == "relativeToStartPoint"
                _text(folder, "waylineId"), _text(folder, "autoFlightSpeed")
                heights = [float(_text(p, "executeHeight")) for p in marks]
            else:
                assert _text(folder, "templateType") == "waypoint"
                sys_ = "waylineCoordinateSysParam/wpml:"
                assert _text(folder, sys_ + "heightMode") == "relativeToStartPoint"
                assert _text(folder, sys_ + "coordinateMode") == "WGS84"
                for p in marks:  # useGlobalHeight 0: both heights required
                    assert _text(p, "ellipsoidHeight") == _text(p, "height")
        # read back: where the waypoints are, how high above the take-off point
        wl = docs["waylines.wpml"].find("k:Document/k:Folder", NS)
        assert wl is not None
        lonlat = [p.find("k:Point/k:coordinates", NS).text for p in wl.findall("k:Placemark", NS)]  # type: ignore[union-attr]
        geo = np.array([[float(c.split(",")[1]), float(c.split(",")[0]), 0.0] for c in lonlat])
        local = m.origin.to_local(geo)
        P = np.unique(tr.points, axis=0, return_index=True)[1]
        want = tr.points[np.sort(P)]
        assert local[:, :2] == pytest.approx(want[:, :2], abs=0.01)
        ground0 = float(sc.terrain.height(*want[0, :2]))  # type: ignore[union-attr]
        assert heights == pytest.approx(want[:, 2] - ground0, abs=0.001)


def test_speeds_and_holds(tmp_path: Path) -> None:
    m = _mission(_doc(speed=8.0))
    path = get_exporter("wpml").write(m, tmp_path)[1]  # uav1 hovers at its second point
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("wpmz/waylines.wpml"))
    marks = root.findall("k:Document/k:Folder/k:Placemark", NS)
    assert [float(_text(p, "waypointSpeed")) for p in marks[:-1]] == pytest.approx([8.0, 8.0])
    modes = [_text(p, "waypointTurnParam/wpml:waypointTurnMode") for p in marks]
    assert modes == [PASS, STOP, STOP]  # through the first, stopping to hover, and at the end
    action = marks[1].find("wpml:actionGroup/wpml:action", NS)
    assert action is not None and _text(action, "actionActuatorFunc") == "hover"
    assert float(_text(action, "actionActuatorFuncParam/wpml:hoverTime")) == pytest.approx(6.0)
    assert marks[0].find("wpml:actionGroup", NS) is None


def test_what_a_dji_aircraft_cannot_fly_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ExportError, match="DJI's waylines fly 1-15 m/s"):
        get_exporter("wpml").write(_mission(_doc(speed=20.0)), tmp_path)
    fixed = Mission(parse_plan(_doc()), resolve("ppswarm1"), ExportOptions())
    with pytest.raises(ExportError, match="fixed wing"):
        get_exporter("wpml").write(fixed, tmp_path)


def test_the_command_writes_kmz_and_refuses_an_unknown_drone(tmp_path: Path) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(_doc()))
    r = CliRunner().invoke(app, ["export", str(plan), "--format", "wpml", "--drone", "m3t"])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "wpml").iterdir()) == [
        "launch.csv", "uav0.kmz", "uav1.kmz"]  # fmt: skip
    r = CliRunner().invoke(app, ["export", str(plan), "--format", "wpml", "--drone", "x9"])
    assert r.exit_code == 2 and "--drone 'x9'" in r.output
