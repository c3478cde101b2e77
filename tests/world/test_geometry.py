"""Geometry kernels against their NumPy references and against brute-force dense sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as MplPath

from uavplan.world import Circle, MovingObstacle, Polygon
from uavplan.world.geometry import (
    pack_polygons,
    point_in_polygon,
    point_segment_distance_2d,
    segment_circle_inside_fraction,
    segment_cylinder_distance,
    segment_cylinder_distance_reference,
    segment_polygon_distance,
    segment_polygon_inside_fraction,
    timed_path_min_distance,
)

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)
N_SAMPLES = 4000


# ----------------------------------------------------------------------------- helpers
def random_paths(rng: np.random.Generator, P: int, N: int, box: float = 10.0) -> np.ndarray:
    """(P, N, 3) polylines with some horizontal, vertical, zero-length and axis-aligned segments."""
    p = rng.uniform(-box, box, (P, N, 3))
    for q in range(P):
        for s in range(N - 1):
            mode = rng.integers(8)
            if mode == 0:  # horizontal
                p[q, s + 1, 2] = p[q, s, 2]
            elif mode == 1:  # vertical
                p[q, s + 1, :2] = p[q, s, :2]
            elif mode == 2:  # zero length
                p[q, s + 1] = p[q, s]
            elif mode == 3:  # at an integer height (the cylinders' z ranges are integers)
                p[q, s, 2] = p[q, s + 1, 2] = float(rng.integers(-5, 6))
    return p


def random_cylinders(rng: np.random.Generator, J: int, box: float = 10.0):
    centers = rng.uniform(-box, box, (J, 2))
    lo = np.full(J, -np.inf)
    hi = np.full(J, np.inf)
    for j in range(J):
        kind = rng.integers(4)
        a, b = sorted(rng.integers(-6, 7, 2).astype(float))
        b = b + 1.0
        if kind == 1:
            lo[j], hi[j] = a, b
        elif kind == 2:
            lo[j] = a
        elif kind == 3:
            hi[j] = b
    return centers, lo, hi


def sampled_cylinder_distance(a, b, c, lo, hi, n=N_SAMPLES):
    """Min horizontal distance from c over sampled points of a->b whose z is in [lo, hi]."""
    t = np.linspace(0.0, 1.0, n)
    p = a + t[:, None] * (b - a)
    keep = (p[:, 2] >= lo) & (p[:, 2] <= hi)
    if not keep.any():
        return math.inf
    return float(np.hypot(p[keep, 0] - c[0], p[keep, 1] - c[1]).min())


def z_interval(a, b, lo, hi) -> tuple[float, float] | None:
    """Parameter interval of a->b whose z lies in [lo, hi] (written from scratch)."""
    za, zb = a[2], b[2]
    if za == zb:
        return (0.0, 1.0) if lo <= za <= hi else None
    ts = sorted(((lo - za) / (zb - za), (hi - za) / (zb - za)))
    t0, t1 = max(0.0, ts[0]), min(1.0, ts[1])
    return (t0, t1) if t0 <= t1 else None


def convex_polygon(rng: np.random.Generator) -> np.ndarray:
    k = int(rng.integers(3, 9))
    ang = np.sort(rng.uniform(0, 2 * np.pi, k))
    r = rng.uniform(1.0, 5.0)
    c = rng.uniform(-6, 6, 2)
    v = c + r * np.stack([np.cos(ang), np.sin(ang)], -1)
    if rng.integers(2):
        v = v[::-1]  # either orientation
    return v


def star_polygon(rng: np.random.Generator) -> np.ndarray:
    """A simple, non-convex star: angles sorted, radii alternating big and small."""
    k = int(rng.integers(3, 8))
    ang = np.sort(rng.uniform(0, 2 * np.pi, 2 * k))
    r = np.where(
        np.arange(2 * k) % 2 == 0, rng.uniform(3.0, 6.0, 2 * k), rng.uniform(0.5, 2.0, 2 * k)
    )
    c = rng.uniform(-5, 5, 2)
    return c + r[:, None] * np.stack([np.cos(ang), np.sin(ang)], -1)


def random_polygon(rng: np.random.Generator) -> np.ndarray:
    return convex_polygon(rng) if rng.integers(2) else star_polygon(rng)


def dist_to_polygon(points: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Brute force: 0 inside (matplotlib's test), else the distance to the nearest edge."""
    a = verts
    b = np.roll(verts, -1, axis=0)
    d = point_segment_distance_2d(a, b, points).min(axis=0)
    inside = MplPath(verts).contains_points(points)
    return np.where(inside, 0.0, d)


