"""One simulated execution of a plan (:func:`simulate_once`): the conditions drawn from a
seed (each UAV's take-off error within the plan's execution model, a steady wind, the
turbulence's intensity, the navigation errors), every UAV's exported mission flown by the
batched model (:mod:`uavplan.sim.fleet`), and the flown tracks with their tracking and timing
errors against the trajectories the plan verified. Whether the tracks are safe is for the
independent verifier to say (:mod:`uavplan.bench.simulation`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import PlanFile, Trajectory
from uavplan.sim import _error_kernels as EK
from uavplan.sim.fleet import DRAWS, init_state, params, step_fleet
from uavplan.sim.missions import Legs, mission_legs
from uavplan.sim.turbulence import INTENSITIES
from uavplan.world.airframes import Airframe, airframe_of

FloatArray = NDArray[np.float64]

#: Time step of the batched model, s, the recording interval of the tracks, s, and the steps
#: the kernel takes per call (the random draws of that many steps are made at once).
DT = 0.05
REC_DT = 0.5
CHUNK = 400


@dataclass(frozen=True)
class Conditions:
    """What one execution meets: ``wind_max`` (m/s, the steady wind's speed is uniform up to
    it, its direction uniform), ``turbulence`` (a name of
    :data:`~uavplan.sim.turbulence.INTENSITIES`), ``takeoff_s`` (each UAV's take-off error is
    uniform within it; None: the plan's execution model's), the navigation errors on
    (``nav``), the height the gust scales use (``h_agl``, m)."""

    wind_max: float = 3.0
    turbulence: str = "light"
    takeoff_s: float | None = None
    nav: bool = True
    h_agl: float = 100.0

    def record(self) -> dict[str, Any]:
        return {"wind_max": self.wind_max, "turbulence": self.turbulence,
                "takeoff_s": self.takeoff_s, "nav": self.nav, "h_agl": self.h_agl}  # fmt: skip


@dataclass
class Execution:
    """One simulated execution: the tracks (as trajectories the verifier reads), the drawn
    conditions, per UAV the largest horizontal and vertical tracking errors (the vertical
    beyond the height lag the plan was verified with, :func:`plan_slack`) and the timing
    error range (s, actual minus planned time at the same point of the path), and all samples'
    errors pooled (for quantiles); per UAV the range of its schedule lag and how far it went
    outside the plan's execution model (:func:`conformance`: ``excess`` > 0 s: outside)."""

    tracks: list[Trajectory]
    wind: FloatArray
    takeoff_errors: dict[str, float]
    track_h: dict[str, float] = field(default_factory=dict)
    track_v: dict[str, float] = field(default_factory=dict)
    timing: dict[str, tuple[float, float]] = field(default_factory=dict)
    samples_h: FloatArray = field(default_factory=lambda: np.zeros(0))
    samples_v: FloatArray = field(default_factory=lambda: np.zeros(0))
    samples_t: FloatArray = field(default_factory=lambda: np.zeros(0))
    lag: dict[str, tuple[float, float]] = field(default_factory=dict)
    excess: dict[str, float] = field(default_factory=dict)
    finished: int = 0
    items: dict[str, int] = field(default_factory=dict)


def pack(legs: list[Legs]) -> tuple[FloatArray, NDArray[np.int64], FloatArray, FloatArray]:
    """The kernel's padded arrays of every UAV's legs."""
    U = len(legs)
    N = max(len(lg.points) for lg in legs)
    P = np.zeros((U, N, 3))
    S = np.zeros((U, N))
    H = np.zeros((U, N))
    n = np.zeros(U, dtype=np.int64)
    for i, lg in enumerate(legs):
        m = len(lg.points)
        P[i, :m] = lg.points
        P[i, m:] = lg.points[-1]
        S[i, : m - 1] = lg.speeds
        H[i, :m] = lg.holds
        n[i] = m
    return P, n, S, H


