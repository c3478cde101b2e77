"""Reservation table: query time against the number of UAVs already reserved.

Prioritized planning asks, for every candidate path of every swarm, whether it comes closer
than S2 to any UAV planned before (PPSwarm Sect. 4.3). The reservation table answers in time
proportional to the candidate's own pieces; a pairwise check (every candidate against every
reserved trajectory, exact, vectorized over the reserved pieces) grows with the fleet. Both give
the same answers (checked here on every query). Prints µs per candidate path and the ratio; and
the per-axis separation (a box of the same widest axis, (S2, S2, 0.4 S2)) against the sphere on
the same table and candidates.

    python benchmarks/reservation_scaling.py
"""

from __future__ import annotations

import time

import numpy as np

from uavplan.world.reservations import ReservationTable, split_pieces

LO = np.array([0.0, 0.0, 100.0])
HI = np.array([1045.0, 879.0, 300.0])
SPEED = 20.0
S2 = 10.0


def random_paths(rng: np.random.Generator, n: int, k: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """n crossing paths west/south -> east/north with k points, and their times at 20 m/s."""
    a = rng.uniform([0, 0, 140], [200, 879, 160], (n, 3))
    b = rng.uniform([845, 0, 140], [1045, 879, 160], (n, 3))
    t = np.linspace(0, 1, k)[None, :, None]
    p = a[:, None] * (1 - t) + b[:, None] * t
    p[:, 1:-1] += rng.normal(0, [40, 40, 10], (n, k - 2, 3))
    seg = np.linalg.norm(np.diff(p, axis=1), axis=2)
    times = np.concatenate([np.zeros((n, 1)), np.cumsum(seg, axis=1)], axis=1) / SPEED
    return p, times


def pairwise(cands: np.ndarray, ctimes: np.ndarray, pieces: tuple[np.ndarray, ...]) -> np.ndarray:
    """Exact, every candidate piece against every reserved piece (NumPy, vectorized)."""
    q0, q1, s0, s1, _ = pieces
    out = np.zeros(len(cands), dtype=bool)
    for i in range(len(cands)):
        a0, a1, t0, t1, _ = split_pieces(cands[i], ctimes[i], 1.0)
        lo = np.maximum(t0[:, None], s0[None])
        hi = np.minimum(t1[:, None], s1[None])
        ok = lo <= hi
        fa0 = (lo - t0[:, None]) / (t1 - t0)[:, None]
        fa1 = (hi - t0[:, None]) / (t1 - t0)[:, None]
        fb0 = (lo - s0[None]) / (s1 - s0)[None]
        fb1 = (hi - s0[None]) / (s1 - s0)[None]
        pa0 = a0[:, None] + fa0[..., None] * (a1 - a0)[:, None]
        pa1 = a0[:, None] + fa1[..., None] * (a1 - a0)[:, None]
        pb0 = q0[None] + fb0[..., None] * (q1 - q0)[None]
        pb1 = q0[None] + fb1[..., None] * (q1 - q0)[None]
        r0 = pa0 - pb0
        dr = (pa1 - pb1) - r0
        dd = np.sum(dr * dr, axis=-1)
        s = np.clip(-np.sum(r0 * dr, axis=-1) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
        d2 = np.sum((r0 + s[..., None] * dr) ** 2, axis=-1)
        out[i] = bool(np.any(ok & (d2 < S2 * S2)))
    return out


def per_path(
    table: ReservationTable, cands: np.ndarray, ctimes: np.ndarray, reps: int = 20
) -> tuple[float, np.ndarray]:
    """µs per candidate path of ``table.conflicts``, and its answers."""
    table.conflicts(cands[:2], ctimes[:2])  # compile
    t0 = time.perf_counter()
    for _ in range(reps):
        hits = table.conflicts(cands, ctimes)
    return (time.perf_counter() - t0) / reps / len(cands) * 1e6, hits


def main() -> None:
    rng = np.random.default_rng(0)
    cands, ctimes = random_paths(rng, 300)
    print(
        f"{'reserved UAVs':>14} {'pieces':>8} {'table us/path':>14} {'pairwise us/path':>17} "
        f"{'ratio':>7} {'conflicts':>9} {'box us/path':>12} {'box/sphere':>10} {'box hits':>8}"
    )
    for n in (10, 40, 100, 200, 500):
        paths, times = random_paths(np.random.default_rng(n), n)
        table = ReservationTable(LO, HI, S2, dt=1.0)
        box = ReservationTable(LO, HI, (S2, S2, 0.4 * S2), dt=1.0)
        for i in range(n):
            table.add(str(i), paths[i], times[i])
            box.add(str(i), paths[i], times[i])
        t_table, got = per_path(table, cands, ctimes)
        t_box, got_box = per_path(box, cands, ctimes)
        allp = [split_pieces(paths[i], times[i], 1.0) for i in range(n)]
        pieces = tuple(np.concatenate([p[j] for p in allp]) for j in range(5))
        sub = 30
        t0 = time.perf_counter()
        ref = pairwise(cands[:sub], ctimes[:sub], pieces)
        t_pair = (time.perf_counter() - t0) / sub * 1e6
        assert np.array_equal(ref, got[:sub]), "table and pairwise disagree"
        print(
            f"{n:>14} {table.n_pieces:>8} {t_table:>14.1f} {t_pair:>17.1f} "
            f"{t_pair / t_table:>7.0f} {int(got.sum()):>9} {t_box:>12.1f} "
            f"{t_box / t_table:>10.2f} {int(got_box.sum()):>8}"
        )


if __name__ == "__main__":
    main()
