"""The batched model's references: the same missions flown through a maintained
flight-dynamics library (the optional extra ``uavplan[sim]``).

* **Multirotor: rotorpy** (Folk et al., PyPI ``rotorpy``): PX4's SIH quadrotor parameters
  (1 kg, rotor dynamics, parasitic drag) under rotorpy's geometric SE(3) controller, tracking
  the setpoint a multicopter mission makes of the legs (:func:`setpoint_series`: the leg speed,
  slowed before corners as the batched model's setpoint is), in Dryden gusts of the same
  intensity (:mod:`uavplan.sim.turbulence`, world-frame ``u`` and ``v`` along x and y).
  :func:`compare_multirotor` flies both and returns their cross-track errors; the batched
  model runs with the reference controller's gains (position and velocity gains of rotorpy's
  SE(3) controller as ``k_pos / tau_vel`` and ``1 / tau_vel``, its drag as rotorpy's at the
  leg speed), so what is compared is the dynamics, not two tunings.

* **Fixed wing: JSBSim** (Berndt et al., PyPI ``jsbsim``): its Cessna 172 (``c172x``, the
  smallest powered airplane its package ships; 50 m/s is its cruise, the speed of the
  ``fast-fixed-wing`` class) trimmed in level flight, flown by the batched model's guidance
  (the same L1 law, period, damping and bank limit, the same height loop's gain and slope
  feed-forward, the same ground-speed target) through inner loops of ours that stand in for
  an autopilot's: bank by aileron (a PI on the bank error with roll-rate damping), the
  commanded climb rate by pitch (a PI on the climb-rate error setting the pitch attitude, held
  by elevator with pitch-rate damping), ground speed by throttle (PI). Turbulence is JSBSim's
  own MIL-F-8785C/MIL-HDBK-1797 Dryden model (``turb-type`` 3) at the same wind at 20 ft, so
  the gusts too are not ours. :func:`compare_fixed_wing` flies both and returns their
  horizontal and vertical errors; the batched model runs with ``fast-fixed-wing`` at the
  Cessna's 30 degree bank limit and without navigation error (JSBSim's flight is flown on
  true position).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.sim.missions import Legs
from uavplan.sim.turbulence import INTENSITIES, gust_series

FloatArray = NDArray[np.float64]


def setpoint_series(legs: Legs, a_max: float, dt: float) -> tuple[FloatArray, ...]:
    """The multirotor setpoint along ``legs`` as a function of time (open loop: it never waits
    for the vehicle): times, positions, velocities, accelerations, (m,) and (m, 3)."""
    P, S = legs.points, legs.speeds
    pos, vel = [P[0].copy()], [np.zeros(3)]
    for k in range(len(P) - 1):
        d = P[k + 1] - P[k]
        L = float(np.linalg.norm(d[:2]))
        if L < 1e-9:
            continue
        u3 = d / L
        v_corner = 0.0
        if k + 2 < len(P):
            n2 = P[k + 2, :2] - P[k + 1, :2]
            nl = float(np.linalg.norm(n2))
            if nl > 1e-9:
                v_corner = float(S[k]) * max(float(n2 @ d[:2]) / (nl * L), 0.0)
        s = 0.0
        while s < L:
            v = min(float(S[k]), math.sqrt(v_corner**2 + a_max * (L - s)))
            s = min(s + v * dt, L)
            pos.append(P[k] + u3 * s)
            vel.append(u3 * v)
    p = np.asarray(pos)
    vv = np.asarray(vel)
    # the feed-forward acceleration, smoothed over 0.3 s and within the braking limit (a
    # velocity step where a leg's slope changes would be an impulse)
    acc = np.clip(np.gradient(vv, dt, axis=0), -a_max, a_max)
    w = max(int(0.3 / dt), 1)
    acc = np.stack([np.convolve(acc[:, i], np.ones(w) / w, mode="same") for i in range(3)], 1)
    t = legs.takeoff + dt * np.arange(len(p), dtype=float)
    return t, p.astype(float), vv.astype(float), acc.astype(float)


def cross_track(points: FloatArray, path: FloatArray) -> FloatArray:
    """Horizontal distance of each point to the polyline ``path``."""
    A, B = path[:-1, :2], path[1:, :2]
    D = B - A
    dd = np.maximum(np.einsum("ij,ij->i", D, D), 1e-12)
    r = points[:, None, :2] - A[None]
    s = np.clip(np.einsum("qij,ij->qi", r, D) / dd, 0.0, 1.0)
    foot = A[None] + s[..., None] * D[None]
    return np.asarray(np.sqrt(np.min(np.sum((points[:, None, :2] - foot) ** 2, axis=2), axis=1)))


def _rotorpy_flight(legs: Legs, turbulence: str, seed: int, rate: float = 100.0) -> FloatArray:
    """rotorpy's SIH quadrotor under its SE(3) controller tracking the legs' setpoint in Dryden
    gusts; its positions every 0.5 s."""
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.environments import Environment
    from rotorpy.vehicles.multirotor import Multirotor
    from rotorpy.vehicles.px4_sihsim_quadx_params import quad_params

    dt = 1.0 / rate
    t, p, v, a = setpoint_series(legs, 5.0, dt)
    t = t - t[0]
    hold = 5.0  # seconds at the last point, to settle
    n = len(t)
    g = gust_series(n + int(hold * rate) + 10, float(np.mean(legs.speeds)), 100.0,
                    INTENSITIES[turbulence], dt, seed)  # fmt: skip

    class Setpoint:
        def update(self, tt: float) -> dict[str, Any]:
            i = min(int(tt * rate), n - 1)
            return {"x": p[i], "x_dot": v[i], "x_ddot": a[i], "x_dddot": np.zeros(3),
                    "x_ddddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0}  # fmt: skip

    class Gusts:
        def update(self, tt: float, position: Any) -> FloatArray:
            i = min(int(tt * rate), len(g) - 1)
            return np.asarray(g[i], dtype=np.float64)

    vehicle = Multirotor(quad_params, initial_state={
        "x": p[0].copy(), "v": v[0].copy(), "q": np.array([0.0, 0.0, 0.0, 1.0]),
        "w": np.zeros(3), "wind": np.zeros(3),
        "rotor_speeds": np.full(4, math.sqrt(quad_params["mass"] * 9.81 / 4
                                             / quad_params["k_eta"])),
    })  # fmt: skip
    env = Environment(vehicle=vehicle, controller=SE3Control(quad_params), trajectory=Setpoint(),
                      wind_profile=Gusts(), sim_rate=int(rate))  # fmt: skip
    res = env.run(t_final=float(t[-1]) + hold, terminate=False, plot=False, animate_bool=False,
                  verbose=False)  # fmt: skip
    x = np.asarray(res["state"]["x"])
    step = int(0.5 * rate)
    return x[::step]


def _batched_flight(legs: Legs, kind: int, prm: tuple[float, ...], w20: float, dt: float,
                    span: float, seed: int) -> FloatArray:  # fmt: skip
    """The batched model flying ``legs`` alone (``kind`` 0 fixed wing, 1 multirotor) for up to
    ``span`` seconds in Dryden gusts of wind ``w20`` at 20 ft, no steady wind; its positions
    every ``REC_DT``."""
    from uavplan.sim.fleet import DRAWS, init_state, step_fleet
    from uavplan.sim.runs import REC_DT, pack

    P, n, S, H = pack([legs])
    t0 = np.array([legs.takeoff])
    st = init_state(P, n, S, H, t0, np.zeros((1, 3)))
    R = int(span / REC_DT) + 10
    xyz, tt, nn = np.zeros((1, R, 3)), np.zeros((1, R)), np.zeros(1, dtype=np.int64)
    rng = np.random.default_rng(seed)
    steps = 400
    t = legs.takeoff
    while t < legs.takeoff + span:
        noise = rng.standard_normal((1, steps, DRAWS))
        done = step_fleet(st, P, n, S, H, t0, kind, prm, np.zeros(3), w20, 100.0, dt, t, steps,
                          REC_DT, noise, xyz, tt, nn)  # fmt: skip
        t += steps * dt
        if done:
            break
    return np.column_stack([tt[0, : nn[0]], xyz[0, : nn[0]]])


def compare_multirotor(
    legs: Legs, turbulence: str = "moderate", seeds: int = 4
) -> dict[str, FloatArray]:
    """Cross-track errors (m, pooled over ``seeds`` gust realizations) of rotorpy's quadrotor
    and of the batched model with the reference controller's gains on the same legs."""
    from uavplan.sim.fleet import params
    from uavplan.world.airframes import QUADROTOR
    from uavplan.world.scenario import UAV

    ref = []
    ours = []
    v_leg = float(np.mean(legs.speeds))
    # rotorpy's SE(3) position loop: a = 6.5 e + 4 e' (+ feed-forward); its parasitic drag
    # c_D |v| v on 1 kg, linearized at the leg speed
    af = dataclasses.replace(QUADROTOR, tau_vel=1 / 4.0, k_pos=6.5 / 4.0, drag=2 * 0.01 * v_leg,
                             lead=1e9, accept=0.5, max_accel=15.0)  # fmt: skip
    uav = UAV(speed=v_leg, max_climb_angle=45.0, max_descent_angle=45.0)
    prm = params(af, uav)
    prm = (*prm[:14], 0.0, 0.0, *prm[16:])  # no navigation error
    span = float(np.sum(np.linalg.norm(np.diff(legs.points, axis=0), axis=1)) / v_leg) * 2
    for sd in range(seeds):
        ref.append(cross_track(_rotorpy_flight(legs, turbulence, 1000 + sd), legs.points))
        flown = _batched_flight(legs, 1, prm, INTENSITIES[turbulence], 0.01, span, 2000 + sd)
        ours.append(cross_track(flown[:, 1:], legs.points))
    return {"reference": np.concatenate(ref), "batched": np.concatenate(ours)}


