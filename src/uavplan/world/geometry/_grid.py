"""What the grid-indexed 2-D kernels share: the block of paths they run side by side, the
obstacle count from which they use the grid, and the candidates a segment's cells list."""

from __future__ import annotations

import numpy as np
from numba import njit

from uavplan.world.obstacle_index import segment_boxes

#: The indexed and blocked kernels: paths per block (the lanes the 2-D scene pass runs its tests
#: in side by side; the block's scratch arrays are allocated once).
BLOCK = 64
#: :func:`scene2d_batch`: from this many circles and polygons together on, a uniform grid
#: (:mod:`uavplan.world.obstacle_index`) picks the obstacles near each segment; below it every
#: pair is tested (the sums over obstacles then keep their order, so results stay bit for bit
#: those of the every-pair pass).
GRID_MIN_OBSTACLES = 64


@njit(cache=True, inline="always")
def _sort_head(a, n):  # pragma: no cover - numba
    """Sort ``a[:n]`` in place (insertion sort for the usual handful, else NumPy's)."""
    if n > 32:
        a[:n] = np.sort(a[:n])
        return
    for q in range(1, n):
        key = a[q]
        r = q - 1
        while r >= 0 and a[r] > key:
            a[r + 1] = a[r]
            r -= 1
        a[r + 1] = key


@njit(cache=True, inline="always")
def _grid_candidates(
    grid, gstarts, gitems, gspan, J, ax, ay, bx, by, buf, cidx, kidx
):  # pragma: no cover - numba
    """The circles (into ``cidx``) and polygons (into ``kidx``, as ``item - J``) listed in the
    cells segment a->b crosses (:func:`uavplan.world.obstacle_index.segment_boxes`, into
    ``buf``), each once and in increasing order (so that sums over them keep the every-pair
    order); returns their counts."""
    n = segment_boxes(grid, gstarts, gitems, gspan, ax, ay, bx, by, buf)
    n_c = 0
    n_k = 0
    for q in range(n):
        b = buf[q]
        if b < J:
            cidx[n_c] = b
            n_c += 1
        else:
            kidx[n_k] = b - J
            n_k += 1
    _sort_head(cidx, n_c)
    _sort_head(kidx, n_k)
    return n_c, n_k
