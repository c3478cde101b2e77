"""How far a flown trajectory may stray from its plan: the execution model a plan is made
robust to, and what it means in space and time.

A plan's trajectories are timed: UAV ``A`` is to be at ``p_A(tau)`` at time ``tau`` from its
take-off ``t0`` to its landing ``tf``. Executed, it is not. :class:`ExecutionModel` bounds how it
is not:

* **take-off** (``takeoff_s``, ``delta0``): it leaves at ``t0 + d``, ``|d| <= delta0`` seconds;
* **speed** (``speed``, ``rho``, a fraction): its ground speed along the path is the planned one
  times a factor ``s(t)`` in ``[1 - rho, 1 + rho]``, varying as it likes (an autopilot holds its
  speed command to within this, and a wind changes ground speed: ``wind`` adds ``|W| / v`` to
  ``rho``, ``v`` the UAV's cruise speed, the worst heading of a UAV that holds airspeed);
* **tracking** (``track_h``, ``track_v``, metres): at every instant it is within ``e_h``
  horizontally and ``e_v`` vertically of the point of its path it is flying (navigation and
  guidance error).

**Windows.** Under the first two, the UAV reaches its path's point ``tau`` at an actual time
``t`` in ``T(tau) = [t0 - delta0 + (tau - t0) / (1 + rho), t0 + delta0 + (tau - t0) / (1 - rho)]``,
and every time in that interval is reachable (a constant speed factor and take-off error hit any
of them). Two UAVs' executions are independent, so ``A`` at ``tau_A`` and ``B`` at ``tau_B`` can
be at the same instant exactly when ``T_A(tau_A)`` and ``T_B(tau_B)`` meet: two linear
inequalities in ``(tau_A, tau_B)`` (:meth:`ExecutionModel.window`). The separation under the
model is the least distance between ``p_A(tau_A)`` and ``p_B(tau_B)`` over that region, less
what tracking can take away: ``sqrt((e_hA + e_hB)^2 + (e_vA + e_vB)^2)`` (the horizontal and
vertical offsets of two points each within its cylinder). The nominal model (all zero) makes
the region the line ``tau_A = tau_B``: the nominal check.

**Static clearances** (obstacles, terrain, the altitude band, the bounds) do not depend on
time: tracking widens them by ``e_h`` horizontally and ``e_v`` vertically
(:func:`widened`). A moving obstacle is a UAV with a nominal model.

The default a user gets from ``uavplan plan`` is :data:`DEFAULT` (``docs/decisions.md`` says
where its numbers come from); experiments and the Python API plan with the scenario's model,
the nominal one unless the scenario states another.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from uavplan.world.scenario import Scenario

#: The largest speed fraction a model may have (beyond it a "schedule" means little, and
#: ``1 - rho`` must stay well above 0).
MAX_RHO = 0.5


@dataclass(frozen=True)
class ExecutionModel:
    """Bounds on how a flown trajectory departs from its plan (see the module docstring).

    Attributes:
        takeoff_s: take-off time error, seconds (``delta0``).
        speed: ground-speed error along the path, a fraction of the planned speed (``rho``).
        track_h, track_v: horizontal and vertical tracking error, metres.
        wind: a steady wind's horizontal speed, m/s (0: none); it adds ``wind / v`` to the
            speed error, ``v`` the UAV's cruise speed.
        source: where the model comes from (for the console and the plan file).
    """

    takeoff_s: float = 0.0
    speed: float = 0.0
    track_h: float = 0.0
    track_v: float = 0.0
    wind: float = 0.0
    source: str = "nominal"

    def __post_init__(self) -> None:
        for name in ("takeoff_s", "speed", "track_h", "track_v", "wind"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"execution {name}: {v!r} is not a finite number")
            if v < 0:
                raise ValueError(f"execution {name}: {v} is negative")
            object.__setattr__(self, name, float(v))
        if self.speed >= MAX_RHO:
            raise ValueError(f"execution speed: {self.speed} is not below {MAX_RHO} (a fraction "
                             "of the planned speed, 0.03 for 3 %)")  # fmt: skip

    @property
    def nominal(self) -> bool:
        """True when the model allows no error at all (the plan as flown exactly)."""
        return not (self.takeoff_s or self.speed or self.track_h or self.track_v or self.wind)

    @property
    def timed(self) -> bool:
        """True when the schedule may drift (take-off, speed or wind)."""
        return bool(self.takeoff_s or self.speed or self.wind)

    def rho(self, cruise: float) -> float:
        """The speed fraction with the wind's share for a UAV cruising at ``cruise`` m/s."""
        r = self.speed + (self.wind / cruise if cruise > 0 else 0.0)
        if r >= MAX_RHO:
            raise ValueError(
                f"execution: speed error {self.speed:g} with a {self.wind:g} m/s wind at "
                f"{cruise:g} m/s is {r:.3g} of the speed, not below {MAX_RHO}"
            )
        return r

    def timing(self, cruise: float) -> tuple[float, float]:
        """``(delta0, rho)`` for a UAV cruising at ``cruise`` m/s."""
        return self.takeoff_s, self.rho(cruise)

    def tracking_gap(self) -> float:
        """How much closer two UAVs with this model may come than their planned positions:
        ``sqrt((2 e_h)^2 + (2 e_v)^2)``, metres."""
        return float(math.hypot(2.0 * self.track_h, 2.0 * self.track_v))

    def tracking_norm(self) -> float:
        """How far one UAV may be from its planned position: ``sqrt(e_h^2 + e_v^2)``."""
        return float(math.hypot(self.track_h, self.track_v))

    def describe(self) -> str:
        """One line for the console."""
        if self.nominal:
            return "nominal (the plan flown exactly: no take-off, speed or tracking error)"
        bits = [f"take-off ±{self.takeoff_s:g} s", f"speed ±{100 * self.speed:g} %",
                f"tracking {self.track_h:g} m horizontal, {self.track_v:g} m vertical"]  # fmt: skip
        if self.wind:
            bits.append(f"wind {self.wind:g} m/s")
        return ", ".join(bits)

    def record(self) -> dict[str, Any]:
        """The plan and scenario files' ``execution`` block."""
        return {"takeoff_s": self.takeoff_s, "speed": self.speed, "track_h": self.track_h,
                "track_v": self.track_v, "wind": self.wind, "source": self.source}  # fmt: skip

    @classmethod
    def from_record(cls, rec: Any) -> ExecutionModel:
        """The inverse of :meth:`record` (ValueError naming the field)."""
        if not isinstance(rec, dict):
            raise ValueError(f"execution: {rec!r} is not a mapping")
        unknown = set(rec) - {"takeoff_s", "speed", "track_h", "track_v", "wind", "source"}
        if unknown:
            raise ValueError(f"execution: unknown fields {sorted(unknown)}")
        return cls(**{k: rec[k] for k in rec})


