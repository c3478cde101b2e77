"""Cost per segment against the number of obstacles (issue 18 item 2's figure), with the
obstacle grid (``uavplan.world.obstacle_index``) and testing every pair, measured in the same run.

Cylinders: the fused
cylinder pass (``uavplan.world.geometry.cylinder_threat_batch``, PPSwarm's threat cost, what
``PathProblem`` uses) on 200 paths x 20 points, with J = 10 ... 10,000 cylinders of radius
20-60 m placed uniformly at one density (100 per 10 km square: the map grows with J, as maps of
more no-fly zones cover more ground), the same path shapes at every J.

Run: ``python benchmarks/obstacle_scaling.py [--repeats N]`` (``NUMBA_NUM_THREADS=1`` on a
shared machine). Prints ns per segment at each J and the ratio to its value at J = 50, for the
production path (from ``GRID_MIN_CYLINDERS`` cylinders on, a uniform grid picks the cylinders
near each segment; the grid is built once per world and kept) and for the every-pair kernel
measured in the same run; then the same for the cylinder check (``cylinder_hits``, which the
validator's check and graded violation use) against its every-pair kernel. The issue's target:
at most 3 times the value at J = 50 at J = 10,000.

Circles and polygons (2-D; ``scene_case``): the 2-D scene pass (``scene2d_batch``: inside
lengths, hits and bounds, what ``length2d`` and the validator's 2-D checks use) on J obstacles at
the same density, half circles and half polygons (3-10 vertices, convex and not, radius 20-60 m),
grid (from ``GRID_MIN_OBSTACLES``) against every pair, the answers compared bit for bit; the
validator end to end (``paths_valid`` of a 2-D scenario: what RRT*'s and the RGG's edge checks
call); HR-MAGA's length inside J danger areas (``danger_length_cost``); and the verifier's
circle and polygon checks of one 4,000-segment trajectory (its broad phase from
``INDEX_MIN`` obstacles on, against every obstacle tested against every segment; the same
violations). ``--quick`` leaves out every pair at 5,000 and 10,000 for the verifier (seconds).
"""

from __future__ import annotations

import argparse

import numpy as np

