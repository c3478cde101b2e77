"""The obstacle index (uniform grid over boxes) against every pair: the cells listing each box,
the candidates of segments (conservative, each pair once), and the 2-D scene pass on the grid
against the every-pair pass bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.world import geometry as G
from uavplan.world.obstacle_index import box_grid, segment_candidates

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=30, deadline=None)


def _boxes(rng: np.random.Generator, n: int, size: float) -> tuple[np.ndarray, ...]:
    """n boxes in a square of ``size``: mostly small, a few much larger than a cell, some
    degenerate (a point, a horizontal line)."""
    c = rng.uniform(0, size, (n, 2))
    half = rng.uniform(0.001, 0.02, (n, 2)) * size
    big = rng.random(n) < 0.05
    half[big] *= rng.uniform(5, 20, (int(big.sum()), 1))
    half[rng.random(n) < 0.05] = 0.0
    return c[:, 0] - half[:, 0], c[:, 1] - half[:, 1], c[:, 0] + half[:, 0], c[:, 1] + half[:, 1]


def _segments(rng: np.random.Generator, m: int, size: float, grid: np.ndarray) -> tuple:
    """m segments: random, short, zero-length, horizontal, vertical, diagonal, and lying on
    cell borders and through cell corners."""
    a = rng.uniform(-0.1 * size, 1.1 * size, (m, 2))
    b = a + rng.normal(0, 0.05 * size, (m, 2)) * rng.choice([0.1, 1.0, 10.0], (m, 1))
    x0, y0, h = grid[0], grid[1], grid[2]
    k = m // 8
    b[:k] = a[:k]  # zero length
    b[k : 2 * k, 1] = a[k : 2 * k, 1]  # horizontal
    b[2 * k : 3 * k, 0] = a[2 * k : 3 * k, 0]  # vertical
    cells = rng.integers(0, 8, (k, 2))
    a[3 * k : 4 * k, 1] = y0 + cells[:, 1] * h  # along a row border
    b[3 * k : 4 * k, 1] = a[3 * k : 4 * k, 1]
    a[4 * k : 5 * k, 0] = x0 + cells[:, 0] * h  # along a column border
    b[4 * k : 5 * k, 0] = a[4 * k : 5 * k, 0]
    a[5 * k : 6 * k] = np.c_[x0 + cells[:, 0] * h, y0 + cells[:, 1] * h]  # from a corner
    b[5 * k : 6 * k] = a[5 * k : 6 * k] + h * rng.integers(-3, 4, (k, 1))  # through corners
    return a, b


def _meets(a: np.ndarray, b: np.ndarray, boxes: tuple[np.ndarray, ...]) -> np.ndarray:
    """(m, n): whether segment i meets closed box j (Liang-Barsky on each pair)."""
    x_lo, y_lo, x_hi, y_hi = (np.asarray(v)[None, :] for v in boxes)
    ax, ay = a[:, :1], a[:, 1:2]
    dx, dy = b[:, :1] - ax, b[:, 1:2] - ay
    t0 = np.zeros((len(a), len(x_lo[0])))
    t1 = np.ones_like(t0)
    ok = np.ones_like(t0, dtype=bool)
    for d, p, lo, hi in ((dx, ax, x_lo, x_hi), (dy, ay, y_lo, y_hi)):
        flat = np.broadcast_to(d == 0, t0.shape)
        ok &= ~flat | ((p >= lo) & (p <= hi))
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo - p) / d, (hi - p) / d
        t0 = np.where(flat, t0, np.maximum(t0, np.minimum(ta, tb)))
        t1 = np.where(flat, t1, np.minimum(t1, np.maximum(ta, tb)))
    return np.asarray(ok & (t0 <= t1))


@FAST
@given(seed=SEEDS, n=st.integers(1, 300))
def test_every_box_is_listed_in_every_cell_it_meets(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    boxes = _boxes(rng, n, 1000.0)
    (x0, y0, h, nx, ny), starts, items, span = box_grid(*boxes)
    nx, ny = int(nx), int(ny)
    assert nx <= 1024 and ny <= 1024
    listed: dict[int, set[int]] = {}
    for k in range(nx * ny):
        cell = items[starts[k] : starts[k + 1]]
        assert np.all(np.diff(cell) > 0)  # increasing, each once
        for j in cell:
            listed.setdefault(int(j), set()).add(k)
    for j in range(n):
        i0, j0, i1, j1 = span[j]
        assert listed[j] == {b * nx + a for a in range(i0, i1 + 1) for b in range(j0, j1 + 1)}
        assert x0 + i0 * h <= boxes[0][j] and boxes[2][j] <= x0 + (i1 + 1) * h
        assert y0 + j0 * h <= boxes[1][j] and boxes[3][j] <= y0 + (j1 + 1) * h


@FAST
@given(seed=SEEDS, n=st.integers(1, 300))
def test_candidates_hold_every_box_a_segment_meets_once(seed: int, n: int) -> None:
    """Conservative (every box a segment meets is a candidate), each pair once, sorted; with
    zero-length segments, segments along cell borders and through cell corners, off the grid,
    and boxes larger than a cell."""
    rng = np.random.default_rng(seed)
    boxes = _boxes(rng, n, 1000.0)
    grid = box_grid(*boxes)
    a, b = _segments(rng, 240, 1000.0, grid[0])
    seg, box = segment_candidates(grid, a, b)
    pairs = seg * n + box
    assert len(np.unique(pairs)) == len(pairs)  # each pair once
    assert np.all(np.diff(box * len(a) + seg) > 0)  # sorted by box, then segment
    want = np.argwhere(_meets(a, b, boxes))
    got = set(pairs.tolist())
    missing = [(int(i), int(j)) for i, j in want if int(i) * n + int(j) not in got]
    assert not missing
    # and not every pair: the index does prune (most boxes are far from most segments)
    assert len(pairs) < 0.5 * len(a) * n or n < 8


def test_candidates_refuse_non_finite_segments() -> None:
    grid = box_grid(np.zeros(1), np.zeros(1), np.ones(1), np.ones(1))
    with pytest.raises(ValueError, match="finite"):
        segment_candidates(grid, np.array([[0.0, np.nan]]), np.array([[1.0, 1.0]]))


def _scene(rng: np.random.Generator, J: int, K: int, size: float) -> tuple[np.ndarray, ...]:
    cc = rng.uniform(0, size, (J, 2))
    cr = rng.uniform(0.005, 0.05, J) * size * rng.choice([1.0, 1.0, 8.0], J)
    polys = []
    for _ in range(K):
        n = int(rng.integers(3, 10))
        c = rng.uniform(0, size, 2)
        r = rng.uniform(0.005, 0.06) * size * rng.choice([1.0, 1.0, 8.0])
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        rad = r * rng.uniform(0.3, 1.0, n)
        polys.append(c + np.c_[rad * np.cos(ang), rad * np.sin(ang)])
    verts, starts = G.pack_polygons(polys)
    margins = np.where(rng.random(K) < 0.2, rng.uniform(0, 0.02 * size, K), 0.0)
    return cc, cr, verts, starts, margins


@FAST
@given(seed=SEEDS, J=st.integers(0, 150), K=st.integers(0, 150))
def test_scene_pass_on_the_grid_equals_every_pair_bit_for_bit(seed: int, J: int, K: int) -> None:
    """The 2-D scene pass with the grid (from GRID_MIN_OBSTACLES obstacles on) returns the
    every-pair pass's bits: each segment's obstacles are taken in index order. Worlds with
    circles and convex, non-convex and margin polygons of very different sizes; paths with
    zero-length, horizontal and vertical segments, nodes on vertices and circles, off the box."""
    if J + K == 0:
        return
    rng = np.random.default_rng(seed)
    size = 1000.0
    w = _scene(rng, J, K, size)
    P, N = 30, 10
    paths = rng.uniform(-0.1 * size, 1.1 * size, (P, N, 2))
    paths[:8] = np.cumsum(rng.normal(0, 0.03 * size, (8, N, 2)), axis=1) + 0.5 * size
    paths[8, 3] = paths[8, 2]
    paths[9, :, 1] = 0.5 * size
    paths[10, :, 0] = 0.3 * size
    if K:
        paths[11, 2:4] = w[2][:2]  # along a polygon's first edge
    if J:
        paths[12, 4] = w[0][0] + [w[1][0], 0.0]  # a node on a circle
    paths = np.ascontiguousarray(paths)
    lo, hi = np.zeros(2), np.full(2, size)
    every = G.scene2d_batch(paths, *w, lo, hi, G.scene_prep(*w, gridded=False))
    prep = G.scene_prep(*w, gridded=True)
    assert prep[-4][3] > 0  # the grid is built
    gridded = G.scene2d_batch(paths, *w, lo, hi, prep)
    for a, b in zip(every, gridded, strict=True):
        np.testing.assert_array_equal(a, b)
    bad = paths.copy()
    bad[0, 1] = np.nan  # not finite: every pair, same answers for the others
    got = G.scene2d_batch(bad, *w, lo, hi, prep)
    np.testing.assert_array_equal(got[1][1:], gridded[1][1:])


@FAST
@given(seed=SEEDS, J=st.integers(1, 200), dim=st.sampled_from([2, 3]))
def test_danger_length_on_the_grid_equals_every_pair(seed: int, J: int, dim: int) -> None:
    """HR-MAGA's length inside danger areas: from GRID_MIN_OBSTACLES areas on the grid-indexed
    pass, against the sum of every segment-circle fraction times the segment's length (1e-12
    relative); below it exactly that sum. With zero-length and vertical segments inside areas."""
    from uavplan.problems import costs as C

    rng = np.random.default_rng(seed)
    size = 1000.0
    cc = rng.uniform(0, size, (J, 2))
    cr = rng.uniform(0.005, 0.05, J) * size * rng.choice([1.0, 1.0, 8.0], J)
    P, N = 20, 9
    paths = np.cumsum(rng.normal(0, 0.05 * size, (P, N, dim)), axis=1) + 0.5 * size
    paths[0] = rng.uniform(-0.1 * size, 1.1 * size, (N, dim))
    paths[1, 3] = paths[1, 2]  # zero length
    paths[2, 4, :2] = paths[2, 3, :2] = cc[0]  # vertical (3-D) or zero length, at a centre
    paths = np.ascontiguousarray(paths)
    want = (
        G.segment_circle_inside_fraction(paths, cc, cr) * C.segment_lengths(paths)[..., None]
    ).sum(axis=(1, 2))
    got = C.danger_length_cost(paths, cc, cr)
    if J < G.GRID_MIN_OBSTACLES:
        np.testing.assert_array_equal(got, want)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    grid = G.circle_grid(cc[:, 0], cc[:, 1], cr)
    circ = np.ascontiguousarray(np.stack([cc[:, 0], cc[:, 1], cr]))
    np.testing.assert_allclose(G.circle_inside_grid(paths, circ, *grid), want, rtol=1e-12,
                               atol=1e-9)  # fmt: skip
    assert got[2] > 0 or dim == 2