# ----------------------------------------------------------------------------- cylinders
@FAST
@given(seed=SEEDS, P=st.integers(1, 4), N=st.integers(2, 6), J=st.integers(1, 6))
def test_cylinder_distance_numba_equals_reference(seed: int, P: int, N: int, J: int) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, P, N)
    centers, lo, hi = random_cylinders(rng, J)
    got = segment_cylinder_distance(paths, centers, lo, hi)
    ref = segment_cylinder_distance_reference(paths, centers, lo, hi)
    assert got.shape == ref.shape == (P, N - 1, J)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(ref))
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


@FAST
@given(seed=SEEDS, P=st.integers(1, 4), N=st.integers(2, 6), J=st.integers(0, 6))
def test_fused_cylinder_passes_equal_the_costs_of_the_distances(
    seed: int, P: int, N: int, J: int
) -> None:
    """cylinder_threat (both threat forms) and cylinder_overlap against the costs computed from
    the (P, N - 1, J) distances: 1e-12 relative, the same infinities, including the pairs
    exactly at the inner radius (inf for PPSwarm's d <= R, finite for SPSO's d < R)."""
    from uavplan.problems import costs as C
    from uavplan.world.geometry import cylinder_distances, cylinder_overlap, cylinder_threat

    rng = np.random.default_rng(seed)
    paths = random_paths(rng, P, N)
    if rng.integers(3) == 0:
        paths[:, :, 2] = paths[:, :1, 2]  # flat segments
    centers, lo, hi = random_cylinders(rng, J)
    d = cylinder_distances(paths, centers, lo, hi)
    R = rng.uniform(0.5, 4.0, J)
    fin = d[..., 0][np.isfinite(d[..., 0])] if J else np.empty(0)
    if fin.size:
        R[0] = fin[0]  # a pair exactly at the inner radius
    margin = rng.uniform(0.0, 1.0, J)
    s1 = float(rng.uniform(0.5, 5.0))

    def same(got: np.ndarray, ref: np.ndarray) -> None:
        assert got.shape == ref.shape == (P,)
        np.testing.assert_array_equal(np.isinf(got), np.isinf(ref))
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)

    same(cylinder_threat(paths, centers, lo, hi, R, R + s1, strict=False), C.threat_cost(d, R, s1))
    bare = R - margin
    Rs = bare + margin
    same(
        cylinder_threat(paths, centers, lo, hi, Rs, Rs + 10.0 * margin, strict=True),
        C.threat_cost_spso(d, bare, margin),
    )
    inside, clearance = cylinder_overlap(paths, centers, lo, hi, R)
    same(inside, np.sum(np.maximum(0.0, R - d), axis=(1, 2)))
    same(clearance, (d - R).min(axis=(1, 2), initial=np.inf))
    np.testing.assert_array_equal(clearance < 0, np.any(d < R, axis=(1, 2)))
    # 2-D paths are at z = 0, as cylinder_distances takes them
    d2 = cylinder_distances(paths[..., :2], centers, lo, hi)
    same(
        cylinder_threat(paths[..., :2], centers, lo, hi, R, R + s1, strict=False),
        C.threat_cost(d2, R, s1),
    )


