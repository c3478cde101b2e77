"""Mission export (issue 16): geo-referencing with pyproj and every format read back by a real
consumer: pymavlink's MAVWPLoader (WPL), our check of QGC's loader rules (.plan), the
``geojson`` library (GeoJSON), an XML parser with the KML namespace (KML)."""

from __future__ import annotations

import json
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import geojson
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pymavlink import mavwp
from pyproj import Geod
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.missions import ExportError, ExportOptions, Mission, get_exporter
from uavplan.io.plan_file import parse_plan
from uavplan.io.scenario_file import load_scenario, save_scenario
from uavplan.scenarios import resolve
from uavplan.world.geo import GeoError, GeoOrigin

runner = CliRunner()
GEOD = Geod(ellps="WGS84")


# ------------------------------------------------------------------------------ geo-referencing
@settings(max_examples=60, deadline=None)
@given(
    lat=st.floats(-80, 80), lon=st.floats(-180, 180),
    x=st.floats(-50e3, 50e3), y=st.floats(-50e3, 50e3), z=st.floats(-500, 9000),
)  # fmt: skip
def test_geo_round_trip_within_a_millimetre_over_50_km(lat, lon, x, y, z) -> None:  # type: ignore[no-untyped-def]
    o = GeoOrigin(lat, lon, 123.0, 10.0, -20.0)
    P = np.array([[x, y, z]])
    G = o.to_geodetic(P)
    assert G[0, 2] == pytest.approx(123.0 + z)
    assert np.abs(o.to_local(G) - P).max() < 1e-3
    # azimuthal equidistant: the geodesic distance from the origin is the local radius
    _, _, d = GEOD.inv(lon, lat, G[0, 1], G[0, 0])
    assert d == pytest.approx(math.hypot(x - 10.0, y + 20.0), abs=1e-3)


def test_flat_earth_would_be_tens_of_metres_off_at_15_km() -> None:
    """The reason for pyproj: metres-per-degree at the origin's latitude misses by > 10 m."""
    o = GeoOrigin(60.0, 10.0)
    G = o.to_geodetic([[15e3, 15e3, 0.0]])
    flat_lat = 60.0 + 15e3 / 111_320.0
    flat_lon = 10.0 + 15e3 / (111_320.0 * math.cos(math.radians(60.0)))
    _, _, miss = GEOD.inv(flat_lon, flat_lat, G[0, 1], G[0, 0])
    assert miss > 10.0


@pytest.mark.parametrize(
    "rec, field",
    [({"lat": 91, "lon": 0}, "lat"), ({"lat": 0, "lon": 181}, "lon"),
     ({"lat": float("nan"), "lon": 0}, "lat"), ({"lon": 0}, "lat"),
     ({"lat": 0, "lon": 0, "up": 1}, "unknown"),
     ({"lat": 0, "lon": 0, "accuracy": -1}, "accuracy")],
)  # fmt: skip
def test_bad_origins_name_the_field(rec: dict[str, Any], field: str) -> None:
    with pytest.raises(GeoError, match=field):
        GeoOrigin.from_record(rec)


def test_builtin_scenarios_have_documented_origins_and_files_keep_them(tmp_path: Path) -> None:
    for name in ("spso", "ppswarm1", "jacksboro", "topobathy", "rscdwoa-mixed", "hrmaga-virtual"):
        o = resolve(name).origin
        assert o is not None and o.note, name
    assert resolve("jacksboro").origin.accuracy > 1  # type: ignore[union-attr]
    assert resolve("simple2d").origin is None
    sc = resolve("jacksboro")
    path = save_scenario(sc, tmp_path / "j.yaml")
    assert load_scenario(path).origin == sc.origin


