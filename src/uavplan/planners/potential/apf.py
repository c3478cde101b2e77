"""Artificial potential field (``apf``): the UAV steps in time along the field's force, within
its kinematic limits, among static and moving obstacles.

The classical method the RSCDWOA paper fuses its optimizer with (Zhang et al., "RSCDWOA",
Sect. 5.1, Fig. 6; Fig. 12(a) shows it stuck in a local minimum): Khatib, "Real-time obstacle
avoidance for manipulators and mobile robots", IJRR 5(1), 90-98, 1986, with the attractive
potential of Choset et al., *Principles of Robot Motion*, MIT Press 2005, Sect. 4.1, and, for
moving obstacles, the velocity-aware repulsion of Ge & Cui, "Dynamic motion planning for mobile
robots using potential field method", Autonomous Robots 13(3), 207-222, 2002.

**Field** (force = minus the gradient; gains dimensionless, distances scaled by the influence
radius so that one set of gains serves a 100 m scene and a 100 km one):

* attractive, conic far from the goal and quadratic within ``d_att``:
  ``F_att = k_att (g - p) / max(|g - p|, d_att)``;
* repulsive, per static obstacle within its influence ``rho0`` (Khatib):
  ``F_rep = eta (1 / r - 1) / r^2 grad(rho)``, ``r = rho / rho0``, with ``rho`` the clearance
  from the obstacle as the motion validator sees it (cylinders with their margin and height
  range, circles, no-fly polygons and revealed uncertain areas), and from the floor and ceiling
  of the flyable altitudes (bounds, altitude band, terrain) within ``rho0_z``;
* repulsive, per moving obstacle (Ge & Cui 2002): with relative position ``r_ro = p - q(t)``,
  relative velocity ``w = v_uav - v_q(t)``, closing speed ``v_a = -w . r_ro / |r_ro|`` and the
  distance the UAV needs to turn away at its largest lateral acceleration ``a_max = v^2 / R``,
  ``rho_m = v_a^2 / (2 a_max)``: the potential ``eta_m (1 / rho_e - 1 / rho0_m)`` of the
  effective clearance ``rho_e = rho_s - rho_m`` (``rho_s`` the clearance now) while closing, whose
  force ``eta_m / r_e^2 (r_hat + v_a w_perp / (a_max |r_ro|))`` (``r_e = rho_e / rho0_m``) pushes
  away from the obstacle and across its relative motion; plus Khatib's term on ``rho_s`` always.

**Motion** (the RSCDWOA paper's Eq. 1, ``x(t+1) = x(t) + v cos(theta)``, extended to 3-D): the
UAV flies at its cruise speed ``v``; every ``dt`` its heading turns towards the force by at most
``v dt / R`` (``R`` the minimum turn radius), its flight-path angle follows the force within the
climb and descent limits, and it moves ``v dt``; it never descends below the floor. It arrives
within ``goal_radius`` of the goal when the straight last segment to it is within the climb
limits and its turn into it within the turn radius (then the last segment goes to the goal
itself). The floor's and ceiling's influence is at most half the goal's room between them (a
goal near the floor must stay reachable). It **stalls** when its best distance to the goal
has not improved by ``v dt / 2`` for ``stall_steps`` steps: a local minimum of the field (or a
goal it cannot turn into); the plan is then infeasible (``local_minimum``) and ``info`` gives
the point where it stalled (the mean of the last ``stall_steps`` positions).

One planner iteration is ``steps_per_iteration`` (50) steps, one evaluation one step; the run
ends at arrival, a stall or the budget (it is not anytime).
The method is deterministic: the seed is not used (:attr:`Planner.deterministic`).
The step loop is one Numba function (about a microsecond per step and obstacle here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from uavplan.planners.core.base import Planner, PlannerSpecs
from uavplan.planners.core.options import PlannerConfig, option
from uavplan.planners.core.registry import register_planner
from uavplan.planners.core.run import Outcome, Run
from uavplan.problems.validity import PackedWorld
from uavplan.world._terrain_kernels import bilinear_one
from uavplan.world.kernel_arrays import read_only
from uavplan.world.scenario import Scenario

FloatArray = NDArray[np.float64]

#: smallest scaled clearance used in a repulsion (inside an obstacle the force stays finite)
R_MIN = 1e-3
#: heading change per step as a share of the turn radius's (the flight check allows 1)
TURN_MARGIN = 0.99
#: the largest turn into the goal at arrival, radians (the flight check allows 30 degrees)
ARRIVAL_TURN = math.radians(29.0)


@dataclass(frozen=True)
class APFConfig(PlannerConfig):
    """APF gains, influence radii and time step (the RSCDWOA paper gives none of them)."""

    k_att: float = option(1.0, "attractive gain (dimensionless)", low=0.0, low_open=True)
    d_att: float = option(0.0, "quadratic attraction within this distance of the goal, m", low=0)
    eta: float = option(1.0, "repulsive gain of static obstacles (dimensionless)", low=0.0)
    influence: float = option(
        1.0, "influence radius of an obstacle as a multiple of its radius (the paper's own)", low=0
    )
    rho0: float | None = option(
        None,
        "one influence radius for every obstacle, m (None: per obstacle, see influence)",
        low=0,
    )
    rho0_z: float | None = option(
        None,
        "floor and ceiling influence, m (None: 10 steps or half a turn radius, <= 1/4 band)",
        low=0,
    )
    eta_m: float = option(1.0, "repulsive gain of moving obstacles (Ge & Cui)", low=0.0)
    dt: float | None = option(
        None,
        "time step, s (None: 1 s, or less so that the route takes 200 steps)",
        low=0.0,
        low_open=True,
    )
    goal_radius: float | None = option(
        None, "arrival distance, m (None: two steps or one turn radius, the larger)", low=0
    )
    stall_steps: int | None = option(
        None, "steps without progress that make a stall (None: 50 or two turning circles)", low=1
    )
    steps_per_iteration: int = option(50, "APF steps per planner iteration", low=1)
    a_max: float | None = option(
        None, "largest lateral acceleration, m/s^2 (None: v^2 / R, or 2 g without a radius)", low=0
    )


@dataclass(frozen=True)
class FieldParams:
    """Everything the step kernel needs, resolved from the config and the scenario."""

    v: float
    dt: float
    k_att: float
    d_att: float
    eta: float
    rho0: float | None  # one radius for all, or None: per obstacle
    rho0_floor: float  # the least influence radius (turning away needs room)
    influence: float
    rho0_z: float
    eta_m: float
    a_max: float
    turn_k: float  # largest heading change per metre flown horizontally (0: no limit)
    climb: float
    descent: float
    goal_radius: float
    stall_steps: int


def field_params(cfg: APFConfig, sc: Scenario, distance: float | None = None) -> FieldParams:
    """The config's defaults made concrete for ``sc`` (see :class:`APFConfig`); ``distance``:
    the route's start-goal distance (sets the default time step)."""
    u = sc.uav
    v = float(u.speed)
    if cfg.dt is not None:
        dt = float(cfg.dt)
    else:
        d = distance if distance is not None else float(np.linalg.norm(sc.bounds.hi - sc.bounds.lo))
        dt = min(1.0, d / (200.0 * v)) if d > 0 else 1.0
    step = v * dt
    R = float(u.turn_radius)
    lo, hi = float(sc.bounds.lo[-1]), float(sc.bounds.hi[-1])
    height = float(sc.altitude.max - sc.altitude.min) if sc.altitude is not None else hi - lo
    rho0_z = (
        float(cfg.rho0_z)
        if cfg.rho0_z is not None
        else min(0.25 * height, max(10.0 * step, 0.5 * R))
    )
    a_max = float(cfg.a_max) if cfg.a_max is not None else (v * v / R if R > 0 else 2 * 9.81)
    turns = math.ceil(2 * 2 * math.pi * R / step) if R > 0 else 0
    return FieldParams(
        v=v,
        dt=dt,
        k_att=float(cfg.k_att),
        d_att=float(cfg.d_att),
        eta=float(cfg.eta),
        rho0=None if cfg.rho0 is None else float(cfg.rho0),
        rho0_floor=max(2.0 * R, 5.0 * step),
        influence=float(cfg.influence),
        rho0_z=max(rho0_z, 1e-9),
        eta_m=float(cfg.eta_m),
        a_max=max(a_max, 1e-9),
        turn_k=TURN_MARGIN / R if R > 0 else 0.0,
        climb=math.radians(u.max_climb_angle) if u.max_climb_angle is not None else math.pi / 2,
        descent=(
            math.radians(u.max_descent_angle) if u.max_descent_angle is not None else math.pi / 2
        ),
        goal_radius=(float(cfg.goal_radius) if cfg.goal_radius is not None else max(2.0 * step, R)),
        stall_steps=int(cfg.stall_steps) if cfg.stall_steps is not None else max(50, turns),
    )


