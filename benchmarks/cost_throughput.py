"""Throughput of the batched path cost: segment-cylinder tests per second, ours vs references.

Run: ``python benchmarks/cost_throughput.py [--repeats N]``

Sizes (issue 2): the SPSO size (500 paths x 12 points x 6 cylinders + the SPSO DEM) and a large
size (1,000 paths x 50 points x 100 cylinders). For each it prints, measured in this one run:

* the Numba kernel (parallel over the population, all cores) in segment-cylinder tests/s;
* the same kernel's plain NumPy reference (one core) and a plain per-path Python loop, with
  our speed-up over each (the Python loop is timed on a slice and scaled per test);
* the fused threat pass (``cylinder_threat_batch``: SPSO's J2 summed per path in one pass, what
  the cost uses) against the previous form (the distances, then NumPy's threat cost) and
  against the limit reference: a minimal fused branchless kernel doing the same work (the same
  clipped distance and threat sum, written with min/max only, no per-pair function) -- the
  ratio to it says how near the machine's limit the production kernel is;
* for the SPSO size, the whole SPSO cost of a population (``PathProblem.cost``: the fused
  kernel of the four terms) against the previous implementation, the terms apart
  (``PathProblem(..., fused=False)``), on a uniform random population and on SPSO's swarm
  during a run, and PPSwarm's cost on its first scenario likewise; and the whole evaluation
  with feasibility (``PathProblem.evaluate``: exact terrain, obstacles), in ms.

Timings are the best of ``--repeats`` runs (the machine is shared; the best is the least noisy).
"""

from __future__ import annotations

import argparse
import math

import numba
import numpy as np
from numba import njit, prange

from _timing import best_time
from uavplan.kernel_builds import set_mode
from uavplan.problems import CartesianEncoding, PathProblem
from uavplan.problems.costs import threat_cost_spso
from uavplan.problems.encoding import SphericalEncoding
from uavplan.scenarios import load_builtin
from uavplan.world.geometry import (
    cylinder_threat_batch,
    segment_cylinder_distance,
    segment_cylinder_distance_reference,
)


@njit(parallel=True, fastmath=True)
def minimal_fused(paths, cx, cy, lo, hi, r_in, r_out):  # pragma: no cover - numba
    """The limit reference: SPSO's threat sum per path with the same clipped distance as the
    production kernel, branchless (min/max and selects), structure-of-arrays cylinders, all of
    LLVM's fast-math licences (so no infinities inside: heights beyond 1e300 stand for
    unbounded, and a hit is counted, the path's inf set at its end)."""
    n_paths, n_points = paths.shape[:2]
    out = np.empty(n_paths)
    for p in prange(n_paths):
        total, hits = 0.0, 0
        for s in range(n_points - 1):
            ax, ay, az = paths[p, s, 0], paths[p, s, 1], paths[p, s, 2]
            ex = paths[p, s + 1, 0] - ax
            ey = paths[p, s + 1, 1] - ay
            dz = paths[p, s + 1, 2] - az
            ee = ex * ex + ey * ey
            inv_ee = 1.0 / ee if ee > 0.0 else 0.0
            inv_dz = 1.0 / dz if dz != 0.0 else 1e300
            for j in range(cx.shape[0]):
                ta = (lo[j] - az) * inv_dz
                tb = (hi[j] - az) * inv_dz
                t0 = max(0.0, min(ta, tb))
                t1 = min(1.0, max(ta, tb))
                qx = cx[j] - ax
                qy = cy[j] - ay
                t = min(max((qx * ex + qy * ey) * inv_ee, t0), t1)
                rx = qx - t * ex
                ry = qy - t * ey
                d = np.sqrt(rx * rx + ry * ry)
                ok = t0 <= t1
                total += max(r_out[j] - d, 0.0) if ok else 0.0
                hits += 1 if (ok and d < r_in[j]) else 0
        out[p] = total if hits == 0 else np.inf
    return out