#: The plan flown exactly.
NOMINAL = ExecutionModel()

#: The least model ``uavplan plan`` plans against unless the scenario states one or
#: ``--nominal`` is given: small UAVs under a standard autopilot (``docs/decisions.md``,
#: "Execution model"); :func:`default_for` raises its tracking error to the UAV class's.
DEFAULT = ExecutionModel(2.0, 0.03, 3.0, 2.0, 0.0, "uavplan's default for small UAVs")


#: How a default model's source says that its airframe's tracking error is not calibrated on
#: the flights of its plans (an airframe without a fitted tail; every built-in airframe has
#: one: the fast fixed wing, before its calibration, stated 8.5 m / 12.5 m, and its simulated
#: flights left them; docs/results.md).
UNCALIBRATED = "assumed, NOT calibrated: simulated flights of its plans leave it"


def default_for(uav: Any, n_uavs: int = 1) -> ExecutionModel:
    """uavplan's default model for a scenario's UAV: :data:`DEFAULT`'s take-off and speed
    errors, and for a UAV that names its airframe (``uav.airframe``) the larger of its
    tracking error and the one calibrated in flight simulation for that airframe and a fleet
    of ``n_uavs`` (:func:`uavplan.world.airframes.fleet_tracking`: the 99th percentile of a
    calibration flight's largest error up to ten UAVs, more for a larger fleet, so that one
    execution's flights are not expected to leave it), and the part of the
    calibration's wind (``turn_wind``) that the airframe has no airspeed to spare for, above
    its cruise (:func:`~uavplan.world.airframes.top_speed`) or below it (down to its minimum
    airspeed, ``uav.min_speed``): a fixed wing that cannot fly faster than it is planned to
    falls behind its schedule into a headwind, and one that cannot fly slower runs ahead of
    it with the wind behind (a UAV of one airspeed, as RSCDWOA's, both; docs/results.md gives
    its simulated flights); a multirotor's controller holds its ground velocity. A UAV that
    names no airframe gets :data:`DEFAULT` (its class is only a guess from its limits)."""
    from uavplan.world.airframes import AIRFRAMES, fleet_tracking, top_speed

    if getattr(uav, "airframe", None) not in AIRFRAMES:
        return DEFAULT
    af = AIRFRAMES[uav.airframe]
    fh, fv = fleet_tracking(af, n_uavs)
    h, v = max(DEFAULT.track_h, fh), max(DEFAULT.track_v, fv)
    fleet = f" for a fleet of {n_uavs}" if (fh, fv) != (af.track_h, af.track_v) else ""
    up = top_speed(af, uav) - float(uav.speed)
    v_min = float(getattr(uav, "min_speed", 0.0))
    spare = min(up, float(uav.speed) - v_min) if v_min > 0 else up  # one airspeed: 0
    wind = round(max(0.0, af.turn_wind - spare), 3) if af.kind == "fixed-wing" else 0.0
    if (h, v, wind) == (DEFAULT.track_h, DEFAULT.track_v, 0.0):
        return DEFAULT
    how = ("tracking calibrated in flight simulation" if af.tail_h is not None else
           f"tracking {UNCALIBRATED}")  # fmt: skip
    return replace(DEFAULT, track_h=h, track_v=v, wind=wind,
                   source=f"uavplan's default for a {af.name}{fleet}, {how}")  # fmt: skip