def rho0_of(prm: FieldParams, size: FloatArray) -> FloatArray:
    """Influence radius per obstacle of radius ``size``: ``rho0`` if set, else ``influence``
    times the radius, never less than two turn radii or five steps."""
    s = np.asarray(size, dtype=np.float64)
    if prm.rho0 is not None:
        return np.full(s.shape, prm.rho0)
    return np.maximum(prm.influence * s, prm.rho0_floor)


# ---------------------------------------------------------------------- the step kernel
@njit(cache=True, inline="always")
def _khatib(rho, rho0):  # pragma: no cover - numba
    """Magnitude of Khatib's repulsion at clearance ``rho`` (0 beyond ``rho0``)."""
    if rho >= rho0 or rho0 <= 0:
        return 0.0
    r = max(rho / rho0, R_MIN)
    return (1.0 / r - 1.0) / (r * r)


@njit(cache=True)
def _limits(z_args, H, x, y):  # pragma: no cover - numba
    """Floor and ceiling at (x, y) and their slopes: (floor, dfx, dfy, ceil, dcx, dcy)."""
    has_t, hx0, hy0, hdx, hdy, f_abs, f_rel, c_abs, c_rel = z_args
    g = gx = gy = 0.0
    if has_t > 0:
        g = bilinear_one(H, hx0, hy0, hdx, hdy, x, y)
        e = 0.5 * min(hdx, hdy)
        gx = bilinear_one(H, hx0, hy0, hdx, hdy, x + e, y)
        gx = (gx - bilinear_one(H, hx0, hy0, hdx, hdy, x - e, y)) / (2 * e)
        gy = bilinear_one(H, hx0, hy0, hdx, hdy, x, y + e)
        gy = (gy - bilinear_one(H, hx0, hy0, hdx, hdy, x, y - e)) / (2 * e)
    f = f_abs
    fx = fy = 0.0
    if g + f_rel > f:
        f = g + f_rel
        fx, fy = gx, gy
    c = c_abs
    cx = cy = 0.0
    if g + c_rel < c:
        c = g + c_rel
        cx, cy = gx, gy
    return f, fx, fy, c, cx, cy