@FAST
@given(seed=SEEDS, J=st.integers(64, 400), strict=st.booleans())
def test_grid_threat_equals_every_pair(seed: int, J: int, strict: bool) -> None:
    """The grid-indexed pass (from GRID_MIN_CYLINDERS cylinders on: the threat, the metres
    inside and the hits) against testing every segment-cylinder pair: 1e-12 relative, the same
    infinities; with paths partly off the grid, flat and zero-length segments, radii of very
    different sizes, and pairs exactly at the inner radius."""
    from uavplan.world.geometry import (
        GRID_MIN_CYLINDERS,
        cylinder_distances,
        cylinder_grid,
        cylinder_grid_pass,
        cylinder_hits,
        cylinder_overlap,
        cylinder_threat_batch,
    )

    assert J >= GRID_MIN_CYLINDERS
    rng = np.random.default_rng(seed)
    cx, cy = rng.uniform(0, 3000, J), rng.uniform(0, 3000, J)
    R = np.where(rng.random(J) < 0.03, rng.uniform(40, 80, J), rng.uniform(1, 10, J))
    band = rng.uniform(0.0, 40.0, J)
    lo = np.where(rng.random(J) < 0.5, -np.inf, rng.uniform(0, 100, J))
    hi = np.where(rng.random(J) < 0.5, np.inf, lo + rng.uniform(10, 200, J))
    P, N = 12, 8
    paths = np.cumsum(rng.normal(0, 80, (P, N, 3)), axis=1) + np.array([1500.0, 1500.0, 60.0])
    paths[0] = rng.uniform(-500, 3500, (N, 3))  # long segments, off the grid
    paths[1, :, 2] = 50.0  # flat
    paths[2, 3] = paths[2, 2]  # zero length
    paths = np.ascontiguousarray(paths)
    # ten cylinders placed beside path vertices, inside their threat bands
    near = paths[2:12, 4, :2]
    R[6:16], band[6:16] = 1.0, 40.0
    cx[6:16], cy[6:16] = near[:, 0] + 20.0, near[:, 1]
    lo[6:16], hi[6:16] = -np.inf, np.inf
    cx[16], cy[16], R[16], lo[16], hi[16] = paths[3, 2, 0], paths[3, 2, 1], 5.0, -np.inf, np.inf
    d = cylinder_distances(paths, np.c_[cx, cy], lo, hi)
    fin = np.isfinite(d[..., 5])
    if fin.any():
        R[5] = d[..., 5][fin].min()  # the nearest pair exactly at the inner radius
    r_out = R + band
    want = cylinder_threat_batch(paths, cx, cy, lo, hi, R, r_out, strict)
    radii = 0.8 * R  # the check's radii, inside the threat's inner ones
    g = cylinder_grid(cx, cy, np.maximum(r_out, radii))
    got, inside, hit = cylinder_grid_pass(paths, cx, cy, lo, hi, radii, R, r_out, strict, *g)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    want_inside, clearance = cylinder_overlap(paths, np.c_[cx, cy], lo, hi, radii)
    np.testing.assert_allclose(inside, want_inside, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(hit, clearance < 0)
    assert hit[3]  # the cylinder on one of its vertices
    inside2, hit2 = cylinder_hits(paths, np.c_[cx, cy], lo, hi, radii)  # the public form
    np.testing.assert_allclose(inside2, want_inside, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(hit2, hit)
    assert (np.isfinite(want) & (want > 0)).any()  # the case has threats to find


@FAST
@given(seed=SEEDS)
def test_cylinder_distance_vs_dense_sampling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, 3, 5)
    centers, lo, hi = random_cylinders(rng, 5)
    got = segment_cylinder_distance(paths, centers, lo, hi)
    step = 1.0 / (N_SAMPLES - 1)
    for q in range(3):
        for s in range(4):
            a, b = paths[q, s], paths[q, s + 1]
            lxy = math.hypot(*(b[:2] - a[:2]))
            for j in range(5):
                d = float(got[q, s, j])
                sampled = sampled_cylinder_distance(a, b, centers[j], lo[j], hi[j])
                iv = z_interval(a, b, lo[j], hi[j])
                if iv is None:
                    assert d == math.inf
                    assert sampled == math.inf
                    continue
                assert math.isfinite(d)
                if sampled == math.inf:  # the in-range part is shorter than a sample step
                    assert iv[1] - iv[0] < step
                    continue
                assert sampled >= d - 1e-12
                assert sampled - d <= lxy * step + 1e-12


@FAST
@given(seed=SEEDS, P=st.integers(1, 4), N=st.integers(2, 6), J=st.integers(1, 5))
def test_infinite_cylinders_equal_spso_point_segment_distance(
    seed: int, P: int, N: int, J: int
) -> None:
    rng = np.random.default_rng(seed)
    paths = random_paths(rng, P, N)
    centers = rng.uniform(-10, 10, (J, 2))
    inf = np.full(J, np.inf)
    got = segment_cylinder_distance(paths, centers, -inf, inf)
    want = point_segment_distance_2d(paths[:, :-1, :2], paths[:, 1:, :2], centers)
    assert want.shape == (P, N - 1, J)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    # and the 2-D distance is SPSO's DistP2S, computed the MATLAB way
    for q in range(P):
        for s in range(N - 1):
            for j in range(J):
                assert got[q, s, j] == pytest.approx(
                    dist_p2s(centers[j], paths[q, s, :2], paths[q, s + 1, :2]), rel=1e-9, abs=1e-9
                )


def dist_p2s(x, a, b) -> float:
    """SPSO's DistP2S.m, line by line."""
    d_ab = float(np.linalg.norm(a - b))
    d_ax = float(np.linalg.norm(a - x))
    d_bx = float(np.linalg.norm(b - x))
    if d_ab != 0:
        if np.dot(a - b, x - b) * np.dot(b - a, x - a) >= 0:
            A = np.array([b - a, x - a])
            return abs(float(np.linalg.det(A))) / d_ab
        return min(d_ax, d_bx)
    return d_ax


def test_cylinder_distance_vertical_clipping_cases() -> None:
    c = np.array([[0.0, 0.0]])
    lo, hi = np.array([0.0]), np.array([10.0])
    # climbs through the cylinder's top: only the part below z = 10 counts (x from -10 to 0)
    p = np.array([[[-10.0, 3.0, 0.0], [10.0, 3.0, 20.0]]])
    assert segment_cylinder_distance(p, c, lo, hi)[0, 0, 0] == pytest.approx(3.0)
    p = np.array([[[-10.0, 3.0, 5.0], [-2.0, 3.0, 15.0]]])  # leaves the range at x = -6
    assert segment_cylinder_distance(p, c, lo, hi)[0, 0, 0] == pytest.approx(math.hypot(6.0, 3.0))
    # entirely above / below
    p = np.array([[[-10.0, 0.0, 11.0], [10.0, 0.0, 30.0]], [[-1.0, 0.0, -1.0], [1.0, 0.0, -0.5]]])
    np.testing.assert_array_equal(segment_cylinder_distance(p, c, lo, hi)[:, 0, 0], np.inf)
    # horizontal, exactly at the top and bottom faces: inside the closed range
    p = np.array([[[-10.0, 2.0, 10.0], [10.0, 2.0, 10.0]], [[-10.0, 2.0, 0.0], [10.0, 2.0, 0.0]]])
    np.testing.assert_allclose(segment_cylinder_distance(p, c, lo, hi)[:, 0, 0], 2.0)
    np.testing.assert_allclose(segment_cylinder_distance_reference(p, c, lo, hi)[:, 0, 0], 2.0)
    # touching the top at one end only
    p = np.array([[[5.0, 0.0, 10.0], [-5.0, 0.0, 20.0]]])
    assert segment_cylinder_distance(p, c, lo, hi)[0, 0, 0] == pytest.approx(5.0)
    # vertical segment through the range; zero-length inside and outside the range
    p = np.array([[[1.0, 1.0, -5.0], [1.0, 1.0, 50.0]], [[1.0, 1.0, 5.0], [1.0, 1.0, 5.0]]])
    np.testing.assert_allclose(segment_cylinder_distance(p, c, lo, hi)[:, 0, 0], math.sqrt(2))
    p = np.array([[[1.0, 1.0, 50.0], [1.0, 1.0, 50.0]]])
    assert segment_cylinder_distance(p, c, lo, hi)[0, 0, 0] == math.inf


# ----------------------------------------------------------------------------- circles
@FAST
@given(seed=SEEDS)
def test_circle_inside_fraction_vs_dense_sampling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    P, N, J = 3, 5, 4
    paths = random_paths(rng, P, N)
    centers = rng.uniform(-8, 8, (J, 2))
    radii = rng.uniform(0.5, 6.0, J)
    got = segment_circle_inside_fraction(paths, centers, radii)
    assert got.shape == (P, N - 1, J)
    assert np.all((got >= 0.0) & (got <= 1.0))
    t = (np.arange(N_SAMPLES) + 0.5) / N_SAMPLES
    for q in range(P):
        for s in range(N - 1):
            a, b = paths[q, s], paths[q, s + 1]
            pts = a[:2] + t[:, None] * (b[:2] - a[:2])
            for j in range(J):
                inside = np.hypot(*(pts - centers[j]).T) < radii[j]
                assert got[q, s, j] == pytest.approx(inside.mean(), abs=2.0 / N_SAMPLES + 1e-12)


def test_circle_inside_fraction_exact_cases() -> None:
    c, r = np.array([[0.0, 0.0]]), np.array([1.0])
    p = np.array(
        [
            [[-2.0, 0.0, 0.0], [2.0, 0.0, 9.0]],  # diameter: half of the segment
            [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]],  # from the centre out
            [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]],  # fully inside
            [[-2.0, 1.0, 0.0], [2.0, 1.0, 0.0]],  # tangent
            [[-2.0, 3.0, 0.0], [2.0, 3.0, 0.0]],  # outside
            [[0.2, 0.2, 0.0], [0.2, 0.2, 5.0]],  # vertical, inside: point-like ground track
            [[3.0, 0.2, 0.0], [3.0, 0.2, 5.0]],  # vertical, outside
        ]
    )
    got = segment_circle_inside_fraction(p, c, r)[:, 0, 0]
    np.testing.assert_allclose(got, [0.5, 0.5, 1.0, 0.0, 0.0, 1.0, 0.0], atol=1e-15)


