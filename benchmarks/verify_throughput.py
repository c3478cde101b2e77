"""Throughput of the fleet verifier's separation check on a synthetic fleet.

Run: ``python benchmarks/verify_throughput.py [--uavs 500] [--segments 50] [--repeats 3]``

The fleet: ``--uavs`` UAVs cross a square of side ``--side`` metres between random points on
its edge, each path a jittered polyline of ``--segments`` segments at 20 m/s, altitudes 50-150 m,
take-off times spread over the first minute (so most flights overlap in time). It prints, measured
in this one run (best of ``--repeats``; the machine is shared):

* pruning (sort-and-sweep on boxes grown by S2 and time windows): pairs kept out of all pairs;
* the exact continuous-time check of the kept pairs, in pairs/s and common intervals/s;
* the same exact check on every pair (no pruning), for comparison;
* the whole ``verify_trajectories`` (every check, on a flat scenario without terrain).
"""

from __future__ import annotations

import argparse

import numpy as np

from _timing import best_time
from uavplan.verify import Trajectory, verify_trajectories
from uavplan.verify.separation import candidate_pairs, check_separation
from uavplan.world import UAV, Bounds, Scenario, Task


def fleet(n: int, segments: int, side: float, seed: int = 0) -> list[Trajectory]:
    """``n`` UAVs crossing a ``side`` x ``side`` square, ``segments`` segments each."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        ends = []
        for _ in range(2):
            edge, s = rng.integers(4), rng.uniform(0, side)
            ends.append([(s, 0.0), (side, s), (s, side), (0.0, s)][edge])
        (x0, y0), (x1, y1) = ends
        w = np.linspace(0.0, 1.0, segments + 1)
        xy = np.stack([x0 + w * (x1 - x0), y0 + w * (y1 - y0)], axis=1)
        xy[1:-1] += rng.normal(0.0, side / (4 * segments), (segments - 1, 2))
        xy = np.clip(xy, 0.0, side)
        z = rng.uniform(50.0, 150.0, segments + 1)
        pts = np.column_stack([xy, z])
        dt = np.linalg.norm(np.diff(pts, axis=0), axis=1) / 20.0
        times = rng.uniform(0.0, 60.0) + np.concatenate([[0.0], np.cumsum(dt)])
        out.append(Trajectory(f"uav{k}", pts, times))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--uavs", type=int, default=500)
    ap.add_argument("--segments", type=int, default=50)
    ap.add_argument("--side", type=float, default=5000.0)
    ap.add_argument("--s2", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    trajs = fleet(args.uavs, args.segments, args.side)
    n = len(trajs)
    total = n * (n - 1) // 2
    t_prune = best_time(lambda: candidate_pairs(trajs, args.s2), args.repeats)
    kept = len(candidate_pairs(trajs, args.s2))
    t_sep = best_time(lambda: check_separation(trajs, args.s2), args.repeats)
    t_all = best_time(lambda: check_separation(trajs, args.s2, prune=False), args.repeats)
    intervals = 2 * args.segments  # at most, per pair
    sep = check_separation(trajs, args.s2)
    print(f"fleet: {n} UAVs x {args.segments} segments over {args.side:g} m, S2 {args.s2:g} m")
    print(f"pruning: {kept} of {total} pairs kept ({100 * kept / total:.1f} %) in {t_prune:.4f} s")
    print(
        f"separation (pruned): {t_sep:.4f} s, {kept / max(t_sep, 1e-12):,.0f} kept pairs/s; "
        f"min separation {sep.min_distance:.2f} m, {len(sep.violations)} violations"
    )
    print(
        f"separation (all pairs): {t_all:.4f} s, {total / t_all:,.0f} pairs/s, "
        f"up to {total * intervals / t_all:,.0f} intervals/s"
    )
    scenario = Scenario(
        "bench",
        Bounds((0.0, 0.0, 0.0), (args.side, args.side, 200.0)),
        tuple(Task(t.id, tuple(t.points[0]), tuple(t.points[-1])) for t in trajs),
        uav=UAV(speed=20.0, s2=args.s2),
    )
    t_verify = best_time(lambda: verify_trajectories(trajs, scenario), args.repeats)
    print(f"verify_trajectories (every check, no terrain): {t_verify:.4f} s")


if __name__ == "__main__":
    main()