@njit(cache=True)
def _force(
    p, vel, t, goal, prm, cyl_c, cyl_r, cyl_lo, cyl_hi, circ_c, circ_r, pv, ps, pm,
    mo_r, mo_s, mo_t, mo_p, mo_hold, H, z_args, q_cyl, q_circ, q_poly, q_mo, walls, dim3,
):  # fmt: skip  # pragma: no cover - numba
    """The field's force at ``p`` (3,) moving at ``vel`` (3,) at time ``t``; ``q_*`` the
    influence radius of each obstacle."""
    k_att, d_att, eta, rho0_z, eta_m, a_max = prm
    F = np.zeros(3)
    e0 = goal[0] - p[0]
    e1 = goal[1] - p[1]
    e2 = goal[2] - p[2] if dim3 else 0.0
    d = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    s = k_att / max(d, d_att, 1e-12)
    F[0] += s * e0
    F[1] += s * e1
    F[2] += s * e2
    # cylinders (their height range) and circles (infinite)
    n_cyl = cyl_r.shape[0]
    for j in range(n_cyl + circ_r.shape[0]):
        if j < n_cyl:
            hx, hy, r = p[0] - cyl_c[j, 0], p[1] - cyl_c[j, 1], cyl_r[j]
            lo, hi = cyl_lo[j], cyl_hi[j]
            rho0 = q_cyl[j]
        else:
            k = j - n_cyl
            hx, hy, r, lo, hi = p[0] - circ_c[k, 0], p[1] - circ_c[k, 1], circ_r[k], -np.inf, np.inf
            rho0 = q_circ[k]
        dh = math.sqrt(hx * hx + hy * hy)
        ux = hx / dh if dh > 0 else 1.0
        uy = hy / dh if dh > 0 else 0.0
        radial = dh - r
        gz = 0.0
        if dim3 and p[2] > hi:
            gz = p[2] - hi
        elif dim3 and p[2] < lo:
            gz = p[2] - lo
        if gz == 0.0:
            rho, g0, g1, g2 = radial, ux, uy, 0.0
        elif radial > 0:
            rho = math.sqrt(radial * radial + gz * gz)
            g0, g1, g2 = ux * radial / rho, uy * radial / rho, gz / rho
        else:
            rho, g0, g1, g2 = abs(gz), 0.0, 0.0, 1.0 if gz > 0 else -1.0
        m = eta * _khatib(rho, rho0)
        F[0] += m * g0
        F[1] += m * g1
        F[2] += m * g2
    # no-fly polygons (vertical prisms): nearest boundary point
    for q in range(ps.shape[0] - 1):
        v0, v1 = ps[q], ps[q + 1]
        best = np.inf
        nx_ = ny_ = 0.0
        inside = False
        jv = v1 - 1
        for iv in range(v0, v1):
            ax, ay, bx, by = pv[jv, 0], pv[jv, 1], pv[iv, 0], pv[iv, 1]
            if (by > p[1]) != (ay > p[1]):
                xc = bx + (p[1] - by) * (ax - bx) / (ay - by)
                if p[0] < xc:
                    inside = not inside
            ex, ey = bx - ax, by - ay
            L = ex * ex + ey * ey
            tt = ((p[0] - ax) * ex + (p[1] - ay) * ey) / L if L > 0 else 0.0
            tt = min(max(tt, 0.0), 1.0)
            cx, cy = ax + tt * ex, ay + tt * ey
            dd = math.sqrt((p[0] - cx) ** 2 + (p[1] - cy) ** 2)
            if dd < best:
                best, nx_, ny_ = dd, cx, cy
            jv = iv
        ox, oy = p[0] - nx_, p[1] - ny_
        if best > 0:
            ox, oy = ox / best, oy / best
        if inside:
            ox, oy, rho = -ox, -oy, -best
        else:
            rho = best
        m = eta * _khatib(rho - pm[q], q_poly[q])
        F[0] += m * ox
        F[1] += m * oy
    # the map's side walls: [lo_x, hi_x, lo_y, hi_y, and their influence radii]
    for a in range(2):
        F[a] += eta * _khatib(p[a] - walls[2 * a], walls[4 + 2 * a])
        F[a] -= eta * _khatib(walls[2 * a + 1] - p[a], walls[5 + 2 * a])
    # floor and ceiling
    if dim3:
        f, fx, fy, c, cx, cy = _limits(z_args, H, p[0], p[1])
        m = eta * _khatib(p[2] - f, rho0_z)
        nrm = math.sqrt(fx * fx + fy * fy + 1.0)
        F[0] -= m * fx / nrm
        F[1] -= m * fy / nrm
        F[2] += m / nrm
        m = eta * _khatib(c - p[2], rho0_z)
        nrm = math.sqrt(cx * cx + cy * cy + 1.0)
        F[0] += m * cx / nrm
        F[1] += m * cy / nrm
        F[2] -= m / nrm
    # moving obstacles: Khatib on the clearance, Ge & Cui while closing
    for o in range(mo_r.shape[0]):
        k0, k1 = mo_s[o], mo_s[o + 1]
        if mo_hold[o] == 0 and (t < mo_t[k0] or t > mo_t[k1 - 1]):
            continue  # another UAV before take-off or after landing: no hazard
        qx, qy, qz = mo_p[k0, 0], mo_p[k0, 1], mo_p[k0, 2]
        wx = wy = wz = 0.0
        if t >= mo_t[k1 - 1]:
            qx, qy, qz = mo_p[k1 - 1, 0], mo_p[k1 - 1, 1], mo_p[k1 - 1, 2]
        elif t > mo_t[k0]:
            # the sample interval holding t: the last k with mo_t[k] <= t (binary search; the
            # times do not decrease, so mo_t[k + 1] > t; other UAVs' flights have thousands)
            lo_k, hi_k = k0, k1 - 1
            while hi_k - lo_k > 1:
                mid = (lo_k + hi_k) // 2
                if mo_t[mid] <= t:
                    lo_k = mid
                else:
                    hi_k = mid
            k = lo_k
            h = mo_t[k + 1] - mo_t[k]
            a = (t - mo_t[k]) / h
            wx = (mo_p[k + 1, 0] - mo_p[k, 0]) / h
            wy = (mo_p[k + 1, 1] - mo_p[k, 1]) / h
            wz = (mo_p[k + 1, 2] - mo_p[k, 2]) / h
            qx = mo_p[k, 0] + a * (mo_p[k + 1, 0] - mo_p[k, 0])
            qy = mo_p[k, 1] + a * (mo_p[k + 1, 1] - mo_p[k, 1])
            qz = mo_p[k, 2] + a * (mo_p[k + 1, 2] - mo_p[k, 2])
        rx, ry = p[0] - qx, p[1] - qy
        rz = p[2] - qz if dim3 else 0.0
        dist = math.sqrt(rx * rx + ry * ry + rz * rz)
        if dist <= 0:
            continue
        ux, uy, uz = rx / dist, ry / dist, rz / dist
        rho_s = dist - mo_r[o]
        rho0_m = q_mo[o]
        m = eta_m * _khatib(rho_s, rho0_m)
        F[0] += m * ux
        F[1] += m * uy
        F[2] += m * uz
        relx, rely = vel[0] - wx, vel[1] - wy
        relz = vel[2] - wz if dim3 else 0.0
        v_a = -(relx * ux + rely * uy + relz * uz)
        if v_a > 0:
            rho_e = rho_s - v_a * v_a / (2.0 * a_max)
            if rho_e < rho0_m:
                r_e = max(rho_e / rho0_m, R_MIN)
                m = eta_m / (r_e * r_e)
                px_, py_, pz_ = relx + v_a * ux, rely + v_a * uy, relz + v_a * uz  # w_perp
                c2 = v_a / (a_max * dist)
                F[0] += m * (ux + c2 * px_)
                F[1] += m * (uy + c2 * py_)
                F[2] += m * (uz + c2 * pz_)
    # the horizontal force straight against the goal's direction with no side to it: the field
    # is symmetric about the line to the goal and no side is preferred; go left (ours)
    h = math.hypot(e0, e1)
    if h > 0:
        a0, a1 = e0 / h, e1 / h
        along = F[0] * a0 + F[1] * a1
        side = abs(F[1] * a0 - F[0] * a1)
        mag = math.hypot(F[0], F[1])
        if along < 0 and side <= 1e-9 * mag:
            F[0] -= 0.1 * mag * a1
            F[1] += 0.1 * mag * a0
    return F


