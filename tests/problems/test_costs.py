"""Cost terms against per-path Python loops written from the papers' equations, and the ``spso``
preset against a pure-Python port of SPSO's reference ``MyCost.m`` (Phung & Ha 2021)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as MplPath

from uavplan.problems import CartesianEncoding, PathProblem
from uavplan.problems import costs as C
from uavplan.world import AltitudeBand, Cylinder, Scenario, Task, Terrain
from uavplan.world import geometry as G
from uavplan.world.geometry import pack_polygons
from uavplan.world.scenario import Bounds

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=30, deadline=None)


def random_paths(
    rng: np.random.Generator, P: int, N: int, dim: int, box: float = 20.0
) -> np.ndarray:
    """Random polylines with some repeated nodes, vertical and horizontal segments, U-turns."""
    p = rng.uniform(-box, box, (P, N, dim))
    for q in range(P):
        for s in range(N - 1):
            mode = rng.integers(10)
            if mode == 0:
                p[q, s + 1] = p[q, s]  # zero length
            elif mode == 1 and dim == 3:
                p[q, s + 1, :2] = p[q, s, :2]  # vertical
            elif mode == 2 and dim == 3:
                p[q, s + 1, 2] = p[q, s, 2]  # level
            elif mode == 3 and s > 0:
                p[q, s + 1] = p[q, s - 1]  # straight back: a U-turn
            elif mode == 4 and s > 0:
                p[q, s + 1] = 2 * p[q, s] - p[q, s - 1]  # straight on
    return p


def norm(v) -> float:
    return math.sqrt(sum(float(c) * float(c) for c in v))


def cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b) -> float:
    return sum(float(x) * float(y) for x, y in zip(a, b, strict=True))


# ----------------------------------------------------------------------------- PPSwarm Eqs. 2-3
@FAST
@given(seed=SEEDS, N=st.integers(2, 8), dim=st.sampled_from([2, 3]))
def test_length_cost_eqs_2_3(seed: int, N: int, dim: int) -> None:
    paths = random_paths(np.random.default_rng(seed), 5, N, dim)
    want = []
    for path in paths:
        F1 = 0.0
        for i in range(N - 1):
            F1 += math.sqrt(sum((path[i + 1][k] - path[i][k]) ** 2 for k in range(dim)))
        want.append(F1)
    np.testing.assert_allclose(C.length_cost(paths), want, rtol=1e-12)
    assert C.segment_lengths(paths).shape == (5, N - 1)


# ----------------------------------------------------------------------------- PPSwarm Eqs. 4-5
def tr_eq5(d: float, R: float, S1: float) -> float:
    if d > S1 + R:
        return 0.0
    if R < d <= S1 + R:
        return (S1 + R) - d
    return math.inf  # d <= R


def test_threat_cost_eq5_three_cases_and_boundaries() -> None:
    R = np.array([10.0, 3.0])
    S1 = 15.0
    d = np.array(
        [
            [[30.0, 30.0], [25.0, 18.0]],  # d == S1 + R: band value 0; and inside the band
            [[25.0 + 1e-9, 18.0 + 1e-9], [12.0, 4.0]],  # just beyond the band; inside the band
            [[10.0, 30.0], [20.0, 18.0]],  # d == R: infinite
            [[10.0 + 1e-9, 3.0 + 1e-12], [np.inf, np.inf]],  # just outside R; not at its height
            [[9.0, 100.0], [50.0, 2.9]],  # inside
        ]
    )  # (pop 5, segments 2, threats 2)
    want = []
    for q in range(5):
        F2 = 0.0
        for i in range(2):
            for j in range(2):
                F2 += tr_eq5(float(d[q, i, j]), float(R[j]), S1)
        want.append(F2)
    got = C.threat_cost(d, R, S1)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert got[2] == math.inf  # d == R exactly
    assert np.isfinite(got[3])
    # the same through moving_threat_cost (PPSwarm's Eq. 5 applied to moving obstacles)
    np.testing.assert_allclose(C.moving_threat_cost(d, R, S1), want, rtol=1e-12)


@FAST
@given(seed=SEEDS, N=st.integers(2, 6), J=st.integers(0, 4), S1=st.floats(0.0, 20.0))
def test_threat_cost_end_to_end_with_infinite_cylinders(
    seed: int, N: int, J: int, S1: float
) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, 4, N, 3)
    centers = rng.uniform(-20, 20, (J, 2))
    R = rng.uniform(1.0, 8.0, J)
    inf = np.full(J, np.inf)
    dist = G.cylinder_distances(paths, centers, -inf, inf)
    assert dist.shape == (4, N - 1, J)
    got = C.threat_cost(dist, R, S1)
    for q in range(4):
        F2 = 0.0
        for i in range(N - 1):
            a, b = paths[q, i, :2], paths[q, i + 1, :2]
            for j in range(J):
                # distance from the threat's axis to the segment's ground track (infinite cylinder)
                ab = b - a
                den = dot(ab, ab)
                t = 0.0 if den == 0 else min(max(dot(centers[j] - a, ab) / den, 0.0), 1.0)
                dj = norm(a + t * ab - centers[j])
                F2 += tr_eq5(dj, float(R[j]), S1)
        assert got[q] == pytest.approx(F2, rel=1e-9, abs=1e-9)
    # 2-D paths are taken at z = 0 against the same infinitely tall cylinders
    if J:
        np.testing.assert_allclose(
            G.cylinder_distances(paths[..., :2], centers, -inf, inf), dist, rtol=1e-12, atol=1e-12
        )


def test_threat_cost_spso_cases() -> None:
    R = np.array([80.0])
    # collision when d < R + 1; danger band up to R + 1 + 10; boundaries
    d = np.array([80.5, 81.0, 85.0, 91.0, 91.0 + 1e-9, 200.0]).reshape(6, 1, 1)
    want = [math.inf, 10.0, 6.0, 0.0, 0.0, 0.0]
    np.testing.assert_allclose(C.threat_cost_spso(d, R, 1.0), want, rtol=1e-12)


# ----------------------------------------------------------------------------- PPSwarm Eqs. 6-7
@FAST
@given(seed=SEEDS, N=st.integers(1, 8), lo=st.floats(-50, 50), width=st.floats(1e-3, 100))
def test_altitude_cost_eq7(seed: int, N: int, lo: float, width: float) -> None:
    rng = np.random.default_rng(seed)
    hi = lo + width
    h = rng.uniform(lo - 0.3 * width, hi + 0.3 * width, (6, N))
    h[0, 0] = lo  # on the band's edges: finite
    h[1, -1] = hi
    h[2, :] = 0.5 * (lo + hi)
    want = []
    for row in h:
        F3 = 0.0
        for hi_ in row:
            F3 += abs(hi_ - (hi + lo) / 2) if lo <= hi_ <= hi else math.inf
        want.append(F3)
    np.testing.assert_allclose(C.altitude_cost(h, lo, hi), want, rtol=1e-12, atol=1e-12)
    # SPSO's J3: inf only below the ground
    want_spso = [sum(math.inf if z < 0 else abs(z - (hi + lo) / 2) for z in row) for row in h]
    np.testing.assert_allclose(C.altitude_cost_spso(h, lo, hi), want_spso, rtol=1e-12, atol=1e-12)


# ----------------------------------------------------------------------------- PPSwarm Eqs. 8-10
@FAST
@given(
    seed=SEEDS,
    N=st.integers(2, 8),
    dim=st.sampled_from([2, 3]),
    a1=st.floats(0.0, 5.0),
    a2=st.floats(0.0, 5.0),
)
def test_smoothness_eqs_8_to_10(seed: int, N: int, dim: int, a1: float, a2: float) -> None:
    paths = random_paths(np.random.default_rng(seed), 5, N, dim)
    turn = C.turn_angles(paths)
    assert turn.shape == (5, N - 2)
    got = C.smoothness_cost(paths, a1, a2)
    for q, path in enumerate(paths):
        P3 = [tuple(p) + ((0.0,) if dim == 2 else ()) for p in path]
        phis = []
        for i in range(N - 2):
            u = [P3[i + 1][k] - P3[i][k] for k in range(3)]
            v = [P3[i + 2][k] - P3[i + 1][k] for k in range(3)]
            # the true turn angle (Eq. 8's intent): atan2(|u x v|, u . v)
            phis.append(math.atan2(norm(cross3(u, v)), dot(u, v)))
        np.testing.assert_allclose(turn[q], phis, rtol=1e-9, atol=1e-12)
        F4 = a1 * sum(phis)
        if dim == 3:
            psis = []
            for i in range(N - 1):
                L = norm([P3[i + 1][k] - P3[i][k] for k in range(3)])
                dz = P3[i + 1][2] - P3[i][2]
                psis.append(math.atan(dz / L) if L > 0 else 0.0)  # Eq. 9
            np.testing.assert_allclose(C.climb_angles(paths)[q], psis, rtol=1e-9, atol=1e-12)
            F4 += a2 * sum(abs(psis[j] - psis[j - 1]) for j in range(1, N - 1))
        assert got[q] == pytest.approx(F4, rel=1e-9, abs=1e-9)


def test_turn_angle_is_monotone_not_arctan_of_sine() -> None:
    """Eq. 8 as printed, arctan(|a x b| / (|a| |b|)), scores a U-turn 0; the documented
    angle (atan2) is pi."""
    p = np.array(
        [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [[0, 0, 0], [1, 0, 0], [1, 1, 0]]]
    )
    np.testing.assert_allclose(C.turn_angles(p.astype(float))[:, 0], [math.pi, math.pi / 2])
    straight = np.array([[[0.0, 0.0], [1.0, 1.0], [3.0, 3.0]]])
    assert C.smoothness_cost(straight)[0] == pytest.approx(0.0, abs=1e-12)


# ----------------------------------------------------------------------------- HR-MAGA Eq. 9
@FAST
@given(seed=SEEDS, N=st.integers(2, 6), J=st.integers(0, 4))
def test_danger_length_eq9_vs_dense_sampling(seed: int, N: int, J: int) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, 4, N, 3)
    centers = rng.uniform(-15, 15, (J, 2))
    radii = rng.uniform(1.0, 12.0, J)
    got = C.danger_length_cost(paths, centers, radii)
    n = 4000
    t = (np.arange(n) + 0.5) / n
    for q in range(4):
        want = 0.0
        tol = 1e-9
        for i in range(N - 1):
            a, b = paths[q, i], paths[q, i + 1]
            L = norm(b - a)
            pts = a[:2] + t[:, None] * (b[:2] - a[:2])
            for j in range(J):
                inside = np.hypot(*(pts - centers[j]).T) < radii[j]
                want += L * inside.mean()
                tol += 2 * L / n
        assert got[q] == pytest.approx(want, abs=tol)


# ----------------------------------------------------------------------------- 2-D inside length
def star(rng: np.random.Generator) -> np.ndarray:
    k = int(rng.integers(3, 7))
    ang = np.sort(rng.uniform(0, 2 * np.pi, 2 * k))
    r = np.where(np.arange(2 * k) % 2 == 0, rng.uniform(3, 7, 2 * k), rng.uniform(1, 3, 2 * k))
    return rng.uniform(-10, 10, 2) + r[:, None] * np.stack([np.cos(ang), np.sin(ang)], -1)


@FAST
@given(seed=SEEDS, N=st.integers(2, 6))
def test_inside_length_2d_vs_dense_sampling(seed: int, N: int) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, 3, N, 2)
    cc = rng.uniform(-15, 15, (3, 2))
    cr = rng.uniform(1.0, 6.0, 3)
    polys = [star(rng) for _ in range(2)]
    verts, starts = pack_polygons(polys)
    got = C.inside_length_2d(paths, cc, cr, verts, starts)
    only_circles = C.inside_length_2d(paths, cc, cr, *pack_polygons([]))
    only_polys = C.inside_length_2d(paths, np.zeros((0, 2)), np.zeros(0), verts, starts)
    np.testing.assert_allclose(got, only_circles + only_polys, rtol=1e-12, atol=1e-12)
    n = 4000
    t = (np.arange(n) + 0.5) / n
    for q in range(3):
        want, tol = 0.0, 1e-9
        for i in range(N - 1):
            a, b = paths[q, i], paths[q, i + 1]
            L = norm(b - a)
            pts = a + t[:, None] * (b - a)
            for j in range(3):
                want += L * (np.hypot(*(pts - cc[j]).T) < cr[j]).mean()
                tol += 2 * L / n
            for poly in polys:
                want += L * MplPath(poly).contains_points(pts).mean()
                tol += (len(poly) + 1) * L / n
        assert got[q] == pytest.approx(want, abs=tol)


def test_penalized_length_cost() -> None:
    L = np.array([10.0, 10.0, 0.0, 4.0])
    inside = np.array([0.0, 2.5, 0.0, 4.0])
    np.testing.assert_allclose(
        C.penalized_length_cost(L, inside, 100.0), [10.0, 10.0 * (1 + 100 * 0.25), 0.0, 404.0]
    )


def test_path_times_and_hrmaga_altitude() -> None:
    p = np.array([[[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 10.0]]])
    np.testing.assert_allclose(C.path_times(p, 5.0, 2.0), [[2.0, 3.0, 3.0, 5.0]])
    np.testing.assert_allclose(
        C.hrmaga_altitude_cost(np.array([[1.0, 2.0], [3.0, -1.0]])), [3.0, 2.0]
    )


# ----------------------------------------------------------------------------- SPSO MyCost.m port
def matlab_round(v: float) -> int:
    """MATLAB round (half away from zero), exact for doubles."""
    f = math.floor(abs(v))
    r = f + 1 if abs(v) - f >= 0.5 else f
    return int(math.copysign(r, v))


def dist_p2s(x, a, b) -> float:
    """SPSO's DistP2S.m."""
    d_ab = norm([a[0] - b[0], a[1] - b[1]])
    d_ax = norm([a[0] - x[0], a[1] - x[1]])
    d_bx = norm([b[0] - x[0], b[1] - x[1]])
    if d_ab != 0:
        if (
            dot([a[0] - b[0], a[1] - b[1]], [x[0] - b[0], x[1] - b[1]])
            * dot([b[0] - a[0], b[1] - a[1]], [x[0] - a[0], x[1] - a[1]])
            >= 0
        ):
            # A = [b - a; x - a]; abs(det(A)) / d_ab
            det = (b[0] - a[0]) * (x[1] - a[1]) - (b[1] - a[1]) * (x[0] - a[0])
            return abs(det) / d_ab
        return min(d_ax, d_bx)
    return d_ax


