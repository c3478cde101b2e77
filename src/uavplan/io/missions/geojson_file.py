"""``geojson``: the fleet in one RFC 7946 FeatureCollection: a ``LineString`` per UAV
(``[lon, lat, alt]``, altitude in metres above mean sea level, the times in seconds in
``properties.times_s``), and the scenario's static no-fly zones as ``Polygon`` features (a
cylinder or circle as a 72-gon that contains it, exterior rings counter-clockwise). GIS tools
(QGIS, geojson.io, shapely) read it; the tests validate it with the ``geojson`` library."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from uavplan.io.atomic import write_text_atomic
from uavplan.io.missions import Mission, register_exporter, tolerances

#: sides of the polygon that stands for a no-fly circle (circumscribed: it contains the circle)
CIRCLE_SIDES = 72


def _ring(latlon: np.ndarray) -> list[list[float]]:
    """A closed, counter-clockwise ``[lon, lat]`` ring (RFC 7946 Sect. 3.1.6)."""
    xy = np.column_stack([latlon[:, 1], latlon[:, 0]])
    area = np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1])
    if area < 0:
        xy = xy[::-1]
    ring = np.round(np.vstack([xy, xy[:1]]), 8)
    return ring.tolist()


def circle_latlon(mission: Mission, center: tuple[float, float], radius: float) -> np.ndarray:
    """(CIRCLE_SIDES, 2) [lat, lon] of a polygon around a local circle that contains it."""
    a = np.linspace(0.0, 2 * math.pi, CIRCLE_SIDES, endpoint=False)
    r = radius / math.cos(math.pi / CIRCLE_SIDES)
    pts = np.column_stack([center[0] + r * np.cos(a), center[1] + r * np.sin(a)])
    return mission.geodetic(pts)[:, :2]


def geojson_document(mission: Mission) -> dict[str, Any]:
    features: list[dict[str, Any]] = []
    by_id = {u.id: u for u in mission.plan.uavs}
    for tr in mission.trajectories():
        G = mission.geodetic(tr.points)
        coords = np.column_stack([np.round(G[:, 1], 8), np.round(G[:, 0], 8), np.round(G[:, 2], 3)])
        u = by_id.get(tr.id)
        features.append({
            "type": "Feature",
            "geometry": {"type": "LineString", "coordinates": coords.tolist()},
            "properties": {
                "uav": tr.id,
                "trajectory": mission.options.kind,
                "feasible": u.flown_feasible if u is not None and mission.options.kind == "flown"
                else tr.feasible,
                "altitude": "metres above mean sea level",
                "times_s": np.round(tr.times, 6).tolist(),
                "takeoff_s": round(float(tr.times[0]), 6),
                "execution": dict(mission.plan.execution or {}),
            },
        })  # fmt: skip
    sc = mission.scenario
    if sc is not None:
        for center, radius in mission.discs():
            ring = _ring(circle_latlon(mission, center, radius))
            features.append(
                {
                    "type": "Feature",
                    "geometry": {"type": "Polygon", "coordinates": [ring]},
                    "properties": {"kind": "no-fly circle", "radius_m": radius},
                }
            )
        _, polygons = mission.keep_out()
        for P in polygons:
            features.append({"type": "Feature",
                             "geometry": {"type": "Polygon", "coordinates": [_ring(P)]},
                             "properties": {"kind": "no-fly polygon"}})  # fmt: skip
    return {"type": "FeatureCollection", "features": features,
            "tolerances": tolerances(mission)}  # fmt: skip


@register_exporter("geojson", ".geojson", "RFC 7946 GeoJSON: paths and no-fly zones (fleet)")
def write_geojson(mission: Mission, out: Path) -> list[Path]:
    text = json.dumps(geojson_document(mission), allow_nan=False)
    return [write_text_atomic(out, text + "\n")]
