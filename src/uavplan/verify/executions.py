"""Random executions of a plan drawn from its execution model, checked as if they were plans:
the Monte Carlo counterpart of :mod:`uavplan.verify.robust`'s bounds.

An execution of a UAV's flown trajectory (points ``p_k`` at times ``tau_k``): it takes off
``d`` seconds late (``d`` uniform in ``[-delta0, delta0]``), flies each segment with a ground
speed factor ``s_k`` (uniform in ``[1 - rho, 1 + rho]``, or one of the two ends with
``extremes``), so reaching ``p_k`` at ``t_k = tau_0 + d + sum_{i<k} (tau_{i+1} - tau_i) / s_i``,
and is off its path by a tracking offset that wanders within ``e_h`` horizontally and ``e_v``
vertically (drawn anew at every point, so the executed polyline stays inside the cylinders
around the path's points, not only at them). Whatever an execution does, the robust checks bound
it; sampling shows how close they are and catches a bound that is wrong.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory

FloatArray = NDArray[np.float64]


def sample_execution(
    traj: Trajectory,
    timing: Any,
    rng: np.random.Generator,
    extremes: bool = False,
) -> Trajectory:
    """One random execution of ``traj`` under ``timing`` (``delta0``, ``rho``, ``track_h``,
    ``track_v``: :class:`uavplan.verify.robust.Timing`)."""
    tau = np.asarray(traj.times, dtype=np.float64)
    P = np.asarray(traj.points, dtype=np.float64)
    n = len(tau)
    d = rng.uniform(-timing.delta0, timing.delta0) if timing.delta0 else 0.0
    if timing.rho:
        if extremes:
            s = np.where(rng.random(n - 1) < 0.5, 1.0 - timing.rho, 1.0 + timing.rho)
        else:
            s = rng.uniform(1.0 - timing.rho, 1.0 + timing.rho, n - 1)
    else:
        s = np.ones(n - 1)
    t = tau[0] + d + np.concatenate([[0.0], np.cumsum(np.diff(tau) / s)])
    Q = P.copy()
    if timing.track_h or timing.track_v:
        r = timing.track_h * np.sqrt(rng.random(n))
        a = rng.uniform(0.0, 2.0 * math.pi, n)
        Q[:, 0] += r * np.cos(a)
        Q[:, 1] += r * np.sin(a)
        if P.shape[1] == 3:
            Q[:, 2] += rng.uniform(-timing.track_v, timing.track_v, n)
    return Trajectory(traj.id, Q, t)


def sample_fleet(
    trajs: Sequence[Trajectory], timing: Any, rng: np.random.Generator, extremes: bool = False
) -> list[Trajectory]:
    """One random execution of every UAV, drawn independently."""
    return [sample_execution(t, timing, rng, extremes) for t in trajs]
