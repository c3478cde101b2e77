"""The fleet engine's low-level objective in one Numba pass per swarm (PPSwarm, Meng, Chen & Qu
2024, Alg. 4 line 5 with the collision lookup of Alg. 5).

Each of a UAV's ``N_iter`` low-level iterations evaluates its whole swarm: decode the genes
into paths (:class:`~uavplan.problems.encoding.CartesianEncoding`: heights above ground turned
into altitudes), the cost F1-F4 of the ``ppswarm`` preset (Eqs. 2-10,
:mod:`uavplan.problems.costs`), the world's checks (bounds, cylinders, circles and polygons,
terrain and the band along whole segments,
:func:`uavplan.problems._validity_kernels.static_path_ok`) and F5, the separation from the
UAVs planned before it (:func:`uavplan.world.reservations.path_query`), under the ``"inf"``
rule (Sect. 2: any violation costs infinity). The reference is
:meth:`uavplan.problems.path_problem.PathProblem.evaluate_cv` (NumPy terms, one kernel per
check); :class:`FleetObjective` does the same per particle in one kernel, without the
intermediate arrays and Python calls of about thirty NumPy operations per swarm.

**Checked only where it can matter** (``below``): PSO replaces a particle's personal best only
on a strict improvement, and a check can only make a cost infinite, so a particle whose cost
without the checks is not below its personal best cannot change the swarm whatever the checks
say: it is reported ``inf`` unchecked. The swarm is the same as with every particle checked
(:meth:`PathProblem.evaluate_cv` takes the same ``below``; the tests compare the two).

**Agreement with the reference**: the same operations in the same order (NumPy's pairwise
summation of a row, :func:`_row_sum`; the same scalar kernels for the terrain, the checks and
the table), except the threat sum, which the reference kernel adds in a vectorised order
(:data:`uavplan.world.geometry.FUSED_MATH`), and ``arctan2``, which NumPy computes with its
own SIMD code on some CPUs (an ulp apart from the C library's in a few % of the angles): the
costs agree to 1e-12 relative and every verdict (infinite or not) is the same; the tests check
both. The reported result of a UAV is evaluated afresh by the reference
(:func:`uavplan.planners.core.results.make_result`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from uavplan.kernel_builds import population_kernel
from uavplan.problems import path_problem as PP
from uavplan.problems import work
from uavplan.problems._validity_kernels import static_path_ok
from uavplan.problems.costs import altitude_target
from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import PathProblem
from uavplan.world._terrain_kernels import bilinear_one
from uavplan.world.geometry import clipped_dist, seg_setup
from uavplan.world.kernel_arrays import read_only
from uavplan.world.reservations import ReservationTable, path_query

FloatArray = NDArray[np.float64]

#: The cost terms the kernel computes, in the order :class:`PathProblem` adds them.
FUSED_TERMS = (PP._t_length, PP._t_threat, PP._t_altitude, PP._t_smooth)
#: NumPy's pairwise summation adds blocks of up to this many values in one loop; longer rows
#: are summed by the reference path.
PW_BLOCK = 128


@njit(cache=True, inline="always")
def _row_sum(a, n):  # pragma: no cover - numba
    """``np.add.reduce`` of the contiguous ``a[:n]`` (``n <= PW_BLOCK``) bit for bit: NumPy's
    pairwise summation (eight running sums from eight values on, then the rest one by one),
    added to 0."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return 0.0 + res
    r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
    r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
    i = 8
    while i < n - (n % 8):
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return 0.0 + res


@njit(cache=True, inline="always")
def _separated(paths, times, seg, p, speed, t_start, table):  # pragma: no cover - numba
    """Whether path ``p`` keeps the table's separation (times at ``speed`` from
    ``t_start``)."""
    N = paths.shape[1]
    acc = 0.0
    times[p, 0] = 0.0 / speed + t_start
    for s in range(N - 1):
        acc += seg[p, s]
        times[p, s + 1] = acc / speed + t_start
    return not path_query(paths, times, p, table) < table[4]