def _slack(planned: Trajectory, slack: FloatArray | None) -> FloatArray:
    """The plan's vertical slack per point (zeros: none)."""
    if slack is None:
        return np.zeros(len(planned.times))
    return np.ascontiguousarray(slack, dtype=np.float64)


def errors_against(
    track: Trajectory, planned: Trajectory, window: float = 120.0, slack: FloatArray | None = None
) -> tuple[FloatArray, ...]:
    """:func:`errors_against_reference`'s answers from a Numba kernel
    (:func:`uavplan.sim._error_kernels.errors_kernel`: only the segments within the window)."""
    Q = np.ascontiguousarray(track.points, dtype=np.float64)
    P = np.ascontiguousarray(planned.points, dtype=np.float64)
    tp = np.ascontiguousarray(planned.times, dtype=np.float64)
    g = _slack(planned, slack)
    n = len(Q)
    h, v, te = np.empty(n), np.empty(n), np.empty(n)
    EK.errors_kernel(Q, np.ascontiguousarray(track.times, dtype=np.float64), P[:-1], P[1:],
                     tp[:-1], tp[1:], g[:-1], g[1:], float(window), h, v, te)  # fmt: skip
    return h, v, te


def errors_against_reference(
    track: Trajectory, planned: Trajectory, window: float = 120.0, slack: FloatArray | None = None
) -> tuple[FloatArray, ...]:
    """Per sample of ``track``: the horizontal and vertical distances to the nearest point of
    the ``planned`` path (nearest in 3-D, each segment's point horizontally nearest, among the
    segments the plan flies within ``window`` seconds of the sample's time: a path that
    passes near itself, as a climbing or descending loop does a few metres above or below,
    is not matched to its other pass) and the time error there (actual minus the planned time
    at that point). ``slack`` (per planned point, m, interpolated along the segments): heights
    within it of the plan's count as on it, and the vertical distance is what lies beyond it
    (:func:`plan_slack`: the height lag the verifier allows a fixed wing)."""
    A = planned.points[:-1]
    B = planned.points[1:]
    tA, tB = planned.times[:-1], planned.times[1:]
    g = _slack(planned, slack)
    gA, gB = g[:-1], g[1:]
    Q = track.points
    h = np.empty(len(Q))
    v = np.empty(len(Q))
    te = np.empty(len(Q))
    D = B[:, :2] - A[:, :2]
    dd = np.maximum(np.einsum("ij,ij->i", D, D), 1e-12)
    for lo in range(0, len(Q), 256):
        q = Q[lo : lo + 256]
        r = q[:, None, :2] - A[None, :, :2]
        s = np.clip(np.einsum("qij,ij->qi", r, D) / dd, 0.0, 1.0)
        foot = A[None, :, :2] + s[..., None] * D[None]
        d2 = np.sum((q[:, None, :2] - foot) ** 2, axis=2)
        dz = q[:, None, 2] - (A[None, :, 2] + s * (B[None, :, 2] - A[None, :, 2]))
        dz = np.copysign(np.maximum(np.abs(dz) - (gA[None] + s * (gB - gA)[None]), 0.0), dz)
        tq = track.times[lo : lo + 256, None]
        near = (tB[None] >= tq - window) & (tA[None] <= tq + window)
        j = np.argmin(np.where(near | ~near.any(axis=1, keepdims=True), d2 + dz * dz, np.inf),
                      axis=1)  # fmt: skip
        rows = np.arange(len(q))
        sj = s[rows, j]
        h[lo : lo + 256] = np.sqrt(d2[rows, j])
        v[lo : lo + 256] = dz[rows, j]
        te[lo : lo + 256] = track.times[lo : lo + 256] - (tA[j] + sj * (tB[j] - tA[j]))
    return h, v, te


#: The least time window of :func:`errors_against`, s, and what :func:`error_window` adds to
#: the schedule error a flight can reach.
ERROR_WINDOW, WINDOW_SLACK = 120.0, 60.0


