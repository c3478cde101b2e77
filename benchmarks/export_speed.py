"""Mission export speed (issue 16's figure: a 500-UAV plan to every format in <= 5 s).

A synthetic fleet plan on ``ppswarm1`` (N UAVs, each a flown trajectory of ``--points``
points, 150 m above the terrain) is exported to every registered format; printed per format:
seconds, and the ratio to reading the same plan file (``read_plan_file``, measured in the same
run: the reference every export starts from).
Run: ``python benchmarks/export_speed.py [--uavs 500] [--points 200]``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from uavplan.io.missions import ExportOptions, Mission, exporters
from uavplan.io.plan_file import read_plan_file
from uavplan.scenarios import resolve


def fleet_doc(n: int, points: int) -> dict:  # type: ignore[type-arg]
    sc = resolve("ppswarm1")
    assert sc.terrain is not None and sc.origin is not None
    rng = np.random.default_rng(0)
    uavs = []
    for k in range(n):
        a, b = rng.uniform([50, 50], [1000, 800], (2, 2))
        s = np.linspace(0, 1, points)[:, None]
        xy = a + s * (b - a)
        P = np.column_stack([xy, sc.terrain.height(xy[:, 0], xy[:, 1]) + 150.0])
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1) / 20)])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": t.tolist(),
                     "feasible": True})  # fmt: skip
    return {"format": "uavplan.plan/2", "scenario": "ppswarm1", "feasible": True,
            "origin": sc.origin.record(), "uavs": uavs}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--uavs", type=int, default=500)
    ap.add_argument("--points", type=int, default=200)
    args = ap.parse_args()
    sc = resolve("ppswarm1")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "plan.json"
        path.write_text(json.dumps(fleet_doc(args.uavs, args.points)))
        t = time.perf_counter()
        plan = read_plan_file(path)
        t_read = time.perf_counter() - t
        print(f"{args.uavs} UAVs x {args.points} points; reading the plan file: {t_read:.3f} s")
        print(f"{'format':10s} {'seconds':>8s} {'x read':>7s} files")
        total = 0.0
        for e in exporters().values():
            out = Path(tmp) / e.name
            if e.per_uav:
                out.mkdir()
            else:
                out = out.with_suffix(e.suffix)
            t = time.perf_counter()
            written = e.write(Mission(plan, sc, ExportOptions()), out)
            dt = time.perf_counter() - t
            total += dt
            print(f"{e.name:10s} {dt:8.3f} {dt / t_read:7.1f} {len(written)}")
        print(f"every format: {total:.3f} s (target <= 5 s)")


if __name__ == "__main__":
    main()