def _jsbsim_flight(legs: Legs, speed: float, l1_period: float, l1_damping: float,
                   max_bank_deg: float, k_height: float, w20: float,
                   seed: int) -> FloatArray:  # fmt: skip
    """JSBSim's Cessna 172 flying ``legs`` (local metres, heights AMSL over a flat sea-level
    ground) under the batched model's guidance and our inner loops; rows ``(t, x, y, z)``
    every 0.5 s. The local frame is an azimuthal equidistant projection about a fixed
    origin (pyproj), exact at the metres compared here."""
    import jsbsim
    from pyproj import Transformer

    from uavplan.sim.fleet import _l1_point, _leg_geometry

    ft, g0 = 0.3048, 9.80665
    aeqd = "+proj=aeqd +lat_0=37 +lon_0=-122 +ellps=WGS84 +units=m"
    to_local = Transformer.from_crs("EPSG:4326", aeqd, always_xy=True)
    to_geo = Transformer.from_crs(aeqd, "EPSG:4326", always_xy=True)
    P = np.ascontiguousarray(legs.points, dtype=np.float64)
    n = len(P)
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    logs = tempfile.TemporaryDirectory()  # the model's own CSV log, not in the working folder
    fdm.set_output_path(logs.name)
    fdm.load_model("c172x")
    fdm["simulation/randomseed"] = seed
    dt = fdm.get_delta_t()
    d = P[1] - P[0]
    lon, lat = to_geo.transform(P[0, 0], P[0, 1])
    fdm["ic/lat-geod-deg"], fdm["ic/long-gc-deg"] = lat, lon
    fdm["ic/h-sl-ft"] = P[0, 2] / ft
    fdm["ic/psi-true-deg"] = math.degrees(math.atan2(d[0], d[1])) % 360.0
    fdm["ic/vt-kts"] = speed / 0.514444
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    fdm["fcs/mixture-cmd-norm"] = 1.0
    fdm["simulation/do_simple_trim"] = 1
    thr0, el0, th0 = (fdm["fcs/throttle-cmd-norm"], fdm["fcs/elevator-cmd-norm"],
                      fdm["attitude/theta-rad"])  # fmt: skip
    if w20 > 0:
        fdm["atmosphere/turb-type"] = 3
        fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = w20 / ft
        fdm["atmosphere/turbulence/milspec/severity"] = 3
    max_bank = math.radians(max_bank_deg)
    k = 0
    i_roll = i_rate = i_speed = 0.0
    t, next_rec = 0.0, 0.0
    span = 2.0 * float(np.sum(np.linalg.norm(np.diff(P[:, :2], axis=0), axis=1))) / speed + 60
    out = []
    while t < span:
        fdm.run()
        t += dt
        x, y = to_local.transform(fdm["position/long-gc-deg"], fdm["position/lat-geod-deg"])
        z = fdm["position/h-sl-meters"]
        gx, gy = fdm["velocities/v-east-fps"] * ft, fdm["velocities/v-north-fps"] * ft
        vz = -fdm["velocities/v-down-fps"] * ft
        vg = math.hypot(gx, gy)
        if t >= next_rec:
            out.append((t, x, y, z))
            next_rec += 0.5
        _, _, L, along, cross = _leg_geometry(P, k, x, y)
        while k < n - 1 and along >= L - 10.0:  # a waypoint is passed 10 m before it
            k += 1
            if k < n - 1:
                _, _, L, along, cross = _leg_geometry(P, k, x, y)
        if k >= n - 1:
            break
        # the batched model's L1 guidance: a lateral acceleration, as a bank (JSBSim's phi is
        # positive right wing down, a right turn; the L1 law's acceleration is positive left)
        L1 = max(l1_damping * l1_period * vg / math.pi, 1.0)
        px, py = _l1_point(P, n, k, x, y, along, cross, L1)
        px, py = px - x, py - y
        eta = min(max(math.atan2(gx * py - gy * px, gx * px + gy * py), -math.pi / 2),
                  math.pi / 2)  # fmt: skip
        a_lat = 4.0 * l1_damping**2 * vg * vg / L1 * math.sin(eta)
        bank_cmd = -min(max(math.atan(a_lat / g0), -max_bank), max_bank)
        e_roll = bank_cmd - fdm["attitude/phi-rad"]
        i_roll = min(max(i_roll + e_roll * dt, -0.5), 0.5)
        ail = 2.0 * e_roll + 0.5 * i_roll - 0.3 * fdm["velocities/p-rad_sec"]
        fdm["fcs/aileron-cmd-norm"] = min(max(ail, -1.0), 1.0)
        # the batched model's height loop: a climb rate, held by pitch (JSBSim's positive
        # elevator command pitches the nose down)
        dz = P[k + 1, 2] - P[k, 2]
        z_cmd = P[k, 2] + (min(max(along / L, 0.0), 1.0) if L > 0 else 1.0) * dz
        rate = k_height * (z_cmd - z) + (dz / L if L > 0 else 0.0) * vg
        i_rate = min(max(i_rate + (rate - vz) * dt, -20.0), 20.0)
        theta_cmd = th0 + 0.04 * (rate - vz) + 0.01 * i_rate
        e_pitch = theta_cmd - fdm["attitude/theta-rad"]
        elev = el0 - (4.0 * e_pitch - 1.0 * fdm["velocities/q-rad_sec"])
        fdm["fcs/elevator-cmd-norm"] = min(max(elev, -1.0), 1.0)
        # the leg's ground speed, by throttle
        v_leg = float(legs.speeds[min(k, len(legs.speeds) - 1)])
        i_speed = min(max(i_speed + (v_leg - vg) * dt, -30.0), 30.0)
        thr = thr0 + 0.1 * (v_leg - vg) + 0.02 * i_speed
        fdm["fcs/throttle-cmd-norm"] = min(max(thr, 0.0), 1.0)
    del fdm  # closes its log
    logs.cleanup()
    return np.asarray(out, dtype=np.float64)


