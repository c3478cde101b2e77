"""Static obstacles and areas. Frame: x east, y north, z up, metres.

* :class:`Circle`, :class:`Polygon`: 2-D obstacles of the RGG-PSO+ scenes (Liu et al. 2024,
  Sect. 5.2.1); in a 3-D world they act as infinitely tall prisms.
* :class:`Cylinder`: a vertical cylinder threat (PPSwarm Sect. 2.2; SPSO treats them as infinitely
  tall), optionally finite between ``z_min`` and ``z_max`` (absolute metres).
* :class:`DangerArea`: a cylindrical area that may be crossed at a cost (HR-MAGA Eq. 1).
* :class:`UncertainArea`: a rectangle known only when revealed (HR-MAGA Eq. 2); once revealed it is
  a no-fly area.
* :class:`AltitudeBand`: allowed altitudes, above ground or absolute.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def _xy(value: object, what: str) -> tuple[float, float]:
    arr = np.asarray(value, dtype=np.float64).ravel()
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} must be two finite numbers, got {value!r}")
    return float(arr[0]), float(arr[1])


@dataclass(frozen=True)
class Circle:
    """A disc obstacle. ``margin`` is added to the radius for collision checks."""

    center: tuple[float, float]
    radius: float
    margin: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _xy(self.center, "circle center"))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"circle radius must be positive, got {self.radius}")
        if not (np.isfinite(self.margin) and self.margin >= 0):
            raise ValueError(f"circle margin must be >= 0, got {self.margin}")

    @property
    def effective_radius(self) -> float:
        return self.radius + self.margin

    def contains(self, points: FloatArray) -> NDArray[np.bool_]:
        p = np.asarray(points, dtype=np.float64)
        d = np.hypot(p[..., 0] - self.center[0], p[..., 1] - self.center[1])
        return np.asarray(d < self.effective_radius)


@dataclass(frozen=True)
class Polygon:
    """A simple polygon (convex or not), vertices (k, 2) in order, k >= 3.

    ``margin``: a path must keep at least this distance from the polygon.
    """

    vertices: tuple[tuple[float, float], ...]
    margin: float = 0.0

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise ValueError(f"a polygon needs at least 3 vertices of 2 numbers, got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError("polygon vertices must be finite")
        if abs(self._signed_area(v)) <= 0:
            raise ValueError("polygon has zero area")
        object.__setattr__(self, "vertices", tuple((float(a), float(b)) for a, b in v))
        if not (np.isfinite(self.margin) and self.margin >= 0):
            raise ValueError(f"polygon margin must be >= 0, got {self.margin}")

    @staticmethod
    def _signed_area(v: FloatArray) -> float:
        x, y = v[:, 0], v[:, 1]
        return float(0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))

    @property
    def array(self) -> FloatArray:
        return np.asarray(self.vertices, dtype=np.float64)

    def contains(self, points: FloatArray) -> NDArray[np.bool_]:
        from uavplan.world.geometry import point_in_polygon

        return point_in_polygon(points, self.array)


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder threat: axis at ``center``, ``radius``, between ``z_min`` and ``z_max``
    (absolute metres; infinite by default, as SPSO treats threats). ``margin`` widens it for
    collision checks (SPSO's drone size)."""

    center: tuple[float, float]
    radius: float
    z_min: float = -np.inf
    z_max: float = np.inf
    margin: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _xy(self.center, "cylinder center"))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"cylinder radius must be positive, got {self.radius}")
        if np.isnan(self.z_min) or np.isnan(self.z_max) or self.z_max <= self.z_min:
            raise ValueError(f"cylinder needs z_min < z_max, got {self.z_min}, {self.z_max}")
        if not (np.isfinite(self.margin) and self.margin >= 0):
            raise ValueError(f"cylinder margin must be >= 0, got {self.margin}")

    @property
    def effective_radius(self) -> float:
        return self.radius + self.margin

    @property
    def infinite(self) -> bool:
        return bool(np.isinf(self.z_min) and np.isinf(self.z_max))


@dataclass(frozen=True)
class DangerArea:
    """HR-MAGA Eq. (1): a cylindrical danger area ``(x, y, d)``, crossing it costs its length."""

    center: tuple[float, float]
    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _xy(self.center, "danger area center"))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"danger area radius must be positive, got {self.radius}")


@dataclass(frozen=True)
class UncertainArea:
    """HR-MAGA Eq. (2): a rectangle from ``(x, y)`` of ``width`` x ``height`` (metres).

    ``revealed``: whether the planner knows about it. A revealed area is a no-fly area;
    HR-MAGA reveals them on its finer map levels.
    """

    x: float
    y: float
    width: float
    height: float
    revealed: bool = True
    #: how far a path must keep from it once revealed, metres (a robust plan's tracking error)
    margin: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "width", "height"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"uncertain area {name} must be finite")
        if self.width <= 0 or self.height <= 0:
            raise ValueError(
                f"uncertain area width and height must be positive, got {self.width}, {self.height}"
            )
        if not (self.x + self.width > self.x and self.y + self.height > self.y):
            raise ValueError(
                f"uncertain area {self.width:g} x {self.height:g} m at ({self.x:g}, {self.y:g}) "
                "is too small to have an area in float64"
            )

    def as_polygon(self) -> Polygon:
        x, y, w, h = self.x, self.y, self.width, self.height
        return Polygon(((x, y), (x + w, y), (x + w, y + h), (x, y + h)), self.margin)


@dataclass(frozen=True)
class AltitudeBand:
    """Allowed altitudes ``[min, max]`` metres, ``reference`` ``"ground"`` (above the terrain) or
    ``"absolute"``. PPSwarm Eq. (7) and SPSO both use such a band."""

    min: float
    max: float
    reference: Literal["ground", "absolute"] = "ground"

    def __post_init__(self) -> None:
        if np.isnan(self.min) or np.isnan(self.max) or self.max <= self.min:
            raise ValueError(f"altitude band needs min < max, got {self.min}, {self.max}")
        if self.reference not in ("ground", "absolute"):
            raise ValueError(f"altitude reference must be ground or absolute, got {self.reference}")

    @property
    def mid(self) -> float:
        return 0.5 * (self.min + self.max)