# ----------------------------------------------------------------------------- polygons
@FAST
@given(seed=SEEDS)
def test_point_in_polygon_vs_matplotlib(seed: int) -> None:
    rng = np.random.default_rng(seed)
    verts = random_polygon(rng)
    pts = rng.uniform(-12, 12, (500, 2))
    # points on (or within rounding of) the boundary may go either way
    d_edge = point_segment_distance_2d(verts, np.roll(verts, -1, axis=0), pts).min(axis=0)
    ok = d_edge > 1e-9
    got = point_in_polygon(pts, verts)
    want = MplPath(verts).contains_points(pts)
    np.testing.assert_array_equal(got[ok], want[ok])
    np.testing.assert_array_equal(Polygon(tuple(map(tuple, verts))).contains(pts)[ok], want[ok])
    # broadcasting over leading axes
    assert point_in_polygon(pts.reshape(20, 25, 2), verts).shape == (20, 25)


@FAST
@given(seed=SEEDS)
def test_segment_polygon_distance_vs_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    polys = [random_polygon(rng) for _ in range(3)]
    verts, starts = pack_polygons(polys)
    paths = random_paths(rng, 3, 4)
    got = segment_polygon_distance(paths, verts, starts)
    assert got.shape == (3, 3, 3)
    t = np.linspace(0.0, 1.0, N_SAMPLES)
    for q in range(3):
        for s in range(3):
            a, b = paths[q, s, :2], paths[q, s + 1, :2]
            pts = a + t[:, None] * (b - a)
            lxy = float(np.hypot(*(b - a)))
            for k, poly in enumerate(polys):
                d = float(got[q, s, k])
                sampled = dist_to_polygon(pts, poly)
                assert d >= 0.0
                assert sampled.min() >= d - 1e-9
                assert sampled.min() - d <= lxy / (N_SAMPLES - 1) + 1e-9
                if (sampled == 0.0).any():  # some sampled point is inside: it crosses
                    assert d == 0.0


