"""``csv``: every UAV's timed trajectory as one table, a row per point: ``uav, point, time_s, x_m,
y_m[, z_m]`` (the plan's local frame: x east, y north, z up, absolute altitude; seconds from the
plan's time origin). Spreadsheets, pandas and plotting tools read it as it is."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from uavplan.io.atomic import write_text_atomic
from uavplan.io.missions import Mission, register_exporter


@register_exporter("csv", ".csv", "one table of every UAV's timed points (local ENU metres)")
def write_csv(mission: Mission, out: Path) -> list[Path]:
    plan = mission.plan
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    axes = ["x_m", "y_m", "z_m"][: plan.dim]
    w.writerow(["uav", "point", "time_s", *axes])
    for tr in mission.trajectories():
        for k, (t, p) in enumerate(zip(tr.times, tr.points, strict=True)):
            w.writerow([tr.id, k, f"{t:.6f}", *(f"{v:.6f}" for v in p)])
    return [write_text_atomic(out, buf.getvalue())]
