"""The independent verifier for fleet plans (``plan.json``): is every UAV's timed path flyable, and
do the UAVs keep their distance from each other?

This module is written apart from the planner's own cost and feasibility code on purpose: it
does not import :mod:`uavplan.problems`, :mod:`uavplan.world.geometry`, the terrain kernels or
``Terrain.clears / min_clearance / max_clearance``, nor :mod:`uavplan.world.reservations`. It
reads the scenario only as data (bounds, obstacles, the DEM grid, the altitude band, UAV limits)
and does its own geometry, so that a bug in the planner's geometry cannot hide itself.

Semantics (frame: metres, x east, y north, z up, absolute altitudes; seconds):

* **Which trajectories.** :func:`verify_plan` checks each UAV's ``flown`` trajectory by default
  (the one the plan declares it is to fly; the planned polyline where the plan declares none),
  or the planned polylines, or the informative smoothed paths (``trajectory=``).

* **Timed paths.** A UAV flies its polyline piecewise-linearly in time between
  ``(times[k], waypoints[k])``. It is in the air only during ``[times[0], times[-1]]`` (it takes
  off at its start and lands at its goal); before and after it is no hazard. A repeated time with
  two different points is an instantaneous jump: it is reported as a ``speed`` violation and, for
  separation, the jump is swept as a straight motion at that instant.
* **Separation** (``separation``): for every pair of UAVs, the minimum distance over continuous
  time must be at least ``S2 = scenario.uav.s2``. Between the union of both UAVs' time
  breakpoints the relative motion is linear, so the minimum on each common interval is the
  minimum of a quadratic (closed form, clamped to the interval): exact, not sampled. Pairs are
  pruned first (sort-and-sweep on whole-flight boxes grown by ``S2``, and the flights' time
  windows); a pruned pair is farther apart than ``S2`` at every instant. With a per-axis
  separation ``scenario.uav.s2_axes = (S_x, S_y, S_z)`` (the RSCDWOA paper's [50, 50, 20] m) the
  UAVs must not be closer than all three at once: the measure is ``max(S) max_i |r_i| / S_i``
  and its minimum per interval is found by bisection on the level set (an intersection of three
  intervals; :mod:`uavplan.verify.separation`). One violation is
  reported per close encounter (a stretch of time during which the pair is closer than ``S2``),
  at its closest point. The report's minimum separation is the fleet's exact minimum over all
  pairs (when no pair comes within ``S2``, the pruning is widened until it is found).
* **Obstacles.** Cylinders (``cylinder``): the part of a segment between ``z_min - margin`` and
  ``z_max + margin`` must stay at a horizontal distance of at least ``radius + margin`` from the
  axis. Circles (``circle``) are infinite vertical prisms of radius ``radius + margin``. Polygons
  and revealed uncertain areas (``polygon``) are infinite vertical prisms: a segment must not
  enter the interior and must keep at least ``margin`` from the boundary (touching a polygon
  with no margin is allowed). Moving obstacles (``moving``): the distance over continuous time
  from the UAV to the obstacle's centre (which holds its first and last positions outside its
  knots) must be at least its radius. All exact.
* **Bounds** (``bounds``): every waypoint lies in the scenario's box (the box is convex, so whole
  segments do).
* **Terrain** (``terrain``): ``z - h(x, y) >= 0`` along every segment against the bilinear DEM
  (outside the grid the height of the nearest edge point). Along a straight segment inside one
  grid cell the bilinear surface is a quadratic in the segment parameter, so each segment is split
  at the grid lines it crosses and the exact minimum is taken per piece. When the terrain was
  read from a raster (GeoTIFF, SRTM tiles, ...), ``h`` is the raster's own ground, read again
  from its files by :mod:`uavplan.verify.source_terrain` (not the planner's resampled grid),
  and the planner's grid is compared with it (a disagreement beyond its stated bound is
  warned).
* **Altitude band** (``altitude``): with reference ``"ground"`` the height above ground stays in
  ``[min, max]`` along the whole segment (exact, with the same per-cell quadratic for the minimum
  and the maximum; ground is 0 without terrain); with ``"absolute"``, ``z`` stays in
  ``[min, max]`` (linear along a segment, so the waypoints suffice).
* **Timing.** ``times`` must be non-decreasing (``times``); the implied speed ``|dp| / dt`` of a
  segment must not exceed ``v = scenario.uav.v_max`` (``max_speed``, else ``speed``) times
  ``1 + 1e-6`` (``speed``), with an extra ``1e-6 (v + 2)`` m of slack per segment for the
  6-decimal rounding of ``plan.json``. A UAV whose times decrease is left out of the separation
  and moving-obstacle checks (its motion is undefined) and a warning says so.
* **Kinematics** (:mod:`uavplan.verify.kinematics`; only with ``kinematics=True``, the flown and
  smoothed trajectories, and only for the limits the UAV declares): the minimum speed
  (``speed``: every segment with ``dt > 0`` at least ``min_speed (1 - 1e-6)``, less
  ``1e-6 (min_speed + 2)`` m; a hover flies at 0 m/s), the climb and descent angles (``climb``,
  3-D: ``atan2(dz, h)`` of every segment that moves, within ``max_climb_angle`` /
  ``max_descent_angle`` + ``ANGLE_TOL_DEG``) and the turn radius of the horizontal track
  (``turn``: at every interior point, a heading change of at most ``MAX_SAMPLE_TURN_DEG`` and a
  discrete curvature ``theta / mean(L_a, L_b)`` at most ``(1 + TURN_RTOL) / turn_radius``).
  A planned polyline is a geometric path: checked with ``kinematics=False`` it gets clearances,
  separation, times and the maximum speed only.
* **Heights flown in the wind** (under a model that is not nominal, for a UAV that names a
  fixed-wing airframe): the flight as flown with the airframe's calibration wind behind it,
  pursuing its planned heights within the flight-path angle that wind leaves over the ground
  (:func:`uavplan.verify.kinematics.heights_in_wind`), keeps the model's vertical error from the
  ground, the band and the bounds (reported as their kinds) and reaches its goal within the
  model's vertical error (``climb``); and a pair of UAVs (a UAV and a moving obstacle) must
  keep what the model requires plus, for each pair of segments, the lag of each segment of a
  UAV whose heights lag (the larger of its ends': along a segment the lag closes and opens at
  most once; in a calmer wind it is between 0 and that, so each UAV stays within its
  segment's lag of its plan); a flight whose lag stays under ``LAG_TOL`` is not checked.
* **Warnings** (not violations): the plan's scenario name differs from the scenario's; a UAV's
  first or last point differs from its task's start or goal; a UAV the plan calls feasible
  fails a check.

All geometric comparisons use a tolerance of ``TOL = 1e-6`` m: a distance exactly equal to the
required one passes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory, TrajectoryKind, parse_plan
from uavplan.verify import robust as R
from uavplan.verify.kinematics import check_climb, check_turn, heights_in_wind
from uavplan.verify.obstacles import check_circles, check_cylinders, check_polygons
from uavplan.verify.report import (
    KINDS,
    TOL,
    VerifyReport,
    Violation,
    fmt_points,
)
from uavplan.verify.separation import check_moving, check_separation
from uavplan.verify.source_terrain import check_source_terrain, read_source, source_clearance
from uavplan.verify.terrain import check_terrain, terrain_clearance_extrema, within_reach
from uavplan.verify.timing import check_bounds, check_speed, check_times
from uavplan.world.scenario import Scenario
from uavplan.world.tolerances import LAG_TOL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ================================================================================ everything
#: The trajectories :func:`verify_plan` can check, and whether their kinematics are checked.
TRAJECTORIES: dict[str, bool] = {"flown": True, "planned": False, "smoothed": True}


def verify_trajectories(
    trajs: Sequence[Trajectory],
    scenario: Scenario,
    plan_scenario: str | None = None,
    smoothed: bool = False,
    kinematics: bool = True,
    *,
    trajectory: str | None = None,
    model: Any = None,
    speed: bool = True,
) -> VerifyReport:
    """Run every check on parsed trajectories (see the module docstring).

    Args:
        trajs: one timed polyline per UAV.
        scenario: the world to check against.
        plan_scenario: the scenario name the plan gives (a warning if it differs).
        smoothed: the trajectories are the plan's informative smoothed paths (for the report).
        kinematics: also check the UAV's kinematic limits (turn radius, climb and descent
            angles, minimum speed); the maximum speed is checked either way.
        trajectory: what the trajectories are, for the report (``"flown"``, ``"planned"`` or
            ``"smoothed"``); default ``"smoothed"`` with ``smoothed``, else ``"flown"`` with
            ``kinematics`` and ``"planned"`` without.
        model: the execution model the plan must tolerate (an ``ExecutionModel`` or its
            record); None or nominal: the plan as flown exactly. Under a model the checks of
            :mod:`uavplan.verify.robust` run too and the report carries the margins.
        speed: check the maximum speed (False: for sampled executions of a plan, which fly
            off its speeds by design and would each carry tens of thousands of speed findings).
    """
    sc = scenario
    u = sc.uav
    if trajectory is None:
        trajectory = "smoothed" if smoothed else ("flown" if kinematics else "planned")
    report = VerifyReport(
        scenario=sc.name,
        plan_scenario=plan_scenario,
        smoothed=smoothed or trajectory == "smoothed",
        uav_ids=[t.id for t in trajs],
        n_segments=sum(len(t.times) - 1 for t in trajs),
        s2=float(max(u.s2_axes)) if u.s2_axes is not None else float(u.s2),
        s2_axes=u.s2_axes,
        trajectory=trajectory,
        kinematics=kinematics,
    )
    if plan_scenario is not None and plan_scenario != sc.name:
        report.warnings.append(
            f"the plan is for scenario {plan_scenario!r}, verifying against {sc.name!r}"
        )
    source = read_source(sc.terrain)
    report.terrain_source = source.name if source is not None else None
    tasks = {t.id: t for t in sc.tasks}
    per_uav: list[Violation] = []
    timed: list[Trajectory] = []
    polygons = sc.no_fly_polygons
    for tr in trajs:
        task = tasks.get(tr.id)
        if task is not None:
            for what, want, got in (
                ("start", task.start, tr.points[0]),
                ("goal", task.goal, tr.points[-1]),
            ):
                gap = float(np.linalg.norm(np.asarray(want) - got))
                if gap > 1e-3:
                    report.warnings.append(
                        f"{tr.id}: path {what} {fmt_points(got)} is {gap:.3f} m from the task's "
                        f"{what} {fmt_points(want)}"
                    )
        vs = check_times(tr)
        times_ok = not vs
        if not times_ok:
            report.warnings.append(
                f"{tr.id}: times decrease, left out of the separation and moving-obstacle checks"
            )
        else:
            timed.append(tr)
        if speed or kinematics:
            vs += check_speed(tr, u.v_max, float(u.min_speed) if kinematics else 0.0)
        if kinematics:
            vs += check_turn(tr, float(u.turn_radius))
            vs += check_climb(tr, u.max_climb_angle, u.max_descent_angle)
        vs += check_bounds(tr, sc.bounds.lower, sc.bounds.upper)
        if tr.dim == 3 and sc.cylinders:
            vs += check_cylinders(tr, sc.cylinders)
        if sc.circles:
            vs += check_circles(tr, sc.circles)
        if polygons:
            vs += check_polygons(tr, polygons)
        if sc.moving_obstacles and times_ok:
            vs += check_moving(tr, sc.moving_obstacles)
        if source is not None and tr.dim == 3:  # the raster's own ground, read again
            found, said = check_source_terrain(tr, source, sc.altitude, sc.terrain)
            vs += found
            report.warnings += said
            if sc.altitude is not None and sc.altitude.reference != "ground":
                vs += check_terrain(tr, None, sc.altitude)
        else:
            vs += check_terrain(tr, sc.terrain, sc.altitude)
        if tr.feasible and vs:
            report.warnings.append(
                f"{tr.id}: the plan calls it feasible, the verifier found {len(vs)} violation(s)"
            )
        per_uav += vs
    sep = check_separation(timed, report.s2, axes=report.s2_axes)
    n = len(trajs)
    report.pairs_total = n * (n - 1) // 2
    report.pairs_checked = sep.pairs_checked
    report.min_separation = sep.min_distance
    report.min_separation_pair = sep.min_pair
    report.min_separation_time = sep.min_time
    under: list[Violation] = []
    if model is not None and not _nominal(model):
        nominal_bad = {v.uavs for v in sep.violations} | {(v.uavs[1], v.uavs[0])
                                                          for v in sep.violations}  # fmt: skip
        under = _under_model(trajs, timed, sc, report, model, source, nominal_bad)
    order = {k: i for i, k in enumerate(KINDS)}
    report.violations = sorted(per_uav + sep.violations + under,
                               key=lambda v: order.get(v.kind, 99))  # fmt: skip
    return report


def _nominal(model: Any) -> bool:
    rec = model.record() if hasattr(model, "record") else dict(model)
    return not any(float(rec.get(k, 0.0)) for k in ("takeoff_s", "speed", "track_h", "track_v",
                                                    "wind"))  # fmt: skip


#: The kind of violation a static clearance under the model is reported as.
_STATIC_KIND = {"cylinders": "cylinder", "circles": "circle", "polygons": "polygon",
                "bounds": "bounds", "terrain": "terrain", "altitude band's floor": "altitude",
                "altitude band's ceiling": "altitude", "obstacles": "cylinder"}  # fmt: skip


def _under_model(
    trajs: Sequence[Trajectory],
    timed: Sequence[Trajectory],
    sc: Scenario,
    report: VerifyReport,
    model: Any,
    source: Any,
    skip_pairs: set[tuple[str, ...]],
) -> list[Violation]:
    """The checks under the execution model and the margins (:mod:`uavplan.verify.robust`)."""
    u = sc.uav
    rec = model.record() if hasattr(model, "record") else dict(model)
    report.model = rec
    timing = R.timing_of(rec, float(u.speed))
    out: list[Violation] = []
    margins = {t.id: R.UAVMargin(t.id) for t in trajs}
    checks = (check_cylinders, check_circles, check_polygons)
    # the heights above the raster's ground a flight must keep to leave the model's vertical
    # error (over the ground, and inside a band above it): what the bound of the ground
    # within reach is refined toward
    band = sc.altitude
    targets = (timing.track_v, float("inf"))
    if band is not None and band.reference == "ground":
        targets = (max(timing.track_v, band.min + timing.track_v), band.max - timing.track_v)
    src = None if source is None else (
        lambda tr, reach: source_clearance(tr, source, reach, targets))  # fmt: skip
    what_model = (f"the execution model's tracking error ({timing.track_h:g} m horizontal, "
                  f"{timing.track_v:g} m vertical)")  # fmt: skip
    wind = _slope_wind(u, rec)
    ground_refs = sc.terrain is not None or (
        sc.altitude is not None and sc.altitude.reference == "ground")  # fmt: skip
    for tr in trajs:
        m = margins[tr.id]

        scratch: dict[str, Any] = {}  # the flight's grid nodes, kept over its bisections

        def vertical(reach: float, tr: Trajectory = tr, scratch: dict[str, Any] = scratch
                     ) -> tuple[float, str]:  # fmt: skip
            return R.vertical_clearance(tr, sc, src, terrain_clearance_extrema, reach,
                                        within_reach, scratch)  # fmt: skip

        def ground(e: float, vertical: Any = vertical) -> str:
            # a horizontal error moves the ground under the UAV: the ground checks must
            # still leave the model's vertical error
            ev_, by_ = vertical(e)
            return by_ if ev_ < timing.track_v - TOL else ""

        def ground_fails(e: float, tr: Trajectory = tr, scratch: dict[str, Any] = scratch
                         ) -> bool:  # fmt: skip
            return R.vertical_fails(tr, sc, terrain_clearance_extrema, e, timing.track_v - TOL,
                                    within_reach, scratch)  # fmt: skip

        use_ground = ground if tr.dim == 3 and ground_refs else None
        eh, by_h = R.horizontal_clearance(tr, sc, checks, timing.track_h, use_ground,
                                          ground_fails if src is None else None)  # fmt: skip
        hb = R.horizontal_bounds(tr, sc)
        if hb < eh:
            eh, by_h = hb, "bounds"
        m.take("track_h", eh, by_h)
        ev, by_v = vertical(timing.track_h)
        m.take("track_v", ev, by_v)
        for tol, need, by, axis in ((eh, timing.track_h, by_h, "horizontally"),
                                    (ev, timing.track_v, by_v, "vertically")):  # fmt: skip
            if tol < need - TOL:
                out.append(Violation(
                    _STATIC_KIND.get(by, "bounds"), (tr.id,), None, (), tol, need,
                    f"{tr.id}: keeps only {tol:.3f} m {axis} from its {by}, under "
                    f"{what_model}",
                ))  # fmt: skip
        if wind and tr.dim == 3:
            out += _lagged_under(tr, sc, src, timing, wind, what_model)
    # how far each fixed wing's heights can lag its plan in that wind, segment by segment:
    # the pairs and the moving obstacles are held that much farther apart
    lags = {tr.id: _lag_extent(tr, sc, wind) for tr in timed}
    if sc.moving_obstacles:
        for tr in timed:
            found, pm = R.moving_under(tr, sc.moving_obstacles, timing, lags[tr.id])
            out += found
            for p in pm:
                margins[tr.id].take("takeoff_s", p.takeoff_s, p.other)
                margins[tr.id].take("speed", p.speed, p.other)
                margins[tr.id].take("track_h", p.track_h, p.other)
                margins[tr.id].take("track_v", p.track_v, p.other)
            report.pair_margins += pm
    found, pm = R.separation_under(
        timed, float(u.separation_radius), timing, [lags[tr.id] for tr in timed]
    )
    out += [v for v in found if v.uavs not in skip_pairs]
    for p in pm:
        for a in (p.uav, p.other):
            margins[a].take("takeoff_s", p.takeoff_s, p.other if a == p.uav else p.uav)
            margins[a].take("speed", p.speed, p.other if a == p.uav else p.uav)
            margins[a].take("track_h", p.track_h, p.other if a == p.uav else p.uav)
            margins[a].take("track_v", p.track_v, p.other if a == p.uav else p.uav)
    report.pair_margins += pm
    report.pair_margins.sort(key=lambda p: (p.takeoff_s, p.speed, p.track_h))
    report.uav_margins = [margins[t.id] for t in trajs]
    return out


def _slope_wind(uav: Any, rec: Mapping[str, Any]) -> float:
    """The wind a fixed wing's heights are flown in under the model ``rec`` (not nominal): the
    larger of the model's and its airframe's calibration wind (``turn_wind``); 0 for a UAV
    that names no fixed-wing airframe or declares no climb or descent limit."""
    from uavplan.world.airframes import AIRFRAMES

    af = AIRFRAMES.get(getattr(uav, "airframe", None) or "")
    if af is None or af.kind != "fixed-wing":
        return 0.0
    if uav.max_climb_angle is None and uav.max_descent_angle is None:
        return 0.0
    return max(float(rec.get("wind", 0.0) or 0.0), float(af.turn_wind))


def _lag_extent(tr: Trajectory, sc: Scenario, wind: float) -> FloatArray:
    """Per segment, how far a fixed wing's heights can lag its plan in ``wind``
    (:func:`uavplan.verify.kinematics.heights_in_wind`; the larger of the segment's ends',
    where a segment's extremes lie), all 0 when the whole flight's lag is within ``LAG_TOL``
    or without wind: how much farther from the other UAVs and the moving obstacles each
    segment is held."""
    n = max(len(tr.times) - 1, 0)
    if not wind or tr.dim != 3 or not n:
        return np.zeros(n)
    u = sc.uav
    off = np.abs(heights_in_wind(tr, wind, u.max_climb_angle, u.max_descent_angle))
    if float(off.max()) <= LAG_TOL:
        return np.zeros(n)
    return np.maximum(off[:-1], off[1:])


def _lagged_under(
    tr: Trajectory, sc: Scenario, src: Any, timing: Any, wind: float, what_model: str
) -> list[Violation]:
    """A fixed wing's flight flown as high as its flight-path angle in ``wind`` lets it follow
    its planned heights (:func:`uavplan.verify.kinematics.heights_in_wind`) must still leave the
    model's vertical tracking error to the ground, the band and the bounds."""
    u = sc.uav
    off = heights_in_wind(tr, wind, u.max_climb_angle, u.max_descent_angle)
    k = int(np.argmax(np.abs(off)))
    if abs(off[k]) <= LAG_TOL:
        return []
    pairs = (("climbs", u.max_climb_angle), ("descents", u.max_descent_angle))
    limits = ", ".join(f"{w} within {a:g} degrees" for w, a in pairs if a is not None)
    why = (f"{tr.id}: flown with {wind:g} m/s of wind behind it, its slopes are steeper than its "
           f"airframe flies over the ground ({limits} through the air)")  # fmt: skip
    if abs(off[-1]) > max(LAG_TOL, timing.track_v) + TOL:
        side = "above" if off[-1] > 0 else "below"
        return [Violation(
            "climb", (tr.id,), float(tr.times[-1]), (tuple(float(x) for x in tr.points[-1]),),
            abs(float(off[-1])), max(LAG_TOL, timing.track_v),
            f"{why}: it reaches its goal's position {abs(off[-1]):.1f} m {side} the goal, "
            f"beyond {what_model}",
        )]  # fmt: skip
    pts = np.array(tr.points)
    pts[:, 2] += off
    lagged = Trajectory(tr.id, pts, tr.times, tr.feasible)
    ev, by = R.vertical_clearance(lagged, sc, src, terrain_clearance_extrema, timing.track_h,
                                  within_reach)  # fmt: skip
    if ev >= timing.track_v - TOL:
        return []
    side = "above" if off[k] > 0 else "below"
    return [Violation(
        _STATIC_KIND.get(by, "bounds"), (tr.id,), float(tr.times[k]),
        (tuple(float(x) for x in pts[k]),), ev, timing.track_v,
        f"{why}: up to {abs(off[k]):.1f} m {side} "
        f"its plan at t={tr.times[k]:.1f} s, it then keeps only {ev:.3f} m vertically from its "
        f"{by}, under {what_model}",
    )]  # fmt: skip


def verify_plan(
    plan: Mapping[str, Any],
    scenario: Scenario,
    smoothed: bool = False,
    trajectory: TrajectoryKind = "flown",
) -> VerifyReport:
    """Verify a decoded ``plan.json`` against ``scenario`` (see the module docstring).

    Args:
        plan: the decoded plan (``{"format", "scenario", "uavs": [{"id", "waypoints", "times",
            "flown", ...}, ...]}``).
        scenario: the world to check against.
        smoothed: the same as ``trajectory="smoothed"`` (kept for compatibility).
        trajectory: which trajectory of each UAV: ``"flown"`` (its declared ``flown`` block, the
            planned polyline where the plan declares none) and ``"smoothed"`` (the informative
            smoothed paths) are checked with the UAV's kinematic limits; ``"planned"`` (the
            planned polylines, geometric paths) without them.

    The flown trajectories are checked under the execution model the plan states (its
    ``execution`` block; none: as flown exactly).

    Raises:
        PlanFormatError: the plan cannot be read (a missing or malformed field, mismatched
            lengths, points of the wrong dimension, no smoothed path with ``smoothed=True``).
        ValueError: an unknown ``trajectory``, or ``smoothed=True`` with ``"planned"``.
    """
    if trajectory not in TRAJECTORIES:
        raise ValueError(f"trajectory must be one of {', '.join(TRAJECTORIES)}, got {trajectory!r}")
    if smoothed:
        if trajectory == "planned":
            raise ValueError("smoothed=True verifies the smoothed paths, not the planned ones")
        trajectory = "smoothed"
    pf = parse_plan(plan, scenario.dim)
    trajs = pf.trajectories(trajectory)
    return verify_trajectories(
        trajs,
        scenario,
        pf.scenario,
        smoothed=trajectory == "smoothed",
        kinematics=TRAJECTORIES[trajectory],
        trajectory=trajectory,
        model=pf.execution if trajectory == "flown" else None,
    )