def test_the_jacksboro_origin_is_the_dems_centre() -> None:
    """The DEM's centre node lands on its own latitude/longitude (matplotlib's georeference)."""
    from matplotlib import cbook

    d: Any = cbook.get_sample_data("jacksboro_fault_dem.npz")
    ny, nx = d["elevation"].shape
    sc = resolve("jacksboro")
    t, o = sc.terrain, sc.origin
    assert t is not None and o is not None
    G = o.to_geodetic([[(nx - 1) / 2 * t.dx, (ny - 1) / 2 * t.dy, 0.0]])[0]
    assert G[0] == pytest.approx(float(d["ymax"]) + (ny - 1) / 2 * float(d["dy"]), abs=1e-6)
    assert G[1] == pytest.approx(float(d["xmin"]) + (nx - 1) / 2 * float(d["dx"]), abs=1e-6)


# ----------------------------------------------------------------------------- a plan to export
def _plan_doc(feasible: bool = True) -> dict[str, Any]:
    """Three UAVs across the SPSO map at 20 m/s, 150 m above its ground; uav1 waits 5 s at its
    second point and then flies at 15 m/s; uav2 departs at t = 10 s."""
    sc = resolve("ppswarm1")
    assert sc.terrain is not None and sc.origin is not None
    uavs = []
    for k, (y0, t0) in enumerate([(100.0, 0.0), (300.0, 0.0), (500.0, 10.0)]):
        xy = np.array([[100.0, y0], [400.0, y0 + 50], [700.0, y0 + 100], [900.0, y0 + 120]])
        z = sc.terrain.height(xy[:, 0], xy[:, 1]) + 150.0
        P = np.column_stack([xy, z])
        seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
        times = t0 + np.concatenate([[0.0], np.cumsum(seg / 20.0)])
        if k == 1:  # a wait of 5 s at the second point, then 15 m/s
            P = np.vstack([P[:2], P[1:2], P[2:]])
            rest = np.cumsum(seg[1:] / 15.0)
            times = np.concatenate([times[:2], [times[1] + 5.0], times[1] + 5.0 + rest])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": times.tolist(),
                     "feasible": feasible})  # fmt: skip
    return {"format": "uavplan.plan/2", "scenario": "ppswarm1", "feasible": feasible,
            "origin": sc.origin.record(), "uavs": uavs}  # fmt: skip


@pytest.fixture
def plan_json(tmp_path: Path) -> Path:
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(_plan_doc()))
    return path


def _mission(**options: Any) -> Mission:
    return Mission(parse_plan(_plan_doc()), resolve("ppswarm1"), ExportOptions(**options))


# ------------------------------------------------------------------------------------ the formats
def test_wpl_reads_back_with_pymavlink(tmp_path: Path) -> None:
    m = _mission()
    paths = get_exporter("wpl").write(m, tmp_path)
    assert [p.name for p in paths] == ["uav0.waypoints", "uav1.waypoints", "uav2.waypoints"]
    for path, tr in zip(paths, m.trajectories(), strict=True):
        lines = path.read_text().splitlines()
        assert lines[0] == "QGC WPL 110"
        assert all(len(line.split("\t")) == 12 for line in lines[1:])
        loader = mavwp.MAVWPLoader()
        n = loader.load(str(path))
        items = [loader.wp(i) for i in range(n)]
        home = m.home(tr)
        assert items[0].seq == 0 and items[0].command == 16
        assert (items[0].x, items[0].y, items[0].z) == pytest.approx(tuple(home), abs=1e-3)
        assert items[1].command == 22 and items[-1].command == 21
        wps = [it for it in items[1:] if it.command == 16]
        G = m.geodetic(tr.points)
        keep = np.r_[True, np.linalg.norm(np.diff(tr.points, axis=0), axis=1) > 1e-9]
        G = G[keep]  # a wait is the previous waypoint's hold time, not a point
        got = np.array([[w.x, w.y, w.z] for w in wps])
        assert got.shape == G.shape
        assert np.abs(got[:, :2] - G[:, :2]).max() < 1e-7  # pymavlink keeps 8 decimals here
        assert np.abs(got[:, 2] - G[:, 2]).max() < 1e-3
        speeds = [it.param2 for it in items if it.command == 178]
        # ground speeds are horizontal (MAV_CMD_DO_CHANGE_SPEED's): a little under the 3-D
        # 20 and 15 m/s where the path climbs over the terrain
        hs = np.linalg.norm(np.diff(tr.points[:, :2], axis=0), axis=1) / np.diff(tr.times)
        assert speeds[0] == pytest.approx(hs[0], rel=1e-6) and hs[0] < 20.0
        if tr.id == "uav1":
            assert [w.param1 for w in wps][1] == pytest.approx(5.0)
            assert speeds == pytest.approx([20.0, 15.0], rel=0.01)
            # each speed right after the waypoint its leg starts from: WP0 20 WP1(hold) 15 WP2
            cmds = [it.command for it in items[1:]]
            assert cmds[:6] == [22, 16, 178, 16, 178, 16]
        else:
            assert all(s == pytest.approx(20.0, rel=0.02) for s in speeds)


