"""Geodetic origin of a scenario: where its local frame sits on Earth.

A scenario's frame is local metres, x east, y north, z up. :class:`GeoOrigin` ties it to WGS84:
the local point ``(x, y)`` is at latitude ``lat``, longitude ``lon``, and the local height
``z = 0`` is ``alt`` metres above mean sea level, so a point's AMSL altitude is ``alt + z``
(heights are passed through: no geoid or ellipsoid height is involved, as ground stations and
DEMs give heights above mean sea level).

The horizontal conversion is an azimuthal equidistant projection centred on the origin on the
WGS84 ellipsoid (``pyproj``, ``+proj=aeqd``): distances and bearings from the origin are exact,
and a round trip local -> WGS84 -> local is exact to well under a millimetre over 50 km
(tested). A flat-earth conversion (metres per degree at one latitude) is off by tens of metres
at 15 km and is not used. An origin with a ``crs`` (a projected CRS in metres, such as a UTM
zone) makes the local frame that CRS's grid, shifted so that the local point ``(x, y)`` is at
``(lat, lon)``: a projected DEM kept on its own grid, whose positions then convert exactly (its
metres are the projection's: a UTM metre is 0.9996 to 1.001 true metres, and its y axis is grid
north). ``pyproj`` is imported on first use.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


class GeoError(ValueError):
    """An origin that is not a place on Earth."""


@lru_cache(maxsize=16)
def _crs_transformers(crs: str) -> tuple[Any, Any]:
    """(CRS -> WGS84, WGS84 -> CRS), longitude first."""
    from pyproj import CRS, Transformer

    frame = CRS.from_user_input(crs)
    wgs84 = CRS.from_epsg(4326)
    return (
        Transformer.from_crs(frame, wgs84, always_xy=True),
        Transformer.from_crs(wgs84, frame, always_xy=True),
    )


def projected_crs_problem(crs: str) -> str | None:
    """Why ``crs`` cannot be a local frame (not a CRS pyproj knows, not projected, not in
    metres), or None."""
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        c = CRS.from_user_input(crs)
    except CRSError as exc:
        return f"not a coordinate reference system pyproj knows ({exc})"
    if not c.is_projected:
        return f"{c.name} is not a projected CRS (a local frame is in metres)"
    factors = {a.unit_conversion_factor for a in c.axis_info[:2]}
    if factors != {1.0}:
        return f"{c.name} is not in metres"
    return None


@lru_cache(maxsize=64)
def _transformers(lat: float, lon: float) -> tuple[Any, Any]:
    from pyproj import CRS, Transformer

    local = CRS.from_proj4(
        f"+proj=aeqd +lat_0={lat!r} +lon_0={lon!r} +x_0=0 +y_0=0 +datum=WGS84 +units=m +no_defs"
    )
    wgs84 = CRS.from_epsg(4326)
    return (
        Transformer.from_crs(local, wgs84, always_xy=True),
        Transformer.from_crs(wgs84, local, always_xy=True),
    )


@dataclass(frozen=True)
class GeoOrigin:
    """The local frame's tie to WGS84.

    Attributes:
        lat, lon: degrees (WGS84) of the local point ``(x, y)``.
        alt: metres above mean sea level of the local height z = 0.
        x, y: the local point at ``(lat, lon)``, metres (0, 0 by default; a DEM's centre keeps
            the projection's distortion smallest over the map).
        note: where the origin comes from (a DEM's georeference, or a documented choice).
        accuracy: how far, at most, an exported position may lie from where the scenario's
            terrain data puts that local point, metres (0: exact, or no terrain data on
            Earth). A lat/lon DEM laid out flat at its mean latitude (the matplotlib DEMs)
            has a few tens of metres to kilometres; exports warn above 1 m.
        crs: empty for the azimuthal equidistant frame about ``(lat, lon)``; else a projected
            CRS in metres (``"EPSG:32616"``, or WKT) whose grid, shifted, is the local frame.
    """

    lat: float
    lon: float
    alt: float = 0.0
    x: float = 0.0
    y: float = 0.0
    note: str = ""
    accuracy: float = 0.0
    crs: str = ""

    def __post_init__(self) -> None:
        for name in ("lat", "lon", "alt", "x", "y", "accuracy"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise GeoError(f"origin {name}: {v!r} is not a finite number")
            object.__setattr__(self, name, float(v))
        if not -90.0 < self.lat < 90.0:
            raise GeoError(f"origin lat: {self.lat} is not in (-90, 90) degrees")
        if not -180.0 <= self.lon <= 180.0:
            raise GeoError(f"origin lon: {self.lon} is not in [-180, 180] degrees")
        if self.accuracy < 0:
            raise GeoError(f"origin accuracy: {self.accuracy} is negative")
        if self.crs and (why := projected_crs_problem(self.crs)) is not None:
            raise GeoError(f"origin crs: {why}")

    def _crs_origin(self) -> tuple[float, float]:
        """The origin's coordinates in :attr:`crs`."""
        _, from_wgs = _crs_transformers(self.crs)
        X, Y = from_wgs.transform(self.lon, self.lat)
        return float(X), float(Y)

    def to_geodetic(self, points: ArrayLike) -> FloatArray:
        """Local points (n, 2) or (n, 3), metres -> (n, 3) ``[lat, lon, alt AMSL]`` (a 2-D
        point's altitude is the origin's)."""
        P = np.atleast_2d(np.asarray(points, dtype=np.float64))
        if self.crs:
            to_wgs, _ = _crs_transformers(self.crs)
            X0, Y0 = self._crs_origin()
            lon, lat = to_wgs.transform(X0 + (P[:, 0] - self.x), Y0 + (P[:, 1] - self.y))
        else:
            fwd, _ = _transformers(self.lat, self.lon)
            lon, lat = fwd.transform(P[:, 0] - self.x, P[:, 1] - self.y)
        z = P[:, 2] if P.shape[1] > 2 else np.zeros(len(P))
        return np.column_stack([lat, lon, self.alt + z])

    def to_local(self, geodetic: ArrayLike) -> FloatArray:
        """(n, 3) ``[lat, lon, alt AMSL]`` -> local (n, 3) metres."""
        G = np.atleast_2d(np.asarray(geodetic, dtype=np.float64))
        if self.crs:
            _, from_wgs = _crs_transformers(self.crs)
            X0, Y0 = self._crs_origin()
            X, Y = from_wgs.transform(G[:, 1], G[:, 0])
            x, y = np.asarray(X) - X0, np.asarray(Y) - Y0
        else:
            _, inv = _transformers(self.lat, self.lon)
            x, y = inv.transform(G[:, 1], G[:, 0])
        return np.column_stack([x + self.x, y + self.y, G[:, 2] - self.alt])

    def record(self) -> dict[str, Any]:
        """The scenario and plan files' ``origin`` block."""
        out: dict[str, Any] = {"lat": self.lat, "lon": self.lon, "alt": self.alt}
        if self.x or self.y:
            out.update(x=self.x, y=self.y)
        if self.note:
            out["note"] = self.note
        if self.accuracy:
            out["accuracy"] = self.accuracy
        if self.crs:
            out["crs"] = self.crs
        return out

    @classmethod
    def from_record(cls, rec: Any) -> GeoOrigin:
        """The inverse of :meth:`record`; GeoError naming the field on a bad block."""
        if not isinstance(rec, dict):
            raise GeoError(f"origin: {rec!r} is not a mapping with lat, lon, alt")
        unknown = set(rec) - {"lat", "lon", "alt", "x", "y", "note", "accuracy", "crs"}
        if unknown:
            raise GeoError(f"origin: unknown fields {sorted(unknown)}")
        for key in ("lat", "lon"):
            if key not in rec:
                raise GeoError(f"origin {key}: missing")
        return cls(
            rec["lat"], rec["lon"], rec.get("alt", 0.0), rec.get("x", 0.0), rec.get("y", 0.0),
            str(rec.get("note", "")), rec.get("accuracy", 0.0), str(rec.get("crs", "")),
        )  # fmt: skip