def python_loop(paths: np.ndarray, centers: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> list:
    """Per-path, per-segment, per-cylinder loop in plain Python (the naive implementation)."""
    out = []
    for path in paths.tolist():
        rows = []
        for s in range(len(path) - 1):
            ax, ay, az = path[s]
            bx, by, bz = path[s + 1]
            row = []
            for (cx, cy), zl, zh in zip(centers.tolist(), lo.tolist(), hi.tolist(), strict=True):
                dz = bz - az
                t0, t1 = 0.0, 1.0
                if dz != 0.0:
                    ta, tb = sorted(((zl - az) / dz, (zh - az) / dz))
                    t0, t1 = max(t0, ta), min(t1, tb)
                elif not zl <= az <= zh:
                    t1 = -1.0
                if t0 > t1:
                    row.append(math.inf)
                    continue
                px, py = ax + t0 * (bx - ax), ay + t0 * (by - ay)
                qx, qy = ax + t1 * (bx - ax), ay + t1 * (by - ay)
                ex, ey = qx - px, qy - py
                den = ex * ex + ey * ey
                t = 0.0 if den == 0 else min(max(((cx - px) * ex + (cy - py) * ey) / den, 0.0), 1.0)
                row.append(math.hypot(cx - px - t * ex, cy - py - t * ey))
            rows.append(row)
        out.append(rows)
    return out


def kernel_case(name: str, pop: int, n: int, J: int, repeats: int, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    paths = rng.uniform([0, 0, 0], [1000, 1000, 300], (pop, n, 3))
    centers = rng.uniform(0, 1000, (J, 2))
    lo = np.where(rng.random(J) < 0.5, -np.inf, 0.0)
    hi = np.where(rng.random(J) < 0.5, np.inf, rng.uniform(50, 300, J))
    tests = pop * (n - 1) * J
    t_numba = best_time(lambda: segment_cylinder_distance(paths, centers, lo, hi), repeats)
    t_numpy = best_time(
        lambda: segment_cylinder_distance_reference(paths, centers, lo, hi), max(1, repeats // 2)
    )
    k = max(1, min(pop, 20_000 // max(1, (n - 1) * J)))
    t_py = best_time(lambda: python_loop(paths[:k], centers, lo, hi), 1) * pop / k
    assert np.allclose(
        segment_cylinder_distance(paths, centers, lo, hi),
        segment_cylinder_distance_reference(paths, centers, lo, hi),
    )
    print(f"\n{name}: {pop} paths x {n} points x {J} cylinders = {tests:,} segment-cylinder tests")
    print(
        f"  numba kernel ({numba.get_num_threads()} threads) {t_numba * 1e3:7.2f} ms  "
        f"{tests / t_numba / 1e6:9.1f} M tests/s"
    )
    print(
        f"  numpy reference (1 core)   {t_numpy * 1e3:9.2f} ms  "
        f"{tests / t_numpy / 1e6:9.1f} M tests/s"
        f"  -> ours x{t_numpy / t_numba:.1f}"
    )
    print(
        f"  python per-path loop       {t_py * 1e3:9.1f} ms  {tests / t_py / 1e6:9.3f} M tests/s"
        f"  -> ours x{t_py / t_numba:.0f}"
    )
    # the threat cost itself (SPSO's J2 form), fused vs before vs the limit reference
    margin = np.full(J, 1.0)
    bare = rng.uniform(20.0, 80.0, J)
    r_in = bare + margin
    r_out = r_in + 10.0 * margin
    cx, cy = np.ascontiguousarray(centers[:, 0]), np.ascontiguousarray(centers[:, 1])
    fused = lambda: cylinder_threat_batch(paths, cx, cy, lo, hi, r_in, r_out, True)  # noqa: E731
    before = lambda: threat_cost_spso(  # noqa: E731
        segment_cylinder_distance(paths, centers, lo, hi), bare, margin
    )
    big = lambda a: np.clip(a, -1e300, 1e300)  # noqa: E731  (the minimal kernel has no infinities)
    limit = lambda: minimal_fused(paths, cx, cy, big(lo), big(hi), r_in, r_out)  # noqa: E731
    np.testing.assert_allclose(fused(), before(), rtol=1e-12)
    np.testing.assert_allclose(limit(), before(), rtol=1e-9)
    t_f, t_b, t_l = (best_time(f, repeats) for f in (fused, before, limit))
    for label, t in (("fused threat pass", t_f), ("distances + numpy cost", t_b)):
        print(
            f"  {label:26} {t * 1e3:9.2f} ms  {tests / t / 1e6:9.1f} M tests/s"
            f"  -> {t_l / t * 100:5.1f} % of the limit reference"
        )
    print(f"  limit reference (minimal)  {t_l * 1e3:9.2f} ms  {tests / t_l / 1e6:9.1f} M tests/s")


def spso_swarms() -> dict[str, np.ndarray]:
    """Paths of SPSO's swarm on its benchmark (500 particles, seed 0) after 1, 20 and 200
    iterations: the populations the cost sees in a run (a uniform random population in the box
    collides almost everywhere, where the fused kernel stops early)."""
    from uavplan.optimizers.spso import SPSO

    enc = SphericalEncoding(PathProblem(load_builtin("spso")))
    opt = SPSO(enc, seed=0)
    out = {}
    for it in range(1, 201):
        X = opt.ask()
        opt.tell(X, enc.evaluate(X))
        if it in (1, 20, 200):
            out[f"SPSO swarm, iteration {it}"] = enc.decode(X)
    return out


def spso_cost_case(repeats: int) -> None:
    sc = load_builtin("spso")
    problem = PathProblem(sc)
    before = PathProblem(sc, fused=False)  # the four terms apart: the previous implementation
    enc = CartesianEncoding(problem)
    rng = np.random.default_rng(1)
    X = enc.lower + rng.random((500, enc.dim)) * (enc.upper - enc.lower)
    pops = {"uniform in the box": enc.decode(X), **spso_swarms()}
    print("\nSPSO scenario, populations of 500 paths x 12 points (6 cylinders, 1045 x 879 DEM):")
    print("  whole SPSO cost (PathProblem.cost), ms per population; before = the terms apart")
    print(f"  {'population':28} {'finite':>6} {'fused':>8} {'before':>8} {'speed-up':>8}")
    for name, paths in pops.items():
        f = problem.cost(paths)
        np.testing.assert_allclose(f, before.cost(paths), rtol=1e-12)
        t_f = best_time(lambda p=paths: problem.cost(p), repeats)
        t_b = best_time(lambda p=paths: before.cost(p), repeats)
        print(f"  {name:28} {int(np.isfinite(f).sum()):>6} {t_f * 1e3:8.3f} {t_b * 1e3:8.3f}"
              f" {t_b / t_f:7.1f}x")  # fmt: skip
    # PPSwarm's preset, fused the same way: its first scenario (terrain, cylinders, the band)
    pp = load_builtin("ppswarm1")
    fused_pp, before_pp = PathProblem(pp), PathProblem(pp, fused=False)
    sph = SphericalEncoding(fused_pp)
    Y = sph.lower + np.random.default_rng(2).random((500, sph.dim)) * (sph.upper - sph.lower)
    pp_paths = sph.decode(Y)
    f = fused_pp.cost(pp_paths)
    np.testing.assert_allclose(f, before_pp.cost(pp_paths), rtol=1e-12)
    t_f = best_time(lambda: fused_pp.cost(pp_paths), repeats)
    t_b = best_time(lambda: before_pp.cost(pp_paths), repeats)
    print(f"  {'PPSwarm cost, ppswarm1':28} {int(np.isfinite(f).sum()):>6} {t_f * 1e3:8.3f}"
          f" {t_b * 1e3:8.3f} {t_b / t_f:7.1f}x")  # fmt: skip
    paths = pops["uniform in the box"]
    t_cost = best_time(lambda: problem.cost(paths), repeats)
    t_dec = best_time(lambda: enc.evaluate(X), repeats)
    t_eval = best_time(lambda: problem.evaluate(paths), repeats)
    t_loop = best_time(lambda: [problem.cost(paths[i : i + 1]) for i in range(50)], 1) * 10
    print(f"  genes -> paths -> cost (encoding.evaluate) {t_dec * 1e3:7.3f} ms per population")
    print(f"  cost + feasibility (exact terrain etc.)  {t_eval * 1e3:7.3f} ms per population")
    print(
        f"  same cost, one path per call (loop)      {t_loop * 1e3:7.1f} ms per population"
        f"  -> batched x{t_loop / t_cost:.0f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    # the population kernels' parallel builds when there are threads to run them (a CLI run
    # switches to them after a second of serial calls: uavplan.kernel_builds)
    set_mode("always" if numba.get_num_threads() > 1 else "never")
    print(f"population kernels: {'parallel' if numba.get_num_threads() > 1 else 'serial'} builds")
    kernel_case("SPSO size", 500, 12, 6, args.repeats)
    kernel_case("large size", 1000, 50, 100, args.repeats)
    spso_cost_case(args.repeats)


if __name__ == "__main__":
    main()
