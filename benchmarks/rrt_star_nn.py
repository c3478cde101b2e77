"""RRT* nearest-neighbour throughput (grid vs brute force) and RRT* iterations/s on ``spso``.

Run: ``python benchmarks/rrt_star_nn.py [--repeats N] [--seeds S] [--threads T]``

It prints, measured in this one run:

* **Nearest neighbour.** Queries/s of :class:`uavplan.planners.sampling.rrt_star.GridIndex`
(``nearest``
  and ``near(r)``, with the cell RRT* would use for that many nodes) against a
  brute-force scan of every point on the same queries: the NumPy reference
  (:func:`nearest_brute` / :func:`near_brute`, what the tests compare against) and a compiled
  (Numba) scan, so the ratio is not just NumPy's call overhead. Point sets: the nodes of a
  5,000-iteration anytime RRT* tree on ``spso``, and uniform points in spso's sampling region
  (1k, 10k, 100k); queries are samples from the same sampler. Every answer is checked against
  the brute force.
* **RRT* on spso.** Alg. 1 with the defaults (stop at the goal) over ``--seeds`` seeds: time and
  iterations to the first path, iterations/s; and an anytime run of 5,000 iterations
  (iterations/s, segment checks per iteration). spso reads node heights as its cost does
  (nearest node), which the compiled segment check does not, so these run the Python loop.
* **The loops.** On ``dense`` and ``ppswarm1`` (terrain, cylinders, a band above ground: the
  compiled check applies), 3,000 anytime iterations, plain and informed: iterations/s of the
  Numba loop and of the Python reference loop (``loop="python"``), their ratio, and the segment
  checks per iteration of each (lazy against batched); the two trees are checked equal.

Timings are the best of ``--repeats`` runs (the machine is shared). ``--threads`` sets Numba's
threads (default 1: the feasibility kernels are ``prange`` loops and RRT*'s batches are small,
so extra threads only add synchronisation; the experiment runner also uses 1).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from functools import partial

import numba
import numpy as np
from numba import njit

from _timing import best_time
from uavplan.planners.sampling.grid_index import GridIndex, near_brute, nearest_brute
from uavplan.planners.sampling.rrt_star import RRTStarConfig, RRTStarTree, rrt_star
from uavplan.scenarios import load_builtin


@njit(cache=True)
def _brute_nearest_numba(pts: np.ndarray, q: np.ndarray) -> int:
    best, bd2 = -1, np.inf
    for j in range(pts.shape[0]):
        d2 = 0.0
        for a in range(pts.shape[1]):
            d = pts[j, a] - q[a]
            d2 += d * d
        if d2 < bd2:
            best, bd2 = j, d2
    return best


def _near_of(grid: GridIndex, q: np.ndarray, r: float) -> object:
    return grid.near(q, r)


def _near_brute_of(pts: np.ndarray, q: np.ndarray, r: float) -> object:
    return near_brute(pts, q, r)


def _tree_points(config: RRTStarConfig, iterations: int) -> tuple[np.ndarray, RRTStarTree]:
    sc = load_builtin("spso")
    tree = RRTStarTree(sc, None, config, np.random.default_rng(0))
    tree.run(iterations, stop_at_goal=False)
    return np.asarray(tree.points.copy()), tree


def _queries(tree: RRTStarTree, n: int) -> np.ndarray:
    return np.array([tree.sample() for _ in range(n)])[:, : tree.dim]


def nn_table(repeats: int) -> None:
    cfg = RRTStarConfig(stop_at_goal=False)
    tree_pts, tree = _tree_points(cfg, 5000)
    sets = [("spso RRT* tree (5k it.)", tree_pts)]
    lo, hi = tree._lo, tree._hi
    rng = np.random.default_rng(1)
    for n in (1_000, 10_000, 100_000):
        p = lo + rng.random((n, 3)) * (hi - lo)
        p[:, 2] += tree.scenario.ground(p[:, 0], p[:, 1])
        sets.append((f"uniform, {n:,} points", p))
    n_q = 2000
    queries = _queries(tree, n_q)
    print(f"Nearest neighbour, {n_q} queries, spso sampling region (metres)")
    print(
        f"{'point set':<26} {'n':>7} {'cell m':>7} {'grid q/s':>10} {'numpy q/s':>10} "
        f"{'ratio':>7} {'numba scan q/s':>15} {'ratio':>7} | {'near(r) grid':>12} "
        f"{'numpy':>9} {'ratio':>7}"
    )
    for label, pts in sets:
        n = len(pts)
        card = n + 1
        r = min(cfg.near_radius, tree.gamma * (math.log(card) / card) ** (1 / 3))
        grid = GridIndex(tree.grid._box_lo, tree.grid._box_hi, 1e9, capacity=n)
        for p in pts:
            grid.add(p)
        grid.balance(r)  # the cell RRT* would have: max(r, about a point per cell)
        # correctness on these very queries
        for q in queries[:200]:
            assert grid.nearest(q)[0] == nearest_brute(pts, q)[0]
            assert np.array_equal(grid.near(q, r), near_brute(pts, q, r))
        nq_np = max(20, min(n_q, int(2e7 / n)))  # keep the NumPy scan of 100k points short

        def per_second(fn: Callable[[np.ndarray], object], qs: np.ndarray) -> float:
            def run() -> None:
                for q in qs:
                    fn(q)

            return len(qs) / best_time(run, repeats)

        tg = per_second(grid.nearest, queries)
        tb = per_second(partial(nearest_brute, pts), queries[:nq_np])
        tn = per_second(partial(_brute_nearest_numba, pts), queries)
        tgr = per_second(partial(_near_of, grid, r=r), queries)
        tbr = per_second(partial(_near_brute_of, pts, r=r), queries[:nq_np])
        print(
            f"{label:<26} {n:>7} {grid.cell:>7.1f} {tg:>10,.0f} {tb:>10,.0f} {tg / tb:>7.1f} "
            f"{tn:>15,.0f} {tg / tn:>7.1f} | {tgr:>12,.0f} {tbr:>9,.0f} {tgr / tbr:>7.1f}"
        )


def rrt_table(seeds: int, repeats: int) -> None:
    sc = load_builtin("spso")
    cfg = RRTStarConfig()
    rrt_star(sc, None, cfg, np.random.default_rng(0))  # warm-up
    times, its, lengths, nodes = [], [], [], []
    for s in range(seeds):
        t0 = time.perf_counter()
        r = rrt_star(sc, None, cfg, np.random.default_rng(s))
        times.append(time.perf_counter() - t0)
        its.append(r.iterations)
        lengths.append(r.cost)
        nodes.append(r.n_nodes)
    t = np.array(times)
    it = np.array(its)
    print(f"\nRRT* (Alg. 1, defaults, stop at goal) on spso, {seeds} seeds")
    print(
        f"  time to first path: median {np.median(t) * 1e3:.1f} ms, max {t.max() * 1e3:.1f} ms; "
        f"iterations: median {np.median(it):.0f}, max {it.max()}; "
        f"path length median {np.median(lengths):.0f} m (straight {_straight(sc):.0f} m); "
        f"{it.sum() / t.sum():,.0f} iterations/s"
    )
    any_cfg = RRTStarConfig(stop_at_goal=False)
    n_it = 5000

    def anytime() -> RRTStarTree:
        tree = RRTStarTree(sc, None, any_cfg, np.random.default_rng(0))
        tree.run(n_it, stop_at_goal=False)
        return tree

    tb = best_time(anytime, repeats)
    tree = anytime()
    print(
        f"  anytime, {n_it} iterations: {n_it / tb:,.0f} iterations/s, {tree.n_nodes} nodes, "
        f"{tree.edge_checks / n_it:.1f} segment checks/iteration, final radius "
        f"{tree.radius():.1f} m, shortest path {_len(tree.path()):.0f} m"
    )


def loop_table(repeats: int) -> None:
    """The Numba loop against the Python reference loop (the same tree) on worlds where it
    applies: anytime runs, plain and informed."""
    print("\nRRT* loops (anytime, the same tree; Numba where the world has a compiled check)")
    print(f"{'scenario':<10} {'informed':>8} {'iters':>6} {'numba it/s':>11} {'python it/s':>12} "
          f"{'ratio':>6} {'checks/it numba':>16} {'python':>7}")  # fmt: skip
    n_it = 3000
    for name in ("dense", "ppswarm1"):
        sc = load_builtin(name)
        for informed in (False, True):

            def grow(loop: str, informed: bool = informed, sc: object = sc) -> RRTStarTree:
                cfg = RRTStarConfig(stop_at_goal=False, informed=informed, loop=loop)
                tree = RRTStarTree(sc, None, cfg, np.random.default_rng(0))  # type: ignore[arg-type]
                tree.run(n_it, stop_at_goal=False)
                return tree

            tf = best_time(lambda: grow("numba"), repeats)
            tp = best_time(lambda: grow("python"), max(1, repeats - 2))
            a, b = grow("numba"), grow("python")
            assert a.fast and np.array_equal(a.points, b.points)  # the same tree
            ca, cb = a.edge_checks / n_it, b.edge_checks / n_it
            print(f"{name:<10} {informed!s:>8} {n_it:>6} {n_it / tf:>11,.0f} {n_it / tp:>12,.0f} "
                  f"{tp / tf:>6.1f} {ca:>16.1f} {cb:>7.1f}")  # fmt: skip


def _straight(sc) -> float:  # type: ignore[no-untyped-def]
    t = sc.tasks[0]
    return float(np.linalg.norm(np.subtract(t.goal, t.start)))


def _len(p: np.ndarray | None) -> float:
    return math.inf if p is None else float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    numba.set_num_threads(min(args.threads, numba.config.NUMBA_NUM_THREADS))
    print(f"numba threads: {numba.get_num_threads()}")
    nn_table(args.repeats)
    rrt_table(args.seeds, args.repeats)
    loop_table(args.repeats)


if __name__ == "__main__":
    main()
