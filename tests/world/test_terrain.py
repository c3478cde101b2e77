"""Terrain: bilinear lookup, nearest lookup, exact segment clearance, mean height, loading.

The exact segment queries are checked two ways: against dense sampling of ``z - height(x, y)``
(which can only over-estimate a minimum, by at most the Lipschitz bound times the sample step), and
against an independent exact reference that splits the segment at the grid lines and minimises the
quadratic of each piece using only :meth:`Terrain.height`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from uavplan.world import Terrain
from uavplan.world.terrain import TerrainError

N_SAMPLES = 4000
SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


# ----------------------------------------------------------------------------- helpers
def random_terrain(seed: int, ny: int = 20, nx: int = 30) -> Terrain:
    """A small random DEM: smooth bumps plus noise, sometimes integer plateaus (exact ties)."""
    rng = np.random.default_rng(seed)
    kind = int(rng.integers(3))
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    if kind == 0:  # rough
        h = rng.normal(0.0, 10.0, (ny, nx))
    elif kind == 1:  # smooth hills plus a little noise
        h = np.zeros((ny, nx))
        for _ in range(4):
            cx, cy = rng.uniform(0, nx), rng.uniform(0, ny)
            w = rng.uniform(2.0, 8.0)
            h += rng.uniform(-40, 60) * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * w * w))
        h += rng.normal(0.0, 0.5, (ny, nx))
    else:  # integer plateaus: many equal heights, minima attained on whole intervals
        h = np.round(rng.uniform(0.0, 3.0, (ny, nx)))
    x0, y0 = (0.0, 0.0) if kind == 2 else tuple(rng.uniform(-50.0, 50.0, 2))
    dx, dy = (1.0, 1.0) if kind == 2 else tuple(rng.uniform(0.5, 5.0, 2))
    return Terrain(h, float(x0), float(y0), float(dx), float(dy))


def random_segments(terrain: Terrain, rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 2, 3) segments, endpoints anywhere in the grid extent widened by 20 % (some leave it),
    including vertical, zero-length and grid-line-aligned ones."""
    xmin, xmax, ymin, ymax = terrain.extent
    wx, wy = xmax - xmin, ymax - ymin
    h = terrain.heights
    lo, hi = float(h.min()) - 5.0, float(h.max()) + 5.0
    seg = np.empty((n, 2, 3))
    seg[..., 0] = rng.uniform(xmin - 0.2 * wx, xmax + 0.2 * wx, (n, 2))
    seg[..., 1] = rng.uniform(ymin - 0.2 * wy, ymax + 0.2 * wy, (n, 2))
    seg[..., 2] = rng.uniform(lo, hi, (n, 2))
    for k in range(n):
        mode = rng.integers(9)
        if mode == 0:  # vertical
            seg[k, 1, :2] = seg[k, 0, :2]
        elif mode == 1:  # zero length
            seg[k, 1] = seg[k, 0]
        elif mode == 2:  # along a grid column (x on a node line)
            i = rng.integers(terrain.shape[1])
            seg[k, :, 0] = terrain.x0 + i * terrain.dx
        elif mode == 3:  # along a grid row
            j = rng.integers(terrain.shape[0])
            seg[k, :, 1] = terrain.y0 + j * terrain.dy
        elif mode == 4:  # short, inside a few cells
            seg[k, 1, :2] = seg[k, 0, :2] + rng.normal(0, 1.5, 2) * (terrain.dx, terrain.dy)
        elif mode == 5:  # level at an integer height: on integer plateaus the minimum is tied
            seg[k, :, 2] = np.round(seg[k, 0, 2])
    return seg


def grid_t_range(terrain: Terrain, a: np.ndarray, b: np.ndarray) -> tuple[float, float] | None:
    """Parameter range [t0, t1] of a->b whose ground track is inside the grid rectangle."""
    ny, nx = terrain.shape
    u0, v0 = (a[0] - terrain.x0) / terrain.dx, (a[1] - terrain.y0) / terrain.dy
    u1, v1 = (b[0] - terrain.x0) / terrain.dx, (b[1] - terrain.y0) / terrain.dy
    t0, t1 = 0.0, 1.0
    for c0, c1, top in ((u0, u1, nx - 1.0), (v0, v1, ny - 1.0)):
        if c1 == c0:
            # on the grid's edge up to rounding counts as on it (Terrain snaps such points)
            tol = 64.0 * np.finfo(np.float64).eps * max(1.0, top)
            if not -tol <= c0 <= top + tol:
                return None
            continue
        ta, tb = sorted(((0.0 - c0) / (c1 - c0), (top - c0) / (c1 - c0)))
        t0, t1 = max(t0, ta), min(t1, tb)
    return (t0, t1) if t0 <= t1 else None


def breakpoints(
    terrain: Terrain, a: np.ndarray, b: np.ndarray, t0: float, t1: float
) -> list[float]:
    """Sorted parameters in [t0, t1] where the ground track crosses a grid line, plus the ends."""
    ts = [t0, t1]
    for k, (org, d) in enumerate(((terrain.x0, terrain.dx), (terrain.y0, terrain.dy))):
        c0, c1 = (a[k] - org) / d, (b[k] - org) / d
        if c1 == c0:
            continue
        lo, hi = sorted((c0 + (c1 - c0) * t0, c0 + (c1 - c0) * t1))
        for m in range(math.floor(lo) + 1, math.ceil(hi)):
            ts.append((m - c0) / (c1 - c0))
    return sorted(t for t in ts if t0 <= t <= t1)


