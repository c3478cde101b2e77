"""Arrays as the kernels take them (:mod:`uavplan.world.kernel_arrays`): read-only and
writable inputs reach a kernel with one signature, so it compiles once."""

from __future__ import annotations

import numpy as np

from uavplan.world.kernel_arrays import read_only, writable


def test_writable_and_read_only_copy_only_where_needed() -> None:
    a = np.arange(6.0).reshape(2, 3)
    assert writable(a) is a
    ro = a.view()
    ro.setflags(write=False)
    w = writable(ro)
    assert w.flags.writeable and w.flags.c_contiguous and np.shares_memory(w, a) is False
    r = read_only(a)
    assert not r.flags.writeable and np.shares_memory(r, a) and a.flags.writeable
    assert writable(np.arange(4)).dtype == np.float64  # int input: float64
    assert read_only(a[:, ::2]).flags.c_contiguous


def test_read_only_paths_reach_the_kernels_as_writable_ones() -> None:
    """The 2-D scene pass and the reservation table's query, asked with a read-only path (a
    trajectory's points) and with a writable one: one signature each."""
    from uavplan.world.geometry.scene2d import scene2d_batch, scene2d_kernel
    from uavplan.world.reservations import ReservationTable, _query

    rng = np.random.default_rng(0)
    paths = rng.uniform(0, 100, (4, 6, 2))
    centers, radii = rng.uniform(0, 100, (3, 2)), rng.uniform(1, 5, 3)
    verts, starts = np.zeros((0, 2)), np.zeros(1, dtype=np.int64)
    margins = np.zeros(0)
    lo, hi = np.zeros(2), np.full(2, 100.0)
    n0 = len(scene2d_kernel.serial.signatures)
    scene2d_batch(paths, centers, radii, verts, starts, margins, lo, hi)
    paths.setflags(write=False)
    scene2d_batch(paths, centers, radii, verts, starts, margins, lo, hi)
    assert len(scene2d_kernel.serial.signatures) <= max(n0, 1)
    table = ReservationTable(np.zeros(3), np.full(3, 200.0), (10.0, 10.0, 5.0), dt=5.0)
    pts = np.stack([np.linspace(0, 100, 11), np.zeros(11), np.full(11, 50.0)], axis=1)
    t = np.linspace(0.0, 100.0, 11)
    table.add("a", pts, t)
    q = pts + np.array([0.0, 3.0, 0.0])
    table.conflicts(q, t)
    q.setflags(write=False)
    t.setflags(write=False)
    table.conflicts(q, t)
    assert len(_query.serial.signatures) == 1, _query.serial.signatures
