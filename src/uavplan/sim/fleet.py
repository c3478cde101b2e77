"""The batched flight model: every UAV of a fleet flying its mission legs at once, one Numba
kernel stepping all of them a stretch of time at a time (:func:`step_fleet`), its random draws
given to it (from the run's ``numpy.random.Generator``).

**Fixed wing** (point mass, coordinated turns, first-order responses):

* lateral: L1 guidance (Park, Deyst & How 2004, with ArduPilot's ``AP_L1_Control`` gains):
  the L1 distance ``L1 = damping * period * V_g / pi``, the lateral acceleration
  ``a = 4 damping^2 V_g^2 sin(eta) / L1`` towards the point of the mission's path ``L1`` ahead
  (Park's reference point, found across the legs ahead; ArduPilot and PX4 look along the
  current leg only, which on a densely sampled curve lags it), ``eta`` the angle from the
  ground velocity to it; the bank ``atan(a / g)``
  within the airframe's limit, reached with ``tau_bank``; the heading turns at
  ``g tan(bank) / V_air``;
* speed: the mission commands ground speeds; the autopilot holds an airspeed, set by a PI loop
  on the ground-speed error (wind compensated by its integral) from the UAV's minimum speed
  to the airframe's top speed (its ``speed_margin`` above the plan's cruise: into a headwind
  the airspeed must exceed the commanded ground speed), reached with ``tau_speed``;
* height: the altitude commanded along the leg (interpolated between its ends, as both
  autopilots do), a climb rate ``k_height * error`` plus the path's slope ``tau_gamma`` ahead
  (the next leg's blended in near a leg's end), as a flight-path
  angle within the climb and descent limits, reached with ``tau_gamma`` (a total-energy
  controller's closed loop, first order).

**Multirotor**: a setpoint moves along the legs at the commanded speed (at most ``lead`` ahead
of the vehicle, as PX4's mission setpoints and ArduCopter's leashed waypoint target wait for
it; never waiting for a vehicle ahead of it), slowed before a corner to the speed the turn
allows and on across the waypoint (ArduCopter's waypoint navigation blends into the next leg
when it is known, PX4's mission trajectory plans through it); it stops only where the mission
does: at a waypoint with a hold, reached within the acceptance radius, for its hold time, and
at the last one. The velocity command is the
setpoint's velocity plus ``k_pos`` times the position error, within the speed limit; the
velocity follows with ``tau_vel`` within ``max_accel``, through the attitude's and rotors'
response (``tau_att``);
gusts push it by ``drag`` times their speed (the steady wind is taken out by the controller's
integral).

**Disturbances**: a steady wind, Dryden gusts (:mod:`uavplan.sim.turbulence`) along the
UAV's heading, across and vertically, and a position estimate off by a Gauss-Markov error:
the guidance sees the estimate, the flight is the true position. A UAV is flown from its
first waypoint at its take-off time (the climb is outside the mission's verified part) to its
last.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.sim.turbulence import gust_step

FloatArray = NDArray[np.float64]
G0 = 9.80665


@njit(cache=True)
def _l1_point(P, n, k, x, y, along, cross, L1):  # pragma: no cover - numba
    """The L1 reference point (Park, Deyst & How 2004): the point of the path ahead of the
    UAV at distance ``L1`` from it (the first leg from ``k`` on whose far end is farther
    than ``L1``, where the circle of radius ``L1`` leaves it), the last waypoint when the
    whole path ahead is within ``L1``; on leg ``k``, the foot of the UAV's perpendicular when
    it is farther than ``L1`` from the leg."""
    ux, uy, L, _, _ = _leg_geometry(P, k, x, y)
    if abs(cross) >= L1:
        s = min(max(along, 0.0), L)
        return P[k, 0] + ux * s, P[k, 1] + uy * s
    for j in range(k, min(n - 1, k + 200)):
        bx = P[j + 1, 0] - x
        by = P[j + 1, 1] - y
        if bx * bx + by * by <= L1 * L1:
            continue
        ux, uy, L, a_j, c_j = _leg_geometry(P, j, x, y)
        # |A + s u - p|^2 = L1^2: s = a_j +- sqrt(L1^2 - c_j^2), the far root
        root = a_j + math.sqrt(max(L1 * L1 - c_j * c_j, 0.0))
        s = min(max(root, 0.0), L)
        return P[j, 0] + ux * s, P[j, 1] + uy * s
    return P[n - 1, 0], P[n - 1, 1]


@njit(cache=True)
def _leg_geometry(P, k, x, y):  # pragma: no cover - numba
    """Leg ``k`` (``P[k] -> P[k+1]``): unit direction (ux, uy), horizontal length, the
    along-track distance and signed cross-track distance (left positive) of ``(x, y)``."""
    dx = P[k + 1, 0] - P[k, 0]
    dy = P[k + 1, 1] - P[k, 1]
    L = math.sqrt(dx * dx + dy * dy)
    if L < 1e-9:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    ux = dx / L
    uy = dy / L
    rx = x - P[k, 0]
    ry = y - P[k, 1]
    return ux, uy, L, rx * ux + ry * uy, ux * ry - uy * rx


#: The per-UAV state's columns (:func:`init_state`, :func:`step_fleet`).
STATE = ("x", "y", "z", "psi", "va", "vx", "vy", "vz", "bank", "gam", "integ", "g0", "g1", "g2",
         "g3", "g4", "ex", "ey", "ez", "s_sp", "hold", "k", "done", "next_rec", "ax", "ay",
         "az")  # fmt: skip
#: Normal draws per UAV and step: three for the gusts, three for the navigation error.
DRAWS = 6


def init_state(P: FloatArray, n_pts: NDArray[np.int64], speeds: FloatArray,
               holds: FloatArray, t0: FloatArray, nav0: FloatArray,
               wind: FloatArray | None = None,
               prm: tuple[float, ...] | None = None) -> FloatArray:  # fmt: skip
    """Every UAV at its first waypoint, heading along its first leg at its speed and climb
    angle (established on the climb that ended there), its navigation error ``nav0`` (U, 3)
    drawn from the error's stationary distribution. With the steady ``wind`` (3,) and the
    fixed wing's ``prm`` (:func:`params`), established in that wind as well: crabbed so that
    its ground track runs along the leg, at the airspeed that gives the leg's ground speed
    (within its speed range, the speed loop's feed-forward; its integral starts at 0)."""
    U = P.shape[0]
    st = np.zeros((U, len(STATE)))
    d = P[:, 1] - P[:, 0] if P.shape[1] > 1 else np.zeros((U, 3))
    psi = np.arctan2(d[:, 1], d[:, 0])
    gam = np.arctan2(d[:, 2], np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9))
    va = np.where(n_pts > 1, speeds[:, 0], 0.0)
    if wind is not None and prm is not None and np.any(wind[:2]):
        v_min, v_max = prm[18], prm[19]
        air = np.stack([va * np.cos(psi) - wind[0], va * np.sin(psi) - wind[1]], axis=1)
        va_wind = np.clip(np.hypot(air[:, 0], air[:, 1]) / np.cos(gam), v_min, v_max)
        moving = n_pts > 1
        psi = np.where(moving, np.arctan2(air[:, 1], air[:, 0]), psi)
        va = np.where(moving, va_wind, va)
    st[:, 0:3] = P[:, 0]
    st[:, 3] = psi
    st[:, 4] = va
    st[:, 5] = va * np.cos(gam) * np.cos(psi) + (wind[0] if wind is not None else 0.0)
    st[:, 6] = va * np.cos(gam) * np.sin(psi) + (wind[1] if wind is not None else 0.0)
    st[:, 7] = va * np.sin(gam)
    st[:, 9] = gam
    st[:, 16:19] = nav0
    st[:, 20] = holds[:, 0]
    st[:, 22] = (n_pts < 2).astype(np.float64)
    st[:, 23] = t0
    return st