def clearance_at(terrain: Terrain, a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    p = a + np.asarray(t, dtype=float)[..., None] * (b - a)
    return np.asarray(p[..., 2] - terrain.height(p[..., 0], p[..., 1]))


def exact_min_clearance_reference(terrain: Terrain, a: np.ndarray, b: np.ndarray) -> float:
    """Independent exact minimum: on every piece between grid-line crossings the clearance is a
    quadratic in t; fit it through three points, evaluate at the ends and at an interior vertex."""
    rng_t = grid_t_range(terrain, a, b)
    if rng_t is None:
        return math.inf
    ts = breakpoints(terrain, a, b, *rng_t)
    best = float(np.min(clearance_at(terrain, a, b, np.array(ts))))
    for ta, tb in itertools.pairwise(ts):
        if tb - ta <= 1e-12:
            continue
        tm = 0.5 * (ta + tb)
        ga, gm, gb = clearance_at(terrain, a, b, np.array([ta, tm, tb]))
        # g(t) through the three points; second difference gives the curvature
        curv = (ga - 2 * gm + gb) / ((0.5 * (tb - ta)) ** 2)
        if curv > 0:
            slope_m = (gb - ga) / (tb - ta)
            tv = tm - slope_m / curv
            if ta < tv < tb:
                best = min(best, float(clearance_at(terrain, a, b, np.array([tv]))[0]))
    return best


def lipschitz(terrain: Terrain, a: np.ndarray, b: np.ndarray) -> float:
    """Bound on |d/dt (z - h)| along a->b."""
    H = terrain.heights
    gx = float(np.abs(np.diff(H, axis=1)).max())
    gy = float(np.abs(np.diff(H, axis=0)).max())
    return (
        abs(b[2] - a[2]) + abs(b[0] - a[0]) / terrain.dx * gx + abs(b[1] - a[1]) / terrain.dy * gy
    )


def sampled_clearance(terrain: Terrain, a: np.ndarray, b: np.ndarray, n: int = N_SAMPLES):
    """Clearance at n evenly spaced points of a->b whose ground track is inside the grid."""
    t = np.linspace(0.0, 1.0, n)
    g = clearance_at(terrain, a, b, t)
    p = a + t[:, None] * (b - a)
    ny, nx = terrain.shape
    u = (p[:, 0] - terrain.x0) / terrain.dx  # the grid test in cell coordinates, as documented
    v = (p[:, 1] - terrain.y0) / terrain.dy
    tx = 64.0 * np.finfo(np.float64).eps * max(1.0, nx - 1.0)
    ty = 64.0 * np.finfo(np.float64).eps * max(1.0, ny - 1.0)
    inside = (u >= -tx) & (u <= nx - 1 + tx) & (v >= -ty) & (v <= ny - 1 + ty)
    return g[inside]


def scale_of(terrain: Terrain, seg: np.ndarray) -> float:
    return 1.0 + float(np.abs(terrain.heights).max()) + float(np.abs(seg[..., 2]).max())


def matlab_round_positive(u: float) -> int:
    """MATLAB round for u >= 0, computed exactly (u - floor(u) is exact for u >= 0)."""
    f = math.floor(u)
    return f + 1 if u - f >= 0.5 else f


# ----------------------------------------------------------------------------- bilinear height
@FAST
@given(seed=SEEDS)
def test_height_equals_grid_at_nodes(seed: int) -> None:
    T = random_terrain(seed)
    ny, nx = T.shape
    jj, ii = np.mgrid[0:ny, 0:nx]
    got = T.height(T.x0 + ii * T.dx, T.y0 + jj * T.dy)
    tol = 1e-9 * (1.0 + np.abs(T.heights).max())
    np.testing.assert_allclose(got, T.heights, rtol=0, atol=tol)
    if T.x0 == 0.0 and T.dx == 1.0 and T.dy == 1.0:  # exact node coordinates: exact values
        np.testing.assert_array_equal(got, T.heights)


@FAST
@given(seed=SEEDS, frac=st.floats(0.0, 1.0), data=st.data())
def test_height_is_linear_along_grid_lines(seed: int, frac: float, data: st.DataObject) -> None:
    T = random_terrain(seed)
    ny, nx = T.shape
    H = T.heights
    tol = 1e-9 * (1.0 + np.abs(H).max())
    # along a row j (y on a node line), between columns i and i + 1
    j = data.draw(st.integers(0, ny - 1))
    i = data.draw(st.integers(0, nx - 2))
    x = T.x0 + (i + frac) * T.dx
    want = H[j, i] + frac * (H[j, i + 1] - H[j, i])
    assert abs(float(T.height(x, T.y0 + j * T.dy)) - want) <= tol
    # along a column i (x on a node line), between rows j and j + 1
    i = data.draw(st.integers(0, nx - 1))
    j = data.draw(st.integers(0, ny - 2))
    y = T.y0 + (j + frac) * T.dy
    want = H[j, i] + frac * (H[j + 1, i] - H[j, i])
    assert abs(float(T.height(T.x0 + i * T.dx, y)) - want) <= tol


@FAST
@given(seed=SEEDS, s=st.floats(0.0, 1.0), r=st.floats(0.0, 1.0))
def test_height_is_bilinear_inside_a_cell(seed: int, s: float, r: float) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed)
    j, i = int(rng.integers(T.shape[0] - 1)), int(rng.integers(T.shape[1] - 1))
    H = T.heights
    want = (
        H[j, i] * (1 - s) * (1 - r)
        + H[j, i + 1] * s * (1 - r)
        + H[j + 1, i] * (1 - s) * r
        + H[j + 1, i + 1] * s * r
    )
    got = float(T.height(T.x0 + (i + s) * T.dx, T.y0 + (j + r) * T.dy))
    assert got == pytest.approx(want, abs=1e-9 * (1.0 + np.abs(H).max()))