def test_segment_polygon_distance_zero_exactly_when_crossing() -> None:
    # an L-shaped (non-convex) polygon; a segment in its notch misses it
    L = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0], [1.0, 4.0], [0.0, 4.0]])
    verts, starts = pack_polygons([L])
    p = np.array(
        [
            [[2.0, 2.0, 0.0], [3.0, 3.0, 0.0]],  # in the notch, outside
            [[2.0, 2.0, 0.0], [2.0, -1.0, 0.0]],  # crosses the lower arm
            [[0.5, 0.5, 0.0], [0.6, 0.6, 0.0]],  # entirely inside
            [[-1.0, 5.0, 0.0], [5.0, 5.0, 0.0]],  # above, 1 away
            [[2.0, 1.0 + 1e-9, 0.0], [3.0, 1.0 + 1e-9, 0.0]],  # just outside an inner edge
            [[3.0, 2.0, 0.0], [5.0, 0.0, 0.0]],  # touches the outer corner (4, 1) only
        ]
    )
    got = segment_polygon_distance(p, verts, starts)[:, 0, 0]
    assert got[0] == pytest.approx(1.0)  # to the inner edge x = 1
    assert got[1] == 0.0
    assert got[2] == 0.0
    assert got[3] == pytest.approx(1.0)
    assert 0.0 < got[4] <= 1.1e-9
    assert got[5] == 0.0


@FAST
@given(seed=SEEDS)
def test_segment_polygon_inside_fraction_vs_dense_sampling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    polys = [random_polygon(rng) for _ in range(3)]
    verts, starts = pack_polygons(polys)
    paths = random_paths(rng, 3, 4)
    got = segment_polygon_inside_fraction(paths, verts, starts)
    assert got.shape == (3, 3, 3)
    assert np.all((got >= 0.0) & (got <= 1.0 + 1e-12))
    t = (np.arange(N_SAMPLES) + 0.5) / N_SAMPLES
    for q in range(3):
        for s in range(3):
            a, b = paths[q, s, :2], paths[q, s + 1, :2]
            pts = a + t[:, None] * (b - a)
            for k, poly in enumerate(polys):
                inside = MplPath(poly).contains_points(pts).mean()
                tol = (len(poly) + 1) / N_SAMPLES + 1e-12  # each edge crossing costs a sample
                assert got[q, s, k] == pytest.approx(inside, abs=tol)


