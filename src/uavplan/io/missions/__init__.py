"""Mission export formats, one module each, found by name (``uavplan export --format NAME``).

An exporter gets a :class:`Mission` (the typed plan file, the scenario when known, the export
options, and the geodetic conversions of :mod:`uavplan.world.geo`) and writes one file for the
fleet, or one file per UAV where the format holds a single vehicle, and returns the paths
written; what the user must know (an approximate georeference, legs outside the verified
trajectory) it appends to ``mission.warnings`` for the CLI to print. A new format is a new
module here that decorates its function with :func:`register_exporter` (every module here is
imported).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import PlanFile, Trajectory, TrajectoryKind
from uavplan.world.geo import GeoOrigin

if TYPE_CHECKING:
    from uavplan.world.scenario import Scenario

FloatArray = NDArray[np.float64]
#: Altitude reference of exported waypoints: above mean sea level, above the home position
#: (the ground under the UAV's start), or above the terrain under each point.
AltitudeFrame = Literal["amsl", "relative", "terrain"]
#: What a single-vehicle mission does after its last waypoint.
MissionEnd = Literal["land", "rtl", "none"]
#: Above this many metres of georeference error (``GeoOrigin.accuracy``) an export warns.
ACCURACY_WARNING_M = 1.0
#: The default most items of a per-vehicle mission (PX4's dataman RAM backend holds 500).
MAX_ITEMS = 500
#: The thinning tolerances tried, metres, smallest first: a per-vehicle mission keeps the
#: fewest waypoints of the dense flown trajectory that stay within the first tolerance that
#: fits ``max_items`` (its deviation is time-aware, so the thinned mission is within it at
#: every instant, not only in space).
THIN_STEPS = (0.25, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0)


class ExportError(ValueError):
    """An unknown format, or a plan the format cannot hold."""


@dataclass(frozen=True)
class ExportOptions:
    """What to export and how: which trajectory (the flown one by default: the one the plan
    declares and the verifier checks), the altitude frame, the mission's end, the autopilot
    and vehicle type written into ground-station files, and the UTC time of the plan's t = 0
    for formats with absolute times (KML)."""

    kind: TrajectoryKind = "flown"
    frame: AltitudeFrame = "amsl"
    end: MissionEnd = "land"
    firmware: Literal["px4", "ardupilot", "generic"] = "px4"
    vehicle: Literal["auto", "fixed-wing", "multirotor"] = "auto"
    epoch: str = "2000-01-01T00:00:00Z"
    #: the most MAVLink items a per-vehicle mission may hold (PX4 stores 500 on its RAM
    #: backend; ArduPilot about 700 on a Pixhawk without SD storage: docs/decisions.md)
    max_items: int = MAX_ITEMS
    #: the DJI aircraft a ``wpml`` export names (:data:`uavplan.io.missions.wpml.DRONES`)
    drone: str = "m3e"


@dataclass(eq=False)
class Mission:
    """A plan on its way out: the plan file, its scenario (None when unknown: no geofence, no
    terrain frame), the options and the warnings gathered while writing."""

    plan: PlanFile
    scenario: Scenario | None = None
    options: ExportOptions = field(default_factory=ExportOptions)
    warnings: list[str] = field(default_factory=list)
    _keep_out: tuple[list[tuple[float, float, float]], list[FloatArray]] | None = field(
        default=None, init=False, repr=False
    )
    _trajectories: list[Trajectory] | None = field(default=None, init=False, repr=False)
    #: per UAV: what its per-vehicle mission holds (items, thinning deviation, take-off time)
    report: dict[str, dict[str, float]] = field(default_factory=dict)

    def trajectories(self) -> list[Trajectory]:
        if self._trajectories is None:
            self._trajectories = self.plan.trajectories(self.options.kind)
        return self._trajectories

    @property
    def origin(self) -> GeoOrigin:
        """The plan's recorded origin, else its scenario's; ExportError saying how to add one."""
        origin = self.plan.origin or (self.scenario.origin if self.scenario else None)
        if origin is None:
            name = self.plan.scenario or "the plan's scenario"
            t = self.scenario.terrain if self.scenario is not None else None
            dem = ""
            if t is not None and "epsg" not in t.georef and "srtm" not in t.georef:
                dem = f" (its DEM {t.name!r} has no georeference of its own)"
            raise ExportError(
                f"{self.plan.source}: scenario {name!r} has no geodetic origin{dem}; add one to "
                "the scenario file (origin: {lat: DEG, lon: DEG, alt: M_AMSL_OF_Z0}), plan "
                "again, or pass --origin LAT,LON,ALT"
            )
        return origin

    def check_accuracy(self) -> None:
        """Warn once when the georeference is approximate (a lat/lon DEM laid out flat)."""
        acc = self.origin.accuracy
        msg = (f"georeference is approximate: an exported position may lie up to {acc:,.0f} m "
               f"from where the scenario's terrain puts it ({self.origin.note}); check the "
               "mission against a real DEM before flight")  # fmt: skip
        if acc > ACCURACY_WARNING_M and msg not in self.warnings:
            self.warnings.append(msg)

    def ground(self, xy: FloatArray) -> FloatArray:
        """Local ground height under (n, 2) points: the terrain, or z = 0 without one."""
        t = self.scenario.terrain if self.scenario is not None else None
        if t is None:
            return np.zeros(len(xy))
        return np.asarray(t.height(xy[:, 0], xy[:, 1]), dtype=np.float64)

    def geodetic(self, points: FloatArray) -> FloatArray:
        """(n, 3) ``[lat, lon, alt AMSL]`` of local points (2-D: at the origin's altitude)."""
        self.check_accuracy()
        return self.origin.to_geodetic(points)

    def home(self, tr: Trajectory) -> FloatArray:
        """``[lat, lon, alt AMSL]`` of the ground under the trajectory's start."""
        p = np.array(tr.points[:1, :2], dtype=np.float64)
        return self.geodetic(np.column_stack([p, self.ground(p)]))[0]

    def altitudes(self, tr: Trajectory, points: FloatArray | None = None) -> FloatArray:
        """The points' (default: the trajectory's) altitudes in the options' frame, metres."""
        P = tr.points if points is None else points
        if P.shape[1] < 3:
            raise ExportError(f"{self.plan.source}: a 2-D plan has no altitudes for a mission")
        z = np.asarray(P[:, 2], dtype=np.float64)
        if self.options.frame == "amsl":
            return self.origin.alt + z
        if self.options.frame == "relative":
            return z - float(self.ground(tr.points[:1, :2])[0])
        if self.scenario is None or self.scenario.terrain is None:
            raise ExportError(
                f"{self.plan.source}: --frame terrain needs the scenario's terrain (give "
                "SCENARIO; this plan's scenario has none)"
            )
        return z - self.ground(P[:, :2])

    def segment_speeds(self, tr: Trajectory) -> FloatArray:
        """Ground speed over each segment, m/s: horizontal, as ``MAV_CMD_DO_CHANGE_SPEED``'s
        ground speed is (ArduCopter's WPNAV_SPEED and PX4's cruise speed are horizontal, a
        climb's rate is the autopilot's own); 0 where the UAV waits or only climbs."""
        d = np.linalg.norm(np.diff(tr.points[:, :2], axis=0), axis=1)
        dt = np.diff(tr.times)
        return np.where(dt > 0, d / np.where(dt > 0, dt, 1.0), 0.0)

    def items(self, tr: Trajectory) -> list[MissionItem]:
        """The MAVLink mission of one UAV after its home (:meth:`_items`) of the trajectory
        thinned to the fewest waypoints within the smallest of :data:`THIN_STEPS` that fits
        ``options.max_items``; records the thinning's deviation in :attr:`report`."""
        from uavplan.world.reservations import simplify_timed

        P = np.asarray(tr.points, dtype=np.float64)
        T = np.asarray(tr.times, dtype=np.float64)
        out: list[MissionItem] = []
        dev = 0.0
        for tol in THIN_STEPS:
            if len(P) > 2:
                keep, pad = simplify_timed(P, T, tol, 4096)
            else:
                keep, pad = np.arange(len(P)), np.zeros(0)
            thin = Trajectory(tr.id, P[keep], T[keep], tr.feasible)
            out = self._items(thin)
            dev = float(pad.max()) if pad.size else 0.0
            if len(out) <= self.options.max_items:
                break
        else:
            raise ExportError(
                f"{self.plan.source}: {tr.id}: {len(out)} mission items even thinned "
                f"{THIN_STEPS[-1]:g} m off its trajectory, above --max-items "
                f"{self.options.max_items}"
            )
        self.report[tr.id] = {"items": float(len(out)), "thinning_m": dev,
                              "takeoff_s": float(T[0]), "waypoints": float(len(keep))}  # fmt: skip
        return out

    def _items(self, tr: Trajectory) -> list[MissionItem]:
        """The MAVLink mission of one UAV after its home: take-off at the start, a waypoint per
        point of the trajectory (a wait becomes the waypoint's hold time), each followed by a
        speed command where the next leg's planned speed differs (by more than 1 %) from the
        last one commanded (MAVLink runs it on reaching that waypoint), then land at the
        goal, return to launch, or nothing (``options.end``). Warns that the take-off climb
        and the landing descent are outside the verified trajectory."""
        P = np.asarray(tr.points, dtype=np.float64)
        G = self.geodetic(P)
        alt = self.altitudes(tr)
        frame = {"amsl": 0, "relative": 3, "terrain": 10}[self.options.frame]
        speeds = self.segment_speeds(tr)
        waits = np.diff(tr.times) * (np.linalg.norm(np.diff(P, axis=0), axis=1) <= 1e-9)
        nan = float("nan")
        pitch = 15.0 if self.is_fixed_wing() else 0.0
        out = [MissionItem(22, frame, (pitch, 0, 0, nan, G[0, 0], G[0, 1], alt[0]))]
        current = -1.0
        for k in range(len(P)):
            if k > 0 and waits[k - 1] > 0:  # a wait: the previous waypoint holds (no new point)
                last = out[-1]
                held = (last.params[0] + float(waits[k - 1]), *last.params[1:])
                out[-1] = MissionItem(last.command, last.frame, held)
            else:
                out.append(MissionItem(16, frame, (0, 0, 0, nan, G[k, 0], G[k, 1], alt[k])))
            # a speed command acts from the waypoint before it: the speed of the leg from k
            if k < len(speeds) and speeds[k] > 0 and abs(speeds[k] - current) > 0.01 * speeds[k]:
                current = float(speeds[k])
                out.append(MissionItem(178, 2, (1, current, -1, 0, 0, 0, 0)))
        end = self.options.end
        if end == "land":
            on_ground = np.column_stack([P[-1:, :2], self.ground(P[-1:, :2])])
            land_alt = float(self.altitudes(tr, on_ground)[0])  # the ground under the goal
            out.append(MissionItem(21, frame, (0, 0, 0, nan, G[-1, 0], G[-1, 1], land_alt)))
        elif end == "rtl":
            out.append(MissionItem(20, 2, (0, 0, 0, 0, 0, 0, 0)))
        note = ("the take-off climb and the "
                + {"land": "landing descent are", "rtl": "return to launch are",
                   "none": "end of the mission is"}[end]
                + " outside the verified trajectory (the plan starts at its first point in the "
                "air and ends at its last)")  # fmt: skip
        if note not in self.warnings:
            self.warnings.append(note)
        return out

    def keep_out(self) -> tuple[list[tuple[float, float, float]], list[FloatArray]]:
        """The scenario's static obstacles as geofence shapes: exclusion circles
        ``(lat, lon, radius)`` from cylinders and circles (radius plus margin; a finite
        cylinder's altitude limits are dropped, which only widens the fence) and exclusion
        polygons ``(n, 2) [lat, lon]`` from polygons and revealed uncertain areas. Moving
        obstacles, danger areas (costs, not limits) and unrevealed areas are not fences."""
        if self._keep_out is not None:
            return self._keep_out
        sc = self.scenario
        circles: list[tuple[float, float, float]] = []
        polygons: list[FloatArray] = []
        if sc is None:
            return circles, polygons
        discs = self.discs()
        if discs:
            C = self.geodetic(np.array([c for c, _ in discs], dtype=np.float64))
            circles = [(float(g[0]), float(g[1]), r) for g, (_, r) in zip(C, discs, strict=True)]
        shapes = [np.asarray(p.vertices, dtype=np.float64) for p in sc.polygons]
        if any(p.margin > 0 for p in sc.polygons):
            self.warnings.append("polygon margins are not in the geofence (its polygons are "
                                 "the obstacles' own outlines)")  # fmt: skip
        for u in sc.uncertain_areas:
            if u.revealed:
                x1, y1 = u.x + u.width, u.y + u.height
                shapes.append(np.array([[u.x, u.y], [x1, u.y], [x1, y1], [u.x, y1]]))
        for V in shapes:
            polygons.append(self.geodetic(V)[:, :2])
        self._keep_out = (circles, polygons)
        return circles, polygons

    def discs(self) -> list[tuple[tuple[float, float], float]]:
        """The scenario's cylinders and circles as ``(center, radius + margin)`` (local)."""
        sc = self.scenario
        if sc is None:
            return []
        out = [(c.center, float(c.radius + c.margin)) for c in sc.cylinders]
        return out + [(c.center, float(c.radius + c.margin)) for c in sc.circles]

    def is_fixed_wing(self) -> bool:
        if self.options.vehicle != "auto":
            return self.options.vehicle == "fixed-wing"
        if self.scenario is None:
            return False
        from uavplan.world.airframes import airframe_of

        return airframe_of(self.scenario.uav).kind == "fixed-wing"


@dataclass(frozen=True)
class MissionItem:
    """One MAVLink mission item: command (MAV_CMD), frame (MAV_FRAME), its seven parameters
    (``nan`` where MAVLink means "unchanged")."""

    command: int
    frame: int
    params: tuple[float, ...]


#: ``exporter(mission, out) -> paths written``; ``out`` is a file for a fleet-wide format and a
#: folder for a per-UAV one.
ExportFn = Callable[[Mission, Path], list[Path]]


@dataclass(frozen=True)
class Exporter:
    """A registered format: its name, file suffix, whether it writes one file per UAV, a line
    of description and the function."""

    name: str
    suffix: str
    per_uav: bool
    description: str
    write: ExportFn


_FORMATS: dict[str, Exporter] = {}


def tolerances(mission: Mission) -> list[str]:
    """What the operator must keep for the plan's guarantee to hold, in words: each UAV's
    take-off time (the launch schedule), and the execution model the plan was verified for,
    less what the missions' thinning already uses of its tracking error."""
    rec = dict(mission.plan.execution or {})
    thin = max((r["thinning_m"] for r in mission.report.values()), default=0.0)
    eh, ev = float(rec.get("track_h", 0.0)), float(rec.get("track_v", 0.0))
    lines = []
    if not rec or not any(float(rec.get(k, 0.0)) for k in ("takeoff_s", "speed", "track_h",
                                                            "track_v", "wind")):  # fmt: skip
        lines.append("the plan was made for an exact execution (the nominal model): every UAV "
                     "must take off at its planned second (launch schedule), hold its planned "
                     "speeds and fly its track exactly; nothing is tolerated")  # fmt: skip
    else:
        lines.append(
            f"the plan holds if every UAV takes off within ±{float(rec.get('takeoff_s', 0)):g} s "
            f"of its time in the launch schedule, keeps its ground speed within "
            f"{100 * float(rec.get('speed', 0)):g} % of the commanded speeds"
            + (f" (wind up to {float(rec['wind']):g} m/s included)" if rec.get("wind") else "")
            + f", and stays within {max(eh - thin, 0):.3g} m horizontally and "
            f"{max(ev - thin, 0):.3g} m vertically of its mission's legs (the plan's "
            f"{eh:g} m and {ev:g} m of tracking error, less {thin:.3g} m the thinning of the "
            "mission takes)"
        )  # fmt: skip
        if thin > min(eh, ev) and (eh or ev):
            lines.append(f"the thinned missions depart up to {thin:.3g} m from the verified "
                         f"trajectories, more than the tracking error the plan tolerates "
                         f"({eh:g} m / {ev:g} m): raise --max-items")  # fmt: skip
    return lines


def write_launch_schedule(mission: Mission, folder: Path) -> Path:
    """``folder/launch.csv``: per UAV its take-off time (the plan's seconds, and UTC from
    ``options.epoch``), the tolerances of the plan's execution model, and what its mission
    holds (items, the thinning's deviation): what the per-vehicle formats cannot carry."""
    import csv
    import io
    from datetime import datetime, timedelta

    from uavplan.io.atomic import write_text_atomic

    rec = dict(mission.plan.execution or {})
    epoch = datetime.fromisoformat(mission.options.epoch.replace("Z", "+00:00"))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["uav", "takeoff_s", "takeoff_utc", "takeoff_tolerance_s", "speed_tolerance",
                "track_h_m", "track_v_m", "mission_items", "waypoints", "thinning_m"])  # fmt: skip
    for tr in mission.trajectories():
        r = mission.report.get(tr.id, {})
        t0 = float(tr.times[0])
        utc = (epoch + timedelta(seconds=t0)).isoformat().replace("+00:00", "Z")
        w.writerow([tr.id, f"{t0:.3f}", utc, rec.get("takeoff_s", 0.0), rec.get("speed", 0.0),
                    rec.get("track_h", 0.0), rec.get("track_v", 0.0), int(r.get("items", 0)),
                    int(r.get("waypoints", 0)), f"{r.get('thinning_m', 0.0):.3f}"])  # fmt: skip
    return write_text_atomic(folder / "launch.csv", buf.getvalue())