def test_height_outside_takes_nearest_edge_point() -> None:
    T = random_terrain(7)
    xmin, xmax, ymin, ymax = T.extent
    np.testing.assert_allclose(T.height(xmin - 100.0, ymin - 3.0), T.heights[0, 0])
    np.testing.assert_allclose(T.height(xmax + 1.0, ymax + 1.0), T.heights[-1, -1])
    y = 0.5 * (ymin + ymax)
    np.testing.assert_allclose(T.height(xmin - 7.0, y), T.height(xmin, y))


def test_height_broadcasts() -> None:
    T = random_terrain(3)
    x = np.linspace(*T.extent[:2], 5)[:, None]
    y = np.linspace(*T.extent[2:], 4)[None, :]
    got = T.height(x, y)
    assert got.shape == (5, 4)
    assert got[2, 3] == pytest.approx(float(T.height(x[2, 0], y[0, 3])))


# ----------------------------------------------------------------------------- nearest height
@settings(max_examples=200, deadline=None)
@given(u=st.floats(0.0, 29.0), v=st.floats(0.0, 19.0))
@example(u=0.5, v=0.5)
@example(u=1.5, v=2.5)
@example(u=28.5, v=18.5)
@example(u=2.4999999999999996, v=3.5000000000000004)
def test_height_nearest_rounds_like_matlab(u: float, v: float) -> None:
    T = Terrain(np.arange(20 * 30, dtype=float).reshape(20, 30))
    assert (
        float(T.height_nearest(u, v))
        == T.heights[matlab_round_positive(v), matlab_round_positive(u)]
    )


def test_height_nearest_halves_round_up() -> None:
    T = Terrain(np.arange(20 * 30, dtype=float).reshape(20, 30), x0=1.0, y0=1.0)
    # SPSO's frame: node (1, 1) at x = y = 1; H(round(y), round(x)) with 1-based indices
    for x, y in [(1.5, 1.5), (2.5, 7.5), (10.5, 3.49), (29.5, 19.5), (1.0, 1.0), (30.0, 20.0)]:
        want = T.heights[matlab_round_positive(y) - 1, matlab_round_positive(x) - 1]
        assert float(T.height_nearest(x, y)) == want
    # lookup() dispatches, and the spread of grid-rounded coordinates is clipped to the grid
    assert float(T.lookup(2.5, 1.0, "nearest")) == T.heights[0, 2]
    assert float(T.height_nearest(-10.0, 100.0)) == T.heights[-1, 0]
    with pytest.raises(ValueError):
        T.lookup(1.0, 1.0, "cubic")


def test_height_nearest_just_below_half() -> None:
    T = Terrain(np.arange(6.0).reshape(2, 3))
    u = 0.49999999999999994  # the largest double below 0.5
    assert matlab_round_positive(u) == 0
    assert float(T.height_nearest(u, 0.0)) == T.heights[0, 0]


# ----------------------------------------------------------------------------- min clearance
@FAST
@given(seed=SEEDS)
def test_min_clearance_matches_references(seed: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed + 1)
    segs = random_segments(T, rng, 12)
    got = T.min_clearance(segs)
    assert got.shape == (12, 1)
    for k, (a, b) in enumerate(segs):
        m = float(got[k, 0])
        tol = 1e-9 * scale_of(T, segs)
        ref = exact_min_clearance_reference(T, a, b)
        if math.isinf(ref):
            assert m == math.inf
            continue
        assert m == pytest.approx(ref, abs=tol), (a, b)
        g = sampled_clearance(T, a, b)
        if g.size:
            sampled = float(g.min())
            assert sampled >= m - tol
            step = 1.0 / (N_SAMPLES - 1)
            assert sampled - m <= lipschitz(T, a, b) * step + tol