def flyable_turns(scenario: Scenario) -> tuple[Scenario, float]:
    """``scenario`` with its UAV's turn radius raised to what its named airframe flies
    (:func:`uavplan.world.airframes.planned_turn_radius`) when that is larger, and the radius
    now planned (0 when unchanged). A fixed wing's turns planned at the bank limit in still
    air swing wide downwind (flown in simulation, such turns carried the largest tracking
    errors of uavplan's default fleets), and turns tighter than its L1 guidance's look-ahead
    are cut on entry and overshot on exit; a multirotor's polyline corners are flown slower
    than the plan's constant speed (its mission slows down for each), late by tens of seconds
    over a flight, so its corners are planned as curves it flies at speed. A fixed wing
    without a turn radius in the scenario keeps it (its limits are the scenario's)."""
    from uavplan.world.airframes import AIRFRAMES, planned_turn_radius

    uav = scenario.uav
    af = AIRFRAMES.get(getattr(uav, "airframe", None) or "")
    if af is None or (af.kind == "fixed-wing" and float(uav.turn_radius) <= 0):
        return scenario, 0.0
    r = planned_turn_radius(af, float(uav.speed))
    if r <= float(uav.turn_radius):
        return scenario, 0.0
    return replace(scenario, uav=replace(uav, turn_radius=r)), r


def flyable_speeds(scenario: Scenario) -> tuple[Scenario, float]:
    """``scenario`` with its UAV's slowest planned speed raised by its named fixed-wing
    airframe's ``turn_wind`` when that stays within its cruise speed, and the speed now the
    slowest (0 when unchanged). A fixed wing cannot fly slower than its minimum airspeed: with
    that wind behind it, its slowest ground speed is the minimum airspeed plus the wind, and a
    leg planned slower is flown early (flown in simulation, a 500-UAV default fleet's
    violations came from a UAV planned at 10 m/s, its minimum airspeed, that ran 13 s early in
    a tailwind). A multirotor holds its ground speed in a steady wind."""
    from uavplan.world.airframes import AIRFRAMES

    uav = scenario.uav
    af = AIRFRAMES.get(getattr(uav, "airframe", None) or "")
    if af is None or af.kind != "fixed-wing" or float(uav.min_speed) <= 0:
        return scenario, 0.0
    v = float(uav.min_speed) + af.turn_wind
    if v > float(uav.speed):
        return scenario, 0.0
    return replace(scenario, uav=replace(uav, min_speed=v)), v


