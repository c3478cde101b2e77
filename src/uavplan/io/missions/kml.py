"""``kml``: the fleet in one KML 2.2 document (Google Earth, QGroundControl's KML import): per
UAV a ``Placemark`` with its path as a ``LineString`` (absolute altitudes, metres above mean
sea level) and its timed flight as a ``gx:Track`` (``when`` = ``options.epoch`` + the plan's
seconds, so Google Earth's time slider plays the fleet), and the scenario's static no-fly zones
as ground polygons. Layout after QGC's own KML export (a Document of Placemarks with styles)."""

from __future__ import annotations

import datetime as dt
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from uavplan.io.atomic import write_bytes_atomic
from uavplan.io.missions import ExportError, Mission, register_exporter, tolerances
from uavplan.io.missions.geojson_file import circle_latlon

KML_NS = "http://www.opengis.net/kml/2.2"
GX_NS = "http://www.google.com/kml/ext/2.2"


def _k(tag: str) -> str:
    return f"{{{KML_NS}}}{tag}"


def _epoch(text: str) -> dt.datetime:
    try:
        t = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise ExportError(f"--epoch {text!r}: not an ISO 8601 time") from None
    return t if t.tzinfo else t.replace(tzinfo=dt.UTC)


def _coords(G: np.ndarray) -> str:
    return " ".join(f"{g[1]:.8f},{g[0]:.8f},{g[2]:.3f}" for g in G)


def kml_bytes(mission: Mission) -> bytes:
    ET.register_namespace("", KML_NS)
    ET.register_namespace("gx", GX_NS)
    t0 = _epoch(mission.options.epoch)
    root = ET.Element(_k("kml"))
    doc = ET.SubElement(root, _k("Document"))
    ET.SubElement(doc, _k("name")).text = mission.plan.scenario or "uavplan"
    ET.SubElement(doc, _k("description")).text = "; ".join(tolerances(mission))
    style = ET.SubElement(doc, _k("Style"), id="nofly")
    ps = ET.SubElement(style, _k("PolyStyle"))
    ET.SubElement(ps, _k("color")).text = "7f0000ff"
    for tr in mission.trajectories():
        G = mission.geodetic(tr.points)
        folder = ET.SubElement(doc, _k("Folder"))
        ET.SubElement(folder, _k("name")).text = tr.id
        when0 = t0 + dt.timedelta(seconds=float(tr.times[0]))
        ET.SubElement(folder, _k("description")).text = (
            f"takes off at t = {float(tr.times[0]):.3f} s "
            f"({when0.isoformat(timespec='milliseconds')})")  # fmt: skip
        pm = ET.SubElement(folder, _k("Placemark"))
        ET.SubElement(pm, _k("name")).text = f"{tr.id} path"
        ls = ET.SubElement(pm, _k("LineString"))
        ET.SubElement(ls, _k("altitudeMode")).text = "absolute"
        ET.SubElement(ls, _k("coordinates")).text = _coords(G)
        pm = ET.SubElement(folder, _k("Placemark"))
        ET.SubElement(pm, _k("name")).text = f"{tr.id} flight"
        track = ET.SubElement(pm, f"{{{GX_NS}}}Track")
        ET.SubElement(track, _k("altitudeMode")).text = "absolute"
        for t in tr.times:
            when = t0 + dt.timedelta(seconds=float(t))
            ET.SubElement(track, _k("when")).text = when.isoformat(timespec="milliseconds")
        for g in G:
            ET.SubElement(track, f"{{{GX_NS}}}coord").text = f"{g[1]:.8f} {g[0]:.8f} {g[2]:.3f}"
    sc = mission.scenario
    if sc is not None:
        shapes = [circle_latlon(mission, c, r) for c, r in mission.discs()]
        shapes += mission.keep_out()[1]
        for P in shapes:
            pm = ET.SubElement(doc, _k("Placemark"))
            ET.SubElement(pm, _k("name")).text = "no-fly zone"
            ET.SubElement(pm, _k("styleUrl")).text = "#nofly"
            poly = ET.SubElement(pm, _k("Polygon"))
            ring = ET.SubElement(ET.SubElement(poly, _k("outerBoundaryIs")), _k("LinearRing"))
            closed = np.vstack([P, P[:1]])
            ET.SubElement(ring, _k("coordinates")).text = " ".join(
                f"{q[1]:.8f},{q[0]:.8f},0" for q in closed)  # fmt: skip
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


@register_exporter("kml", ".kml", "KML 2.2: paths, timed gx:Track flights, no-fly zones (fleet)")
def write_kml(mission: Mission, out: Path) -> list[Path]:
    return [write_bytes_atomic(out, kml_bytes(mission))]