def test_segment_polygon_inside_fraction_exact_cases() -> None:
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    verts, starts = pack_polygons([square, square + 10.0])
    p = np.array(
        [
            [[-1.0, 1.0], [3.0, 1.0]],  # half inside the first
            [[1.0, 1.0], [1.5, 1.5]],  # inside the first
            [[1.0, 1.0], [11.0, 11.0]],  # from the first into the second
        ]
    )
    got = segment_polygon_inside_fraction(p, verts, starts)[:, 0]
    np.testing.assert_allclose(got, [[0.5, 0.0], [1.0, 0.0], [0.1, 0.1]], atol=1e-12)


# ----------------------------------------------------------------------------- moving obstacles
def sampled_timed_distance(a, b, ta, tb, obs: MovingObstacle, n=2000) -> float:
    t = np.linspace(ta, tb, n)
    w = (t - ta) / (tb - ta) if tb > ta else np.zeros(n)
    p = a + w[:, None] * (b - a)
    q = obs.position_at(t)
    return float(np.linalg.norm(p - q, axis=1).min())


@FAST
@given(seed=SEEDS, K=st.integers(1, 6), N=st.integers(2, 7))
def test_timed_path_min_distance_vs_dense_time_sampling(seed: int, K: int, N: int) -> None:
    rng = np.random.default_rng(seed)
    P = 3
    obs_t = np.cumsum(rng.uniform(0.2, 3.0, K)) + rng.uniform(-2.0, 2.0)
    obs_xyz = rng.uniform(-10, 10, (K, 3))
    obs = MovingObstacle(1.0, obs_t, obs_xyz)
    paths = rng.uniform(-10, 10, (P, N, 3))
    # times from well before the obstacle's first knot to well after its last, some repeated
    # (zero-duration segments), segments spanning several obstacle knots
    dts = rng.choice([0.0, 0.3, 1.0, 4.0], (P, N - 1))
    times = np.concatenate([np.zeros((P, 1)), np.cumsum(dts, axis=1)], axis=1)
    times += rng.uniform(obs_t[0] - 5.0, obs_t[-1] + 1.0, (P, 1))
    got = timed_path_min_distance(paths, times, obs_t, obs_xyz)
    assert got.shape == (P, N - 1)
    np.testing.assert_array_equal(obs.min_distance(paths, times), got)
    vmax = float(
        np.max(np.linalg.norm(np.diff(obs_xyz, axis=0), axis=1) / np.diff(obs_t), initial=0.0)
    )
    for q in range(P):
        for s in range(N - 1):
            a, b = paths[q, s], paths[q, s + 1]
            ta, tb = times[q, s], times[q, s + 1]
            sampled = sampled_timed_distance(a, b, ta, tb, obs)
            d = float(got[q, s])
            assert sampled >= d - 1e-9
            vpath = float(np.linalg.norm(b - a)) / (tb - ta) if tb > ta else 0.0
            assert sampled - d <= (vpath + vmax) * (tb - ta) / 1999 + 1e-9


def test_moving_obstacle_exact_cases() -> None:
    # the obstacle crosses the path's line at t = 5 where the path is; held before/after its knots
    obs = MovingObstacle(0.5, np.array([4.0, 6.0]), np.array([[5.0, -1.0, 0.0], [5.0, 1.0, 0.0]]))
    path = np.array([[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]])
    assert obs.min_distance(path, np.array([[0.0, 10.0]]))[0, 0] == pytest.approx(0.0, abs=1e-12)
    # the same path one second late: x = t - 1, the obstacle at (5, t - 5) for t in [4, 6]:
    # d^2 = (t - 6)^2 + (t - 5)^2, least at t = 5.5
    late = obs.min_distance(path, np.array([[1.0, 11.0]]))[0, 0]
    assert late == pytest.approx(math.sqrt(0.5), abs=1e-12)
    # entirely before the obstacle's first knot: it sits at its first position
    assert obs.min_distance(path, np.array([[-20.0, -10.0]]))[0, 0] == pytest.approx(1.0)
    # entirely after its last knot
    assert obs.min_distance(path, np.array([[20.0, 30.0]]))[0, 0] == pytest.approx(1.0)
    # 2-D positions and paths; times broadcast over the population
    obs2 = MovingObstacle(1.0, np.array([0.0]), np.array([[3.0, 4.0]]))
    p2 = np.zeros((2, 3, 2))
    p2[1, :, 0] = [0.0, 3.0, 6.0]
    got = obs2.min_distance(p2, np.array([0.0, 1.0, 2.0]))
    np.testing.assert_allclose(got, [[5.0, 5.0], [4.0, 4.0]])
    np.testing.assert_allclose(obs2.position_at([-1.0, 5.0]), [[3.0, 4.0, 0.0]] * 2)