@FAST
@given(seed=SEEDS, n_points=st.integers(2, 6))
def test_min_clearance_batch_equals_loop(seed: int, n_points: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed)
    xmin, xmax, ymin, ymax = T.extent
    P = 7
    paths = np.stack(
        [
            rng.uniform(xmin - 5, xmax + 5, (P, n_points)),
            rng.uniform(ymin - 5, ymax + 5, (P, n_points)),
            rng.uniform(T.heights.min(), T.heights.max() + 3, (P, n_points)),
        ],
        axis=-1,
    )
    batch = T.min_clearance(paths)
    bmax = T.max_clearance(paths)
    bmean = T.mean_height(paths)
    assert batch.shape == bmax.shape == bmean.shape == (P, n_points - 1)
    for c in (
        0.0,
        float(np.median(batch[np.isfinite(batch)])) if np.isfinite(batch).any() else 0.0,
    ):
        np.testing.assert_array_equal(T.clears(paths, c), batch >= c)
    for p in range(P):
        np.testing.assert_array_equal(T.min_clearance(paths[p : p + 1])[0], batch[p])
        np.testing.assert_array_equal(T.max_clearance(paths[p : p + 1])[0], bmax[p])
        np.testing.assert_array_equal(T.mean_height(paths[p : p + 1])[0], bmean[p])
        # a segment of a polyline is the same as that segment alone
        for s in range(n_points - 1):
            alone = T.min_clearance(paths[p : p + 1, s : s + 2])[0, 0]
            assert alone == batch[p, s]


@settings(max_examples=60, deadline=None)
@given(
    amp=st.floats(0.1, 100.0),
    z0=st.floats(-50.0, 50.0),
    slope=st.floats(-1.9, 1.9),
    dx=st.floats(0.25, 8.0),
    dy=st.floats(0.25, 8.0),
    x0=st.floats(-100.0, 100.0),
    y0=st.floats(-100.0, 100.0),
)
def test_min_clearance_exact_at_saddle_cell_interior(
    amp: float, z0: float, slope: float, dx: float, dy: float, x0: float, y0: float
) -> None:
    """Saddle cell h = A (s + r - 2 s r); along its diagonal s = r = t the terrain is the concave
    parabola A (2t - 2t^2), so with z = z0 + dz t the clearance minimum is interior:
    t* = (2A - dz) / (4A), min = z0 - (2A - dz)^2 / (8A)."""
    H = np.zeros((5, 6))
    j, i = 2, 3
    H[j, i + 1] = H[j + 1, i] = amp
    T = Terrain(H, x0, y0, dx, dy)
    dz = slope * amp  # |dz| < 2A: the vertex is inside the cell
    a = np.array([x0 + i * dx, y0 + j * dy, z0])
    b = np.array([x0 + (i + 1) * dx, y0 + (j + 1) * dy, z0 + dz])
    want = z0 - (2 * amp - dz) ** 2 / (8 * amp)
    got = float(T.min_clearance(np.array([[a, b]]))[0, 0])
    assert got == pytest.approx(want, rel=1e-12, abs=1e-11 * (1 + amp + abs(z0)))
    # every sampled point is at or above it, the closest sample within the sampling error
    g = sampled_clearance(T, a, b)
    assert g.min() >= got - 1e-9 * (1 + amp)
    assert g.min() - got <= 1e-6 * (1 + amp)
    # the endpoints alone (a sampled check at the nodes) would miss it by a lot
    assert min(z0, z0 + dz) - got > 1e-3 * amp
    # the same segment inside a longer one that crosses other (flat) cells
    longer = np.array(
        [[x0 + (i - 1) * dx, y0 + (j - 1) * dy, z0 - dz], [b[0] + dx, b[1] + dy, z0 + 2 * dz]]
    )
    exp_long = exact_min_clearance_reference(T, longer[0], longer[1])
    got_long = float(T.min_clearance(longer[None])[0, 0])
    assert got_long == pytest.approx(exp_long, abs=1e-9 * (1 + amp + abs(z0)))


@settings(max_examples=40, deadline=None)
@given(
    seed=SEEDS,
    ang=st.floats(0.0, 2 * math.pi),
    half=st.floats(0.05, 0.7),
    dz=st.floats(-3.0, 3.0),
)
def test_min_clearance_saddle_any_direction(seed: int, ang: float, half: float, dz: float) -> None:
    """A short segment through the centre of a saddle cell, any direction (generic interior
    stationary points) against the independent piecewise-quadratic reference."""
    rng = np.random.default_rng(seed)
    H = rng.normal(0, 1, (4, 4))
    H[1, 1], H[1, 2], H[2, 1], H[2, 2] = 0.0, 2.0, 2.0, 0.0  # saddle in cell (1, 1)
    T = Terrain(H)
    c = np.array([1.5, 1.5])
    d = half * np.array([math.cos(ang), math.sin(ang)])
    a = np.array([*(c - d), 5.0])
    b = np.array([*(c + d), 5.0 + dz])
    got = float(T.min_clearance(np.array([[a, b]]))[0, 0])
    assert got == pytest.approx(exact_min_clearance_reference(T, a, b), abs=1e-11)
    g = sampled_clearance(T, a, b)
    assert g.min() >= got - 1e-11