@njit(cache=True)
def step_fleet(
    st,
    P,
    n_pts,
    speeds,
    holds,
    t0,
    kind,
    prm,
    wind,
    w20,
    h_agl,
    dt,
    t_start,
    n_steps,
    rec_dt,
    noise,
    out_xyz,
    out_t,
    out_n,
):  # pragma: no cover - numba
    """Advance every UAV ``n_steps`` of ``dt`` from ``t_start`` (a UAV moves from its
    take-off time ``t0``), recording its true position every ``rec_dt`` into ``out_xyz``
    (U, R, 3) at times ``out_t`` (U, R), ``out_n`` (U,) samples so far; a UAV is recorded one
    last time at its last waypoint and then stops. ``st`` (U, len(STATE)) the state;
    ``noise`` (U, n_steps, DRAWS) standard normal draws. ``P`` (U, N, 3) waypoints (padded),
    ``n_pts`` (U,), ``speeds`` (U, N) the leg speeds, ``holds`` (U, N); ``kind`` 0 fixed wing,
    1 multirotor; ``prm`` the airframe's and the UAV's numbers (:func:`params`); ``wind`` (3,)
    steady, m/s; ``w20`` the turbulence's wind at 20 ft, m/s; ``h_agl`` the height the gust
    scales use. Returns how many UAVs are done."""
    U = P.shape[0]
    R = out_xyz.shape[1]
    (tau_v, tau_bank, max_bank, tau_g, l1_period, l1_damp, k_h, k_s, ki_s, tau_vel,
     a_max, k_pos, drag, lead, nav_h, nav_v, nav_tau, accept, v_min, v_max, climb,
     descent, v_cruise, tau_att) = prm  # fmt: skip
    an = math.exp(-dt / nav_tau)
    bn = math.sqrt(1.0 - an * an)
    done_count = 0
    for u in range(U):
        n = n_pts[u]
        x, y, z = st[u, 0], st[u, 1], st[u, 2]
        psi, va = st[u, 3], st[u, 4]
        vx, vy, vz = st[u, 5], st[u, 6], st[u, 7]
        bank, gam, integ = st[u, 8], st[u, 9], st[u, 10]
        g = st[u, 11:16]
        ex, ey, ez = st[u, 16], st[u, 17], st[u, 18]
        s_sp, hold_left = st[u, 19], st[u, 20]
        k = int(st[u, 21])
        done = st[u, 22] > 0.5
        next_rec = st[u, 23]
        ax_a, ay_a, az_a = st[u, 24], st[u, 25], st[u, 26]
        nr = out_n[u]
        for j in range(n_steps):
            t = t_start + j * dt
            if t < t0[u]:
                continue
            if t >= next_rec and nr < R:
                out_xyz[u, nr, 0] = x
                out_xyz[u, nr, 1] = y
                out_xyz[u, nr, 2] = z
                out_t[u, nr] = t
                nr += 1
                next_rec += rec_dt
                if done:
                    next_rec = math.inf
            if done:
                continue
            gu, gv, gw = gust_step(g, va if kind == 0 else v_cruise, h_agl, w20, dt,
                                   noise[u, j, 0], noise[u, j, 1], noise[u, j, 2])  # fmt: skip
            ex = an * ex + nav_h * bn * noise[u, j, 3]
            ey = an * ey + nav_h * bn * noise[u, j, 4]
            ez = an * ez + nav_v * bn * noise[u, j, 5]
            xe, ye, ze = x + ex, y + ey, z + ez  # what the autopilot believes
            # the current leg, passed waypoints skipped
            while k < n - 1:
                ux, uy, L, along, cross = _leg_geometry(P[u], k, xe, ye)
                if kind == 1:
                    # the setpoint moves on across a waypoint (what it ran past the leg's end
                    # carried over) unless the mission stops there: a hold, or the last
                    # waypoint, reached when the vehicle is within the acceptance radius
                    if s_sp < L:
                        break
                    if k + 2 < n and holds[u, k + 1] <= 0.0:
                        k += 1
                        s_sp -= L
                        continue
                    end_reached = (
                        (xe - P[u, k + 1, 0]) ** 2 + (ye - P[u, k + 1, 1]) ** 2
                        + (ze - P[u, k + 1, 2]) ** 2 <= accept * accept)  # fmt: skip
                    if not end_reached:
                        break
                    k += 1
                    s_sp = 0.0
                    hold_left = holds[u, k]
                    continue
                if along < L - accept:
                    break
                k += 1
            if k >= n - 1:
                done = True
                next_rec = t  # the last waypoint: recorded at the next step
                continue
            ux, uy, L, along, cross = _leg_geometry(P[u], k, xe, ye)
            dz_leg = P[u, k + 1, 2] - P[u, k, 2]
            frac = min(max(along / L, 0.0), 1.0) if L > 0 else 1.0
            z_cmd = P[u, k, 2] + frac * dz_leg
            v_leg = speeds[u, k]
            slope = dz_leg / L if L > 0 else 0.0
            if kind == 0:
                # ---------------------------------------------------------- fixed wing
                cg = math.cos(gam)
                wx = wind[0] + gu * math.cos(psi) - gv * math.sin(psi)
                wy = wind[1] + gu * math.sin(psi) + gv * math.cos(psi)
                wz = wind[2] + gw
                gx = va * cg * math.cos(psi) + wx
                gy = va * cg * math.sin(psi) + wy
                vg = math.sqrt(gx * gx + gy * gy)
                # L1 lateral guidance towards the point of the path L1 ahead
                L1 = max(l1_damp * l1_period * vg / math.pi, 1.0)
                px, py = _l1_point(P[u], n, k, xe, ye, along, cross, L1)
                px -= xe
                py -= ye
                eta = math.atan2(gx * py - gy * px, gx * px + gy * py)
                eta = min(max(eta, -math.pi / 2), math.pi / 2)
                a_lat = 4.0 * l1_damp * l1_damp * vg * vg / L1 * math.sin(eta)
                bank_cmd = min(max(math.atan(a_lat / G0), -max_bank), max_bank)
                bank += (bank_cmd - bank) * (1.0 - math.exp(-dt / tau_bank))
                psi += G0 * math.tan(bank) / max(va, 1.0) * dt
                # speed: the ground speed, held through the airspeed: fed forward, the
                # airspeed that flies the leg's ground speed along it in the steady wind (an
                # autopilot's wind estimate; gusts it does not know), the PI loop the rest
                vg_along = gx * ux + gy * uy
                err = v_leg - vg
                ax_ff = v_leg * ux - wind[0]
                ay_ff = v_leg * uy - wind[1]
                va_ff = math.sqrt(ax_ff * ax_ff + ay_ff * ay_ff) / max(cg, 0.1)
                # the integral's share bounded by the speed range (anti-windup)
                i_max = (v_max - v_min) / max(ki_s, 1e-9)
                integ = min(max(integ + err * dt, -i_max), i_max)
                va_cmd = min(max(va_ff + k_s * err + ki_s * integ, v_min), v_max)
                va += (va_cmd - va) * (1.0 - math.exp(-dt / tau_v))
                # height: a climb rate as a flight-path angle within the limits; the climb
                # rate fed forward is the path's slope tau_g seconds ahead (the flight-path
                # angle lags its command by about tau_g, so a slope change at a waypoint is
                # commanded that much before it)
                ahead = max(vg_along, 0.0) * tau_g
                slope_ff = slope
                if ahead > 0.0 and L - along < ahead and k + 2 < n:
                    L2 = math.sqrt((P[u, k + 2, 0] - P[u, k + 1, 0]) ** 2
                                   + (P[u, k + 2, 1] - P[u, k + 1, 1]) ** 2)  # fmt: skip
                    if L2 > 0.0:
                        w = min(max(1.0 - (L - along) / ahead, 0.0), 1.0)
                        slope2 = (P[u, k + 2, 2] - P[u, k + 1, 2]) / L2
                        slope_ff = (1.0 - w) * slope + w * slope2
                rate = k_h * (z_cmd - ze) + slope_ff * max(vg_along, 0.0)
                sg = min(max(rate / max(va, 1.0), -math.sin(descent)), math.sin(climb))
                gam += (math.asin(sg) - gam) * (1.0 - math.exp(-dt / tau_g))
                vx = va * math.cos(gam) * math.cos(psi) + wx
                vy = va * math.cos(gam) * math.sin(psi) + wy
                vz = va * math.sin(gam) + wz
            else:
                # ---------------------------------------------------------- multirotor
                d_sp = math.sqrt((P[u, k, 0] + ux * min(s_sp, L) - xe) ** 2
                                 + (P[u, k, 1] + uy * min(s_sp, L) - ye) ** 2)  # fmt: skip
                # the setpoint's speed: the leg's, slowed before a corner so that the vehicle
                # can turn (to the leg's speed times the cosine of the turn, braking at half
                # its acceleration; to a stop where the mission stops), as a multicopter's
                # mission trajectory does
                stops = k + 2 >= n or holds[u, k + 1] > 0.0
                v_corner = 0.0
                if not stops:
                    nx_ = P[u, k + 2, 0] - P[u, k + 1, 0]
                    ny_ = P[u, k + 2, 1] - P[u, k + 1, 1]
                    nl = math.sqrt(nx_ * nx_ + ny_ * ny_)
                    if nl > 1e-9:
                        v_corner = v_leg * max((nx_ * ux + ny_ * uy) / nl, 0.0)
                v_sp = min(v_leg, math.sqrt(v_corner**2 + a_max * max(L - s_sp, 0.0)))
                # the setpoint runs on while the vehicle is within ``lead`` of it or ahead of
                # it along the leg (waiting for a vehicle ahead, with the velocity fed forward,
                # would hold it ``v / k_pos`` ahead for ever), and its velocity is fed forward
                # only while it runs; at a waypoint with a hold it waits for the vehicle to
                # come within the acceptance radius and holds there for the hold time
                runs = (d_sp < lead or along >= s_sp) and hold_left <= 0.0
                if hold_left > 0.0:
                    if ((xe - P[u, k, 0]) ** 2 + (ye - P[u, k, 1]) ** 2
                            + (ze - P[u, k, 2]) ** 2 <= accept * accept):  # fmt: skip
                        hold_left -= dt
                elif runs and s_sp < L:
                    s_sp += v_sp * dt
                    if stops:
                        s_sp = min(s_sp, L)
                moving = runs and (s_sp < L or not stops)
                s_at = min(s_sp, L)
                sx = P[u, k, 0] + ux * s_at
                sy = P[u, k, 1] + uy * s_at
                sz = P[u, k, 2] + (s_at / L if L > 0 else 1.0) * dz_leg
                ff = v_sp if moving else 0.0
                cx = ff * ux + k_pos * (sx - xe)
                cy = ff * uy + k_pos * (sy - ye)
                cz = (ff * slope if moving else 0.0) + k_h * (sz - ze)
                sp = math.sqrt(cx * cx + cy * cy)
                if sp > v_max:
                    cx *= v_max / sp
                    cy *= v_max / sp
                cz = min(max(cz, -v_max * math.sin(descent)), v_max * math.sin(climb))
                ax = (cx - vx) / tau_vel
                ay = (cy - vy) / tau_vel
                az = (cz - vz) / tau_vel
                a_h = math.sqrt(ax * ax + ay * ay)
                if a_h > a_max:
                    ax *= a_max / a_h
                    ay *= a_max / a_h
                # the acceleration reaches the airframe through its attitude (thrust tilt)
                # and rotor response, first order with tau_att
                f_att = 1.0 - math.exp(-dt / tau_att)
                ax_a += (ax - ax_a) * f_att
                ay_a += (ay - ay_a) * f_att
                az_a += (az - az_a) * f_att
                hdg = math.atan2(vy, vx) if vx * vx + vy * vy > 0.01 else math.atan2(uy, ux)
                vx += (ax_a + drag * (gu * math.cos(hdg) - gv * math.sin(hdg))) * dt
                vy += (ay_a + drag * (gu * math.sin(hdg) + gv * math.cos(hdg))) * dt
                vz += (az_a + drag * gw) * dt
            x += vx * dt
            y += vy * dt
            z += vz * dt
        st[u, 0], st[u, 1], st[u, 2] = x, y, z
        st[u, 3], st[u, 4] = psi, va
        st[u, 5], st[u, 6], st[u, 7] = vx, vy, vz
        st[u, 8], st[u, 9], st[u, 10] = bank, gam, integ
        st[u, 16], st[u, 17], st[u, 18] = ex, ey, ez
        st[u, 19], st[u, 20] = s_sp, hold_left
        st[u, 21] = k
        st[u, 22] = 1.0 if done else 0.0
        st[u, 23] = next_rec
        st[u, 24], st[u, 25], st[u, 26] = ax_a, ay_a, az_a
        out_n[u] = nr
        if done and next_rec == math.inf:
            done_count += 1
    return done_count


