"""Test-session settings. Each pytest-xdist worker runs its kernels on one Numba thread: with
``-n auto`` the workers already use every core, and the workers' thread pools competing for the
same cores made the suite 2.3x slower here (488 s against 211 s on 2 cores). An explicit
``NUMBA_NUM_THREADS`` in the environment wins."""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