@njit(cache=True)
def integrate(
    state, goal, n_steps, kin, prm, cyl_c, cyl_r, cyl_lo, cyl_hi, circ_c, circ_r, pv, ps, pm,
    mo_r, mo_s, mo_t, mo_p, mo_hold, H, z_args, q_cyl, q_circ, q_poly, q_mo, walls, dim3, out,
    final=True,
):  # fmt: skip  # pragma: no cover - numba
    """Up to ``n_steps`` steps from ``state`` = [x, y, z, psi, gamma, t, best_d, since_best]
    (updated in place); positions into ``out`` (n_steps, 3). Returns (steps, status): status 0
    running, 1 arrived (the last row is the goal), 2 stalled. ``final`` False: ``goal`` is a
    sub-goal, reached within ``goal_r`` whatever the last segment (the last row is where the UAV
    is)."""
    v, dt, turn_k, climb, descent, goal_r, stall_steps = kin
    p = np.empty(3)
    vel = np.empty(3)
    for k in range(n_steps):
        p[0], p[1], p[2] = state[0], state[1], state[2]
        psi, gam, t = state[3], state[4], state[5]
        vel[0] = v * math.cos(gam) * math.cos(psi)
        vel[1] = v * math.cos(gam) * math.sin(psi)
        vel[2] = v * math.sin(gam) if dim3 else 0.0
        F = _force(p, vel, t, goal, prm, cyl_c, cyl_r, cyl_lo, cyl_hi, circ_c, circ_r, pv, ps,
                   pm, mo_r, mo_s, mo_t, mo_p, mo_hold, H, z_args, q_cyl, q_circ, q_poly,
                   q_mo, walls, dim3)  # fmt: skip
        step = v * dt
        gam_prev = gam
        if dim3:
            gam = min(max(math.atan2(F[2], math.hypot(F[0], F[1])), -descent), climb)
            f = _limits(z_args, H, p[0], p[1])[0]
            if p[2] + step * math.sin(gam) < f:  # never below the floor
                gam = min(math.asin(max(min((f - p[2]) / step, 1.0), -1.0)), climb)
        # the horizontal track's curvature: heading change over the horizontal step
        # (the flight check divides by the mean of the two horizontal steps at a point)
        cos_g = min(math.cos(gam), math.cos(gam_prev))
        dpsi = turn_k * step * cos_g if turn_k > 0 else math.pi
        want = math.atan2(F[1], F[0])
        turn = (want - psi + math.pi) % (2 * math.pi) - math.pi
        psi += min(max(turn, -dpsi), dpsi)
        p[0] += step * math.cos(gam) * math.cos(psi)
        p[1] += step * math.cos(gam) * math.sin(psi)
        if dim3:
            p[2] += step * math.sin(gam)
        t += dt
        state[0], state[1], state[2], state[3], state[4], state[5] = p[0], p[1], p[2], psi, gam, t
        d = math.sqrt((goal[0] - p[0]) ** 2 + (goal[1] - p[1]) ** 2 + (goal[2] - p[2]) ** 2)
        if d < state[6] - 0.5 * step:
            state[6] = d
            state[7] = 0.0
        else:
            state[7] += 1.0
        dz = goal[2] - p[2]
        flat = math.hypot(goal[0] - p[0], goal[1] - p[1])
        slope_ok = dz <= flat * math.tan(climb) and -dz <= flat * math.tan(descent)
        if turn_k > 0 and flat > 0:  # the last turn, into the goal, as the flight check sees it
            last = abs((math.atan2(goal[1] - p[1], goal[0] - p[0]) - psi + math.pi) % (2 * math.pi)
                       - math.pi)  # fmt: skip
            limit = min(ARRIVAL_TURN, turn_k * 0.5 * (step * math.cos(gam) + flat))
            slope_ok = slope_ok and last <= limit
        if not final and d <= goal_r:
            out[k, 0], out[k, 1], out[k, 2] = p[0], p[1], p[2]
            return k + 1, 1
        if d <= goal_r and (slope_ok or d <= 1e-9):
            out[k, 0], out[k, 1], out[k, 2] = goal[0], goal[1], goal[2]
            return k + 1, 1
        out[k, 0], out[k, 1], out[k, 2] = p[0], p[1], p[2]
        if state[7] >= stall_steps:
            return k + 1, 2
    return n_steps, 0