@population_kernel(error_model="numpy")
def fleet_costs(
    X, below, n_free, start, goal, ends_ground, ground_genes, H, x0, y0, dx, dy,
    weights, nonneg, cx, cy, cz_lo, cz_hi, r_in, r_out, band_mode, bmin, bmax, mid, speed,
    t_start,
    static, has_table, table,
):  # fmt: skip  # pragma: no cover - numba
    """The "inf" rule's cost of every particle ``X`` (P, 3 n_free), (P,): F1-F4 with
    ``weights`` (length, threat, altitude, smoothness), inf where a check fails or the
    separation (with ``has_table``) is broken, and inf unchecked where F1-F4 is not below
    ``below`` (P,) (see the module docstring): with ``nonneg`` (every weight >= 0) as soon
    as a partial sum of the terms is not below it.

    Decoding: ``ground_genes``: z genes are heights above the bilinear terrain ``H``. Threat:
    cylinders as structure of arrays, PPSwarm's Eqs. (4)-(5) (``r_in`` = R, ``r_out`` = R +
    S1, not strict). Altitude (Eqs. 6-7): ``band_mode`` 0 none, 1 above the terrain, 2
    absolute, band ``[bmin, bmax]``, each node's cost its distance to ``mid`` (the band's
    middle, or the UAV's cruise layer); ``ends_ground``: the terrain under the start and the
    goal. Times at ``speed`` from ``t_start``. ``static`` and ``table`` are the ``args`` of
    :func:`static_path_ok` and :func:`path_query`. The separation query runs after F2, before
    F4 and the static checks (each gate can only make a cost infinite, so any order gives the
    same costs: only the work differs).
    """
    P = X.shape[0]
    N = n_free + 2
    paths = np.empty((P, N, 3))
    times = np.empty((P, N))
    seg = np.empty((P, N))
    tmp = np.empty((P, N))
    ground = np.empty((P, N))
    out = np.full(P, np.inf)
    for p in prange(P):
        for d in range(3):
            paths[p, 0, d] = start[d]
            paths[p, N - 1, d] = goal[d]
        ground[p, 0] = ends_ground[0]
        ground[p, N - 1] = ends_ground[1]
        for k in range(n_free):
            gx = X[p, 3 * k]
            gy = X[p, 3 * k + 1]
            gz = X[p, 3 * k + 2]
            g = 0.0
            if ground_genes or band_mode == 1:
                g = bilinear_one(H, x0, y0, dx, dy, gx, gy)
            ground[p, k + 1] = g  # the band's reference below (the same value: no new lookup)
            if ground_genes:
                gz = gz + g
            paths[p, k + 1, 0] = gx
            paths[p, k + 1, 1] = gy
            paths[p, k + 1, 2] = gz
        # F1 (Eqs. 2-3): segment lengths
        for s in range(N - 1):
            ex = paths[p, s + 1, 0] - paths[p, s, 0]
            ey = paths[p, s + 1, 1] - paths[p, s, 1]
            ez = paths[p, s + 1, 2] - paths[p, s, 2]
            seg[p, s] = np.sqrt(((0.0 + ex * ex) + ey * ey) + ez * ez)
        f_len = 0.0 + weights[0] * _row_sum(seg[p], N - 1)
        # F3 (Eqs. 6-7): the band at every node
        f_alt = 0.0
        if band_mode:
            for k in range(N):
                h = paths[p, k, 2]
                if band_mode == 1:
                    h = h - ground[p, k]
                tmp[p, k] = abs(h - mid) if (h >= bmin and h <= bmax) else np.inf
            f_alt = _row_sum(tmp[p], N)
        band_in = f_alt < np.inf
        f_alt = weights[2] * f_alt
        # the terms are >= 0 and F adds them in the order F1, F2, F3, F4: a partial sum at or
        # above ``below`` means F is too (additions round monotonically)
        if nonneg and not f_len + f_alt < below[p]:
            continue
        # F2 (Eqs. 4-5): cylinder threats
        f_thr = 0.0
        hits = 0
        for s in range(N - 1):
            ax, ay, az, ex, ey, inv_ee, flat_s, inv_dz = seg_setup(paths, p, s)
            sx0 = min(ax, paths[p, s + 1, 0])
            sx1 = max(ax, paths[p, s + 1, 0])
            sy0 = min(ay, paths[p, s + 1, 1])
            sy1 = max(ay, paths[p, s + 1, 1])
            for j in range(cx.shape[0]):
                # farther than r_out (and a micrometre, far above round-off) from the axis in
                # x or y: the segment adds 0 (d is at least that gap)
                reach = r_out[j] + 1e-6
                if cx[j] - sx1 > reach or sx0 - cx[j] > reach:
                    continue
                if cy[j] - sy1 > reach or sy0 - cy[j] > reach:
                    continue
                dd = clipped_dist(
                    ax, ay, az, ex, ey, inv_ee, flat_s, inv_dz, cx[j], cy[j], cz_lo[j], cz_hi[j]
                )
                hits += 1 if dd <= r_in[j] else 0
                f_thr += (r_out[j] - dd) if dd <= r_out[j] else 0.0
        if hits:
            f_thr = np.inf
        f = (f_len + weights[1] * f_thr) + f_alt
        if nonneg and not f < below[p]:
            continue
        # F5 (the separation) before F4 and the static checks: under an execution model most
        # particles that get here conflict (a UAV blocked at its take-off time is blocked
        # whatever its path), and F2 has already turned away those that hit a cylinder
        if has_table and not _separated(paths, times, seg, p, speed, t_start, table):
            continue
        # F4 (Eqs. 8-10): turning angles, then climb-angle changes
        for i in range(N - 2):
            a0 = paths[p, i + 1, 0] - paths[p, i, 0]
            a1 = paths[p, i + 1, 1] - paths[p, i, 1]
            a2 = paths[p, i + 1, 2] - paths[p, i, 2]
            b0 = paths[p, i + 2, 0] - paths[p, i + 1, 0]
            b1 = paths[p, i + 2, 1] - paths[p, i + 1, 1]
            b2 = paths[p, i + 2, 2] - paths[p, i + 1, 2]
            c0 = a1 * b2 - a2 * b1
            c1 = a2 * b0 - a0 * b2
            c2 = a0 * b1 - a1 * b0
            cross = np.sqrt(((0.0 + c0 * c0) + c1 * c1) + c2 * c2)
            dot = ((0.0 + a0 * b0) + a1 * b1) + a2 * b2
            tmp[p, i] = np.arctan2(cross, dot)
        f_turn = _row_sum(tmp[p], N - 2)
        psi_prev = np.arctan2(paths[p, 1, 2] - paths[p, 0, 2], seg[p, 0])
        for s in range(1, N - 1):
            psi = np.arctan2(paths[p, s + 1, 2] - paths[p, s, 2], seg[p, s])
            tmp[p, s - 1] = abs(psi - psi_prev)
            psi_prev = psi
        f_smooth = 1.0 * f_turn + 1.0 * _row_sum(tmp[p], N - 2)
        f = f + weights[3] * f_smooth
        if not f < below[p]:
            continue
        # F3 finite: every node inside the band, so the check's band at the waypoints passes
        ok = static_path_ok(paths, p, static, not (band_mode and band_in))
        if not ok:
            continue
        out[p] = f
    return out