from _timing import best_time
from uavplan.world.geometry import (
    cylinder_hits,
    cylinder_overlap,
    cylinder_threat,
    cylinder_threat_batch,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--only", choices=("cylinders", "2d"), default=None)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    if a.only != "2d":
        cylinder_case(a.repeats)
    if a.only != "cylinders":
        scene_case(a.repeats)
        verifier_case(a.quick)


def cylinder_case(repeats: int) -> None:
    """The cylinders' threat cost and check, then the 3-D validator."""
    rng = np.random.default_rng(0)
    P, N = 200, 20
    steps = np.cumsum(rng.normal(0.0, 150.0, (P, N, 3)), axis=1)
    segments = P * (N - 1)
    base = None
    print(f"{P} paths x {N} points ({segments:,} segments), 100 cylinders per 10 km square")
    print("threat cost; cylinder check (hits and metres inside), ns per segment:")
    print(f"{'cylinders':>9} {'threat':>8} {'vs J=50':>8} {'every pair':>11} {'vs J=50':>8}"
          f" {'check':>8} {'every pair':>11}")  # fmt: skip
    base_all = None
    for J in (10, 50, 100, 500, 1_000, 5_000, 10_000):
        side = 10_000.0 * np.sqrt(J / 100.0)
        centers = rng.uniform(0.0, side, (J, 2))
        paths = np.ascontiguousarray(steps + np.array([side / 2, side / 2, 100.0]))
        R = rng.uniform(20.0, 60.0, J)
        lo, hi = np.full(J, -np.inf), rng.uniform(150.0, 400.0, J)

        cx, cy = np.ascontiguousarray(centers[:, 0]), np.ascontiguousarray(centers[:, 1])

        def cost() -> object:
            return cylinder_threat(paths, centers, lo, hi, R, R + 50.0, False)  # noqa: B023

        def every_pair() -> object:
            return cylinder_threat_batch(paths, cx, cy, lo, hi, R, R + 50.0, False)  # noqa: B023

        def check() -> object:
            return cylinder_hits(paths, centers, lo, hi, R)  # noqa: B023

        def check_every_pair() -> object:
            return cylinder_overlap(paths, centers, lo, hi, R)  # noqa: B023

        np.testing.assert_allclose(cost(), every_pair(), rtol=1e-12)
        hit_ref = check_every_pair()[1] < 0  # type: ignore[index]
        assert np.array_equal(check()[1], hit_ref)  # type: ignore[index]
        ns = best_time(cost, repeats) / segments * 1e9
        ns_all = best_time(every_pair, repeats) / segments * 1e9
        base = ns if J == 50 else base
        base_all = ns_all if J == 50 else base_all
        ratio = f"{ns / base:8.1f}" if base else f"{'-':>8}"
        ratio_all = f"{ns_all / base_all:8.1f}" if base_all else f"{'-':>8}"
        ns_c = best_time(check, repeats) / segments * 1e9
        ns_c_all = best_time(check_every_pair, repeats) / segments * 1e9
        row = f"{J:>9,} {ns:>8.1f} {ratio} {ns_all:>11.1f} {ratio_all}"
        print(f"{row} {ns_c:>8.1f} {ns_c_all:>11.1f}", flush=True)

    validator_case(repeats)


def validator_case(repeats: int) -> None:
    """The motion validator end to end (``paths_valid``: the fused 3-D static kernel for bounds,
    terrain and band, then the cylinders) on the SPSO terrain with J small cylinders, against
    the same validator with the grid turned off (every pair inside the fused kernel)."""
    import dataclasses

    from uavplan.problems.validity import MotionValidator
    from uavplan.scenarios import resolve
    from uavplan.world import Cylinder
    from uavplan.world import geometry as G

    sc0 = resolve("spso")
    rng = np.random.default_rng(1)
    lo, hi = np.asarray(sc0.bounds.lo), np.asarray(sc0.bounds.hi)
    start = rng.uniform(lo[:2], hi[:2], (300, 1, 2))
    xy = start + np.cumsum(rng.normal(0.0, 5.0, (300, 8, 2)), axis=1)
    z = sc0.ground(xy[..., 0], xy[..., 1]) + 150.0
    paths = np.ascontiguousarray(np.concatenate([xy, z[..., None]], axis=-1))
    print("\nmotion validator on the SPSO terrain, 300 paths x 8 points, ns per segment:")
    print(f"{'cylinders':>9} {'grid':>9} {'every pair':>11} {'valid':>6}")
    default = G.GRID_MIN_CYLINDERS
    for J in (50, 1_000, 10_000):
        cyl = tuple(
            Cylinder(tuple(c), float(r))
            for c, r in zip(
                rng.uniform(lo[:2], hi[:2], (J, 2)), rng.uniform(0.5, 2.0, J), strict=True
            )
        )
        sc = dataclasses.replace(sc0, cylinders=cyl)
        times, verdicts = [], []
        for threshold in (default, 10**9):
            G.GRID_MIN_CYLINDERS = threshold
            v = MotionValidator(sc, sc.tasks[0])
            verdicts.append(v.paths_valid(paths))
            times.append(best_time(lambda: v.paths_valid(paths), repeats) / paths[:, 1:].size * 3e9)  # noqa: B023
        G.GRID_MIN_CYLINDERS = default
        assert np.array_equal(verdicts[0], verdicts[1])
        print(f"{J:>9,} {times[0]:>9.1f} {times[1]:>11.1f} {int(verdicts[0].sum()):>6}", flush=True)


COUNTS = (10, 50, 100, 500, 1_000, 5_000, 10_000)


def _scene_world(rng: np.random.Generator, J: int) -> tuple[float, np.ndarray, np.ndarray, list]:
    """J obstacles at 100 per 10 km square: half circles (centres, radii), half polygons."""
    side = 10_000.0 * np.sqrt(J / 100.0)
    n_c = J // 2
    centers = rng.uniform(0.0, side, (n_c, 2))
    radii = rng.uniform(20.0, 60.0, n_c)
    polys = []
    for _ in range(J - n_c):
        k = int(rng.integers(3, 11))
        ang = np.sort(rng.uniform(0.0, 2 * np.pi, k))
        rad = rng.uniform(20.0, 60.0) * (rng.uniform(0.4, 1.0, k) if rng.random() < 0.5 else 1.0)
        polys.append(rng.uniform(0.0, side, 2) + np.c_[rad * np.cos(ang), rad * np.sin(ang)])
    return side, centers, radii, polys


def _ratio(x: float, base: float | None) -> str:
    return f"{x / base:8.1f}" if base else f"{'-':>8}"


def scene_case(repeats: int) -> None:
    """Circles and polygons: the 2-D scene pass, the 2-D validator, danger areas."""
    from uavplan.problems import costs as C
    from uavplan.problems.validity import MotionValidator
    from uavplan.world import Bounds, Circle, Polygon, Scenario, Task
    from uavplan.world import geometry as G

    rng = np.random.default_rng(2)
    P, N = 200, 20
    steps = np.cumsum(rng.normal(0.0, 150.0, (P, N, 2)), axis=1)
    segments = P * (N - 1)
    print(f"\n2-D: {P} paths x {N} points, 100 obstacles per 10 km square (half circles, half "
          "polygons), ns per segment:")  # fmt: skip
    print(f"{'obstacles':>9} {'scene':>8} {'vs J=50':>8} {'every pair':>11} {'vs J=50':>8}"
          f" {'validator':>9} {'vs J=50':>8} {'danger':>8} {'vs J=50':>8}")  # fmt: skip
    base: dict[str, float] = {}
    for J in COUNTS:
        side, centers, radii, polys = _scene_world(rng, J)
        paths = np.ascontiguousarray(steps + side / 2)
        verts, starts = G.pack_polygons(polys)
        margins = np.zeros(len(polys))
        box = (np.zeros(2), np.full(2, side))
        world = (centers, radii, verts, starts, margins)
        grid, every = G.scene_prep(*world), G.scene_prep(*world, gridded=False)
        a = G.scene2d_batch(paths, *world, *box, grid)
        b = G.scene2d_batch(paths, *world, *box, every)
        for x, y in zip(a, b, strict=True):
            assert np.array_equal(x, y)
        t = {
            "scene": best_time(lambda: G.scene2d_batch(paths, *world, *box, grid), repeats),  # noqa: B023
            "all": best_time(lambda: G.scene2d_batch(paths, *world, *box, every), repeats),  # noqa: B023
        }
        sc = Scenario(
            f"scaling{J}", Bounds((0.0, 0.0), (side, side)),
            (Task("t", (1.0, 1.0), (side - 1.0, side - 1.0)),),
            circles=tuple(Circle((float(x), float(y)), float(r))
                          for (x, y), r in zip(centers, radii, strict=True)),
            polygons=tuple(Polygon(tuple(map(tuple, v))) for v in polys),
        )  # fmt: skip
        v = MotionValidator(sc)
        t["validator"] = best_time(lambda: v.paths_valid(paths), repeats)  # noqa: B023
        few = slice(0, 20)  # the every-pair reference's (P, N - 1, J) array stays small
        want = (
            G.segment_circle_inside_fraction(paths[few], centers, radii)
            * C.segment_lengths(paths[few])[..., None]
        ).sum(axis=(1, 2))
        got = C.danger_length_cost(paths[few], centers, radii)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
        t["danger"] = best_time(lambda: C.danger_length_cost(paths, centers, radii), repeats)  # noqa: B023
        ns = {k: x / segments * 1e9 for k, x in t.items()}
        if J == 50:
            base = dict(ns)
        print(f"{J:>9,} {ns['scene']:>8.1f} {_ratio(ns['scene'], base.get('scene'))}"
              f" {ns['all']:>11.1f} {_ratio(ns['all'], base.get('all'))}"
              f" {ns['validator']:>9.1f} {_ratio(ns['validator'], base.get('validator'))}"
              f" {ns['danger']:>8.1f} {_ratio(ns['danger'], base.get('danger'))}",
              flush=True)  # fmt: skip


def verifier_case(quick: bool) -> None:
    """The verifier's circle and polygon checks of one long trajectory: broad phase against
    every pair (``INDEX_MIN`` raised), the same violations."""
    import time

    from uavplan.verify import Trajectory
    from uavplan.verify import obstacles as VO
    from uavplan.world import Circle, Polygon

    rng = np.random.default_rng(3)
    M = 4000
    walk = np.cumsum(rng.normal(0.0, 8.0, (M + 1, 2)), axis=0)
    print(f"\nverifier, circle and polygon checks of a {M:,}-segment trajectory, us per segment:")
    print(f"{'obstacles':>9} {'grid':>8} {'vs J=50':>8} {'every pair':>11} {'vs J=50':>8}"
          f" {'violations':>10}")  # fmt: skip
    base: dict[str, float] = {}
    default = VO.INDEX_MIN
    for J in COUNTS:
        side, centers, radii, polys = _scene_world(rng, J)
        circles = tuple(Circle((float(x), float(y)), float(r))
                        for (x, y), r in zip(centers, radii, strict=True))  # fmt: skip
        polygons = tuple(Polygon(tuple(map(tuple, v))) for v in polys)
        traj = Trajectory("u", walk + side / 2, np.arange(M + 1, dtype=np.float64))

        def run() -> list:
            return VO.check_circles(traj, circles) + VO.check_polygons(traj, polygons)  # noqa: B023

        got = run()  # builds and keeps the grids
        t0 = time.perf_counter()
        got = run()
        us = {"grid": (time.perf_counter() - t0) / M * 1e6}
        if not (quick and J >= 5_000):
            VO.INDEX_MIN = 10**9
            t0 = time.perf_counter()
            want = run()
            us["all"] = (time.perf_counter() - t0) / M * 1e6
            VO.INDEX_MIN = default
            assert got == want
        if J == 50:
            base = dict(us)
        every = f"{us['all']:>11.1f} {_ratio(us['all'], base.get('all'))}" if "all" in us else (
            f"{'-':>11} {'-':>8}")  # fmt: skip
        print(f"{J:>9,} {us['grid']:>8.1f} {_ratio(us['grid'], base.get('grid'))} {every}"
              f" {len(got):>10}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