def force_at(
    sc: Scenario, prm: FieldParams, p: FloatArray, vel: FloatArray, t: float, goal: FloatArray,
    others: list[tuple[FloatArray, FloatArray]] | None = None, separation: float = 0.0,
) -> FloatArray:  # fmt: skip
    """The kernel's force at one state (3,) (2-D scenes: z = 0), for tests and benchmarks."""
    dim3 = sc.dim == 3
    q, v, g = (np.zeros(3) for _ in range(3))
    q[: sc.dim], v[: sc.dim], g[: sc.dim] = p, vel, goal
    fp = (prm.k_att, prm.d_att, prm.eta, prm.rho0_z, prm.eta_m, prm.a_max)
    args = (*_packed(sc, prm, others or [], separation), _walls(sc, prm, g))
    return np.asarray(_force(q, v, float(t), g, fp, *args, dim3))  # type: ignore[call-arg]


def force_reference(
    sc: Scenario, prm: FieldParams, p: FloatArray, vel: FloatArray, t: float, goal: FloatArray
) -> FloatArray:
    """The same field written plainly from the scenario's objects in NumPy (the reference
    :func:`force_at` is tested against; no floor-room adjustment, no other UAVs)."""
    dim = sc.dim
    P = np.zeros(3)
    V = np.zeros(3)
    G = np.zeros(3)
    P[:dim], V[:dim], G[:dim] = p, vel, goal

    def khatib(rho: float, rho0: float) -> float:
        if rho >= rho0 or rho0 <= 0:
            return 0.0
        r = max(rho / rho0, R_MIN)
        return (1.0 / r - 1.0) / r**2

    e = G - P
    F = prm.k_att * e / max(float(np.linalg.norm(e)), prm.d_att, 1e-12)
    discs = [(c.center, c.effective_radius, c.z_min - c.margin, c.z_max + c.margin)
             for c in sc.cylinders] + [(c.center, c.effective_radius, -np.inf, np.inf)
                                       for c in sc.circles]  # fmt: skip
    for center, radius, lo, hi in discs:
        h = P[:2] - np.asarray(center)
        dh = float(np.hypot(*h))
        u = h / dh if dh > 0 else np.array([1.0, 0.0])
        radial = dh - radius
        gap = 0.0 if dim == 2 or lo <= P[2] <= hi else P[2] - (hi if P[2] > hi else lo)
        if gap == 0.0:
            rho, grad = radial, np.array([u[0], u[1], 0.0])
        elif radial > 0:
            rho = float(np.hypot(radial, gap))
            grad = np.array([u[0] * radial, u[1] * radial, gap]) / rho
        else:
            rho, grad = abs(gap), np.array([0.0, 0.0, np.sign(gap)])
        F += prm.eta * khatib(rho, float(rho0_of(prm, np.array([radius]))[0])) * grad
    for poly in sc.no_fly_polygons:
        v = poly.array
        a, b = v, np.roll(v, -1, axis=0)
        ab = b - a
        u = np.clip(np.einsum("kd,kd->k", P[:2] - a, ab) / np.einsum("kd,kd->k", ab, ab), 0, 1)
        near = a + u[:, None] * ab
        dist = np.linalg.norm(P[:2] - near, axis=1)
        k = int(np.argmin(dist))
        out = (P[:2] - near[k]) / dist[k] if dist[k] > 0 else np.zeros(2)
        inside = bool(poly.contains(P[None, :2])[0])
        rho = -dist[k] if inside else dist[k]
        size = 0.5 * float(np.ptp(v, axis=0).max())
        m = prm.eta * khatib(rho - poly.margin, float(rho0_of(prm, np.array([size]))[0]))
        F[:2] += m * (-out if inside else out)
    for i_ax in range(2):  # side walls, influence at most half the goal's room
        lo_a, hi_a = float(sc.bounds.lo[i_ax]), float(sc.bounds.hi[i_ax])
        q_lo = min(prm.rho0_floor, 0.5 * max(G[i_ax] - lo_a, 0.0))
        q_hi = min(prm.rho0_floor, 0.5 * max(hi_a - G[i_ax], 0.0))
        F[i_ax] += prm.eta * (khatib(P[i_ax] - lo_a, q_lo) - khatib(hi_a - P[i_ax], q_hi))
    if dim == 3:
        lo_z, hi_z = float(sc.bounds.lo[2]), float(sc.bounds.hi[2])
        band, ter = sc.altitude, sc.terrain

        def limits(x: float, y: float) -> tuple[float, float]:
            ground = float(ter.height(x, y)) if ter is not None else 0.0
            f, c = lo_z, hi_z
            if band is not None and band.reference == "absolute":
                f, c = max(f, band.min), min(c, band.max)
            rel_f = band.min if band is not None and band.reference == "ground" else -np.inf
            rel_c = band.max if band is not None and band.reference == "ground" else np.inf
            if ter is not None and ter.lower is not None:
                rel_c -= float(np.max(ter.heights - ter.lower))  # as the kernel's
            if ter is not None:
                rel_f = max(rel_f, 0.0)
            return max(f, ground + rel_f), min(c, ground + rel_c)

        ee = 0.5 * min(ter.dx, ter.dy) if ter is not None else 1.0
        f0, c0 = limits(P[0], P[1])
        fx = (limits(P[0] + ee, P[1])[0] - limits(P[0] - ee, P[1])[0]) / (2 * ee)
        fy = (limits(P[0], P[1] + ee)[0] - limits(P[0], P[1] - ee)[0]) / (2 * ee)
        cx = (limits(P[0] + ee, P[1])[1] - limits(P[0] - ee, P[1])[1]) / (2 * ee)
        cy = (limits(P[0], P[1] + ee)[1] - limits(P[0], P[1] - ee)[1]) / (2 * ee)
        n_f = np.array([-fx, -fy, 1.0])
        n_c = np.array([cx, cy, -1.0])
        F += prm.eta * khatib(P[2] - f0, prm.rho0_z) * n_f / np.linalg.norm(n_f)
        F += prm.eta * khatib(c0 - P[2], prm.rho0_z) * n_c / np.linalg.norm(n_c)
    for o in sc.moving_obstacles:
        Q = o.position_at(t)
        inside = o.times[0] < t < o.times[-1]
        k = int(np.searchsorted(o.times, t, side="right")) - 1
        W = 0 * Q
        if inside:
            W = (o.positions[k + 1] - o.positions[k]) / (o.times[k + 1] - o.times[k])
        if dim == 2:
            Q, W = Q * [1, 1, 0], W * [1, 1, 0]
        r = P - Q
        dist = float(np.linalg.norm(r))
        if dist <= 0:
            continue
        u = r / dist
        rho_s = dist - o.radius
        rho0_m = float(rho0_of(prm, np.array([o.radius]))[0])
        F += prm.eta_m * khatib(rho_s, rho0_m) * u
        w = V - W
        v_a = -float(w @ u)
        if v_a > 0:
            rho_e = rho_s - v_a**2 / (2 * prm.a_max)
            if rho_e < rho0_m:
                r_e = max(rho_e / rho0_m, R_MIN)
                w_perp = w + v_a * u
                F += prm.eta_m / r_e**2 * (u + v_a / (prm.a_max * dist) * w_perp)
    h = float(np.hypot(e[0], e[1]))
    if h > 0:
        a = e[:2] / h
        along = float(F[:2] @ a)
        side = abs(F[1] * a[0] - F[0] * a[1])
        mag = float(np.hypot(F[0], F[1]))
        if along < 0 and side <= 1e-9 * mag:
            F[:2] += 0.1 * mag * np.array([-a[1], a[0]])
    return F