def test_qgc_plans_pass_qgcs_loader_rules(tmp_path: Path) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    from qgc_plan_check import qgc_plan_problems

    m = _mission()
    for path in get_exporter("qgc").write(m, tmp_path):
        text = path.read_text()
        assert "NaN" not in text and "Infinity" not in text
        doc = json.loads(text)
        assert qgc_plan_problems(doc) == []
        mission = doc["mission"]
        cruise = 15.0 if path.stem == "uav1" else 20.0  # the median planned speed
        assert mission["cruiseSpeed"] == pytest.approx(cruise, rel=0.02)  # ground speed: horizontal
        assert qgc_plan_problems(doc, strict=True) == []
        cmds = [it["command"] for it in mission["items"]]
        assert cmds[0] == 22 and cmds[-1] == 21 and cmds.count(16) >= 4
        assert all(it["frame"] == 0 for it in mission["items"] if it["command"] == 16)  # AMSL
        assert mission["items"][0]["params"][3] is None  # yaw NaN -> null
    fence = doc["geoFence"]
    sc = resolve("ppswarm1")
    assert len(fence["circles"]) == len(sc.cylinders) and fence["polygons"] == []
    assert doc["rallyPoints"] == {"version": 2, "points": []}


@pytest.mark.parametrize("frame, code", [("relative", 3), ("terrain", 10)])
def test_altitude_frames(frame: str, code: int) -> None:
    m = _mission(frame=frame)
    tr = m.trajectories()[0]
    items = [it for it in m.items(tr) if it.command == 16]
    assert {it.frame for it in items} == {code}
    alts = np.array([it.params[6] for it in items])
    if frame == "terrain":
        assert alts == pytest.approx(150.0, abs=1e-6)  # the fixture flies 150 m above ground
    else:
        assert alts[0] == pytest.approx(150.0, abs=1e-6)  # above home, the ground at the start


def test_terrain_frame_needs_a_terrain() -> None:
    m = Mission(parse_plan(_plan_doc()), None, ExportOptions(frame="terrain"))
    with pytest.raises(ExportError, match="terrain"):
        m.items(m.trajectories()[0])


def test_geojson_validates_and_is_lon_lat(tmp_path: Path) -> None:
    m = _mission()
    (path,) = get_exporter("geojson").write(m, tmp_path / "f.geojson")
    obj = geojson.loads(path.read_text())
    assert obj.is_valid, obj.errors()
    lines = [f for f in obj["features"] if f["geometry"]["type"] == "LineString"]
    assert len(lines) == 3
    first = lines[0]["geometry"]["coordinates"][0]
    G = m.geodetic(m.trajectories()[0].points[:1])[0]
    assert first == pytest.approx([G[1], G[0], G[2]], abs=1e-3)  # altitudes to the millimetre
    assert len(lines[0]["properties"]["times_s"]) == len(lines[0]["geometry"]["coordinates"])
    polys = [f for f in obj["features"] if f["geometry"]["type"] == "Polygon"]
    assert len(polys) == len(resolve("ppswarm1").cylinders)
    ring = np.array(polys[0]["geometry"]["coordinates"][0])
    assert (ring[0] == ring[-1]).all()
    area = np.sum(ring[:-1, 0] * ring[1:, 1] - ring[1:, 0] * ring[:-1, 1])
    assert area > 0  # exterior ring counter-clockwise (RFC 7946)