def test_moving_obstacle_validation() -> None:
    with pytest.raises(ValueError):
        MovingObstacle(1.0, np.array([0.0, 0.0]), np.zeros((2, 3)))
    with pytest.raises(ValueError):
        MovingObstacle(0.0, np.array([0.0]), np.zeros((1, 3)))
    with pytest.raises(ValueError):
        MovingObstacle(1.0, np.array([0.0, 1.0]), np.zeros((3, 3)))
    with pytest.raises(ValueError):
        Circle((0.0, 0.0), -1.0)
    with pytest.raises(ValueError):
        Polygon(((0.0, 0.0), (1.0, 1.0), (2.0, 2.0)))  # zero area


def test_fused_scene_kernel_matches_the_separate_kernels() -> None:
    """scene2d_batch = inside lengths + circle and polygon clearance of the separate kernels."""
    from uavplan.problems import PathProblem
    from uavplan.problems import costs as C
    from uavplan.scenarios import resolve
    from uavplan.world.geometry import (
        scene2d_batch,
        segment_cylinder_distance,
        segment_polygon_distance,
    )

    for name in ("simple2d", "rgg-n14-i003", "rgg-n07-i010"):
        pp = PathProblem(resolve(name))
        rng = np.random.default_rng(1)
        P = rng.uniform(0, 100, (300, 8, 2))
        P[:, 0], P[:, -1] = pp.start, pp.goal
        P[::5, 3] = P[::5, 2]  # zero-length segments
        w = pp.validator.world
        verts, starts = w.poly_verts, w.poly_starts
        P[::7, 4] = -1.0  # some nodes out of the box
        length, inside, circle_hit, polygon_hit, outside = scene2d_batch(
            np.ascontiguousarray(P),
            w.circ_centers,
            w.circ_radii,
            verts,
            starts,
            w.poly_margin,
            w.lo2,
            w.hi2,
        )
        np.testing.assert_allclose(length, C.segment_lengths(P).sum(axis=1), rtol=1e-12)
        assert np.array_equal(outside, ~np.all(pp.scenario.bounds.contains(P), axis=1))
        assert outside.any() and not outside.all()
        ref = C.inside_length_2d(P, w.circ_centers, w.circ_radii, verts, starts)
        np.testing.assert_allclose(inside, ref, rtol=1e-12, atol=1e-9)
        P3 = np.concatenate([P, np.zeros((*P.shape[:2], 1))], axis=-1)
        J = len(w.circ_radii)
        d = segment_cylinder_distance(P3, w.circ_centers, np.full(J, -np.inf), np.full(J, np.inf))
        assert np.array_equal(circle_hit, np.any(d < w.circ_radii, axis=(1, 2)))
        dp = segment_polygon_distance(P3, verts, starts)
        assert np.array_equal(polygon_hit, np.any((dp <= 0.0) | (dp < w.poly_margin), axis=(1, 2)))


def test_fused_kernel_convex_fast_path_agrees_with_the_general_method() -> None:
    """Convex polygons (both orientations, a collinear vertex) go through Cyrus-Beck clipping in
    scene2d_batch; non-convex ones (and a pentagram, whose turns share a sign) through the
    crossing-and-midpoint method. Both must agree with the separate kernels."""
    from uavplan.problems import costs as C
    from uavplan.world.geometry import (
        pack_polygons,
        polygon_convexity,
        scene2d_batch,
        segment_polygon_distance,
    )

    square_ccw = np.array([[10, 10], [30, 10], [30, 20], [30, 30], [10, 30]], float)
    tri_cw = np.array([[50, 10], [60, 40], [70, 10]], float)
    ell = np.array([[10, 50], [40, 50], [40, 60], [20, 60], [20, 80], [10, 80]], float)
    ang = 2 * np.pi * np.arange(5) / 5
    star = np.c_[75 + 15 * np.cos(ang * 2), 70 + 15 * np.sin(ang * 2)]  # pentagram order
    verts, starts = pack_polygons([square_ccw, tri_cw, ell, star])
    assert list(polygon_convexity(verts, starts)) == [1, -1, 0, 0]
    rng = np.random.default_rng(7)
    P = rng.uniform(0, 100, (400, 6, 2))
    P[:50, 1] = [10.0, 10.0]  # segments from a vertex
    P[50:60, 2:4] = [[5.0, 20.0], [35.0, 20.0]]  # through the collinear vertex's edge line
    K = len(starts) - 1
    _, inside, _, polygon_hit, _ = scene2d_batch(
        np.ascontiguousarray(P),
        np.zeros((0, 2)),
        np.zeros(0),
        verts,
        starts,
        np.zeros(K),
        np.zeros(2),
        np.full(2, 100.0),
    )
    ref = C.inside_length_2d(P, np.zeros((0, 2)), np.zeros(0), verts, starts)
    np.testing.assert_allclose(inside, ref, rtol=1e-12, atol=1e-9)
    P3 = np.concatenate([P, np.zeros((*P.shape[:2], 1))], axis=-1)
    dp = segment_polygon_distance(P3, verts, starts)
    assert np.array_equal(polygon_hit, np.any(dp <= 0.0, axis=(1, 2)))
    assert polygon_hit.any() and not polygon_hit.all()


