"""What the verifier reports: the kinds of violation, :class:`Violation`, :class:`VerifyReport`,
and the formatting of numbers and points in its messages (see :mod:`uavplan.verify`)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.io.plan_file import Trajectory
from uavplan.world.tolerances import VERIFY_TOL

FloatArray = NDArray[np.float64]

#: Geometric tolerance, metres.
TOL = VERIFY_TOL

#: Every kind of violation, in the order they are reported.
KINDS = (
    "times",
    "speed",
    "turn",
    "climb",
    "bounds",
    "separation",
    "cylinder",
    "circle",
    "polygon",
    "moving",
    "terrain",
    "altitude",
)


@dataclass(frozen=True)
class Violation:
    """One failed check.

    Attributes:
        kind: one of :data:`KINDS`.
        uavs: the UAV ids involved (two for ``separation``).
        time: seconds at the worst point (None when not tied to an instant).
        where: the worst point of each UAV in ``uavs``, metres (x, y[, z]).
        value: the measured quantity (distance, clearance, height, speed, time step), in its unit.
        required: the bound it breaks (the minimum, or the maximum for upper limits).
        message: one human-readable line.
    """

    kind: str
    uavs: tuple[str, ...]
    time: float | None
    where: tuple[tuple[float, ...], ...]
    value: float
    required: float
    message: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "uavs": list(self.uavs),
            "time": self.time,
            "where": [list(p) for p in self.where],
            "value": json_number(self.value),
            "required": json_number(self.required),
            "message": self.message,
        }


@dataclass
class VerifyReport:
    """What :func:`verify_plan` found.

    Attributes:
        scenario: the scenario's name; plan_scenario: the name the plan gives (None if absent).
        smoothed: whether the informative smoothed paths were verified.
        trajectory: which trajectories were verified: ``"flown"`` (each UAV's declared flown
            trajectory, its planned polyline where the plan declares none), ``"planned"`` (the
            planned polylines) or ``"smoothed"``.
        kinematics: whether the UAV's kinematic limits were checked (turn radius, climb and
            descent angles, minimum speed); the maximum speed is always checked.
        uav_ids: the UAVs, in plan order; n_segments: segments checked over all UAVs.
        s2: the required UAV-UAV separation, metres (per axis: the widest axis).
        s2_axes: the per-axis separation ``(S_x, S_y, S_z)`` when the UAV has one (an
            axis-aligned box; the separations reported are then the box measure
            ``max(S) max_i |r_i| / S_i``, below ``s2`` exactly inside the box), else None.
        pairs_total: ``n (n - 1) / 2``; pairs_checked: pairs left after pruning, checked exactly.
        min_separation: the smallest distance between two UAVs over continuous time, over all
            pairs (exact; inf if no two flights overlap in time).
        min_separation_pair, min_separation_time: where it happens (None if no pair checked).
        violations: every failed check; warnings: remarks that do not fail the plan.
        terrain_source: the raster the terrain and the band were checked against (its files'
            names), None when they were checked against the scenario's grid.
        model: the execution model the plan was checked under (its record), None: nominal
            only (:mod:`uavplan.verify.robust`).
        uav_margins, pair_margins: what each UAV, and each pair of UAVs (or a UAV and a moving
            obstacle) that can come close, tolerates (empty without a model); pairs tightest
            first.
    """

    scenario: str
    plan_scenario: str | None
    smoothed: bool
    uav_ids: list[str]
    n_segments: int
    s2: float
    s2_axes: tuple[float, float, float] | None = None
    pairs_total: int = 0
    pairs_checked: int = 0
    min_separation: float = math.inf
    min_separation_pair: tuple[str, str] | None = None
    min_separation_time: float | None = None
    trajectory: str = "flown"
    kinematics: bool = True
    violations: list[Violation] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    terrain_source: str | None = None
    model: dict[str, Any] | None = None
    uav_margins: list[Any] = field(default_factory=list)
    pair_margins: list[Any] = field(default_factory=list)

    def tightest_pairs(self, k: int = 10) -> list[Any]:
        """The ``k`` pairs with the smallest take-off margin (then speed, then tracking)."""
        return self.pair_margins[:k]

    @property
    def ok(self) -> bool:
        """True if no check failed."""
        return not self.violations

    @property
    def counts(self) -> dict[str, int]:
        """Violations per kind (every kind of :data:`KINDS`, zeros included)."""
        out = dict.fromkeys(KINDS, 0)
        for v in self.violations:
            out[v.kind] = out.get(v.kind, 0) + 1
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": "uavplan.verify/3",
            "scenario": self.scenario,
            "plan_scenario": self.plan_scenario,
            "smoothed": self.smoothed,
            "trajectory": self.trajectory,
            "kinematics": self.kinematics,
            "ok": self.ok,
            "uavs": len(self.uav_ids),
            "segments": self.n_segments,
            "s2": self.s2,
            "s2_axes": list(self.s2_axes) if self.s2_axes is not None else None,
            "pairs_total": self.pairs_total,
            "pairs_checked": self.pairs_checked,
            "min_separation": json_number(self.min_separation),
            "min_separation_pair": (
                list(self.min_separation_pair) if self.min_separation_pair else None
            ),
            "min_separation_time": self.min_separation_time,
            "counts": self.counts,
            "violations": [v.to_dict() for v in self.violations],
            "warnings": list(self.warnings),
            "terrain_source": self.terrain_source,
            "model": self.model,
            "uav_margins": [m.to_dict() for m in self.uav_margins],
            "pair_margins": [m.to_dict() for m in self.pair_margins],
        }


def json_number(v: float) -> float | None:
    """JSON has no infinity: null (format 2; format 1 wrote the strings "inf", "-inf")."""
    v = float(v)
    return v if math.isfinite(v) else None


# ================================================================================ formatting
def fmt_point(p: Iterable[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in p)


def fmt_num(v: float) -> str:
    v = float(v)
    if not math.isfinite(v):
        return "inf" if v > 0 else "-inf"
    return f"{v:.3f}"


def fmt_points(p: Iterable[float]) -> str:
    return "(" + ", ".join(f"{float(v):.2f}" for v in p) + ")"


def segment_ends(traj: Trajectory) -> tuple[FloatArray, FloatArray]:
    return traj.points[:-1], traj.points[1:]


def point_at(traj: Trajectory, k: int, s: float) -> tuple[tuple[float, ...], float]:
    """Point and time at parameter ``s`` of segment ``k``."""
    p = traj.points[k] + s * (traj.points[k + 1] - traj.points[k])
    t = traj.times[k] + s * (traj.times[k + 1] - traj.times[k])
    return fmt_point(p), float(t)