def params(airframe: object, uav: object) -> tuple[float, ...]:
    """The kernel's ``prm``: the airframe's numbers, the UAV's speed range (up to the
    airframe's :func:`~uavplan.world.airframes.top_speed`) and climb and descent limits
    (radians; 60 degrees where the UAV has none)."""
    from uavplan.world.airframes import top_speed

    a = airframe
    v_cruise = float(uav.speed)  # type: ignore[attr-defined]
    v_max = top_speed(a, uav)  # type: ignore[arg-type]
    v_min = float(uav.min_speed)  # type: ignore[attr-defined]
    if a.kind == "fixed-wing":  # type: ignore[attr-defined]
        v_min = max(v_min, 0.5 * v_cruise)  # a wing needs air over it
    climb = getattr(uav, "max_climb_angle", None)
    descent = getattr(uav, "max_descent_angle", None)
    return (
        a.tau_speed, a.tau_bank, math.radians(a.max_bank_deg), a.tau_gamma,  # type: ignore[attr-defined]
        a.l1_period, a.l1_damping, a.k_height, a.k_speed, a.ki_speed, a.tau_vel,  # type: ignore[attr-defined]
        a.max_accel, a.k_pos, a.drag, a.lead, a.nav_h, a.nav_v, a.nav_tau, a.accept,  # type: ignore[attr-defined]
        v_min, v_max, math.radians(climb if climb else 60.0),
        math.radians(descent if descent else 60.0), v_cruise, a.tau_att,  # type: ignore[attr-defined]
    )  # fmt: skip