def atan2d(y: float, x: float) -> float:
    return math.degrees(math.atan2(y, x))


def nnz(v) -> int:
    return sum(1 for c in v if c != 0)


def spso_mycost_reference(free_nodes_rel, model: dict) -> dict[str, float]:
    """A line-by-line port of SPSO's ``MyCost.m`` (1-based MATLAB indices kept via ``M``).

    ``free_nodes_rel``: the n free nodes (x, y, z) with z above the ground; ``model``: ``H`` (the
    DEM, row = y), ``start``/``end`` (x, y, z above ground), ``threats`` rows [x, y, z, R],
    ``zmin``, ``zmax``, ``n``.
    """
    J_inf = math.inf
    n = model["n"]
    H = model["H"]

    def Hm(r: int, c: int) -> float:  # H(r, c), 1-based
        return float(H[r - 1, c - 1])

    x = [float(p[0]) for p in free_nodes_rel]
    y = [float(p[1]) for p in free_nodes_rel]
    z = [float(p[2]) for p in free_nodes_rel]
    xs, ys, zs = model["start"]
    xf, yf, zf = model["end"]
    x_all = [xs, *x, xf]
    y_all = [ys, *y, yf]
    z_all = [zs, *z, zf]
    N = len(x_all)

    def M(arr, k):  # arr(k), 1-based
        return arr[k - 1]

    z_abs = [0.0] * N
    for i in range(1, N + 1):
        z_abs[i - 1] = M(z_all, i) + Hm(matlab_round(M(y_all, i)), matlab_round(M(x_all, i)))

    # J1 - path length
    J1 = 0.0
    for i in range(1, N):
        diff = [
            M(x_all, i + 1) - M(x_all, i),
            M(y_all, i + 1) - M(y_all, i),
            M(z_abs, i + 1) - M(z_abs, i),
        ]
        J1 = J1 + norm(diff)

    # J2 - threats
    threats = model["threats"]
    drone_size = 1
    danger_dist = 10 * drone_size
    J2 = 0.0
    for i in range(1, len(threats) + 1):
        threat = threats[i - 1]
        threat_x, threat_y, threat_radius = threat[0], threat[1], threat[3]
        for j in range(1, N):
            dist = dist_p2s(
                [threat_x, threat_y], [M(x_all, j), M(y_all, j)], [M(x_all, j + 1), M(y_all, j + 1)]
            )
            if dist > (threat_radius + drone_size + danger_dist):
                threat_cost = 0.0
            elif dist < (threat_radius + drone_size):
                threat_cost = J_inf
            else:
                threat_cost = (threat_radius + drone_size + danger_dist) - dist
            J2 = J2 + threat_cost

    # J3 - altitude (heights above ground), over the n free nodes
    zmax, zmin = model["zmax"], model["zmin"]
    J3 = 0.0
    for i in range(1, n + 1):
        J3_node = J_inf if M(z, i) < 0 else abs(M(z, i) - (zmax + zmin) / 2)
        J3 = J3 + J3_node

    # J4 - smoothness, degrees
    J4 = 0.0
    turning_max = 45
    climb_max = 45
    for i in range(1, N - 1):
        segment1_proj = None
        for j in range(i, 0, -1):  # j = i:-1:1
            segment1_proj = [M(x_all, j + 1) - M(x_all, j), M(y_all, j + 1) - M(y_all, j), 0.0]
            if nnz(segment1_proj) != 0:
                break
        segment2_proj = None
        for j in range(i, N - 1):  # j = i:N-2
            segment2_proj = [
                M(x_all, j + 2) - M(x_all, j + 1),
                M(y_all, j + 2) - M(y_all, j + 1),
                0.0,
            ]
            if nnz(segment2_proj) != 0:
                break
        climb_angle1 = atan2d(M(z_abs, i + 1) - M(z_abs, i), norm(segment1_proj))
        climb_angle2 = atan2d(M(z_abs, i + 2) - M(z_abs, i + 1), norm(segment2_proj))
        turning_angle = atan2d(
            norm(cross3(segment1_proj, segment2_proj)), dot(segment1_proj, segment2_proj)
        )
        if abs(turning_angle) > turning_max:
            J4 = J4 + abs(turning_angle)
        if abs(climb_angle2 - climb_angle1) > climb_max:
            J4 = J4 + abs(climb_angle2 - climb_angle1)

    b1, b2, b3, b4 = 5, 1, 10, 1
    cost = b1 * J1 + b2 * J2 + b3 * J3 + b4 * J4
    return {"cost": cost, "J1": J1, "J2": J2, "J3": J3, "J4": J4}