def test_kml_parses_with_its_namespace_and_times(tmp_path: Path) -> None:
    m = _mission(epoch="2026-12-02T10:00:00Z")
    (path,) = get_exporter("kml").write(m, tmp_path / "f.kml")
    root = ET.parse(path).getroot()
    ns = {"k": "http://www.opengis.net/kml/2.2", "gx": "http://www.google.com/kml/ext/2.2"}
    assert root.tag == "{http://www.opengis.net/kml/2.2}kml"
    tracks = root.findall(".//gx:Track", ns)
    assert len(tracks) == 3
    whens = [w.text for w in tracks[2].findall("k:when", ns)]
    assert len(whens) == len(tracks[2].findall("gx:coord", ns))
    assert whens[0] == "2026-12-02T10:00:10.000+00:00"  # uav2 departs at t = 10 s
    assert len(root.findall(".//k:Polygon", ns)) == len(resolve("ppswarm1").cylinders)


# ------------------------------------------------------------------------------------ the command
def test_export_command_writes_every_format(plan_json: Path, tmp_path: Path) -> None:
    for fmt in ("qgc", "wpl", "geojson", "kml", "csv"):
        r = runner.invoke(app, ["export", str(plan_json), "--format", fmt])
        assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "qgc").iterdir()) == [
        "launch.csv", "uav0.plan", "uav1.plan", "uav2.plan"]  # fmt: skip
    launch = (tmp_path / "qgc" / "launch.csv").read_text().splitlines()
    assert launch[0].split(",")[0] == "uav" and len(launch) == 4
    assert (tmp_path / "plan.geojson").exists() and (tmp_path / "plan.kml").exists()
    r = runner.invoke(app, ["export", str(plan_json), "--format", "qgc"])
    assert "take-off climb" in r.output and "take-off times are in" in r.output
    assert "must take off at its planned second" in r.output  # a nominal plan tolerates nothing


def test_a_single_file_format_writes_into_an_existing_folder(
    plan_json: Path, tmp_path: Path
) -> None:
    """``--out DIR`` naming a folder that exists: the file goes inside it, as ``cp`` does."""
    folder = tmp_path / "exports"
    folder.mkdir()
    r = runner.invoke(app, ["export", str(plan_json), "--format", "geojson", "--out", str(folder)])
    assert r.exit_code == 0, r.output
    assert (folder / "plan.geojson").is_file() and f"wrote {folder / 'plan.geojson'}" in r.output


def test_export_without_origin_says_how_to_add_one(tmp_path: Path) -> None:
    doc = _plan_doc()
    del doc["origin"]
    doc["scenario"] = "not-a-builtin"
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    r = runner.invoke(app, ["export", str(path), "--format", "qgc"])
    assert r.exit_code == 2 and "no geodetic origin" in r.output and "origin: {lat" in r.output
    assert "Traceback" not in r.output
    assert not (tmp_path / "qgc").exists() or not any((tmp_path / "qgc").iterdir())
    r = runner.invoke(app, ["export", str(path), "--format", "wpl", "--origin", "-32.2,148.2,240"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["export", str(path), "--format", "wpl", "--origin", "95,0"])
    assert r.exit_code == 2 and "lat" in r.output
    r = runner.invoke(app, ["export", str(path), "--format", "wpl", "--frame", "up"])
    assert r.exit_code == 2 and "--frame" in r.output


def test_approximate_georeference_is_said_loudly(tmp_path: Path) -> None:
    doc = _plan_doc()
    doc["origin"] = {**doc["origin"], "accuracy": 78.0, "note": "a flat DEM"}
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    r = runner.invoke(app, ["export", str(path), "--format", "geojson"])
    assert r.exit_code == 0 and "up to 78 m" in r.output


def test_an_infeasible_plan_exports_but_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(_plan_doc(feasible=False)))
    r = runner.invoke(app, ["export", str(path), "--format", "qgc"])
    assert r.exit_code == 1 and "do not fly it" in r.output