def error_window(planned: Trajectory, takeoff_error: float, wind: float, speed: float) -> float:
    """The time window (s) a flight's errors against ``planned`` are measured in: the
    schedule error it can reach (its take-off error, and over its planned duration the share
    ``wind / speed`` by which a UAV of one airspeed runs ahead or behind in a steady wind),
    plus :data:`WINDOW_SLACK`, at least :data:`ERROR_WINDOW`. A fast fixed wing of one
    airspeed on a 50-minute flight runs minutes off its plan's times in 3 m/s; with a fixed
    two-minute window its samples were matched to the nearest segment of the wrong
    stretch, hundreds of metres off."""
    span = float(planned.times[-1] - planned.times[0])
    reach = takeoff_error + span * wind / max(speed, 1e-9)
    return max(ERROR_WINDOW, reach + WINDOW_SLACK)


#: The schedule shifts :func:`conformance` tries reach at least this far, s, in steps of
#: ``LAG_STEP`` (a flight farther off its schedule reads as never conforming).
LAG_SPAN, LAG_STEP = 60.0, 0.05


def shifts(track: Trajectory, planned: Trajectory, delta0: float, rho: float) -> FloatArray:
    """The schedule shifts :func:`conformance` tries: ``LAG_STEP`` apart, symmetric about 0,
    out to :data:`LAG_SPAN` or twice the largest the model allows over the flight
    (``delta0 + rho * (t - planned take-off)``), whichever is more: a fast fixed wing of one
    airspeed is allowed minutes on a long flight."""
    allowed = delta0 + rho * max(float(track.times[-1] - planned.times[0]), 0.0)
    span = max(LAG_SPAN, math.ceil(2.0 * allowed / LAG_STEP) * LAG_STEP)
    return np.arange(-span, span + LAG_STEP / 2, LAG_STEP)