SPSO_THREATS = [
    [400, 500, 100, 80],
    [600, 200, 150, 70],
    [500, 350, 150, 80],
    [350, 200, 150, 70],
    [700, 550, 150, 70],
    [650, 750, 150, 80],
]


@pytest.fixture(scope="module")
def spso():
    terrain = Terrain.builtin("spso")
    start_rel, goal_rel = (200.0, 100.0, 150.0), (800.0, 800.0, 150.0)
    start = (*start_rel[:2], start_rel[2] + float(terrain.height(*start_rel[:2])))
    goal = (*goal_rel[:2], goal_rel[2] + float(terrain.height(*goal_rel[:2])))
    scenario = Scenario(
        name="spso",
        bounds=Bounds((1.0, 1.0, 0.0), (1045.0, 879.0, 500.0)),
        tasks=(Task("uav", start, goal),),
        terrain=terrain,
        cylinders=tuple(Cylinder((x, y), float(R), margin=1.0) for x, y, _z, R in SPSO_THREATS),
        altitude=AltitudeBand(100.0, 200.0, "ground"),
        cost="spso",
        n_waypoints=10,
    )
    problem = PathProblem(scenario)
    encoding = CartesianEncoding(problem)
    model = {
        "H": np.asarray(terrain.heights),  # H(row = y, col = x), node (1, 1) at x = y = 1
        "start": start_rel,
        "end": goal_rel,
        "threats": SPSO_THREATS,
        "zmin": 100.0,
        "zmax": 200.0,
        "n": 10,
    }
    return problem, encoding, model


