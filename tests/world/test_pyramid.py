"""The terrain pyramid: a coarse map never below the fine one, so a coarse clear segment is
clear at full resolution."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.world.pyramid import conservative_level, pyramid_factors, terrain_pyramid
from uavplan.world.terrain import Terrain


def _terrain(seed: int, ny: int, nx: int) -> Terrain:
    rng = np.random.default_rng(seed)
    H = rng.normal(0, 30, (ny, nx)).cumsum(0).cumsum(1) * 0.05 + rng.uniform(0, 50, (ny, nx))
    return Terrain(H, x0=-3.0, y0=7.0, dx=2.5, dy=4.0)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    ny=st.integers(2, 40),
    nx=st.integers(2, 40),
    factor=st.integers(1, 12),
)
def test_coarse_heights_never_below_fine(seed: int, ny: int, nx: int, factor: int) -> None:
    t = _terrain(seed, ny, nx)
    lv = conservative_level(t, factor)
    rng = np.random.default_rng(seed + 1)
    x0, x1, y0, y1 = t.extent
    # points inside and somewhat beyond the fine grid
    x = rng.uniform(x0 - 10, x1 + 10, 2000)
    y = rng.uniform(y0 - 10, y1 + 10, 2000)
    assert np.all(lv.feasibility.height(x, y) >= t.height(x, y) - 1e-9)
    # and at every fine node (where the fine map is exact)
    X, Y = np.meshgrid(x0 + np.arange(nx) * t.dx, y0 + np.arange(ny) * t.dy)
    assert np.all(lv.feasibility.height(X, Y) >= t.heights - 1e-9)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), factor=st.integers(2, 9))
def test_a_segment_clear_of_the_coarse_map_is_clear_of_the_fine_one(seed: int, factor: int) -> None:
    t = _terrain(seed, 31, 37)
    lv = conservative_level(t, factor)
    rng = np.random.default_rng(seed)
    x0, x1, y0, y1 = t.extent
    n = 400
    lo, hi = float(t.heights.min()), float(t.heights.max()) + 20.0

    def pts() -> np.ndarray:
        return np.column_stack(
            [rng.uniform(x0, x1, n), rng.uniform(y0, y1, n), rng.uniform(lo, hi, n)]
        )

    a, b = pts(), pts()
    seg = np.stack([a, b], axis=1)
    coarse = lv.feasibility.clears(seg)[:, 0]
    fine = t.clears(seg)[:, 0]
    assert coarse.any() and not np.all(fine)  # the test sees both kinds
    assert np.all(fine[coarse])  # never clear at the coarse level and colliding at the fine


def test_cost_map_is_the_fine_map_sampled_at_the_coarse_nodes() -> None:
    t = _terrain(3, 21, 25)
    lv = conservative_level(t, 4)
    assert lv.cost.heights.shape == lv.feasibility.heights.shape == (6, 7)
    assert np.allclose(lv.cost.heights[:5, :6], t.heights[::4, ::4][:5, :6])
    assert np.all(lv.feasibility.heights >= lv.cost.heights)


def test_factors_of_the_builtin_maps() -> None:
    assert pyramid_factors((879, 1045), 3) == [26, 5, 1]  # spso: ~40 cells per side first
    assert pyramid_factors((344, 403), 3) == [10, 3, 1]  # jacksboro
    assert pyramid_factors((91, 120), 3) == [3, 2, 1]  # topobathy
    assert pyramid_factors((10, 10), 3) == [1, 1, 1]
    levels = terrain_pyramid(Terrain.builtin("jacksboro"))
    assert [lv.factor for lv in levels] == [10, 3, 1]
    assert max(levels[0].feasibility.shape) == 42
    with pytest.raises(ValueError, match="factor must be >= 1"):
        conservative_level(t := _terrain(0, 5, 5), 0)
    assert conservative_level(t, 1).feasibility is t


def test_relaxed_near_the_fixed_ends_only() -> None:
    from uavplan.world.pyramid import relaxed_near

    t = _terrain(5, 41, 41)
    lv = conservative_level(t, 5)
    ends = np.array([[t.x0 + 1.0, t.y0 + 1.0, 0.0]])
    r = relaxed_near(lv, ends)
    changed = r.heights != lv.feasibility.heights
    assert changed.any() and np.all(r.heights <= lv.feasibility.heights)
    assert np.array_equal(r.heights[changed], lv.cost.heights[changed])
    js, is_ = np.nonzero(changed)
    assert js.max() <= 2 and is_.max() <= 2  # the end's cell and one ring around it
    assert relaxed_near(conservative_level(t, 1), ends) is t
