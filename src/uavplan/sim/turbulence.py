"""The Dryden turbulence model of MIL-HDBK-1797 (MIL-F-8785C), low altitude, for the batched
simulation: gust velocities along the UAV's heading (``u``), across it (``v``) and vertically
(``w``), each a shaping filter driven by white noise, integrated with the flight.

Low altitude (the handbook's form below 1,000 ft, ``h`` in feet, clamped to [10, 1000]):
``L_w = h``, ``L_u = L_v = h / (0.177 + 0.000823 h)^1.2``; ``sigma_w = 0.1 W20``,
``sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4``, ``W20`` the wind speed at 20 ft:
15 kt light, 30 kt moderate, 45 kt severe turbulence. Spectra as transfer functions of unit
white noise, ``T = L / V``:

* ``u``: ``sigma_u sqrt(2 T) / (1 + T s)``, discretized exactly (an AR(1) process);
* ``v``, ``w``: ``sigma sqrt(T) (1 + sqrt(3) T s) / (1 + T s)^2``, a second-order state-space
  system driven by the noise held over each step, integrated in sub-steps of at most ``T/10``.

Each has variance ``sigma^2`` (the gains above are the spectra of the handbook normalized to
it: ``(1/2pi) int |H|^2 = sigma^2``). ``tests/sim`` checks the variances and correlation times of
the processes this module makes. The frozen-field airspeed ``V`` is at least
:data:`MIN_AIRSPEED` (a hovering multirotor meets the same eddies as wind carries them by).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: ``W20`` (m/s) per named intensity.
INTENSITIES = {"none": 0.0, "light": 15 * 0.514444, "moderate": 30 * 0.514444,
               "severe": 45 * 0.514444}  # fmt: skip
#: The least airspeed the frozen-field scales use, m/s.
MIN_AIRSPEED = 5.0
FT = 0.3048


@njit(cache=True)
def dryden_scales(h_m, w20):  # pragma: no cover - numba
    """``(L_u, L_w, sigma_u, sigma_w)`` in metres and m/s at height ``h_m`` above ground."""
    h = min(max(h_m / FT, 10.0), 1000.0)
    d = 0.177 + 0.000823 * h
    Lu = h / d**1.2 * FT
    Lw = h * FT
    sw = 0.1 * w20
    su = sw / d**0.4
    return Lu, Lw, su, sw


@njit(cache=True)
def gust_step(g, V, h_m, w20, dt, n0, n1, n2):  # pragma: no cover - numba
    """Advance one UAV's gust state ``g`` (5,: ``u``, ``v``'s two states, ``w``'s two) by
    ``dt`` at airspeed ``V`` and height ``h_m``, with standard normal draws ``n0, n1, n2``;
    returns ``(u, v, w)`` after the step."""
    if w20 <= 0.0:
        return 0.0, 0.0, 0.0
    Lu, Lw, su, sw = dryden_scales(h_m, w20)
    V = max(V, 5.0)
    Tu = Lu / V
    a = math.exp(-dt / Tu)
    g[0] = a * g[0] + su * math.sqrt(1.0 - a * a) * n0
    out_v = 0.0
    out_w = 0.0
    for k in range(2):
        T = (Lu if k == 0 else Lw) / V
        s = su if k == 0 else sw
        n = n1 if k == 0 else n2
        i = 1 + 2 * k
        x1n = g[i]
        x2n = g[i + 1]
        # T^2 x1'' + 2 T x1' + x1 = noise (unit intensity, held over the step), x2 = x1';
        # sub-steps of at most T / 10 keep the explicit integration close and stable
        m = math.ceil(10.0 * dt / T)
        hstep = dt / m
        drive = n / math.sqrt(dt)
        for _ in range(m):
            x1o = x1n
            x1n = x1o + hstep * x2n
            x2n = x2n + hstep * (drive - x1o - 2.0 * T * x2n) / (T * T)
        g[i] = x1n
        g[i + 1] = x2n
        y = s * math.sqrt(T) * (x1n + math.sqrt(3.0) * T * x2n)
        if k == 0:
            out_v = y
        else:
            out_w = y
    return g[0], out_v, out_w


def gust_series(n: int, V: float, h_m: float, w20: float, dt: float, seed: int) -> np.ndarray:
    """``n`` steps of one gust process, (n, 3): for tests and figures."""
    rng = np.random.default_rng(seed)
    g = np.zeros(5)
    out = np.empty((n, 3))
    noise = rng.standard_normal((n, 3))
    for k in range(n):
        out[k] = gust_step(g, V, h_m, w20, dt, noise[k, 0], noise[k, 1], noise[k, 2])
    return out