class FleetObjective:
    """The "inf" rule's objective of one UAV's low-level run in one kernel (the module
    docstring): ``evaluate(X, below)`` gives :meth:`PathProblem.evaluate_cv`'s cost under
    the "inf" rule (``inf`` where ``cv > 0``) with the same ``below``.

    :meth:`of` returns one only where the kernel computes exactly what the problem does: the
    ``ppswarm`` preset's terms (any weights) and the separation term, a 3-D world whose checks
    the static kernel makes (:meth:`~uavplan.problems.validity.MotionValidator.
    static_kernel_args`), the Cartesian encoding, the problem's own terrain for the cost.
    """

    def __init__(self, problem: PathProblem, enc: CartesianEncoding, static: tuple[Any, ...]):
        sc = problem.scenario
        v = problem.validator
        w = v.world
        terrain = sc.terrain
        band = sc.altitude
        if terrain is not None:
            H = terrain.heights
            grid: tuple[Any, ...] = (float(terrain.x0), float(terrain.y0), float(terrain.dx),
                                     float(terrain.dy))  # fmt: skip
        else:
            H, grid = read_only(np.zeros((2, 2))), (0.0, 0.0, 1.0, 1.0)
        ends = np.stack([problem.start, problem.goal])
        ends_ground = (terrain.height(ends[:, 0], ends[:, 1]) if terrain is not None
                       else np.zeros(2))  # fmt: skip
        band_mode = 0
        if band is not None:
            band_mode = 1 if band.reference == "ground" and terrain is not None else 2
        R = w.cyl_radii
        weights = np.array([t.weight for t in problem.terms if t.check is None])
        self.enc = enc
        self.problem = problem
        self.n_free = enc.n_waypoints
        self._head = (
            self.n_free,
            np.ascontiguousarray(problem.start),
            np.ascontiguousarray(problem.goal),
            ends_ground,
            enc.z_mode == "ground",
            H,
            *grid,
            weights,
            bool(np.all(weights >= 0)),
            np.ascontiguousarray(w.cyl_centers[:, 0]),
            np.ascontiguousarray(w.cyl_centers[:, 1]),
            w.cyl_lo,
            w.cyl_hi,
            R,
            R + sc.uav.s1,
            band_mode,
            float(band.min) if band is not None else 0.0,
            float(band.max) if band is not None else 0.0,
            altitude_target(band.min, band.max, problem.task.cruise) if band is not None else 0.0,
            float(sc.uav.speed),
            float(problem.task.start_time),
        )
        table = v.reservations
        if table is None or not len(table) or not table.n_pieces:
            table = ReservationTable(np.zeros(3), np.ones(3), 1.0)  # not read: one signature
        self._tail = (static, table is v.reservations, table.query_args(False))

    @classmethod
    def of(cls, problem: PathProblem, enc: Any) -> FleetObjective | None:
        """The fused objective of ``problem`` under ``enc``, or None where it does not apply."""
        sc = problem.scenario
        if not isinstance(enc, CartesianEncoding) or sc.dim != 3 or sc.moving_obstacles:
            return None
        if problem.validator.cost_terrain is not sc.terrain or problem.lookup != "bilinear":
            return None
        terms = [t for t in problem.terms if t.check is None]
        checks = [t.check for t in problem.terms if t.check is not None]
        if tuple(t.fn for t in terms) != FUSED_TERMS or checks not in ([], ["separation"]):
            return None
        if enc.n_waypoints + 2 > PW_BLOCK:
            return None
        if sc.terrain is not None and min(sc.terrain.heights.shape) < 2:
            return None
        static = problem.validator.static_kernel_args()
        if static is None:
            return None
        return cls(problem, enc, static)

    def evaluate(self, X: FloatArray, below: FloatArray) -> FloatArray:
        """(pop,) costs of the genes ``X`` (pop, dim) under the "inf" rule, ``inf`` unchecked
        where the cost without the checks is not below ``below`` (pop,)."""
        Xc = np.ascontiguousarray(X, dtype=np.float64)
        b = np.ascontiguousarray(below, dtype=np.float64)
        self.enc.evaluations += Xc.shape[0]
        work.add(cost_paths=Xc.shape[0])  # its checks, inside the kernel, are not counted
        return np.asarray(fleet_costs(Xc, b, *self._head, *self._tail))