def test_min_clearance_segment_parts_outside_grid() -> None:
    T = Terrain(np.full((20, 30), 10.0))
    # entirely outside: nothing to check
    out = np.array([[[-5.0, -5.0, 0.0], [-1.0, 40.0, 0.0]]])
    assert T.min_clearance(out)[0, 0] == math.inf
    assert bool(T.clears(out, 100.0)[0, 0])
    # partly outside: only the inside part counts; z is low outside, high inside
    part = np.array([[[-10.0, 5.0, -100.0], [10.0, 5.0, 100.0]]])  # inside from x = 0 (z = 0)
    assert T.min_clearance(part)[0, 0] == pytest.approx(0.0 - 10.0, abs=1e-12)
    assert T.max_clearance(part)[0, 0] == pytest.approx(100.0 - 10.0, abs=1e-12)
    # crossing the grid, leaving on the other side
    across = np.array([[[-10.0, 5.0, 50.0], [40.0, 5.0, 0.0]]])  # x in [0, 29] -> z in [40, 11]
    assert T.min_clearance(across)[0, 0] == pytest.approx(11.0 - 10.0, abs=1e-12)
    assert T.max_clearance(across)[0, 0] == pytest.approx(40.0 - 10.0, abs=1e-12)
    # exactly along the grid's edge counts as inside
    edge = np.array([[[0.0, 19.0, 12.0], [29.0, 19.0, 11.0]]])
    assert T.min_clearance(edge)[0, 0] == pytest.approx(1.0, abs=1e-12)


def test_segment_on_the_extent_edge_is_checked() -> None:
    d = 1.2677123256557055
    T = Terrain(np.full((20, 30), 10.0), 41.52381547988982, 41.52381547988982, d, d)
    xmin, xmax, ymin, ymax = T.extent
    assert (ymax - T.y0) / T.dy > 19.0  # the rounding that trips it
    # both segments lie on the extent's edges, 10 m under the (flat) terrain
    p = np.array(
        [
            [[xmin + 1, ymax, 0.0], [xmax - 1, ymax, 0.0]],
            [[xmax, ymin + 1, 0.0], [xmax, ymax - 1, 0.0]],
        ]
    )
    np.testing.assert_array_equal(T.height(p[..., 0], p[..., 1]), 10.0)
    np.testing.assert_allclose(T.min_clearance(p).ravel(), [-10.0, -10.0])
    assert not T.clears(p, 0.0).any()


def test_min_clearance_vertical_and_zero_length() -> None:
    T = random_terrain(11)
    x, y = T.x0 + 3.3 * T.dx, T.y0 + 7.7 * T.dy
    h = float(T.height(x, y))
    vertical = np.array([[[x, y, h + 5.0], [x, y, h - 2.0]]])
    assert T.min_clearance(vertical)[0, 0] == pytest.approx(-2.0, abs=1e-9)
    assert T.max_clearance(vertical)[0, 0] == pytest.approx(5.0, abs=1e-9)
    assert T.mean_height(vertical)[0, 0] == pytest.approx(h, abs=1e-9)
    point = np.array([[[x, y, h + 1.5], [x, y, h + 1.5]]])
    assert T.min_clearance(point)[0, 0] == pytest.approx(1.5, abs=1e-9)
    assert T.max_clearance(point)[0, 0] == pytest.approx(1.5, abs=1e-9)
    assert T.mean_height(point)[0, 0] == pytest.approx(h, abs=1e-9)
    assert bool(T.clears(point, 1.5)[0, 0])
    assert not bool(T.clears(point, 1.5 + 1e-6)[0, 0])
    # a vertical segment on the grid edge (exactly representable there) and one off the grid
    T = Terrain(T.heights, 0.0, 0.0, 1.0, 0.5)
    xe, y = T.extent[1], 3.25
    edge = np.array([[[xe, y, 1e3], [xe, y, -1e3]]])
    assert T.min_clearance(edge)[0, 0] == pytest.approx(-1e3 - float(T.height(xe, y)), abs=1e-9)
    off = np.array([[[xe + 1.0, y, 1e3], [xe + 1.0, y, -1e3]]])
    assert T.min_clearance(off)[0, 0] == math.inf


# ----------------------------------------------------------------------------- clears
@FAST
@given(seed=SEEDS)
def test_clears_agrees_with_min_clearance_near_the_boundary(seed: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed + 2)
    segs = random_segments(T, rng, 16)
    m = T.min_clearance(segs)
    finite = m[np.isfinite(m)]
    # Thresholds at, just below and just above the exact minima. The minima are exact to
    # rounding (about 1e-14 here): a threshold within a few ulps of a minimum may be decided by
    # the pruning bound, or a true tie (a level path over a plateau) may come out 1e-14 low, so
    # agreement is required wherever the threshold is more than 1e-12 (relative) away.
    scale = scale_of(T, segs)
    cs = [0.0, -1.0, 3.0]
    for v in finite[:6]:
        cs += [float(v) - 1e-9, float(v) + 1e-9, float(v) + 1e-11 * scale]
        cs += [float(v) - 1e-11 * scale]
    for c in cs:
        decided = np.abs(m - c) > 1e-12 * scale
        got = T.clears(segs, c)
        np.testing.assert_array_equal(got[decided], (m >= c)[decided], err_msg=f"clearance {c!r}")
    # at a segment's own minimum it clears: the search never finds less than it reports
    for k in np.flatnonzero(np.isfinite(m[:, 0])):
        v = float(m[k, 0])
        assert bool(T.clears(segs[k : k + 1], v)[0, 0])
        assert not bool(T.clears(segs[k : k + 1], v + 1e-11 * scale)[0, 0])
        assert bool(T.clears(segs[k : k + 1], float(np.nextafter(v, -np.inf)))[0, 0])
    # the cap: values below it are exact, values at or above it are at least the cap
    for cap in cs:
        capped = T.min_clearance(segs, cap=cap)
        below = m < cap - 1e-12 * scale
        np.testing.assert_array_equal(capped[below], m[below])
        assert np.all(capped[m >= cap] >= cap)


