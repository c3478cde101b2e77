"""UAV classes and their airframes: what the simulated autopilot and airframe do.

A scenario's ``uav.airframe`` names one of :data:`AIRFRAMES`; without one, a UAV with a turn
radius or a minimum speed is a fixed wing (:data:`SMALL_FIXED_WING`), else a multirotor
(:data:`QUADROTOR`). The parameters are those of a point-mass model with first-order responses
(the batched model of :mod:`uavplan.sim.fleet`): docs/decisions.md ("Flight simulation") says
where each comes from and how the reference libraries were used to check them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

#: The UAV classes.
Kind = Literal["fixed-wing", "multirotor"]


@dataclass(frozen=True)
class Airframe:
    """A UAV class's airframe, autopilot and navigation.

    Attributes:
        name, kind: the airframe's name and its class.
        tau_speed: airspeed (fixed wing) response time constant, s.
        tau_bank: bank-angle response time constant, s (fixed wing).
        max_bank_deg: the bank limit, degrees (fixed wing; the turn radius the plan assumes
            needs ``atan(v^2 / (g R))``).
        tau_gamma: flight-path-angle response time constant, s (fixed wing).
        l1_period, l1_damping: L1 guidance period (s) and damping (ArduPilot's NAVL1_PERIOD
            and NAVL1_DAMPING; PX4's L1 controller the same).
        k_height: height error to climb-rate gain, 1/s (fixed wing) or vertical position gain
            (multirotor).
        k_speed, ki_speed: ground-speed error to airspeed command, proportional (-) and
            integral (1/s) (a fixed wing holds an airspeed; the mission commands ground
            speeds).
        tau_vel: velocity response time constant, s (multirotor).
        max_accel: the largest horizontal acceleration, m/s^2 (multirotor).
        k_pos: position error to velocity command gain, 1/s (multirotor, PX4's MPC_XY_P).
        drag: how gusts push a multirotor: acceleration per m/s of gust, 1/s.
        lead: how far the multirotor's setpoint may run ahead of it, m.
        nav_h, nav_v: the position estimate's error, 1-sigma, m (horizontal per axis,
            vertical); a first-order Gauss-Markov process.
        nav_tau: its correlation time, s.
        accept: the waypoint acceptance radius, m (a waypoint is passed within it, or once
            the UAV is past the line through it normal to the leg).
        tau_att: how fast a multirotor's acceleration follows its command (the attitude loop
            tilting the thrust, and the rotors), s.
        track_h, track_v: the tracking error the default execution model assumes for the
            class, m (horizontal, vertical): the largest per-flight error of the class's
            calibration flights (``benchmarks/calibrate_tracking.py``: the 99th percentile of
            each UAV flight's largest error, rounded up to half a metre; the default model
            never assumes less than 3 m and 2 m): the figure for a fleet of up to ten.
        tail_h, tail_v: the same flights' per-flight largest errors (horizontal, vertical) as
            ``(u, scale)``: their 95th percentile ``u`` and the scale of the exponential tail
            fitted above it (the mean excess over ``u``), from which :func:`fleet_tracking`
            reads the error a larger fleet's flights stay within (None: ``track_h``,
            ``track_v`` for every fleet).
        turn_wind: the wind (m/s) a fixed wing's planned turns leave room for, the
            calibration's: uavplan's default plans its turns no tighter than the airframe can
            fly at its bank limit with this much wind behind it (:func:`turn_radius_in_wind`)
            nor than its L1 distance at that ground speed (:func:`planned_turn_radius`).
        speed_margin: how much faster than the plan's cruise speed the airframe can fly, a
            fraction of it (the airspeed a fixed wing may take to hold its commanded ground
            speed into a headwind; a multirotor's velocity limit, whose controller holds
            ground velocity in a steady wind); the scenario's ``max_speed`` when that is
            larger (:func:`top_speed`). The quadrotor's is 0: its calibration flew it at
            the plan's speed.
        turn_accel: the horizontal acceleration a multirotor's planned turns take at its
            cruise speed, m/s^2 (uavplan's default plans its corners as curves of radius
            ``v^2 / turn_accel``, :func:`planned_turn_radius`; 0: corners as given). A
            multicopter's mission slows down for a sharp corner, so a polyline timed at a
            constant speed is flown late by seconds per corner; a curve it can fly at its
            cruise speed keeps its schedule.
    """

    name: str
    kind: Kind
    tau_speed: float = 2.0
    tau_bank: float = 0.3
    max_bank_deg: float = 65.0
    tau_gamma: float = 0.8
    l1_period: float = 6.0
    l1_damping: float = 0.75
    k_height: float = 0.4
    k_speed: float = 0.5
    ki_speed: float = 0.1
    tau_vel: float = 0.4
    max_accel: float = 5.0
    k_pos: float = 0.95
    drag: float = 0.35
    lead: float = 10.0
    nav_h: float = 1.0
    nav_v: float = 1.5
    nav_tau: float = 100.0
    accept: float = 2.0
    tau_att: float = 0.15
    track_h: float = 3.0
    track_v: float = 2.0
    tail_h: tuple[float, float] | None = None
    tail_v: tuple[float, float] | None = None
    turn_wind: float = 3.0
    speed_margin: float = 0.25
    turn_accel: float = 0.0

    def record(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


#: The expected number of a fleet's flights that leave the tracking error uavplan's default
#: model states, in one execution (:func:`fleet_tracking`).
FLEET_ALPHA = 0.1


def fleet_tracking(af: Airframe, n_uavs: int) -> tuple[float, float]:
    """The tracking error ``(h, v)`` uavplan's default model states for a fleet of ``n_uavs``
    UAVs of airframe ``af``.

    The airframe's ``track_h``, ``track_v`` are the 99th percentile of a calibration flight's
    largest error: about one flight in a hundred leaves them, so a fleet of hundreds has
    several flights outside its plan's model in every execution, and any of them near the
    band's edge or another UAV breaks the plan. For a fleet, the stated error is the quantile
    a flight exceeds with probability ``FLEET_ALPHA / n_uavs`` (so that the expected number of
    the fleet's flights beyond it in one execution is at most :data:`FLEET_ALPHA`): on the
    exponential tail fitted to the calibration flights above their 95th percentile ``u``
    (``tail_h``, ``tail_v``), ``u + scale * ln(0.05 n / FLEET_ALPHA)``, rounded up to half a
    metre, never below ``track_h``, ``track_v``. An exponential tail is the extreme-value
    model of a maximum whose parent distribution is light-tailed (the Gumbel domain: Gaussian
    navigation error, turbulence); beyond the calibration's flights it is an extrapolation,
    which the fleets' simulated executions check (docs/results.md)."""

    def one(base: float, tail: tuple[float, float] | None) -> float:
        if tail is None or n_uavs <= 0:
            return base
        u, scale = tail
        q = u + scale * math.log(0.05 * n_uavs / FLEET_ALPHA)
        return max(base, math.ceil(2.0 * q - 1e-9) / 2.0)

    return one(af.track_h, af.tail_h), one(af.track_v, af.tail_v)


#: A small fixed wing (the PPSwarm UAV: 20 m/s, 20 m turns, a 64 degree bank at cruise; up to
#: 1.3 times its cruise airspeed, as small survey airframes fly 15-20 m/s and reach 25-30).
SMALL_FIXED_WING = Airframe("small-fixed-wing", "fixed-wing", track_h=6.0, track_v=8.0,
                            tail_h=(4.20, 0.49), tail_v=(6.50, 0.74),
                            speed_margin=0.3)  # fmt: skip
#: A fast fixed wing (RSCDWOA's UAV: 50 m/s, 2 km turns): slower responses, gentle banks. Its
#: tracking error is calibrated on the default plans of both RSCDWOA layouts (polylines: their
#: corners are cut by the L1 guidance, which sets the horizontal figure).
FAST_FIXED_WING = Airframe("fast-fixed-wing", "fixed-wing", tau_speed=4.0, tau_bank=0.6,
                           max_bank_deg=35.0, tau_gamma=1.5, l1_period=17.0,
                           k_height=0.2, accept=10.0, track_h=14.5, track_v=22.0,
                           tail_h=(11.65, 1.89), tail_v=(17.30, 2.98),
                           speed_margin=0.2)  # fmt: skip
#: A quadrotor under a position and velocity controller (PX4's multicopter defaults; its
#: planned turns at PX4's default horizontal acceleration in missions, MPC_ACC_HOR 3 m/s^2,
#: within the 5 m/s^2 it can take, MPC_ACC_HOR_MAX, leaving the rest for gusts).
QUADROTOR = Airframe(
    "quadrotor",
    "multirotor",
    nav_h=0.8,
    nav_v=1.0,
    accept=2.0,
    track_h=4.5,
    track_v=4.0,
    tail_h=(2.93, 0.38),
    tail_v=(3.06, 0.39),
    speed_margin=0.0,
    turn_accel=3.0,
)

AIRFRAMES: dict[str, Airframe] = {a.name: a for a in (SMALL_FIXED_WING, FAST_FIXED_WING,
                                                      QUADROTOR)}  # fmt: skip


def airframe_of(uav: Any) -> Airframe:
    """The airframe of a scenario's UAV: its ``airframe`` when named, else by its limits."""
    name = getattr(uav, "airframe", None)
    if name:
        try:
            return AIRFRAMES[name]
        except KeyError:
            raise ValueError(
                f"unknown airframe {name!r}; choose from {', '.join(sorted(AIRFRAMES))}"
            ) from None
    if float(getattr(uav, "turn_radius", 0.0)) > 0 or float(getattr(uav, "min_speed", 0.0)) > 0:
        return SMALL_FIXED_WING
    return QUADROTOR


def top_speed(af: Airframe, uav: Any) -> float:
    """The fastest the airframe flies a plan of ``uav`` (m/s): ``1 + speed_margin`` times the
    UAV's cruise speed, or the scenario's ``max_speed`` when that is larger. The plan's own
    speeds stay within the scenario's limits; the margin is what the autopilot may use to hold
    them (a fixed wing holds a commanded ground speed into a headwind only with airspeed to
    spare)."""
    return max(float(uav.v_max), (1.0 + af.speed_margin) * float(uav.speed))


def bank_for(speed: float, radius: float) -> float:
    """The bank angle (degrees) of a coordinated turn of ``radius`` at ``speed``."""
    return math.degrees(math.atan(speed * speed / (9.80665 * radius))) if radius > 0 else 0.0


def planned_turn_radius(af: Airframe, speed: float) -> float:
    """The tightest turn (m) uavplan's default plans for airframe ``af`` at ``speed``: a fixed
    wing's at its bank limit with its ``turn_wind`` behind it (:func:`turn_radius_in_wind`),
    and no tighter than its guidance's L1 distance at that ground speed
    (:func:`l1_distance`); a multirotor's at its ``turn_accel`` (``v^2 / a``: a turn it flies
    at the planned speed, where its mission would slow down for a corner); 0 for none."""
    if af.kind == "fixed-wing":
        return max(turn_radius_in_wind(af, speed), l1_distance(af, speed + af.turn_wind))
    return speed * speed / af.turn_accel if af.turn_accel > 0 else 0.0


def l1_distance(af: Airframe, ground_speed: float) -> float:
    """How far ahead (m) a fixed wing's L1 guidance aims at ``ground_speed``:
    ``damping * period * v / pi`` (ArduPilot's ``AP_L1_Control``, Park, Deyst and How 2004).

    The law steers towards the point of the path this far ahead, so along a turn whose radius
    is below it the point runs off the arc onto the next leg before the UAV does: it turns in
    late and swings out of a long turn at its bank limit: in simulation such turns carried
    most of the flights that left the plan's tracking error (docs/decisions.md, "A fixed
    wing's tightest planned turn"; docs/results.md gives the runs). The simulated guidance
    (:mod:`uavplan.sim.fleet`) aims at this distance too."""
    return af.l1_damping * af.l1_period * ground_speed / math.pi


def turn_radius_in_wind(af: Airframe, speed: float, wind: float | None = None) -> float:
    """The tightest turn (m) a fixed wing of airframe ``af`` holds at airspeed ``speed`` with
    ``wind`` (m/s, the airframe's ``turn_wind`` when None) behind it: the ground speed
    ``speed + wind`` at the bank limit, ``(v + W)^2 / (g tan(bank))``. 0 for a multirotor."""
    if af.kind != "fixed-wing":
        return 0.0
    w = af.turn_wind if wind is None else wind
    return (speed + w) ** 2 / (9.80665 * math.tan(math.radians(af.max_bank_deg)))
