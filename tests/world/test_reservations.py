"""The reservation table finds exactly the conflicts a brute-force scan finds."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from uavplan.world.reservations import ReservationTable, _split, split_pieces, window_min_dist2

LO = np.array([0.0, 0.0, 0.0])
HI = np.array([400.0, 400.0, 100.0])


def _random_path(rng: np.random.Generator, n: int = 6) -> np.ndarray:
    pts = rng.uniform(LO, HI, size=(n, 3))
    pts[:, 2] = rng.uniform(40, 60, size=n)  # a thin layer, so that paths meet often
    return pts


def _times(points: np.ndarray, speed: float = 20.0, t0: float = 0.0) -> np.ndarray:
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return t0 + np.concatenate([[0.0], np.cumsum(seg)]) / speed


def _dense_min_distance(pa, ta, pb, tb, step=0.002):
    """Sampled reference: both positions at common instants (fine grid)."""
    lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
    if lo > hi:
        return np.inf
    t = np.linspace(lo, hi, max(2, int((hi - lo) / step)))
    a = np.stack([np.interp(t, ta, pa[:, d]) for d in range(3)], axis=1)
    b = np.stack([np.interp(t, tb, pb[:, d]) for d in range(3)], axis=1)
    return float(np.min(np.linalg.norm(a - b, axis=1)))


def test_pieces_stay_in_one_bucket_and_cover_the_path():
    rng = np.random.default_rng(1)
    p = _random_path(rng)
    t = _times(p)
    p0, p1, t0, t1, k = split_pieces(p, t, 0.7)
    assert np.all(t1 > t0)
    assert np.all(np.floor(t0 / 0.7 + 1e-12) == k)
    assert np.all(t1 <= (k + 1) * 0.7 + 1e-12)
    assert t0[0] == t[0] and t1[-1] == t[-1]
    np.testing.assert_allclose(t0[1:], t1[:-1])
    np.testing.assert_allclose(p0[1:], p1[:-1], atol=1e-9)


def test_entries_stay_sorted_as_one_stable_sort_of_all_would_sort_them():
    """Each ``add`` merges its entries into the sorted ones (not a sort of all of them): by
    key, and within a key in the order added (a later UAV's pieces have larger indices)."""
    rng = np.random.default_rng(5)
    table = ReservationTable(LO, HI, separation=10.0, dt=1.0)
    for i in range(15):
        p = _random_path(rng)
        table.add(f"u{i}", p, _times(p, t0=rng.uniform(0, 5)), tolerance=0.1 * (i % 2))
    keys, idx = table._keys, table._idx
    assert np.all(np.diff(keys) >= 0)
    same = np.diff(keys) == 0
    assert same.any() and np.all(np.diff(idx)[same] > 0)
    order = np.lexsort((idx, keys))  # the stable sort of every entry, added in index order
    np.testing.assert_array_equal(order, np.arange(len(keys)))


@pytest.mark.parametrize("dt", [0.25, 1.0, 3.0])
@pytest.mark.parametrize("cell", [None, 7.0, 300.0])
def test_conflicts_equal_brute_force(dt, cell):
    rng = np.random.default_rng(int(dt * 100) + (0 if cell is None else int(cell)))
    table = ReservationTable(LO, HI, separation=10.0, dt=dt, cell=cell)
    _agrees_with_brute_force(table, rng, _random_path, 12, 20.0)


def _agrees_with_brute_force(table, rng, path, n_reserved, speed):
    """Reserve ``n_reserved`` random timed paths, then check 60 candidates: conflicts and
    minimum distances equal the brute-force reference's, in a case neither trivial nor
    saturated."""
    for i in range(n_reserved):
        p = path(rng)
        table.add(f"u{i}", p, _times(p, speed=speed, t0=rng.uniform(0, 5)))
    cands = np.stack([path(rng) for _ in range(60)])
    times = np.stack([_times(c, speed=speed, t0=rng.uniform(0, 5)) for c in cands])
    got = table.conflicts(cands, times)
    mind = table.min_distance(cands, times)
    ref = np.array([table.min_distance_reference(c, t) for c, t in zip(cands, times, strict=True)])
    close = ref < table.separation
    np.testing.assert_array_equal(got, close)
    np.testing.assert_allclose(mind[close], ref[close], rtol=1e-9, atol=1e-9)
    assert 5 < close.sum() < 55


def test_exact_distance_agrees_with_dense_sampling():
    rng = np.random.default_rng(7)
    table = ReservationTable(LO, HI, separation=10.0, dt=1.0)
    pa = _random_path(rng)
    ta = _times(pa)
    table.add("a", pa, ta)
    for _ in range(30):
        pb = _random_path(rng)
        tb = _times(pb, t0=rng.uniform(0, 3))
        exact = table.min_distance_reference(pb, tb)
        dense = _dense_min_distance(pa, ta, pb, tb)
        assert exact <= dense + 1e-9
        assert dense - exact < 0.05  # 40 m/s closing speed x 0.002 s sampling / 2 + slack


def test_head_on_crossing_between_samples_is_a_conflict():
    # Two UAVs swap places along x at 20 m/s: they meet at t = 5 s, between 1-s samples of the
    # positions (4.5 s and 5.5 s would be 20 m apart).
    table = ReservationTable(LO, HI, separation=10.0, dt=1.0)
    a = np.array([[0.0, 100.0, 50.0], [200.0, 100.0, 50.0]])
    table.add("a", a, np.array([0.0, 10.0]))
    b = a[::-1].copy()
    tb = np.array([0.5, 10.5])
    assert table.conflicts(b[None], tb[None])[0]
    # The same path one second later in an offset lane (12 m) is clear.
    b2 = b + np.array([0.0, 12.0, 0.0])
    assert not table.conflicts(b2[None], tb[None])[0]
    np.testing.assert_allclose(table.min_distance(b2[None], tb[None]), [12.0], atol=1e-9)


def test_landed_uav_is_no_hazard_and_boundary_instants_count():
    table = ReservationTable(LO, HI, separation=10.0, dt=1.0)
    # a lands at (100, 100, 50) at t = 5 exactly (a bucket boundary)
    a = np.array([[0.0, 100.0, 50.0], [100.0, 100.0, 50.0]])
    table.add("a", a, np.array([0.0, 5.0]))
    # b takes off from there at t = 5: they share that instant at distance 0
    b = np.array([[100.0, 100.0, 50.0], [100.0, 300.0, 50.0]])
    assert table.conflicts(b[None], np.array([[5.0, 15.0]]))[0]
    # b takes off from there 0.6 s later: a is down, no hazard
    assert not table.conflicts(b[None], np.array([[5.6, 15.6]]))[0]


def test_empty_table_and_bad_shapes():
    table = ReservationTable(LO, HI, separation=10.0)
    p = np.zeros((3, 4, 3))
    assert not table.conflicts(p, np.zeros((3, 4))).any()
    with pytest.raises(ValueError):
        table.add("x", np.zeros((4, 2)), np.zeros(4))
    with pytest.raises(ValueError):
        table.conflicts(p, np.zeros((3, 5)))
    with pytest.raises(ValueError):
        ReservationTable(LO, HI, separation=0.0)


def _dense_curve(rng: np.random.Generator, n_turns: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """A smoothed-flight-like trajectory: straight legs and arcs of radius 20 m, sampled 5 m
    apart, flown at 20 m/s (the kind of trajectory reserved with a tolerance)."""
    pts = [np.array([rng.uniform(50, 150), rng.uniform(50, 150), 50.0])]
    head = rng.uniform(0, 2 * np.pi)
    for _ in range(n_turns):
        for _ in range(int(rng.integers(3, 12))):  # a straight leg
            pts.append(pts[-1] + 5.0 * np.array([np.cos(head), np.sin(head), 0.02]))
        turn = rng.uniform(-np.pi / 2, np.pi / 2)
        k = max(2, int(abs(turn) * 20 / 5))
        for _ in range(k):  # an arc of radius 20 m
            head += turn / k
            pts.append(pts[-1] + 20 * abs(turn) / k * np.array([np.cos(head), np.sin(head), 0]))
    p = np.array(pts)
    return p, _times(p)


def test_simplified_reservation_is_conservative_within_its_pad():
    """A trajectory reserved with a tolerance: fewer pieces, every conflict with the true
    trajectory still found, and distances lower bounds within the tolerance of the truth."""
    from uavplan.world.reservations import simplify_timed

    rng = np.random.default_rng(7)
    tol, sep = 0.1, 10.0
    for _ in range(15):
        p, t = _dense_curve(rng)
        keep, pad = simplify_timed(p, t, tol)
        assert keep[0] == 0 and keep[-1] == len(p) - 1 and np.all(np.diff(keep) > 0)
        assert pad.shape == (len(keep) - 1,) and np.all(pad <= tol + 1e-12)
        # the stated deviation is the largest one, at the original samples
        for i, (a, b) in enumerate(itertools.pairwise(keep)):
            f = (t[a : b + 1] - t[a]) / (t[b] - t[a])
            chord = p[a] + f[:, None] * (p[b] - p[a])
            assert np.max(np.linalg.norm(p[a : b + 1] - chord, axis=1)) == pytest.approx(
                pad[i], abs=1e-9
            )
        exact = ReservationTable(LO, HI, sep)
        padded = ReservationTable(LO, HI, sep)
        exact.add("a", p, t)
        padded.add("a", p, t, tolerance=tol)
        assert padded.n_pieces < exact.n_pieces
        # candidates: straight lines passing near the curve at random times
        q0 = p[rng.integers(0, len(p), 200)] + rng.normal(0, 15, (200, 3))
        q1 = q0 + rng.normal(0, 40, (200, 3))
        qp = np.stack([q0, q1], axis=1)
        t0 = rng.uniform(0, t[-1], 200)
        qt = np.stack([t0, t0 + np.linalg.norm(q1 - q0, axis=1) / 20.0], axis=1)
        ce, cp = exact.conflicts(qp, qt), padded.conflicts(qp, qt)
        assert np.all(cp[ce])  # never misses a real conflict
        de, dp = exact.min_distance(qp, qt), padded.min_distance(qp, qt)
        near = np.isfinite(de) & (de < sep)
        assert np.all(dp[near] <= de[near] + 1e-9)
        assert np.all(dp[near] >= de[near] - 2 * tol - 1e-9)  # chord within tol, less tol
        assert (cp & ~ce).sum() <= max(2, ce.sum() // 5)  # few false alarms


# ------------------------------------------------------------------ per-axis separation (box)
AXES = (50.0, 50.0, 20.0)  # the RSCDWOA paper's minimal distance between UAVs, Sect. 5


def _box_path(rng: np.random.Generator, n: int = 6) -> np.ndarray:
    """A random path in a 1.6 km x 1.6 km x 100 m box (sized to the 50 m separation)."""
    return rng.uniform(LO, HI * [4.0, 4.0, 1.0], size=(n, 3))


def _dense_box_measure(pa, ta, pb, tb, axes=AXES, step=0.002):
    """Sampled reference of the box measure max(S) max_i |r_i| / S_i."""
    lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
    if lo > hi:
        return np.inf
    t = np.linspace(lo, hi, max(2, int((hi - lo) / step)))
    a = np.stack([np.interp(t, ta, pa[:, d]) for d in range(3)], axis=1)
    b = np.stack([np.interp(t, tb, pb[:, d]) for d in range(3)], axis=1)
    S = np.asarray(axes)
    return float(S.max() * np.min(np.max(np.abs(a - b) / S, axis=1)))


@pytest.mark.parametrize("dt", [1.0, 3.0])
def test_box_conflicts_equal_brute_force(dt):
    rng = np.random.default_rng(int(dt * 10))
    table = ReservationTable(LO, HI * [4.0, 4.0, 1.0], separation=AXES, dt=dt)
    assert table.axes == AXES and table.separation == 50.0
    _agrees_with_brute_force(table, rng, _box_path, 10, 80.0)


def test_box_measure_agrees_with_dense_sampling():
    rng = np.random.default_rng(3)
    table = ReservationTable(LO, HI, separation=AXES, dt=1.0)
    pa = _box_path(rng)
    ta = _times(pa)
    table.add("a", pa, ta)
    for _ in range(30):
        pb = _box_path(rng)
        tb = _times(pb, t0=rng.uniform(0, 3))
        exact = table.min_distance_reference(pb, tb)
        got = float(table.min_distance(pb[None], tb[None])[0])
        dense = _dense_box_measure(pa, ta, pb, tb)
        assert exact <= dense + 1e-9
        # closing at <= 40 m/s, scaled by at most 50 / 20 on z, sampled every 0.002 s
        assert dense - exact < 0.3
        if exact < 50.0:
            assert got == pytest.approx(exact, abs=1e-9)


def test_box_is_not_a_sphere():
    """Stacked 30 m apart in z: clear of the [50, 50, 20] box though 30 m is less than 50; side
    by side 40 m apart in x and 10 m in z: inside the box though farther apart than 10 m."""
    a = np.array([[0.0, 100.0, 50.0], [200.0, 100.0, 50.0]])
    t = np.array([0.0, 10.0])
    box = ReservationTable(LO, HI, separation=AXES)
    box.add("a", a, t)
    above = a + np.array([0.0, 0.0, 30.0])
    assert not box.conflicts(above[None], t[None])[0]
    np.testing.assert_allclose(box.min_distance(above[None], t[None]), [75.0])  # 50 * 30 / 20
    beside = a + np.array([40.0, 0.0, 10.0])
    assert box.conflicts(beside[None], t[None])[0]
    sphere = ReservationTable(LO, HI, separation=50.0)
    sphere.add("a", a, t)
    assert sphere.conflicts(above[None], t[None])[0]
    small = ReservationTable(LO, HI, separation=10.0)
    small.add("a", a, t)
    assert not small.conflicts(beside[None], t[None])[0]
    # the enclosing sphere a sphere-minded planner keeps
    assert box.radius == pytest.approx(np.sqrt(50**2 + 50**2 + 20**2))


def test_box_crossing_between_samples_is_a_conflict():
    # Two UAVs cross at right angles, 15 m apart in z (inside the box's 20 m), both at 20 m/s:
    # at whole seconds they are >= 20 m apart in x or y, yet for 2.5 s inside 50 m on both.
    table = ReservationTable(LO, HI, separation=AXES, dt=1.0)
    table.add("a", np.array([[0.0, 200.0, 50.0], [400.0, 200.0, 50.0]]), np.array([0.0, 20.0]))
    b = np.array([[200.0, 0.0, 65.0], [200.0, 400.0, 65.0]])
    tb = np.array([0.0, 20.0])
    assert table.conflicts(b[None], tb[None])[0]
    np.testing.assert_allclose(table.min_distance(b[None], tb[None]), [37.5])  # 50 * 15 / 20
    assert not table.conflicts((b + np.array([0, 0, 20.0]))[None], tb[None])[0]


def test_box_separation_rejects_bad_axes():
    with pytest.raises(ValueError, match="separation"):
        ReservationTable(LO, HI, separation=(50.0, 0.0, 20.0))
    with pytest.raises(ValueError, match="separation"):
        ReservationTable(LO, HI, separation=(50.0, 20.0))


@pytest.mark.parametrize(
    ("timing", "axes"), [(None, False), (None, True), ((2.0, 0.03), False)]
)  # a per-axis separation has no execution model
def test_the_first_free_take_off_is_the_first_wait_without_a_conflict(timing, axes):
    """:meth:`ReservationTable.first_free` gives the first wait at which :meth:`conflicts`
    says the path, taking off that much later, is clear (whatever segment the search starts
    on), and the segment it names is one where the path conflicts at the last blocked
    wait: alone in the nominal table (its other segments left out); under the model, a
    window reading the path's take-off, against every reserved piece by brute force."""
    rng = np.random.default_rng(5 + 2 * axes + (timing is not None))
    sep = (10.0, 10.0, 4.0) if axes else 10.0
    table = ReservationTable(LO, HI, separation=sep, dt=1.0, timing=timing)
    spread, n = (20.0, 12) if timing is None else (120.0, 4)  # a drifting schedule: wide windows
    for i in range(n):
        p = _random_path(rng)
        table.add(f"u{i}", p, _times(p, t0=rng.uniform(0, spread)))
    waits = np.arange(0.0, 200.0, 2.5)
    checked = found = 0
    for _ in range(30):
        c = _random_path(rng, 9)
        t = _times(c, t0=rng.uniform(0, 5))
        hit = table.conflicts(np.broadcast_to(c, (len(waits), *c.shape)), t + waits[:, None])
        for start, stop, first in ((0, len(waits), 0), (3, 40, 5), (10, 12, 99)):
            i, seg = table.first_free(c, t, waits, start, stop, first)
            free = np.flatnonzero(~hit[start:stop])
            assert i == (start + free[0] if free.size else -1)
            checked += 1
            if seg == first or (i >= 0 and i == start):
                continue  # no conflict found: the hint is handed back
            found += 1
            last = (i if i >= 0 else stop) - 1  # the last blocked wait searched
            tl = t + waits[last]
            if timing is None:
                assert table.conflicts(c[seg : seg + 2][None], tl[seg : seg + 2][None])[0]
                continue
            a0, a1, t0, t1, _ = _split(c[seg : seg + 2], tl[seg : seg + 2], 1.0)
            d2 = min(
                window_min_dist2(a0[k], a1[k], t0[k], t1[k], table._p0[j], table._p1[j],
                                 table._t0[j], table._t1[j], tl[0], *timing,
                                 table._take[j], *timing)
                for k in range(len(t0)) for j in range(table.n_pieces)
            )  # fmt: skip
            assert np.sqrt(d2) < table.separation
    assert found > 10
    empty = ReservationTable(LO, HI, separation=10.0)
    assert empty.first_free(c, t, waits, 4, 9, 2) == (4, 2)


def _descent_and_level() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 28.6 degree descent at 13 m/s (its heights lag about 40 m with 3 m/s of wind behind
    a 30 degree limit) and a level flight 30 m beside its first leg, at the same times."""
    g = math.tan(math.radians(28.6))
    x = np.array([0.0, 100.0, 500.0, 550.0, 900.0])
    z = np.array([300.0, 300.0, 300.0 - 400.0 * g, 300.0 - 400.0 * g, 300.0 - 400.0 * g])
    a = np.column_stack([x, np.zeros_like(x), z])
    b = np.column_stack([x, np.full_like(x, 30.0), np.full_like(x, 300.0)])
    return a, b, x / 13.0


def test_a_lagging_flight_is_held_off_by_its_lag_reserved_or_asked() -> None:
    """With a lag (wind, climb and descent limits), a reserved flight whose heights lag is
    padded by its segments' lags, and a path asked about is held off by its own; the first
    free take-off says the same; without wind there is no lag."""
    from uavplan.world.execution import lag_extents

    a, b, t = _descent_and_level()
    top = lag_extents(a[None], t[None], 3.0, 30.0, 30.0)[0][0]
    assert 20.0 < top < 50.0  # beyond the 30 m - 10 m the pair has to spare
    lo, hi = np.array([-100.0, -100.0, -200.0]), np.array([1000.0, 200.0, 500.0])
    for reserved, asked in ((a, b), (b, a)):
        plain = ReservationTable(lo, hi, 10.0)
        lagged = ReservationTable(lo, hi, 10.0, lag=(3.0, 30.0, 30.0))
        still = ReservationTable(lo, hi, 10.0, lag=(0.0, 30.0, 30.0))
        for table in (plain, lagged, still):
            table.add("r", reserved, t)
        assert not plain.conflicts(asked[None], t[None])[0]
        assert not still.conflicts(asked[None], t[None])[0] and still.lag is None
        assert lagged.conflicts(asked[None], t[None])[0]
        # a path asked about as a planned polyline is not held off by its own lag
        assert lagged.conflicts(asked[None], t[None], held=False)[0] == (reserved is a)
        waits = np.array([0.0, 200.0])  # after the reserved flight has landed: clear
        assert plain.first_free(asked, t, waits, 0, 2)[0] == 0
        assert lagged.first_free(asked, t, waits, 0, 2)[0] == 1
    # held off by the lag of the descent's segment (the largest), no more
    table = ReservationTable(lo, hi, 10.0, lag=(3.0, 30.0, 30.0))
    table.add("r", a, t)
    for side, conflict in ((10.0 + top - 0.5, True), (10.0 + top + 0.5, False)):
        level = b + np.array([0.0, side - 30.0, 0.0])
        assert table.conflicts(level[None], t[None])[0] == conflict


def test_a_flight_is_held_off_by_the_lag_of_its_segment_not_of_its_whole_flight() -> None:
    """The descent of :func:`_descent_and_level` flown on level to 2 km: its lag closes a
    few hundred metres after the descent, and a level flight 30 m beside its last kilometre
    only (S2 10 m) keeps clear whichever of the two is reserved or asked, though the whole
    flight's largest lag (over 20 m) would not let it; beside the descent it does not."""
    from uavplan.world.execution import lag_extents

    a, _, _ = _descent_and_level()
    a = np.vstack([a, [[1000.0, 0.0, a[-1, 2]], [2000.0, 0.0, a[-1, 2]]]])
    t = np.hypot(np.diff(a[:, 0]), np.diff(a[:, 2])).cumsum() / 13.0
    t = np.concatenate([[0.0], t])
    top, seg = lag_extents(a[None], t[None], 3.0, 30.0, 30.0)
    assert top[0] > 20.0 and seg[0, -1] == 0.0 and seg[0, 1] == top[0]
    lo, hi = np.array([-100.0, -100.0, -200.0]), np.array([2100.0, 200.0, 500.0])
    for x0, z, clear in ((1200.0, a[-1, 2], True), (100.0, 300.0, False)):
        # level beside a from x0 for 800 m, at a's own times there
        bx = np.array([x0, x0 + 800.0])
        b = np.column_stack([bx, np.full(2, 30.0), np.full(2, z)])
        tb = np.interp(bx, a[:, 0], t)
        for reserved, rt, asked, at in ((a, t, b, tb), (b, tb, a, t)):
            table = ReservationTable(lo, hi, 10.0, lag=(3.0, 30.0, 30.0))
            table.add("r", reserved, rt)
            assert bool(table.conflicts(asked[None], at[None])[0]) == (not clear), (x0, reserved)
