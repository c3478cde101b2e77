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

What is not here: a fixed-wing reference (JSBSim ships no small fixed-wing airframe in its
PyPI package, and none is ours yet): docs/decisions.md says so.
"""

from __future__ import annotations

import dataclasses
import math
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


def compare_multirotor(
    legs: Legs, turbulence: str = "moderate", seeds: int = 4
) -> dict[str, FloatArray]:
    """Cross-track errors (m, pooled over ``seeds`` gust realizations) of rotorpy's quadrotor
    and of the batched model with the reference controller's gains on the same legs."""
    from uavplan.sim.fleet import DRAWS, init_state, params, step_fleet
    from uavplan.sim.runs import REC_DT, pack
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
    P, n, S, H = pack([legs])
    dt = 0.01
    for sd in range(seeds):
        ref.append(cross_track(_rotorpy_flight(legs, turbulence, 1000 + sd), legs.points))
        rng = np.random.default_rng(2000 + sd)
        prm = (*params(af, uav)[:14], 0.0, 0.0, *params(af, uav)[16:])
        st = init_state(P, n, S, H, np.array([legs.takeoff]), np.zeros((1, 3)))
        span = float(np.sum(np.linalg.norm(np.diff(legs.points, axis=0), axis=1)) / v_leg) * 2
        R = int(span / REC_DT) + 10
        xyz, tt, nn = np.zeros((1, R, 3)), np.zeros((1, R)), np.zeros(1, dtype=np.int64)
        t = legs.takeoff
        while t < legs.takeoff + span:
            noise = rng.standard_normal((1, 1000, DRAWS))
            done = step_fleet(st, P, n, S, H, np.array([legs.takeoff]), 1, prm, np.zeros(3),
                              INTENSITIES[turbulence], 100.0, dt, t, 1000, REC_DT, noise,
                              xyz, tt, nn)  # fmt: skip
            t += 1000 * dt
            if done:
                break
        ours.append(cross_track(xyz[0, : nn[0]], legs.points))
    return {"reference": np.concatenate(ref), "batched": np.concatenate(ours)}