def compare_fixed_wing(
    legs: Legs, turbulence: str = "light", seeds: int = 3
) -> dict[str, FloatArray]:
    """Horizontal (cross-track) and vertical errors (m, pooled over ``seeds`` gust
    realizations) against ``legs``' path, flown at its mean leg speed by JSBSim's Cessna 172
    and by the batched model (``fast-fixed-wing`` at a 30 degree bank limit, no navigation
    error): keys ``reference_h``, ``batched_h``, ``reference_v``, ``batched_v``."""
    from uavplan.io.plan_file import Trajectory
    from uavplan.sim.fleet import params
    from uavplan.sim.runs import errors_against
    from uavplan.world.airframes import FAST_FIXED_WING
    from uavplan.world.scenario import UAV

    v = float(np.mean(legs.speeds))
    af = dataclasses.replace(FAST_FIXED_WING, max_bank_deg=30.0)
    uav = UAV(speed=v, turn_radius=v * v / (9.80665 * math.tan(math.radians(30.0))),
              min_speed=0.6 * v, max_speed=1.2 * v, max_climb_angle=20.0,
              max_descent_angle=20.0)  # fmt: skip
    seg = np.linalg.norm(np.diff(legs.points, axis=0), axis=1)
    path = Trajectory("path", legs.points, np.r_[0.0, np.cumsum(seg)] / v, True)
    w20 = INTENSITIES[turbulence]
    out: dict[str, list[FloatArray]] = {k: [] for k in ("reference_h", "batched_h",
                                                        "reference_v", "batched_v")}  # fmt: skip
    prm = params(af, uav)
    prm = (*prm[:14], 0.0, 0.0, *prm[16:])  # no navigation error
    for sd in range(seeds):
        ref = _jsbsim_flight(legs, v, af.l1_period, af.l1_damping, af.max_bank_deg,
                             af.k_height, w20, 1000 + sd)  # fmt: skip
        tr = Trajectory("ref", ref[:, 1:], ref[:, 0], True)
        out["reference_h"].append(cross_track(tr.points, legs.points))
        out["reference_v"].append(np.abs(errors_against(tr, path)[1]))
        flown = _batched_flight(legs, 0, prm, w20, 0.05, 2 * float(path.times[-1]), 2000 + sd)
        ours = Trajectory("ours", flown[:, 1:], flown[:, 0], True)
        out["batched_h"].append(cross_track(ours.points, legs.points))
        out["batched_v"].append(np.abs(errors_against(ours, path)[1]))
    return {k: np.concatenate(v_) for k, v_ in out.items()}