def testconvex_hulls_of_packed_polygons() -> None:
    from scipy.spatial import ConvexHull

    from uavplan.world.geometry import convex_hulls, pack_polygons

    rng = np.random.default_rng(11)
    polys = [rng.uniform(0, 10, (n, 2)) for n in (3, 5, 9, 14)]
    polys.append(np.array([[0, 0], [2, 0], [4, 0], [4, 4], [0, 4]], float))  # collinear points
    hv, hs = convex_hulls(*pack_polygons(polys))
    for k, poly in enumerate(polys):
        h = hv[hs[k] : hs[k + 1]]
        ref = poly[ConvexHull(poly).vertices]  # counter-clockwise, no collinear points
        assert len(h) == len(ref)
        assert {tuple(p) for p in h} == {tuple(p) for p in ref}
        x, y = h[:, 0], h[:, 1]
        assert np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) > 0  # counter-clockwise


def test_track_crosses_itself() -> None:
    from uavplan.world.geometry import track_crosses_itself

    assert not track_crosses_itself(np.array([[0, 0], [1, 0], [2, 1], [3, 1]]))
    assert track_crosses_itself(np.array([[0, 0], [2, 0], [2, 1], [1, -1]]))  # a loop
    assert not track_crosses_itself(np.array([[0, 0, 5], [1, 0, 6], [1, 1, 7]]))  # 3-D: track
    assert not track_crosses_itself(np.array([[0, 0], [1, 0], [1, 1], [0, 0]]))  # touches only


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 30), grid=st.booleans())
def test_track_crosses_itself_compiled_equals_the_reference(seed: int, n: int, grid: bool) -> None:
    from uavplan.world.geometry.polygons import (
        track_crosses_itself,
        track_crosses_itself_reference,
    )

    rng = np.random.default_rng(seed)
    # random walks; on a small integer grid, touching and collinear cases are common
    P = rng.integers(0, 4, (n, 3)).astype(float) if grid else np.cumsum(rng.normal(size=(n, 3)), 0)
    assert track_crosses_itself(P) == track_crosses_itself_reference(P)


def test_built_structures_are_kept_by_content() -> None:
    from uavplan.world.geometry import by_content

    calls = []

    def build(a: np.ndarray) -> float:
        calls.append(1)
        return float(a.sum())

    a = np.arange(5.0)
    assert by_content("test sum", build, a) == 10.0
    assert by_content("test sum", build, a.copy()) == 10.0  # same bytes: built once
    assert len(calls) == 1
    assert by_content("test sum", build, a + 1) == 15.0 and len(calls) == 2


@FAST
@given(seed=SEEDS)
def test_cylinder_grid_lists_each_disc_in_every_cell_its_box_meets(seed: int) -> None:
    from uavplan.world.geometry import cylinder_grid

    rng = np.random.default_rng(seed)
    J = int(rng.integers(1, 300))
    cx, cy = rng.uniform(-1e4, 1e4, J), rng.uniform(-50, 50, J) * rng.choice([1.0, 100.0])
    reach = rng.uniform(0.1, 200.0, J)
    (x0, y0, h, nx, ny), starts, items, first = cylinder_grid(cx, cy, reach)
    nx, ny = int(nx), int(ny)
    listed: dict[int, set[int]] = {}
    for k in range(nx * ny):
        for j in items[starts[k] : starts[k + 1]]:
            listed.setdefault(int(j), set()).add(k)
    for j in range(J):
        cells = listed[j]
        ii = sorted({k % nx for k in cells})
        jj = sorted({k // nx for k in cells})
        assert cells == {b * nx + a for a in ii for b in jj}  # a full rectangle
        assert (ii[0], jj[0]) == tuple(first[j])
        # the disc's box lies within the cells listing it
        assert x0 + ii[0] * h <= cx[j] - reach[j] and cx[j] + reach[j] <= x0 + (ii[-1] + 1) * h
        assert y0 + jj[0] * h <= cy[j] - reach[j] and cy[j] + reach[j] <= y0 + (jj[-1] + 1) * h