def slope_wind(uav: Any, model: Any) -> float:
    """The wind (m/s) behind a UAV that the heights of its flights are checked against
    (:func:`height_lag`), 0 where none is: under a model that is not nominal (an
    :class:`ExecutionModel` or its record), for a UAV that names a fixed-wing airframe, the
    larger of the model's ``wind`` and the airframe's ``turn_wind`` (the wind its tracking
    error was calibrated in). A fixed wing's autopilot limits its flight-path angle through
    the air (ArduPilot's and PX4's TECS), so with the wind behind it its slopes over the
    ground are shallower than its limit; a multirotor holds its velocity."""
    from uavplan.world.airframes import AIRFRAMES

    if model is None:
        return 0.0
    m = model if isinstance(model, ExecutionModel) else ExecutionModel.from_record(model)
    if m.nominal:
        return 0.0
    af = AIRFRAMES.get(getattr(uav, "airframe", None) or "")
    if af is None or af.kind != "fixed-wing":
        return 0.0
    if getattr(uav, "max_climb_angle", None) is None and getattr(uav, "max_descent_angle",
                                                                 None) is None:  # fmt: skip
        return 0.0
    return float(max(m.wind, af.turn_wind))


def height_lag(
    paths: np.ndarray, times: np.ndarray, wind: float, max_climb: float | None,
    max_descent: float | None,
) -> np.ndarray:  # fmt: skip
    """(pop, n): how far above (+) or below (-) its planned height a fixed wing is at each
    point of its timed paths ``(pop, n, 3)`` (times ``(pop, n)``) when it flies with ``wind``
    m/s behind it and follows its plan's heights as closely as its flight-path angle limits
    let it: holding the planned ground speed ``v`` of a segment it flies ``v - wind`` through
    the air, so it climbs (descends) over the ground at most ``(v - wind) / v`` times the
    tangent of ``max_climb`` (``max_descent``, degrees; None: no limit). It pursues the plan's
    height as an autopilot's height loop does: as steeply down as it can while above it, up
    while below, on it once there while the plan's slope is within its own. Along a segment
    the gap closes to 0 and then opens at most once, so its extremes lie at the points. In
    simulation the fixed wings that left their band did so where this lag is largest (a
    descent into its goal planned at 28.6 degrees, the airframe's limit 30, ended 54 m above
    the goal in a tailwind).
    A helix or an S-turn that loses height is not modelled: a plan's heights are flown along
    its track."""
    P = np.asarray(paths, dtype=np.float64)
    T = np.asarray(np.broadcast_to(times, P.shape[:2]), dtype=np.float64)
    d = np.diff(P, axis=1)
    L = np.hypot(d[..., 0], d[..., 1])
    dt = np.diff(T, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(dt > 0, L / dt, np.inf)
        share = np.clip(np.where(np.isfinite(v), (v - wind) / v, 1.0), 0.0, 1.0)
        sp = np.where(L > 0, d[..., 2] / L, 0.0)  # the plan's slope
    up = share * (math.inf if max_climb is None else math.tan(math.radians(max_climb)))
    down = share * (math.inf if max_descent is None else math.tan(math.radians(max_descent)))
    out = np.zeros(P.shape[:2])
    # the gap stays 0 up to the first segment steeper than the UAV flies (or straight up)
    steep = (sp > up) | (sp < -down) | ((L <= 0) & (d[..., 2] != 0))
    first = np.flatnonzero(steep.any(axis=0))
    if not first.size:
        return out
    e = np.zeros(P.shape[0])  # the UAV's height less the plan's
    with np.errstate(invalid="ignore", divide="ignore"):  # 0 * inf: no limit, no distance
        for k in range(int(first[0]), d.shape[1]):
            u_, d_, s_, L_ = up[:, k], down[:, k], sp[:, k], L[:, k]
            # pursuing the plan's height: descending as steeply as it can while above it,
            # climbing while below; the gap closes (or opens) at the difference of the slopes
            r1 = np.where(e > 0, -d_ - s_, u_ - s_)
            closing = (e != 0) & (e * r1 < 0)
            s_meet = np.where(closing, -e / r1, np.where(e == 0, 0.0, np.inf))
            met = s_meet < L_
            rest = np.maximum(L_ - np.where(met, s_meet, 0.0), 0.0)
            # from where it meets the plan: on it while the plan's slope is within its limits
            r2 = np.where(s_ > u_, u_ - s_, np.where(s_ < -d_, -d_ - s_, 0.0))
            after = np.where(rest > 0, r2 * rest, 0.0)
            before = e + np.where(np.isfinite(r1), r1, 0.0) * L_
            # a step straight up or down: no height changes without a distance flown
            e = np.where(met, after, np.where(L_ > 0, before, e - d[:, k, 2]))
            out[:, k + 1] = e
    return out


def lag_extents(
    paths: np.ndarray, times: np.ndarray, wind: float, max_climb: float | None,
    max_descent: float | None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """How far a fixed wing's heights can be off its timed paths ``(pop, n, 3)`` (times
    ``(pop, n)``) by its :func:`height_lag` in ``wind``: per path the largest ``|lag|``
    ``(pop,)`` and per segment the larger of its ends' ``(pop, n - 1)`` (along a segment the
    lag's extremes lie at its ends); 0 where the path's lag stays within
    :data:`~uavplan.world.tolerances.LAG_TOL` (the calibrated tracking error carries such
    lags). In a calmer wind the lag is between 0 and these, so a UAV is within its path's
    segment's extent of where it was planned (and the model's tracking error of that): what
    separation is checked with."""
    from uavplan.world.tolerances import LAG_TOL

    off = np.abs(height_lag(paths, times, wind, max_climb, max_descent))
    top = off.max(axis=1) if off.shape[1] else np.zeros(off.shape[0])
    seg = np.maximum(off[:, :-1], off[:, 1:])
    small = top <= LAG_TOL
    top[small] = 0.0
    seg[small] = 0.0
    return top, seg


def windows(t0: float, delta0: float, rho: float, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``T(tau)`` for a UAV taking off at ``t0``: the earliest and latest actual times it can be
    at its path's point ``tau`` (arrays like ``tau``)."""
    s = np.asarray(tau, dtype=np.float64) - t0
    return t0 - delta0 + s / (1.0 + rho), t0 + delta0 + s / (1.0 - rho)


def reach_rise(
    heights: np.ndarray, dx: float, dy: float, reach: float, up: bool = True, how: str = "least"
) -> np.ndarray:
    """Per grid node, how much to raise it (``up``; lower it otherwise) so that the bilinear
    surface of the moved nodes at any point stands above (below) the original surface
    anywhere within ``reach`` metres horizontally. Two constructions, each sound alone; the
    one that moves the grid less on average is used:

    * **by the neighbours' heights**: the highest (lowest) node within ``k + 1`` nodes of it,
      ``k = ceil(reach / d)`` per axis, less (minus) its own height. The original at a point
      within reach of ``p`` is at most the highest corner of the cell it lies in, and those
      corners are within ``k + 1`` nodes of each corner of ``p``'s cell; the moved surface at
      ``p`` is at least its lowest corner. Tight where cells are small beside the reach.
    * **by the slope**: ``reach`` times the steepest gradient the surface has in a cell
      within ``k + 1`` cells of the node (in a cell ``|dh/dx|`` is at most the larger of its
      two x-edge differences over ``dx``, likewise in y, the gradient's norm at most their
      hypot; the surface is continuous, so along the straight line to a point within reach it
      changes by at most the reach times the steepest cell crossed, every such cell within
      that window of each corner of ``p``'s cell). Tight where cells are large.

    (ny, nx) metres, 0 for ``reach`` 0; outside the grid the surface extends its edges, as the
    terrain's lookups do. ``how``: ``"height"`` or ``"slope"`` forces one (for the tests)."""
    from scipy.ndimage import maximum_filter, minimum_filter

    H = np.asarray(heights, dtype=np.float64)
    ny, nx = H.shape
    if reach <= 0:
        return np.zeros_like(H)
    kx = math.ceil(reach / dx) + 1
    ky = math.ceil(reach / dy) + 1
    size = (2 * ky + 1, 2 * kx + 1)
    if up:
        by_height = maximum_filter(H, size=size, mode="nearest") - H
    else:
        by_height = H - minimum_filter(H, size=size, mode="nearest")
    gx = np.abs(np.diff(H, axis=1)) / dx  # (ny, nx - 1): the x edges
    gy = np.abs(np.diff(H, axis=0)) / dy  # (ny - 1, nx): the y edges
    cells = np.zeros((ny + 1, nx + 1))  # cell (j, i) at [j + 1, i + 1]; 0 off the grid
    cells[1:ny, 1:nx] = np.hypot(np.maximum(gx[:-1], gx[1:]), np.maximum(gy[:, :-1], gy[:, 1:]))
    # node (j, i) at [j, i]: the window [j - ky, j + ky] holds the cells j - ky - 1 .. j + ky - 1
    steepest = maximum_filter(cells, size=size, mode="constant", cval=0.0)[:ny, :nx]
    by_slope = reach * steepest
    if how == "height" or (how == "least" and by_height.mean() <= by_slope.mean()):
        return np.asarray(by_height)
    return np.asarray(by_slope)


def widened(scenario: Scenario, model: ExecutionModel) -> Scenario:
    """``scenario`` with every static clearance widened by the model's tracking error, the world
    a robust plan is planned in: cylinders, circles and polygons (and uncertain areas) ``e_h``
    wider, moving obstacles ``sqrt(e_h^2 + e_v^2)`` wider, the terrain's floor ``e_v`` higher and
    its ceiling ``e_v`` lower, each also by what the ground can rise (fall) within ``e_h``
    (:func:`reach_rise`), the altitude band ``e_v`` narrower at each end, the bounds
    ``e_h`` (``e_v``) smaller on each side (a band above the ground follows the terrain's
    grids instead); the scenario's ``execution`` set to ``model``. The
    scenario itself when the model has no tracking error (only ``execution`` set)."""
    eh, ev = model.track_h, model.track_v
    if not (eh or ev):
        return replace(scenario, execution=model)
    from uavplan.world.obstacles import AltitudeBand
    from uavplan.world.scenario import Bounds
    from uavplan.world.terrain import Terrain

    lo, hi = np.asarray(scenario.bounds.lo), np.asarray(scenario.bounds.hi)
    pad = np.array([eh, eh, ev][: scenario.dim])
    if np.any(hi - lo <= 2 * pad):
        raise ValueError(f"the bounds leave no room for a tracking error of {eh:g} m horizontally "
                         f"and {ev:g} m vertically")  # fmt: skip
    bounds = Bounds(tuple(lo + pad), tuple(hi - pad))
    terrain = scenario.terrain
    if terrain is not None and (ev or eh):
        t = terrain
        # within e_h of a point the ground may stand higher (lower) than at the point
        up = ev + reach_rise(t.heights, t.dx, t.dy, eh)
        down = ev + reach_rise(t.ceiling_heights, t.dx, t.dy, eh, up=False)
        terrain = Terrain(t.heights + up, t.x0, t.y0, t.dx, t.dy, t.name, dict(t.georef),
                          t.ceiling_heights - down)  # fmt: skip
    band = scenario.altitude
    if band is not None and ev:
        if band.max - band.min <= 2 * ev:
            raise ValueError(
                f"the altitude band [{band.min:g}, {band.max:g}] m leaves no room for a "
                f"vertical tracking error of {ev:g} m"
            )
        # a band above the ground moves with the terrain's grids, already e_v higher (floor)
        # and lower (ceiling); an absolute band, or one over no terrain, is narrowed itself
        if not (band.reference == "ground" and terrain is not None):
            band = AltitudeBand(band.min + ev, band.max - ev, band.reference)
    norm = model.tracking_norm()
    return replace(
        scenario,
        bounds=bounds,
        terrain=terrain,
        altitude=band,
        cylinders=tuple(replace(c, margin=c.margin + eh) for c in scenario.cylinders),
        circles=tuple(replace(c, margin=c.margin + eh) for c in scenario.circles),
        polygons=tuple(replace(p, margin=p.margin + eh) for p in scenario.polygons),
        uncertain_areas=tuple(replace(u, margin=u.margin + eh) for u in scenario.uncertain_areas),
        moving_obstacles=tuple(
            replace(m, radius=m.radius + norm) for m in scenario.moving_obstacles
        ),
        execution=model,
    )