def test_clears_on_flat_terrain_exact_boundary() -> None:
    T = Terrain(np.full((20, 30), 3.0))
    path = np.array([[[1.0, 1.0, 5.0], [20.0, 15.0, 5.0], [25.0, 15.0, 4.0]]])
    np.testing.assert_array_equal(T.min_clearance(path), [[2.0, 1.0]])
    np.testing.assert_array_equal(T.clears(path, 1.0), [[True, True]])
    np.testing.assert_array_equal(T.clears(path, 2.0), [[True, False]])
    np.testing.assert_array_equal(T.clears(path, np.nextafter(1.0, 2.0)), [[True, False]])
    np.testing.assert_array_equal(T.clears(path, 2.0 + 1e-12), [[False, False]])


# ----------------------------------------------------------------------------- max clearance
@FAST
@given(seed=SEEDS)
def test_max_clearance_matches_sampling(seed: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed + 3)
    segs = random_segments(T, rng, 10)
    got = T.max_clearance(segs)
    # max(z - h) = -min((-z) - (-h)): the reference on the mirrored world
    mirrored = Terrain(-T.heights, T.x0, T.y0, T.dx, T.dy)
    for k, (a, b) in enumerate(segs):
        top = float(got[k, 0])
        tol = 1e-9 * scale_of(T, segs)
        g = sampled_clearance(T, a, b)
        if not g.size and grid_t_range(T, a, b) is None:
            assert top == -math.inf
            continue
        a2, b2 = a * (1, 1, -1), b * (1, 1, -1)
        assert top == pytest.approx(-exact_min_clearance_reference(mirrored, a2, b2), abs=tol)
        if g.size:
            assert g.max() <= top + tol
            assert top - g.max() <= lipschitz(T, a, b) / (N_SAMPLES - 1) + tol
        assert top >= float(T.min_clearance(segs[k : k + 1])[0, 0]) - tol


# ----------------------------------------------------------------------------- mean height
def simpson_mean_reference(T: Terrain, a: np.ndarray, b: np.ndarray) -> float:
    """Exact mean of the bilinear terrain over t in [0, 1]: Simpson's rule is exact for the
    quadratic on each piece between grid-line crossings."""
    ts = breakpoints(T, a, b, 0.0, 1.0)
    total = 0.0
    for ta, tb in itertools.pairwise(ts):
        tt = np.array([ta, 0.5 * (ta + tb), tb])
        p = a + tt[:, None] * (b - a)
        h = T.height(p[:, 0], p[:, 1])
        total += (tb - ta) / 6.0 * (h[0] + 4.0 * h[1] + h[2])
    return total


@FAST
@given(seed=SEEDS)
def test_mean_height_matches_dense_average_inside_grid(seed: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed + 4)
    xmin, xmax, ymin, ymax = T.extent
    n = 10
    segs = np.empty((n, 2, 3))
    segs[..., 0] = rng.uniform(xmin, xmax, (n, 2))
    segs[..., 1] = rng.uniform(ymin, ymax, (n, 2))
    segs[..., 2] = rng.uniform(-10, 10, (n, 2))
    segs[0, 1, :2] = segs[0, 0, :2]  # vertical
    segs[1, :, 0] = T.x0 + 4 * T.dx  # along a column
    segs[2, :, 1] = T.y0 + 2 * T.dy  # along a row
    got = T.mean_height(segs)
    H = T.heights
    for k, (a, b) in enumerate(segs):
        tol = 1e-9 * (1 + np.abs(H).max())
        assert got[k, 0] == pytest.approx(simpson_mean_reference(T, a, b), abs=tol)
        t = np.linspace(0.0, 1.0, N_SAMPLES + 1)
        p = a + t[:, None] * (b - a)
        h = T.height(p[:, 0], p[:, 1])
        dense = float(np.sum(0.5 * (h[1:] + h[:-1])) / N_SAMPLES)
        assert got[k, 0] == pytest.approx(dense, abs=lipschitz(T, a, b) / N_SAMPLES + tol)


def test_mean_height_of_a_plane_is_the_midpoint_height() -> None:
    yy, xx = np.mgrid[0:20, 0:30].astype(float)
    T = Terrain(2.0 * xx - 0.5 * yy + 3.0, x0=-4.0, y0=2.0, dx=2.0, dy=0.5)
    a, b = np.array([-3.0, 3.0, 0.0]), np.array([50.0, 10.5, 7.0])
    mid = 0.5 * (a + b)
    assert T.mean_height(np.array([[a, b]]))[0, 0] == pytest.approx(float(T.height(mid[0], mid[1])))