# ---------------------------------------------------------------------- the planner
def _packed(
    sc: Scenario, prm: FieldParams, others: list[tuple[FloatArray, FloatArray]], sep: float
) -> tuple[Any, ...]:
    """The kernel's obstacle, moving-obstacle, terrain and influence arguments of ``sc``;
    ``others``: other UAVs' timed flights, moving obstacles of radius ``sep`` while airborne."""
    w = PackedWorld.of(sc)
    poly_size = np.array(
        [0.5 * float(np.ptp(q.array, axis=0).max()) for q in sc.no_fly_polygons], dtype=np.float64
    )
    moving = [(o.radius, o.times, o.positions, 1) for o in sc.moving_obstacles]
    moving += [(sep, t, p, 0) for p, t in others]
    mo_r = np.array([m[0] for m in moving], dtype=np.float64)
    mo_s = np.concatenate([[0], np.cumsum([len(m[1]) for m in moving])]).astype(np.int64)
    mo_t = np.concatenate([m[1] for m in moving]) if moving else np.zeros(0)
    mo_p = np.concatenate([m[2] for m in moving]) if moving else np.zeros((0, 3))
    mo_hold = np.array([m[3] for m in moving], dtype=np.int64)
    lo_z, hi_z = float(sc.bounds.lo[-1]), float(sc.bounds.hi[-1])
    f_abs, c_abs, f_rel, c_rel = lo_z, hi_z, -np.inf, np.inf
    band = sc.altitude
    if band is not None and band.reference == "absolute":
        f_abs, c_abs = max(f_abs, band.min), min(c_abs, band.max)
    elif band is not None:
        f_rel, c_rel = band.min, band.max
    t = sc.terrain
    if t is not None and t.lower is not None and band is not None and band.reference == "ground":
        c_rel -= float(np.max(t.heights - t.lower))  # the field reads the floor's grid only
    if t is not None:
        f_rel = max(f_rel, 0.0)  # never below the ground
        H = np.ascontiguousarray(t.heights, dtype=np.float64)
        grid = (float(t.x0), float(t.y0), float(t.dx), float(t.dy))
        z_args = (1.0, *grid, f_abs, f_rel, c_abs, c_rel)
    else:
        H = read_only(np.zeros((1, 1)))  # as a terrain's heights: one kernel signature
        z_args = (0.0, 0.0, 0.0, 1.0, 1.0, f_abs, f_rel, c_abs, c_rel)
    return (
        w.cyl_centers, w.cyl_radii, w.cyl_lo, w.cyl_hi, w.circ_centers, w.circ_radii,
        w.poly_verts, w.poly_starts, w.poly_margin, mo_r, mo_s, mo_t, mo_p, mo_hold, H, z_args,
        rho0_of(prm, w.cyl_radii), rho0_of(prm, w.circ_radii), rho0_of(prm, poly_size),
        rho0_of(prm, mo_r),
    )  # fmt: skip