def spso_population(rng: np.random.Generator, pop: int) -> np.ndarray:
    """(pop, 10, 3) free nodes (x, y, z above ground): random ones (mostly colliding), safe ones
    round the threats with jitter, nodes passing through the danger bands, repeated xy nodes
    (zero projections, also repeating the start's and goal's xy), half-integer coordinates
    (MATLAB round ties), a few below the ground."""
    X = np.empty((pop, 10, 3))
    safe = np.array(
        [[300, 90], [400, 80], [500, 90], [600, 100], [750, 100], [900, 150], [950, 300],
         [950, 450], [920, 600], [880, 720]], dtype=float
    )  # fmt: skip
    for q in range(pop):
        kind = q % 6
        if kind == 0:
            X[q, :, 0] = rng.uniform(1, 1045, 10)
            X[q, :, 1] = rng.uniform(1, 879, 10)
        else:
            X[q, :, :2] = safe + rng.normal(0, 15.0 if kind != 5 else 2.0, (10, 2))
        X[q, :, 2] = rng.uniform(100, 200, 10)
        if kind == 2:  # repeated xy: runs of equal projections, at the start and at the goal
            k = int(rng.integers(0, 8))
            X[q, k + 1, :2] = X[q, k, :2]
            X[q, k + 2, :2] = X[q, k, :2]
            X[q, 0, :2] = (200.0, 100.0)
            X[q, 9, :2] = (800.0, 800.0)
        if kind == 3:  # half-integer and integer coordinates
            X[q, :, :2] = np.round(X[q, :, :2]) + rng.choice([0.0, 0.5], (10, 2))
        if kind == 4:  # one or two nodes under the ground
            X[q, rng.integers(0, 10, 2), 2] = rng.uniform(-50, -1, 2)
        if kind == 5:  # pass 600,200 (R 70) through its danger band [71, 81]
            d = rng.uniform(71.5, 80.5)
            X[q, 3, :2] = (560.0, 200.0 - d)
            X[q, 4, :2] = (640.0, 200.0 - d)
    X[..., 0] = np.clip(X[..., 0], 1, 1045)
    X[..., 1] = np.clip(X[..., 1], 1, 879)
    return X