def uav_file(out: Path, uav_id: str, suffix: str) -> Path:
    """The file of UAV ``uav_id`` in the folder ``out``: refused (ExportError) unless the id is
    a plain file name, so that no id read from a plan (``../../x``, ``/etc/y``) writes
    outside ``out``."""
    name = f"{uav_id}{suffix}"
    plain = (
        uav_id not in ("", ".", "..")
        and not any(c in uav_id for c in "/\\\0")
        and not any(ord(c) < 32 for c in uav_id)
    )
    if not plain or Path(name).name != name:
        raise ExportError(
            f"UAV id {uav_id!r} cannot name a file in {out} (a path separator, a control "
            "character, or '.'/'..'): rename the UAV in the scenario"
        )
    return out / name


def register_exporter(
    name: str, suffix: str, description: str, per_uav: bool = False
) -> Callable[[ExportFn], ExportFn]:
    """Decorator: register an export format."""

    def add(fn: ExportFn) -> ExportFn:
        if name in _FORMATS and _FORMATS[name].write is not fn:
            raise ExportError(f"export format {name!r} is already registered")
        _FORMATS[name] = Exporter(name, suffix, per_uav, description, fn)
        return fn

    return add


def exporters() -> dict[str, Exporter]:
    """The registered formats by name."""
    return dict(_FORMATS)


def get_exporter(name: str) -> Exporter:
    try:
        return _FORMATS[name]
    except KeyError:
        known = sorted(_FORMATS)
        raise ExportError(f"unknown export format {name!r}; choose from {known}") from None


from uavplan._discovery import import_submodules  # noqa: E402

import_submodules(__name__, __path__)  # registers every format module's exporters
