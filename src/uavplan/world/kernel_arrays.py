"""Arrays as the Numba kernels take them: one signature per kernel, so one compilation.

Numba compiles a kernel once per signature, and an array's signature holds its dtype, its
layout and whether it is read-only: a read-only path (a trajectory's points, a view of a
frozen buffer) and a writable one of the same shape compile the same kernel twice, 2-20 s
each with an empty cache (the first plan on a machine, every fresh checkout). Paths and
times are therefore passed writable (copied when read-only) and grids of heights read-only
(a view, no copy), whichever the caller had.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def writable(a: Any) -> NDArray[np.float64]:
    """``a`` as a C-contiguous, writable float64 array (a copy only where it is not one)."""
    return np.require(a, np.float64, ["C", "W"])


def read_only(a: Any) -> NDArray[np.float64]:
    """``a`` as a C-contiguous, read-only float64 array (a read-only view; the caller's array
    keeps its flags)."""
    v = np.ascontiguousarray(a, dtype=np.float64).view()
    v.setflags(write=False)
    return v