def conformance(
    track: Trajectory, planned: Trajectory, delta0: float, rho: float, e_h: float, e_v: float,
    slack: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """:func:`conformance_reference`'s answers from a Numba kernel
    (:func:`uavplan.sim._error_kernels.conformance_kernel`: the shifts searched outwards from
    none, all of them only where none is in tolerance)."""
    taus = shifts(track, planned, delta0, rho)
    t = np.ascontiguousarray(track.times, dtype=np.float64)
    tp = np.ascontiguousarray(planned.times, dtype=np.float64)
    lag, need = np.empty(len(t)), np.empty(len(t))
    EK.conformance_kernel(t, np.ascontiguousarray(track.points, dtype=np.float64), taus, tp,
                          np.ascontiguousarray(planned.points, dtype=np.float64),
                          _slack(planned, slack), max(e_h, 1e-6), max(e_v, 1e-6), lag,
                          need)  # fmt: skip
    allowed = delta0 + rho * np.maximum(t - tp[0], 0.0)
    return lag, need - allowed


def conformance_reference(
    track: Trajectory, planned: Trajectory, delta0: float, rho: float, e_h: float, e_v: float,
    slack: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """How a flown ``track`` conforms to its ``planned`` trajectory under an execution model
    (take-off error ``delta0`` s, speed fraction ``rho``, tracking errors ``e_h``, ``e_v`` m):
    per sample at time ``t``, the schedule lag (the shift ``tau`` that brings the plan's
    position at ``t - tau`` nearest, horizontal and vertical distances scaled by ``e_h`` and
    ``e_v``, among the shifts in tolerance joined to the least one: on a loop, another pass
    is not taken for a lag; where no shift is in tolerance, the nearest) and the excess: the
    least ``|tau|`` that puts the sample within ``e_h`` and ``e_v`` of the plan at
    ``t - tau``, minus the model's allowance
    ``delta0 + rho * (t - planned take-off)``. The model holds for the flight where every
    excess is at most 0: the flown position is always inside the 4-D volume the plan was
    made and verified for (ASTM F3548's conformance of an operational intent). Unlike the
    nearest-point timing error of :func:`errors_against`, a pass of the path near another
    pass of itself cannot be mistaken for it: positions are compared at times. With a
    ``slack`` (per planned point, interpolated), a height is in tolerance within ``e_v`` plus
    the slack of the plan's: the height lag the verifier allows a fixed wing's flight on top
    of the model's error (:func:`plan_slack`)."""
    taus = shifts(track, planned, delta0, rho)
    t = track.times
    tp, pp = planned.times, planned.points
    lag = np.empty(len(t))
    need = np.empty(len(t))
    sh, sv = max(e_h, 1e-6), max(e_v, 1e-6)
    g = _slack(planned, slack)
    for lo in range(0, len(t), 32):
        tq = np.clip(t[lo : lo + 32, None] - taus[None], tp[0], tp[-1])
        q = track.points[lo : lo + 32]
        dz = np.maximum(np.abs(np.interp(tq, tp, pp[:, 2]) - q[:, None, 2])
                        - np.interp(tq, tp, g), 0.0)  # fmt: skip
        dx = np.interp(tq, tp, pp[:, 0]) - q[:, None, 0]
        dy = np.interp(tq, tp, pp[:, 1]) - q[:, None, 1]
        d = np.maximum(np.hypot(dx, dy) / sh, np.abs(dz) / sv)
        ok = d <= 1.0
        within = np.where(ok, np.abs(taus)[None], np.inf)
        least = np.argmin(within, axis=1)
        rows = np.arange(len(q))
        need[lo : lo + 32] = within[rows, least]
        # the best-aligned shift among the admissible ones joined to the least (a run of
        # shifts in tolerance; another pass of a loop is another run)
        run = np.cumsum(~ok, axis=1)
        mine = ok & (run == run[rows, least][:, None])
        best = np.argmin(np.where(mine, d, np.inf) + 1e-9 * np.abs(taus)[None], axis=1)
        nearest = np.argmin(d + 1e-9 * np.abs(taus)[None], axis=1)
        lag[lo : lo + 32] = taus[np.where(np.isfinite(need[lo : lo + 32]), best, nearest)]
    allowed = delta0 + rho * np.maximum(t - tp[0], 0.0)
    return lag, need - allowed


def plan_slack(planned: Trajectory, scenario: Any, model: Any) -> FloatArray | None:
    """Per point of a ``planned`` trajectory, how far the verifier lets its flight's heights
    be off the plan's on top of the model's vertical tracking error: a fixed wing's height lag
    (:func:`uavplan.world.execution.height_lag`) in the wind its heights are checked against
    (:func:`~uavplan.world.execution.slope_wind`: the model's, at least the airframe's
    calibration wind), as the verifier's pairs and heights checks allow it; None where there
    is none (a multirotor, a nominal plan, a lag within
    :data:`~uavplan.world.tolerances.LAG_TOL`). A descent planned at the airframe's limit is
    flown above the plan with the wind behind it: that gap is allowed by the plan and is not
    the tracking error the model states."""
    from uavplan.world.execution import height_lag, slope_wind
    from uavplan.world.tolerances import LAG_TOL

    u = scenario.uav
    wind = slope_wind(u, model)
    if not wind or planned.dim != 3 or len(planned.times) < 2:
        return None
    off = np.abs(height_lag(planned.points[None], planned.times[None], wind,
                            u.max_climb_angle, u.max_descent_angle))[0]  # fmt: skip
    return off if float(off.max()) > LAG_TOL else None


def simulate_once(
    plan: PlanFile,
    scenario: Any,
    seed: int,
    conditions: Conditions = Conditions(),
    airframe: Airframe | None = None,
    max_items: int = 500,
) -> Execution:
    """Fly ``plan``'s exported missions once under conditions drawn from ``seed``."""
    from uavplan.io.missions import ExportOptions, Mission
    from uavplan.world.geo import GeoOrigin

    af = airframe or airframe_of(scenario.uav)
    rng = np.random.default_rng(seed)
    opts = ExportOptions(frame="amsl", end="none", max_items=max_items)
    if plan.origin is None and scenario.origin is None:  # only the round trip needs one
        plan = dataclasses.replace(plan, origin=GeoOrigin(0.0, 0.0, 0.0))
    mission = Mission(plan, scenario, opts)
    legs = mission_legs(mission, float(scenario.uav.speed))
    rec = dict(plan.execution or {})
    d0 = float(conditions.takeoff_s if conditions.takeoff_s is not None
               else rec.get("takeoff_s", 0.0))  # fmt: skip
    errs = rng.uniform(-d0, d0, len(legs)) if d0 > 0 else np.zeros(len(legs))
    speed = rng.uniform(0.0, conditions.wind_max)
    heading = rng.uniform(0.0, 2 * math.pi)
    wind = np.array([speed * math.cos(heading), speed * math.sin(heading), 0.0])
    P, n, S, H = pack(legs)
    t0 = np.array([lg.takeoff for lg in legs]) + errs
    kind = 0 if af.kind == "fixed-wing" else 1
    prm = params(af, scenario.uav)
    if not conditions.nav:
        prm = (*prm[:14], 0.0, 0.0, *prm[16:])
    planned = plan.trajectories("flown")
    span = max(float(tr.times[-1] - tr.times[0]) for tr in planned)
    t_end = float(t0.max()) + 2.0 * span + 120.0
    R = math.ceil((2.0 * span + 120.0) / REC_DT) + 2
    U = len(legs)
    out_xyz = np.zeros((U, R, 3))
    out_t = np.zeros((U, R))
    out_n = np.zeros(U, dtype=np.int64)
    w20 = INTENSITIES[conditions.turbulence]
    nav0 = rng.standard_normal((U, 3)) * np.array([prm[14], prm[14], prm[15]])
    st = init_state(P, n, S, H, t0, nav0, wind, prm if kind == 0 else None)
    t = float(t0.min())
    finished = 0
    while t < t_end and finished < U:
        noise = rng.standard_normal((U, CHUNK, DRAWS))
        finished = step_fleet(st, P, n, S, H, t0, kind, prm, wind, w20, conditions.h_agl, DT, t,
                              CHUNK, REC_DT, noise, out_xyz, out_t, out_n)  # fmt: skip
        t += CHUNK * DT
    tracks = []
    ex = Execution([], wind, {lg.uav: float(e) for lg, e in zip(legs, errs, strict=True)},
                   finished=int(finished), items={lg.uav: lg.items for lg in legs})  # fmt: skip
    hs, vs, ts = [], [], []
    from uavplan.world.execution import ExecutionModel

    model = ExecutionModel.from_record(plan.execution) if plan.execution else None
    delta0, rho = model.timing(float(scenario.uav.speed)) if model else (0.0, 0.0)
    for i, (lg, pl) in enumerate(zip(legs, planned, strict=True)):
        m = int(out_n[i])
        tr = Trajectory(lg.uav, out_xyz[i, :m].copy(), out_t[i, :m].copy(), True)
        tracks.append(tr)
        slack = plan_slack(pl, scenario, model)
        window = error_window(pl, abs(float(errs[i])), float(np.linalg.norm(wind)),
                              float(scenario.uav.speed))  # fmt: skip
        h, v, te = errors_against(tr, pl, window, slack)
        ex.track_h[lg.uav] = float(h.max()) if m else math.nan
        ex.track_v[lg.uav] = float(np.abs(v).max()) if m else math.nan
        ex.timing[lg.uav] = (float(te.min()), float(te.max())) if m else (math.nan, math.nan)
        if m:
            lag, excess = conformance(tr, pl, delta0, rho, model.track_h if model else 0.0,
                                      model.track_v if model else 0.0, slack)  # fmt: skip
            ex.lag[lg.uav] = (float(lag.min()), float(lag.max()))
            ex.excess[lg.uav] = float(excess.max())
        hs.append(h)
        vs.append(v)
        ts.append(te)
    ex.tracks = tracks
    ex.samples_h = np.concatenate(hs) if hs else np.zeros(0)
    ex.samples_v = np.concatenate(vs) if vs else np.zeros(0)
    ex.samples_t = np.concatenate(ts) if ts else np.zeros(0)
    return ex