def _walls(sc: Scenario, prm: FieldParams, goal3: FloatArray) -> FloatArray:
    """The side walls of the map and their influence: the least influence radius, at most half
    the goal's distance to the wall (a goal near the edge stays reachable)."""
    lo, hi = sc.bounds.lo[:2].astype(float), sc.bounds.hi[:2].astype(float)
    q = [min(prm.rho0_floor, 0.5 * max(goal3[a] - lo[a], 0.0)) for a in range(2)]
    r = [min(prm.rho0_floor, 0.5 * max(hi[a] - goal3[a], 0.0)) for a in range(2)]
    return np.array([lo[0], hi[0], lo[1], hi[1], q[0], r[0], q[1], r[1]], dtype=np.float64)


@dataclass(frozen=True)
class Trajectory:
    """An APF flight: positions from the start (the goal last if it arrived), the status and
    the steps taken."""

    points: FloatArray
    status: str  # "arrived", "stalled", "budget"
    steps: int
    stall_point: FloatArray | None


def fly_field(
    sc: Scenario, start: FloatArray, goal: FloatArray, prm: FieldParams, max_steps: int,
    t0: float = 0.0, chunk: int = 4096, on_chunk: Any = None,
    others: list[tuple[FloatArray, FloatArray]] | None = None, separation: float = 0.0,
    via: FloatArray | None = None, via_radius: float | None = None,
) -> Trajectory:  # fmt: skip
    """Integrate the field from ``start`` (heading to the goal, level) for at most
    ``max_steps`` steps. ``on_chunk(k, path)`` after each chunk of ``k`` steps (``path``: the
    whole path if it arrived in this chunk, else None) may return a number of this chunk's
    steps to keep and stop there (the planner's tracker and callback). ``others``: other UAVs'
    timed flights (points (n, 3), times (n,)), repulsive while airborne, of radius
    ``separation``. ``via`` (k, dim): sub-goals flown to in turn before the goal, each left
    for the next once within ``via_radius`` (default: the goal radius); the field's attraction
    is towards the current one (the optimizer-fused APF)."""
    dim3 = sc.dim == 3
    s3 = np.zeros(3)
    g3 = np.zeros(3)
    s3[: sc.dim] = start
    g3[: sc.dim] = goal
    psi = math.atan2(g3[1] - s3[1], g3[0] - s3[0])
    state = np.array([s3[0], s3[1], s3[2], psi, 0.0, t0, np.linalg.norm(g3 - s3), 0.0])
    kin = (prm.v, prm.dt, prm.turn_k, prm.climb, prm.descent, prm.goal_radius,
           float(prm.stall_steps))  # fmt: skip
    fp = (prm.k_att, prm.d_att, prm.eta, prm.rho0_z, prm.eta_m, prm.a_max)
    args = (*_packed(sc, prm, others or [], separation), _walls(sc, prm, g3))
    if dim3:  # a goal near the floor or ceiling: their push must not keep the UAV from it
        f, _, _, c, _, _ = _limits(args[15], args[14], g3[0], g3[1])
        room = min(g3[2] - f, c - g3[2])
        fp = (*fp[:3], max(min(prm.rho0_z, 0.5 * room), 1e-9), *fp[4:])
    targets = [] if via is None else [np.pad(np.asarray(q, float), (0, 3 - sc.dim)) for q in via]
    targets.append(g3)
    r_via = prm.goal_radius if via_radius is None else float(via_radius)
    parts = [s3[None]]
    done, status, leg = 0, 0, 0
    while done < max_steps:
        final = leg == len(targets) - 1
        tgt = targets[leg]
        n = min(chunk, max_steps - done)
        out = np.empty((n, 3))
        kin_leg = kin if final else (*kin[:5], r_via, *kin[6:])
        k, status = integrate(state, tgt, n, kin_leg, fp, *args, dim3, out, final)  # type: ignore[call-arg]
        parts.append(out[:k])
        done += k
        if status == 1 and not final:  # on to the next target, progress measured anew
            leg += 1
            state[6] = float(np.linalg.norm(targets[leg] - state[:3]))
            state[7] = 0.0
            status = 0
        if on_chunk is not None:
            whole = np.concatenate(parts)[:, : sc.dim] if status == 1 else None
            keep = on_chunk(k, whole)
            if keep is not None and keep < k:
                parts[-1] = out[:keep]
                done += keep - k
                status = 3
                break
        if status:
            break
    pts = np.concatenate(parts)[:, : sc.dim]
    name = {0: "budget", 1: "arrived", 2: "stalled", 3: "stopped"}[status]
    stall = pts[-prm.stall_steps :].mean(axis=0) if status == 2 else None
    return Trajectory(pts, name, done, stall)