def test_mean_height_outside_grid_uses_the_terrain_height() -> None:
    T = Terrain(np.arange(12.0).reshape(3, 4) ** 1.5)
    # a zero-length segment off the grid: its mean is the terrain height at that point
    p = np.array([[[-5.0, 1.0, 0.0], [-5.0, 1.0, 0.0]]])
    assert T.mean_height(p)[0, 0] == pytest.approx(float(T.height(-5.0, 1.0)))
    # a segment partly off the grid: the mean of height() along it (Simpson per piece is exact)
    a, b = np.array([-5.0, 1.0, 0.0]), np.array([2.0, 1.5, 0.0])
    ts = np.concatenate(([0.0], [5.0 / 7.0 + k / 7.0 for k in range(3)], [1.0]))
    total = 0.0
    for ta, tb in itertools.pairwise(ts):
        tt = np.array([ta, 0.5 * (ta + tb), tb])
        q = a + tt[:, None] * (b - a)
        h = T.height(q[:, 0], q[:, 1])
        total += (tb - ta) / 6.0 * (h[0] + 4 * h[1] + h[2])
    assert T.mean_height(np.array([[a, b]]))[0, 0] == pytest.approx(total)


@FAST
@given(seed=SEEDS)
def test_mean_height_kernel_gives_the_bits_of_its_sorted_reference(seed: int) -> None:
    """The merged-breakpoint kernel against the first form (breakpoints sorted per segment), on
    segments inside and off the grid, along grid lines, through grid nodes and of zero length."""
    from uavplan.world import _terrain_kernels as tk

    rng = np.random.default_rng(seed)
    H = rng.normal(size=(int(rng.integers(2, 40)), int(rng.integers(2, 40)))) * 100.0
    H.setflags(write=False)  # as a Terrain's heights: the kernel's production signature
    P, N = 12, 9
    u = rng.uniform(-5.0, H.shape[1] + 4.0, (P, N))
    v = rng.uniform(-5.0, H.shape[0] + 4.0, (P, N))
    u[1] = np.round(u[1])  # through grid lines in u
    v[2] = np.round(v[2] * 2.0) / 2.0
    u[3, 1], v[3, 1] = u[3, 0], v[3, 0]  # zero length
    u[4, 2] = u[4, 1]  # along a column
    v[5, 3] = v[5, 2]  # along a row
    u[6], v[6] = np.round(u[6]), np.round(v[6])  # node to node, diagonals through nodes
    np.testing.assert_array_equal(
        tk.mean_height_batch(H, u, v), tk.mean_height_batch_reference(H, u, v)
    )


# ----------------------------------------------------------------------------- loading
def test_npy_round_trip(tmp_path) -> None:
    T = random_terrain(5)
    f = tmp_path / "dem.npy"
    np.save(f, T.heights)
    L = Terrain.from_file(f, cell_size=2.5, origin=(10.0, -3.0))
    np.testing.assert_array_equal(L.heights, T.heights)
    assert (L.x0, L.y0, L.dx, L.dy) == (10.0, -3.0, 2.5, 2.5)
    assert L.name == "dem.npy"
    d = Terrain.from_file(f)
    assert (d.x0, d.y0, d.dx, d.dy) == (0.0, 0.0, 1.0, 1.0)


def test_npz_round_trip(tmp_path) -> None:
    T = random_terrain(6)
    f = tmp_path / "dem.npz"
    np.savez(f, heights=T.heights, dx=T.dx, dy=T.dy, x0=T.x0, y0=T.y0)
    L = Terrain.from_file(f)
    np.testing.assert_array_equal(L.heights, T.heights)
    assert (L.x0, L.y0, L.dx, L.dy) == (T.x0, T.y0, T.dx, T.dy)
    pts = np.array([[[T.x0 + 1.3, T.y0 + 2.2, 0.0], [T.extent[1] - 0.1, T.extent[3], 5.0]]])
    np.testing.assert_array_equal(L.min_clearance(pts), T.min_clearance(pts))
    # other array names, an explicit key, dx alone
    g = tmp_path / "other.npz"
    np.savez(g, elevation=T.heights, custom=2 * T.heights, dx=3.0)
    E = Terrain.from_file(g)
    np.testing.assert_array_equal(E.heights, T.heights)
    assert (E.dx, E.dy) == (3.0, 3.0)
    K = Terrain.from_file(g, key="custom", origin=(1.0, 2.0))
    np.testing.assert_array_equal(K.heights, 2 * T.heights)
    assert (K.x0, K.y0) == (1.0, 2.0)
    with pytest.raises(TerrainError):
        Terrain.from_file(g, key="missing")


def test_from_file_errors(tmp_path) -> None:
    with pytest.raises(TerrainError):
        Terrain.from_file(tmp_path / "nope.npy")
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"not an npy file")
    with pytest.raises(TerrainError):
        Terrain.from_file(bad)
    one_d = tmp_path / "one_d.npy"
    np.save(one_d, np.arange(5.0))
    with pytest.raises(TerrainError):
        Terrain.from_file(one_d)
    txt = tmp_path / "dem.txt"
    txt.write_text("1 2\n3 4\n")
    with pytest.raises(TerrainError):
        Terrain.from_file(txt)
    with pytest.raises(TerrainError):
        Terrain(np.array([[0.0, np.nan], [1.0, 2.0]]))
    with pytest.raises(TerrainError):
        Terrain(np.zeros((3, 3)), dx=0.0)


