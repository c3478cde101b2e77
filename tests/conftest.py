"""Test-session settings. Each pytest-xdist worker runs its kernels on one Numba thread: with
``-n auto`` the workers already use every core, and the workers' thread pools competing for the
same cores made the suite 2.3x slower here (488 s against 211 s on 2 cores). An explicit
``NUMBA_NUM_THREADS`` in the environment wins."""

from __future__ import annotations

import os
import sys

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
# Cached bytecode even where the environment says not to write it (PYTHONDONTWRITEBYTECODE, as on
# the machines this suite is developed on): without it every pytest process, each xdist worker
# included, rewrites the asserts of every test module again, 7-8 s of a run's start (pytest
# caches a rewritten module only where Python may write bytecode).
sys.dont_write_bytecode = False