class APFPlanner(Planner):
    """Artificial potential field in time among static and moving obstacles (see the module
    docstring)."""

    name = "apf"
    Config = APFConfig
    config: APFConfig
    specs = PlannerSpecs(
        default_iterations=400,  # x 50 steps
        deterministic=True,
        anytime=False,
        supports_reservations=True,  # other UAVs' flights are moving obstacles of its field
        steps_in_time=True,  # its path is flown as planned when it passes every check
    )

    def _plan(self, run: Run) -> Outcome:
        sc, task, tr = run.scenario, run.task, run.tracker
        start = np.asarray(task.start, dtype=np.float64)
        goal = np.asarray(task.goal, dtype=np.float64)
        prm = field_params(self.config, sc, float(np.linalg.norm(goal - start)))
        per = int(self.config.steps_per_iteration)
        it_limit = (
            run.max_iterations if run.max_iterations is not None else self.specs.default_iterations
        )
        limit = it_limit * per
        if run.budget.max_evaluations is not None:
            limit = min(limit, int(run.budget.max_evaluations))
        steps = [0]

        def on_chunk(k: int, whole: FloatArray | None) -> int | None:
            for i in range(k):
                steps[0] += 1
                tr.evaluations += 1  # one evaluation of the field per step
                last = whole is not None and i == k - 1
                if last:
                    assert whole is not None
                    ev = run.problem.evaluate(whole[None])
                    tr.offer(whole, float(ev.cost[0]), bool(ev.feasible[0]))
                if (last or steps[0] % per == 0) and tr.end_iteration():
                    return i + 1
            if whole is None and steps[0] >= limit and steps[0] % per:
                tr.end_iteration()  # the budget ended inside an iteration
            return None

        res = run.reservations
        others = res.trajectories() if res is not None else []
        sep = res.radius if res is not None else 0.0
        traj = fly_field(
            sc, start, goal, prm, limit, float(task.start_time), on_chunk=on_chunk,
            others=others, separation=sep,
        )  # fmt: skip
        reasons: tuple[str, ...] = ()
        if traj.status != "arrived":
            reasons = ("local_minimum",) if traj.status == "stalled" else ("no_path",)
        return Outcome(
            path=traj.points,
            reasons=reasons,
            info={
                "status": traj.status,
                "steps": traj.steps,
                "stall_point": None if traj.stall_point is None else traj.stall_point.tolist(),
                "dt": prm.dt,
                "goal_radius": prm.goal_radius,
                "stall_steps": prm.stall_steps,
            },
        )


register_planner(APFPlanner)

__all__ = [
    "APFConfig", "APFPlanner", "FieldParams", "Trajectory", "field_params", "fly_field",
    "force_at", "force_reference",
]  # fmt: skip