def test_spso_all_free_nodes_at_one_xy(spso) -> None:
    """Every projection zero (all nodes at the start's xy except the goal): the backward search
    ends on a zero segment, as MATLAB's loop does."""
    _, enc, model = spso
    X = np.zeros((1, 10, 3))
    X[0, :, :2] = (200.0, 100.0)
    X[0, :, 2] = np.linspace(100, 200, 10)
    ev = enc.evaluate_full(X.reshape(1, -1))
    ref = spso_mycost_reference(X[0], model)
    assert ev.terms["smoothness"][0] == pytest.approx(ref["J4"], rel=1e-9, abs=1e-9)
    assert ev.cost[0] == pytest.approx(ref["cost"], rel=1e-9)


@settings(max_examples=8, deadline=None)
@given(seed=SEEDS)
def test_spso_preset_equals_mycost_reference(spso, seed: int) -> None:
    _, enc, model = spso
    rng = np.random.default_rng(seed)
    X = spso_population(rng, 24)
    ev = enc.evaluate_full(X.reshape(len(X), -1))
    np.testing.assert_array_equal(enc.evaluate(X.reshape(len(X), -1)), ev.cost)
    refs = [spso_mycost_reference(x, model) for x in X]
    names = {"length": "J1", "threat": "J2", "altitude": "J3", "smoothness": "J4", "cost": "cost"}
    for term, key in names.items():
        got = ev.cost if term == "cost" else ev.terms[term]
        want = np.array([r[key] for r in refs])
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9, err_msg=term)
    # the population covers the cases: collisions, finite costs, below-ground nodes
    assert np.isinf(ev.terms["threat"]).any() and np.isfinite(ev.cost).any()
    assert np.isinf(ev.terms["altitude"]).any()
    band = ev.terms["threat"][5::6]
    assert np.any((band > 0) & np.isfinite(band))


def test_spso_costs_of_the_decoded_paths(spso) -> None:
    """The same through PathProblem.evaluate on decoded absolute paths (start and goal included)."""
    problem, enc, model = spso
    X = spso_population(np.random.default_rng(0), 12)
    paths = enc.decode(X.reshape(12, -1))
    assert paths.shape == (12, 12, 3)
    np.testing.assert_array_equal(paths[:, 0], np.broadcast_to(problem.start, (12, 3)))
    np.testing.assert_array_equal(paths[:, -1], np.broadcast_to(problem.goal, (12, 3)))
    np.testing.assert_allclose(enc.encode(paths), X.reshape(12, -1), rtol=0, atol=1e-12)
    ev = problem.evaluate(paths)
    want = [spso_mycost_reference(x, model)["cost"] for x in X]
    np.testing.assert_allclose(ev.cost, want, rtol=1e-9)
    # SPSO's J4 kernel directly vs the port (its z is the absolute altitude)
    J4 = C.smoothness_cost_spso(paths)
    np.testing.assert_allclose(
        J4, [spso_mycost_reference(x, model)["J4"] for x in X], rtol=1e-9, atol=1e-9
    )