def test_builtin_spso_map() -> None:
    T = Terrain.builtin("spso")
    assert T.shape == (879, 1045)
    assert (T.x0, T.y0, T.dx, T.dy) == (1.0, 1.0, 1.0, 1.0)
    assert T.extent == (1.0, 1045.0, 1.0, 879.0)
    assert T.heights.min() >= 0.0
    assert 290.0 < T.heights.max() < 297.0
    # SPSO reads H(round(y), round(x)) with 1-based indices: node (1, 1) is heights[0, 0]
    assert float(T.height_nearest(1.0, 1.0)) == T.heights[0, 0]
    assert float(T.height_nearest(200.0, 100.0)) == T.heights[99, 199]
    assert float(T.height(200.0, 100.0)) == T.heights[99, 199]


@pytest.mark.parametrize(("name", "shape"), [("jacksboro", (344, 403)), ("topobathy", (91, 120))])
def test_builtin_matplotlib_maps(name: str, shape: tuple[int, int]) -> None:
    T = Terrain.builtin(name)
    assert T.shape == shape
    assert T.dx > 0 and T.dy > 0
    assert np.all(np.isfinite(T.heights))
    if name == "topobathy":
        assert T.heights.min() == 0.0  # sea level clipped
    with pytest.raises(TerrainError):
        Terrain.builtin("nowhere")


def test_downsample_keeps_nodes() -> None:
    T = random_terrain(9)
    D = T.downsample(3)
    assert D.dx == 3 * T.dx and D.dy == 3 * T.dy
    np.testing.assert_array_equal(D.heights, T.heights[::3, ::3])


@FAST
@given(seed=SEEDS)
def test_stays_within_agrees_with_max_clearance(seed: int) -> None:
    T = random_terrain(seed)
    rng = np.random.default_rng(seed + 5)
    segs = random_segments(T, rng, 12)
    top = T.max_clearance(segs)
    finite = np.isfinite(top)
    for ceiling in (np.nanmedian(np.where(finite, top, np.nan)), float(np.max(top[finite])) + 1):
        got = T.stays_within(segs, ceiling)
        # a segment whose top is the ceiling to within rounding may go either way (the two
        # kernels round differently: seed 61503 has one 5e-15 m over a median ceiling of 3)
        clear = finite & (np.abs(top - ceiling) > 1e-9 * (1.0 + abs(ceiling)))
        np.testing.assert_array_equal(got[clear], top[clear] <= ceiling)


def test_height_kernel_equals_the_numpy_reference():
    from uavplan.world.terrain import Terrain

    t = Terrain.builtin("spso")
    rng = np.random.default_rng(3)
    lo_x, hi_x, lo_y, hi_y = t.extent
    x = rng.uniform(lo_x - 50, hi_x + 50, size=(37, 11))  # some outside the grid
    y = rng.uniform(lo_y - 50, hi_y + 50, size=(37, 11))
    x[0, :3], y[0, :3] = lo_x, hi_y  # on the edges
    np.testing.assert_array_equal(t.height(x, y), t.height_reference(x, y))
    assert t.height(x[0, 0], y[0, 0]).shape == ()
    np.testing.assert_array_equal(t.height(x[:, 0], 5.0), t.height_reference(x[:, 0], 5.0))


def test_fast_cell_coordinates_equal_the_numpy_ones():
    from uavplan.world.terrain import Terrain

    t = Terrain.builtin("spso")
    rng = np.random.default_rng(4)
    lo_x, hi_x, lo_y, hi_y = t.extent
    p = np.stack([rng.uniform(lo_x, hi_x, (20, 9)), rng.uniform(lo_y, hi_y, (20, 9))], axis=-1)
    p[0, 0] = (lo_x + 1e-13, hi_y - 1e-12)  # within the snapping tolerance of the edges
    p[0, 1] = (hi_x * (1 + 1e-16), lo_y)
    u, v = t._uv_fast(p)
    u2, v2 = t._uv_snapped(p[..., 0], p[..., 1])
    np.testing.assert_array_equal(u, u2)
    np.testing.assert_array_equal(v, v2)


@pytest.mark.parametrize("name", ["hrmaga-spso", "jacksboro", "topobathy"])
def test_the_mean_height_bound_is_never_above_the_exact_mean(name: str) -> None:
    """``mean_height_lower`` (the block minima under each segment) is at most ``mean_height``
    on random paths: long and short segments, repeated points, points off the grid; and its
    blocks hold the least node of each block, edges included (brute force)."""
    from uavplan.scenarios import resolve

    sc = resolve(name)
    t = sc.terrain
    assert t is not None
    lo, hi = np.asarray(sc.bounds.lo), np.asarray(sc.bounds.hi)
    span = hi - lo
    rng = np.random.default_rng(7)
    P = rng.uniform(lo - 0.1 * span, hi + 0.1 * span, (400, 10, 3))
    P[:150, :, :2] = P[:150, :1, :2] + rng.uniform(-3 * t.dx, 3 * t.dx, (150, 10, 2))
    P[150:200, 4] = P[150:200, 3]  # a repeated point: a segment of length 0
    exact, low = t.mean_height(P), t.mean_height_lower(P)
    assert np.all(low <= exact)
    assert np.mean(exact - low) < np.ptp(t.heights)  # a bound, not a constant
    B, H = t.LOWER_BLOCK, t.heights
    blocks = t._block_min
    for j, i in ((0, 0), (blocks.shape[0] - 1, blocks.shape[1] - 1), (1, 2)):
        want = H[j * B : j * B + B + 1, i * B : i * B + B + 1].min()
        assert blocks[j, i] == want
